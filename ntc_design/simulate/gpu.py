"""Monte Carlo on an NVIDIA GPU (``device: gpu``): the device check and the engine.

:class:`GpuEngine` runs a :class:`.montecarlo.MonteCarloSpec` (a fixed topology, a
switching set or a sampled A(t)) or a :class:`.timevarying.TimeVaryingMonteCarloSpec`
(A(t) given as expressions) with the kernels of :mod:`.cuda_kernels` and returns the
same :class:`.montecarlo.PartialStats` as the CPU: the paths are split into the CPU's
blocks and each block's paths are seeded from the same xoshiro256** states
(:func:`.rng.path_states`), so path q on the GPU is path q on the CPU, to rounding. The
gain, whatever its kind (an expression, a power law, a schedule table), is evaluated on
the host on the grid once (c_k·h and c_k·√h per step), as the CPU does. The state is
checked (NaN or overflow) and the statistics recorded at the CPU's check and save
points, so a divergence is reported at the same time, path and agent.

Paths go in chunks of whole blocks (:data:`CHUNK_BYTES` of state at most); a small
network (``slots·N·d`` <= :data:`FUSED_MAX_STATE`) runs one thread per path with every
step fused, a larger one a thread per (row, path) (:mod:`.cuda_kernels`). Only the sums
per save time, the stored paths and the failure come back to the host.

numba-cuda is imported only here and only when a run asks for the GPU; with
``NTC_CUDA_SIMULATOR=1`` it is numba-cuda's simulator (every thread in Python: for
tests, slow), chosen before ``numba.cuda`` is first imported.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, one_line
from .grid import TimeGrid
from .montecarlo import BATCH, XI_BYTES, PartialStats, merge
from .rng import ZIG_R, ZIG_X, path_states

SIMULATOR_ENV = "NTC_CUDA_SIMULATOR"
INSTALL = "pip install 'ntc-design[gpu]'"
LAYOUTS = ("auto", "fused", "sparse")
FUSED_MAX_STATE = 256  # slots·N·d of a thread-per-path state (local memory); to tune on a GPU
FUSED_MAX_DRAW = 512  # normals a thread keeps per step in the fused kernel
CHUNK_BYTES = 2 * 2**30  # device memory for the states of one chunk of paths
THREADS = 128  # threads per block of the path kernels
ROW_THREADS = 256  # threads per block of the (row, path) kernels
PATHS_PER_THREAD = 64  # paths one thread sums in the statistics


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
            "device: gpu needs numba-cuda, which is not installed (ntc-design was not "
            f"installed with the gpu extra: {INSTALL}); or use device: cpu"
        )
    if sim:
        if "numba.cuda" in sys.modules and not _simulating(sys.modules["numba.cuda"]):
            raise InputError(
                f"device: {SIMULATOR_ENV}=1 was set after numba.cuda was imported in this "
                "process; set it before starting Python"
            )
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        from numba.core import config  # numba's, which numba-cuda reads, read at import

        config.reload_config()
    try:
        from numba import cuda
    except ImportError as exc:  # numba-cuda without its CUDA bindings, or a broken install
        raise InputError(
            f"device: gpu: numba-cuda does not import ({one_line(str(exc))}); "
            f"reinstall with {INSTALL}"
        ) from None
    if _simulating(cuda):
        return cuda
    if not cuda.is_available():
        raise InputError(f"device: gpu: {_why_unavailable()}; use device: cpu")
    from numba.cuda.cudadrv import nvvm

    if not nvvm.is_available():
        raise InputError(
            "device: gpu: numba-cuda finds no NVVM (the CUDA compiler of the toolkit); "
            f"install the gpu extra ({INSTALL}), which brings it"
        )
    return cuda


def _simulating(cuda) -> bool:
    """Whether this ``numba.cuda`` is the simulator."""
    from numba.cuda.core import config

    return bool(config.ENABLE_CUDASIM)


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


# -- the modes' arrays, concatenated ----------------------------------------------------


@dataclass(frozen=True, eq=False)
class ModeArrays:
    """Every mode's L_B (CSR, and 3×3 block-CSR when d = 3), u and edges, concatenated
    with absolute offsets per mode (the arrays :mod:`.cuda_kernels` takes), and the edges
    into each agent in ascending order (``eptr``, ``eids``: the sparse layout's sums in
    the CPU kernel's order)."""

    iptr: np.ndarray  # (M, Nd+1)
    ind: np.ndarray
    val: np.ndarray
    bptr: np.ndarray  # (M, N+1), or (M, 1) when d != 3
    bind: np.ndarray
    bval: np.ndarray  # (·, 3, 3)
    u: np.ndarray  # (M, Nd)
    e_off: np.ndarray  # (M,)
    e_cnt: np.ndarray  # (M,)
    src: np.ndarray
    dst: np.ndarray
    kmat: np.ndarray  # (Etot, d, d)
    gvec: np.ndarray  # (Etot, d)
    eptr: np.ndarray  # (M, N+1)
    eids: np.ndarray
    n: int
    d: int

    @property
    def d3(self) -> bool:
        """Whether d = 3 (the drift by 3×3 blocks, as the CPU kernel sums it)."""
        return self.d == 3

    @property
    def e_max(self) -> int:
        """The edges of the widest mode."""
        return int(self.e_cnt.max(initial=0))

    @classmethod
    def build(cls, parts: Sequence[tuple], n: int, d: int) -> ModeArrays:
        """Concatenate the kernel arrays of several modes.

        Parameters
        ----------
        parts : sequence of tuple
            Per mode, :func:`.kernels.kernel_arrays`' (indptr, indices, data, bptr, bind,
            bdata, u, src, dst, kmat, gvec).
        n, d : int
            Agents and state dimension.

        Returns
        -------
        ModeArrays
        """
        nd = n * d
        iptr, ind, val, bptr, bind, bval, us = [], [], [], [], [], [], []
        e_off, e_cnt, src, dst, kmat, gvec, eptr, eids = [], [], [], [], [], [], [], []
        nz = nb = ne = 0
        for indptr, indices, data, bp, bi, bd, u, s, t, km, gv in parts:
            iptr.append(indptr + nz)
            ind.append(indices)
            val.append(data)
            nz += indices.size
            bptr.append(bp + nb if d == 3 else np.zeros(1, np.int64))
            bind.append(bi)
            bval.append(bd)
            nb += bi.size
            us.append(u)
            e_off.append(ne)
            e_cnt.append(s.size)
            src.append(s)
            dst.append(t)
            kmat.append(km.reshape(-1, d, d))
            gvec.append(gv.reshape(-1, d))
            order = np.argsort(t, kind="stable")  # per agent, its edges in ascending order
            eptr.append(np.concatenate([[0], np.cumsum(np.bincount(t, minlength=n))]) + ne)
            eids.append(order)
            ne += s.size

        def cat(xs, dtype, shape=()):
            a = np.concatenate(xs).astype(dtype) if xs else np.zeros(0, dtype)
            a = a.reshape((-1, *shape))
            return a if a.shape[0] else np.zeros((1, *shape), dtype)  # no empty device arrays

        return cls(
            iptr=np.stack(iptr).astype(np.int64),
            ind=cat(ind, np.int64),
            val=cat(val, float),
            bptr=np.stack(bptr).astype(np.int64),
            bind=cat(bind, np.int64),
            bval=cat(bval, float, (3, 3)),
            u=np.stack(us).astype(float).reshape(len(parts), nd),
            e_off=np.array(e_off, np.int64),
            e_cnt=np.array(e_cnt, np.int64),
            src=cat(src, np.int64),
            dst=cat(dst, np.int64),
            kmat=cat(kmat, float, (d, d)),
            gvec=cat(gvec, float, (d,)),
            eptr=np.stack(eptr).astype(np.int64),
            eids=cat(eids, np.int64),
            n=n,
            d=d,
        )

    @classmethod
    def of_systems(cls, systems) -> ModeArrays:
        """The arrays of the modes of a run.

        Parameters
        ----------
        systems : sequence of ModeSystem
            The modes (a compiled f).

        Returns
        -------
        ModeArrays
        """
        from .kernels import kernel_arrays  # numba: only when simulating

        s0 = systems[0]
        return cls.build([kernel_arrays(s) for s in systems], s0.n_agents, s0.dim)

    def device(self, cuda) -> tuple:
        """The arrays on the device, in the fused kernel's order.

        Parameters
        ----------
        cuda : module
            ``numba.cuda``.

        Returns
        -------
        tuple
            (iptr, ind, val, bptr, bind, bval, u, e_off, e_cnt, src, dst, kmat, gvec,
            eptr, eids) as device arrays.
        """
        names = (
            "iptr", "ind", "val", "bptr", "bind", "bval", "u", "e_off", "e_cnt", "src",
            "dst", "kmat", "gvec", "eptr", "eids",
        )  # fmt: skip
        return tuple(cuda.to_device(np.ascontiguousarray(getattr(self, k))) for k in names)


# -- the run ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Schedule:
    """Where a chunk stops: every save step and every check step of the CPU (the end of
    each batch of steps), in order; with the steps' c·h, c·√h and mode on the host."""

    grid: TimeGrid
    ch: np.ndarray
    cs: np.ndarray
    mode: np.ndarray
    stops: np.ndarray  # the grid indices > 0 where a launch ends
    checks: frozenset
    saves: dict  # grid index -> save slot

    @classmethod
    def of(cls, grid: TimeGrid, gain: Callable, batch: int) -> Schedule:
        """The schedule of a grid with the CPU's check batch.

        Parameters
        ----------
        grid : TimeGrid
            The run's grid.
        gain : callable
            Vectorised c(t).
        batch : int
            Steps between the CPU's checks.

        Returns
        -------
        Schedule
        """
        k_total = grid.n_steps
        c_all = np.asarray(gain(grid.t[:-1]), dtype=float) * np.ones(k_total)
        h_all = np.diff(grid.t)
        checks = set(range(batch, k_total, batch)) | {k_total}
        saves = {int(k): i for i, k in enumerate(grid.save_steps)}
        stops = np.array(sorted((checks | set(saves)) - {0}), dtype=np.int64)
        mode = grid.mode.astype(np.int64) if grid.mode.size else np.zeros(k_total, np.int64)
        return cls(grid, c_all * h_all, c_all * np.sqrt(h_all), mode, stops, frozenset(checks), saves)  # fmt: skip


def check_batch(paths: int, e_max: int) -> int:
    """The CPU's steps between two checks of a block of ``paths`` paths
    (:func:`.montecarlo._run_block`).

    Parameters
    ----------
    paths : int
        The block's paths.
    e_max : int
        The edges of the widest mode.

    Returns
    -------
    int
    """
    return int(np.clip(XI_BYTES // (8 * paths * max(2 * e_max, 1)), 1, BATCH))


class _Chunk:
    """One chunk of paths on the device: its ring of states, streams and sums."""

    def __init__(self, run: _Run, g0: int, states: np.ndarray):
        cu, p, nd = run.cuda, states.shape[0], run.nd
        self.run, self.g0, self.p = run, g0, p
        self.x = cu.to_device(np.tile(run.x_init[:, None], (run.ring, p)))
        self.st = cu.to_device(np.ascontiguousarray(states.T))
        n_saves, q = run.sched.grid.save_steps.size, 2 * run.n + nd
        self.acc = cu.to_device(np.zeros((max(n_saves, 1), q)))
        self.n_store = max(0, min(run.store_paths - g0, p))
        self.stored = cu.to_device(np.zeros((max(n_saves, 1), max(self.n_store, 1), nd)))
        self.groups = -(-p // PATHS_PER_THREAD)
        self.part = cu.device_array((self.groups, q))
        self.bad = cu.to_device(np.array([np.iinfo(np.int64).max], np.int64))
        self.valid = 0
        self.failure: dict | None = None
        if run.sparse:
            self.z = cu.device_array((max(run.m_draw, 1), p))

    def at(self, k: int) -> bool:
        """Check and record at grid index k (when it is a check or a save point).

        Parameters
        ----------
        k : int
            The grid index reached.

        Returns
        -------
        bool
            False once a state is not finite (the failure kept).
        """
        run = self.run
        save = run.sched.saves.get(k)
        if save is None and k not in run.sched.checks:
            return True
        from . import cuda_kernels as ck

        row0, cells = (k % run.ring) * run.nd, run.nd * self.p
        ck.check_kernel()[_blocks(cells, ROW_THREADS), min(ROW_THREADS, cells)](
            self.x, row0, run.nd, self.bad
        )
        code = int(self.bad.copy_to_host()[0])
        if code != np.iinfo(np.int64).max:
            q, r = divmod(code, run.nd)
            t = run.sched.grid.save_times[save] if save is not None else run.sched.grid.t[k]
            self.failure = {
                "t": float(t),
                "agent": r // run.d,
                "path": self.g0 + q,
                "save_index": self.valid,
            }
            return False
        if save is not None:
            tn = min(THREADS, run.n)
            ck.stats_kernel()[(_blocks(run.n, tn), self.groups), tn](
                self.x, row0, run.theta, run.n, run.d, PATHS_PER_THREAD, self.part,
                self.stored, self.n_store, save,
            )  # fmt: skip
            q = self.part.shape[1]
            ck.sum_kernel()[_blocks(q, THREADS), min(THREADS, q)](
                self.part, self.groups, self.acc, save
            )
            self.valid = save + 1
        return True

    def advance(self, k_from: int, k_to: int) -> None:
        """Steps k_from … k_to − 1 of every path of the chunk.

        Parameters
        ----------
        k_from, k_to : int
            Grid indices.
        """
        from . import cuda_kernels as ck

        run, p = self.run, self.p
        if not run.sparse:
            kern = ck.fused_kernel(run.nd, run.ring, run.m_draw, run.modes.d3)
            kern[_blocks(p, THREADS), min(THREADS, p)](
                self.x, self.st, k_from, k_to, run.ch, run.cs, run.mode, *run.dev[:13],
                run.d, run.zx, run.zr,
            )  # fmt: skip
            return
        draw, step = ck.draw_kernel(), ck.step_kernel(run.modes.d3)
        dv = run.dev
        cells = run.nd * p
        for k in range(k_from, k_to):
            draw[_blocks(p, THREADS), min(THREADS, p)](
                self.st, self.z, run.m_draw, float(run.sched.cs[k]), run.zx, run.zr
            )
            step[_blocks(cells, ROW_THREADS), min(ROW_THREADS, cells)](
                self.x, self.z, k % run.ring, (k - run.delay) % run.ring,
                (k + 1) % run.ring, float(run.sched.ch[k]), int(run.sched.mode[k]), run.nd,
                *dv[:9], dv[13], dv[14], dv[9], dv[11], dv[12], run.d,
            )  # fmt: skip

    def result(self, blocks: list[int]) -> PartialStats:
        """The chunk's sums, stored paths and failure.

        Parameters
        ----------
        blocks : list of int
            The CPU blocks the chunk holds.

        Returns
        -------
        PartialStats
        """
        run, n = self.run, self.run.n
        n_saves = run.sched.grid.save_steps.size
        acc = self.acc.copy_to_host()[:n_saves]
        stored = self.stored.copy_to_host()[:n_saves, : self.n_store]
        return PartialStats(
            blocks, self.p, acc[:, :n], acc[:, n : 2 * n], acc[:, 2 * n :],
            np.ascontiguousarray(stored.transpose(1, 0, 2)),
            list(range(self.g0, self.g0 + self.n_store)), self.failure, self.valid,
        )  # fmt: skip


def _blocks(count: int, threads: int) -> int:
    return max(1, -(-count // max(threads, 1)))


class _Run:
    """What every chunk of a run shares: the device, the modes, the schedule."""

    def __init__(self, cuda, spec, modes: ModeArrays, sched: Schedule, layout: str, delay: int):
        self.cuda, self.modes, self.sched, self.delay = cuda, modes, sched, delay
        self.n, self.d = modes.n, modes.d
        self.nd = self.n * self.d
        self.m_draw = 2 * modes.e_max
        small = (delay + 1) * self.nd <= FUSED_MAX_STATE and self.m_draw <= FUSED_MAX_DRAW
        self.sparse = layout == "sparse" or (layout == "auto" and not small)
        self.ring = delay + (2 if self.sparse else 1)
        self.x_init = np.asarray(spec.x_init, dtype=float)
        self.store_paths = int(spec.store_paths)
        self.theta = cuda.to_device(np.asarray(spec.theta, dtype=float))
        self.zx, self.zr = cuda.to_device(ZIG_X), cuda.to_device(ZIG_R)
        self.ch, self.cs = cuda.to_device(sched.ch), cuda.to_device(sched.cs)
        self.mode = cuda.to_device(sched.mode)
        self.dev = modes.device(cuda)

    def chunk_paths(self) -> int:
        """Paths whose states fit :data:`CHUNK_BYTES` (at least one)."""
        per = 8 * (self.ring * self.nd + (self.m_draw if self.sparse else 0) + 4)
        return max(1, CHUNK_BYTES // per)


@dataclass(frozen=True)
class GpuEngine:
    """Runs the Monte Carlo blocks on the GPU (``simulate(..., device="gpu")``); the
    result is the CPU's to rounding (see the module docstring).

    Attributes
    ----------
    layout : str
        ``auto`` (a thread per path up to :data:`FUSED_MAX_STATE` numbers of state, else a
        thread per row and path), ``fused`` or ``sparse``.
    """

    layout: str = "auto"

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise InputError(f"layout: expected one of {', '.join(LAYOUTS)}, got {self.layout!r}")

    def describe(self) -> dict:
        """What runs the work, for summaries.

        Returns
        -------
        dict
            ``engine`` ("gpu") and ``device`` (its name).
        """
        return {"engine": "gpu", "device": device_name(load_cuda())}

    def run_mc(self, spec, progress: Callable[[int, int], None] | None = None) -> PartialStats:
        """Every path of ``spec`` on the GPU.

        Parameters
        ----------
        spec : MonteCarloSpec or TimeVaryingMonteCarloSpec
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
        with warnings.catch_warnings():
            if _simulating(cuda):  # uint64 arithmetic wraps by design (xoshiro)
                warnings.simplefilter("ignore", RuntimeWarning)
            if hasattr(spec, "systems"):
                return self._run_modes(cuda, spec, progress)
            from .gpu_timevarying import run_time_varying

            return run_time_varying(self, cuda, spec, progress)

    def _run_modes(self, cuda, spec, progress) -> PartialStats:
        modes = ModeArrays.of_systems(spec.systems)
        bp = spec.block_paths
        sched = Schedule.of(spec.grid, spec.gain, check_batch(bp, modes.e_max))
        run = _Run(cuda, spec, modes, sched, self.layout, int(getattr(spec, "delay", 0)))
        return run_chunks(run, spec, bp, progress, lambda ch, tick: drive(ch, sched, tick))


def drive(chunk: _Chunk, sched: Schedule, tick: Callable[[int], None] | None = None) -> None:
    """Run a chunk over the whole grid, launch by launch, stopping at a failure.

    Parameters
    ----------
    chunk : _Chunk
        The chunk.
    sched : Schedule
        Its stops.
    tick : callable(int), optional
        Called with the path-steps of each launch.
    """
    if not chunk.at(0):
        return
    k = 0
    for stop in sched.stops.tolist():
        chunk.advance(k, stop)
        if tick is not None:
            tick((stop - k) * chunk.p)
        k = stop
        if not chunk.at(k):
            return


def run_chunks(run: _Run, spec, block_paths: int, progress, go) -> PartialStats:
    """Seed the CPU's blocks, group them into chunks that fit the device, run each chunk
    with ``go(chunk)`` and merge the chunks' sums in block order.

    Parameters
    ----------
    run : _Run
        The run's shared arrays.
    spec : MonteCarloSpec or TimeVaryingMonteCarloSpec
        Paths, seed.
    block_paths : int
        The CPU's paths per block (a path's stream depends on its block).
    progress : callable(done, total) or None
        Called with path-steps done.
    go : callable(_Chunk, tick)
        Integrates a chunk.

    Returns
    -------
    PartialStats
    """
    n_blocks = -(-spec.paths // block_paths)
    per_chunk = max(1, run.chunk_paths() // block_paths)
    total = spec.paths * run.sched.grid.n_steps
    done = 0
    parts = []
    for b0 in range(0, n_blocks, per_chunk):
        blocks = list(range(b0, min(b0 + per_chunk, n_blocks)))
        states = np.concatenate(
            [
                path_states(spec.seed, b, min(block_paths, spec.paths - b * block_paths))
                for b in blocks
            ]
        )
        chunk = _Chunk(run, b0 * block_paths, states)

        def tick(n: int) -> None:
            nonlocal done
            done += n
            if progress is not None:
                progress(done, total)

        go(chunk, tick)
        parts.append(chunk.result(blocks))
    return merge(parts)


def check_supported(spec) -> None:
    """Refuse, in one line naming the field, a run the GPU kernels do not do.

    Parameters
    ----------
    spec : MonteCarloSpec or TimeVaryingMonteCarloSpec
        The run.

    Raises
    ------
    InputError
        ``rng: numpy``, ``scheme: implicit`` or a callable f.
    """
    if getattr(spec, "rng", "xoshiro") != "xoshiro":
        raise InputError(
            "rng: numpy stays on the CPU (device: gpu draws xoshiro256** normals in the kernel)"
        )
    if getattr(spec, "scheme", "explicit") != "explicit":
        raise InputError("scheme: implicit runs on the CPU only (device: cpu)")
    systems = getattr(spec, "systems", None) or (getattr(spec, "system", None),)
    if any(s is not None and s.f is not None for s in systems):
        raise InputError("noise.f: a callable f runs on the CPU only (device: cpu)")


__all__ = [
    "FUSED_MAX_STATE",
    "SIMULATOR_ENV",
    "GpuEngine",
    "ModeArrays",
    "Schedule",
    "check_batch",
    "check_supported",
    "device_name",
    "drive",
    "gpu_available",
    "load_cuda",
    "run_chunks",
    "simulator_requested",
]
