"""Monte Carlo on an NVIDIA GPU (``device: gpu``): the device check and the engine.

:class:`GpuEngine` runs a :class:`.montecarlo.MonteCarloSpec` (a fixed topology, a
switching set or a sampled A(t)) or one of A(t) as expressions (:class:`.timevarying.ExpressionModes`)
(A(t) given as expressions) with the kernels of :mod:`.cuda_kernels` and returns the
same :class:`.montecarlo.PartialStats` as the CPU: the paths are split into the CPU's
blocks and each block's paths are seeded from the same xoshiro256** states
(:func:`.rng.path_states`), so path q on the GPU is path q on the CPU, to rounding. The
gain, whatever its kind (an expression, a power law, a schedule table), is evaluated on
the host on the grid once (c_k·h and c_k·√h per step), as the CPU does. The state is
checked (NaN or overflow) and the statistics recorded at the CPU's check and save
points, so a divergence is reported at the same time, path and agent.

How the paths are laid out on the device is :mod:`.gpu_run`'s (a thread per path for a
small network, a thread per row and path for a large one; :mod:`.cuda_kernels`), and an
A(t) given as expressions :mod:`.gpu_timevarying`'s.

numba-cuda is imported only here and only when a run asks for the GPU; with
``NTC_CUDA_SIMULATOR=1`` it is numba-cuda's simulator (every thread in Python: for
tests, slow), chosen before ``numba.cuda`` is first imported.
"""

from __future__ import annotations

import importlib.util
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..choices import Layout, choices
from ..errors import InputError, Option, one_line
from .modes import FixedModes
from .montecarlo import MonteCarloSpec, PartialStats, PathBlocks

SIMULATOR_ENV = "NTC_CUDA_SIMULATOR"
INSTALL = "pip install 'ntc-design[gpu]'"
#: The advice when the GPU cannot run: the CPU (the scenario's field, or the flag that gave it).
CPU = Option("device", "cpu", document=True)
LAYOUTS = choices(Layout)


def simulator_requested() -> bool:
    """Whether ``NTC_CUDA_SIMULATOR=1`` asks for numba-cuda's simulator.

    Returns
    -------
    bool
    """
    return os.environ.get(SIMULATOR_ENV, "") == "1"


def load_cuda() -> Any:
    """``numba.cuda``, imported now (the simulator when :func:`simulator_requested`),
    after checking that it can run a kernel.

    Returns
    -------
    module
        ``numba.cuda``.

    Raises
    ------
    InputError
        One line naming what is missing: numba-cuda (not installed with the ``gpu``
        extra), the CUDA bindings, an NVIDIA driver or device, or NVVM.
    """
    sim = simulator_requested()
    if importlib.util.find_spec("numba_cuda") is None:
        raise InputError(
            "gpu needs numba-cuda, which is not installed (ntc-design was not "
            f"installed with the gpu extra: {INSTALL}); or use ",
            CPU,
            field="device",
        )
    if sim:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        from numba.core import config  # numba's, which numba-cuda reads, read at import

        config.reload_config()
    try:
        from numba import cuda
    except ImportError as exc:  # numba-cuda without its CUDA bindings, or a broken install
        raise InputError(
            f"gpu: numba-cuda does not import ({one_line(str(exc))}); reinstall with {INSTALL}",
            field="device",
        ) from None
    if _simulating(cuda):
        return cuda
    if sim:  # numba.cuda was imported before the variable was set: it keeps the device
        raise InputError(
            f"{SIMULATOR_ENV}=1 was set after numba.cuda was imported in this "
            "process; set it before starting Python",
            field="device",
        )
    if not cuda.is_available():
        raise InputError(f"gpu: {_why_unavailable()}; use ", CPU, field="device")
    from numba.cuda.cudadrv import nvvm

    if not nvvm.is_available():
        raise InputError(
            "gpu: numba-cuda finds no NVVM (the CUDA compiler of the toolkit); "
            f"install the gpu extra ({INSTALL}), which brings it",
            field="device",
        )
    return cuda


def _simulating(cuda) -> bool:
    """Whether this ``numba.cuda`` is the simulator (numba's configuration, which
    numba-cuda reads when numba is there)."""
    from numba.core import config

    return bool(getattr(config, "ENABLE_CUDASIM", 0))


def _why_unavailable() -> str:
    """Why numba-cuda sees no device, in a phrase (the driver's own words, one line)."""
    try:
        from numba.cuda.cudadrv.driver import driver

        err = driver.initialization_error
        if not err:
            driver.get_device_count()  # raises when the driver works but sees no device
            return "no NVIDIA GPU is visible to the CUDA driver"
    except Exception as exc:  # the driver's own failure, whatever its class
        err = str(exc)
    text = one_line(str(err))
    if "cannot be found" in text or "libcuda" in text:
        return "no NVIDIA driver on this machine (the CUDA driver library libcuda.so is not found)"
    return f"no usable NVIDIA GPU ({text})"


def gpu_available() -> tuple[bool, str]:
    """Whether ``device: gpu`` can run here, and why not.

    Returns
    -------
    (bool, str)
        True and the device's name, or False and the one-line reason.
    """
    try:
        cuda = load_cuda()
    except InputError as exc:
        return False, str(exc)
    return True, device_name(cuda)


def device_name(cuda) -> str:
    """The device's name (``CUDA simulator`` for the simulator).

    Parameters
    ----------
    cuda : module
        ``numba.cuda`` from :func:`load_cuda`.

    Returns
    -------
    str
    """
    if _simulating(cuda):
        return "CUDA simulator"
    name = cuda.get_current_device().name
    return name.decode() if isinstance(name, bytes) else str(name)


@dataclass(frozen=True)
class GpuEngine:
    """Runs the Monte Carlo blocks on the GPU (``simulate(..., device="gpu")``); the
    result is the CPU's to rounding (see the module docstring).

    Attributes
    ----------
    layout : str
        ``auto`` (a thread per path up to :data:`.gpu_run.FUSED_MAX_STATE` numbers of
        state, else a thread per row and path), ``fused`` or ``sparse``.
    """

    layout: Layout = "auto"

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise InputError(
                f"expected one of {', '.join(LAYOUTS)}, got {self.layout!r}", field="layout"
            )

    def describe(self) -> dict:
        """What runs the work, for summaries.

        Returns
        -------
        dict
            ``engine`` ("gpu") and ``device`` (its name).

        Raises
        ------
        InputError
            No usable GPU (:func:`load_cuda`).
        """
        return {"engine": "gpu", "device": device_name(load_cuda())}

    def run_mc(self, spec, progress: Callable[[int, int], None] | None = None) -> PartialStats:
        """Every path of ``spec`` on the GPU.

        Parameters
        ----------
        spec : MonteCarloSpec
            The run (explicit scheme, xoshiro normals, a linear f).
        progress : callable(done, total), optional
            Called with path-steps done.

        Returns
        -------
        PartialStats
            Merged over the blocks, as :func:`.montecarlo.run` gives them.

        Raises
        ------
        InputError
            No usable GPU, or a run the GPU does not do (one line naming the field).
        """
        check_supported(spec)
        cuda = load_cuda()
        from numba.core.errors import NumbaPerformanceWarning

        with warnings.catch_warnings():
            if _simulating(cuda):  # uint64 arithmetic wraps by design (xoshiro)
                warnings.simplefilter("ignore", RuntimeWarning)
            # small grids (the statistics of few agents, the simulator's few paths) are
            # by design, not a user's concern
            warnings.simplefilter("ignore", NumbaPerformanceWarning)
            if isinstance(spec, MonteCarloSpec) and isinstance(spec.modes, FixedModes):
                from .gpu_run import run_modes

                return run_modes(cuda, spec, self.layout, progress)
            from .gpu_timevarying import run_time_varying

            return run_time_varying(cuda, spec, self.layout, progress)


def check_supported(spec: PathBlocks) -> None:
    """Refuse, in one line naming the field, a run the GPU kernels do not do.

    Parameters
    ----------
    spec : PathBlocks
        The run.

    Raises
    ------
    InputError
        ``rng: numpy``, ``scheme: implicit`` or a callable f.
    """
    if spec.rng != "xoshiro":
        raise InputError(
            "numpy stays on the CPU (device: gpu draws xoshiro256** normals in the kernel)",
            field="rng",
        )
    if spec.scheme != "explicit":
        raise InputError("implicit runs on the CPU only (device: cpu)", field="scheme")
    if spec.callable_f():
        raise InputError("a callable f runs on the CPU only (device: cpu)", field="noise.f")


__all__ = [
    "INSTALL",
    "LAYOUTS",
    "SIMULATOR_ENV",
    "GpuEngine",
    "check_supported",
    "device_name",
    "gpu_available",
    "load_cuda",
    "simulator_requested",
]
