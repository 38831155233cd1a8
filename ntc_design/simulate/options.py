"""The options of a simulation that validate themselves when made: when to save
(:class:`SaveAt`), how to step (:class:`Stepping`), the Monte Carlo paths
(:class:`MonteCarlo`), a uniformly drawn initial state (:class:`UniformInitial`), and the
checks of vectors, states and worker counts they share with the scenario."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields

import numpy as np

from ..choices import Device, Rng, Scheme, SteppingKind, choices
from ..errors import (
    MAX_SEED,
    InputError,
    Option,
    real_float,
    require_int,
    require_number,
    require_positive,
)
from .noise import MAX_MAGNITUDE, NoiseModel

MAX_VECTOR = 10_000_000  # entries in θ, the initial state or save_times
MAX_WORKERS = 4096
DEVICES = choices(Device)
Noise = NoiseModel


def check_workers(value, name: str = "workers") -> int:
    """A number of worker processes: a positive integer at most :data:`MAX_WORKERS` (one
    check for a scenario's ``workers``, ``--workers`` of every command and the engines).

    Parameters
    ----------
    value : object
        The value given.
    name : str
        The field or option named in the message.

    Returns
    -------
    int

    Raises
    ------
    InputError
        Not an integer in [1, MAX_WORKERS].
    """
    return require_int(name, value, minimum=1, maximum=MAX_WORKERS)


def check_vector(
    name: str, values, max_size: int = MAX_VECTOR, bound: float | None = None
) -> np.ndarray:
    """A flat, finite float vector from a list of numbers (nested lists refused), with
    every entry at most ``bound`` in magnitude if given."""
    if isinstance(values, np.ndarray):
        if values.dtype.kind not in "iuf":
            raise InputError(f"expected numbers, got an array of {values.dtype}", field=name)
        arr = values.astype(float).reshape(-1)
    else:
        if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, Sequence):
            raise InputError(f"expected a list of numbers, got {type(values).__name__}", field=name)
        if len(values) > max_size:
            raise InputError(f"{len(values)} entries, more than the limit {max_size}", field=name)
        for k, v in enumerate(values):
            if isinstance(v, bool) or not isinstance(v, numbers.Real):
                what = "a nested list" if isinstance(v, (list, tuple)) else repr(v)[:40]
                raise InputError(f"expected a number, got {what}", field=f"{name}[{k}]")
        try:
            arr = np.asarray(values, dtype=float).reshape(-1)
        except OverflowError:  # an integer beyond the float range: name its entry
            for k, v in enumerate(values):
                real_float(f"{name}[{k}]", v)
            raise  # pragma: no cover - one of them overflowed
    if arr.size > max_size:
        raise InputError(f"{arr.size} entries, more than the limit {max_size}", field=name)
    bad = ~np.isfinite(arr)
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(f"must be finite, got {float(arr[k])!r}", field=f"{name}[{k}]")
    if bound is not None and np.any(np.abs(arr) > bound):
        k = int(np.argmax(np.abs(arr) > bound))
        raise InputError(
            f"must be at most {bound:g} in magnitude, got {float(arr[k])!r}", field=f"{name}[{k}]"
        )
    arr.setflags(write=False)
    return arr


def check_states(values) -> np.ndarray:
    """x(0) as given: N·d numbers (flat) or N states of d numbers (rows, or a 2-D
    array); finite and at most :data:`MAX_MAGNITUDE` in magnitude. Rows keep their
    shape so that the driver can check it against (N, d): a ragged list (states of
    different lengths) is refused here rather than flattened into N·d numbers that
    happen to add up."""
    if isinstance(values, np.ndarray) and values.ndim == 2:
        arr = check_vector("initial", values, bound=MAX_MAGNITUDE).reshape(values.shape)
        arr.setflags(write=False)
        return arr
    if isinstance(values, (list, tuple)) and any(isinstance(v, (list, tuple)) for v in values):
        first = next(k for k, v in enumerate(values) if isinstance(v, (list, tuple)))
        width = len(values[first])
        for k, row in enumerate(values):
            if not isinstance(row, (list, tuple)):
                raise InputError(
                    f"expected a state (a list of d numbers) like "
                    f"initial[{first}], got {repr(row)[:40]}",
                    field=f"initial[{k}]",
                )
            if len(row) != width:
                raise InputError(
                    f"{len(row)} numbers, but initial[{first}] has {width}; "
                    "every state has d numbers",
                    field=f"initial[{k}]",
                )
            for j, v in enumerate(row):
                if isinstance(v, (list, tuple)):
                    raise InputError("expected d numbers, got a nested list", field=f"initial[{k}]")
                require_number(f"initial[{k}][{j}]", v, bound=MAX_MAGNITUDE)
        if len(values) * width > MAX_VECTOR:
            raise InputError(f"more than the limit {MAX_VECTOR} numbers", field="initial")
        arr = np.array(values, dtype=float).reshape(len(values), width)
        arr.setflags(write=False)
        return arr
    return check_vector("initial", values, bound=MAX_MAGNITUDE)


@dataclass(frozen=True, eq=False)
class SaveAt:
    """Save times: every ``every`` time units from 0 to T (T included), or the listed
    ``times`` (0 is always added). Exactly one of the two."""

    every: float | None = None
    times: np.ndarray | None = None

    def _listed(self) -> np.ndarray:
        # the listed times (the constructor made sure that every or times is given)
        if self.times is None:
            raise InputError("not given", field="save_times")
        return self.times

    def __post_init__(self) -> None:
        if (self.every is None) == (self.times is None):
            raise InputError("give save_every or save_times (exactly one)", field="save_every")
        if self.every is not None:
            require_positive("save_every", self.every)
            object.__setattr__(self, "every", float(self.every))
        else:
            arr = check_vector("save_times", self.times)
            if arr.size == 0:
                raise InputError("expected at least one time", field="save_times")
            if np.any(arr < 0):
                raise InputError("times must be >= 0", field="save_times")
            object.__setattr__(self, "times", arr)

    def count(self, t_end: float) -> float:
        """Number of save times on [0, t_end], before allocating them.

        Parameters
        ----------
        t_end : float
            The horizon T.

        Returns
        -------
        float
            The count (a float: it may be astronomically large).
        """
        if self.every is not None:
            n = t_end / self.every
            return math.floor(n) + 2.0 if math.isfinite(n) and n < 2**53 else n
        return float(self._listed().size + 1)

    def resolve(self, t_end: float) -> np.ndarray:
        """The save times on [0, t_end].

        Parameters
        ----------
        t_end : float
            The horizon T.

        Returns
        -------
        numpy.ndarray
            Sorted, 0 included, and t_end too for ``every``.

        Raises
        ------
        InputError
            A listed time is beyond t_end.
        """
        if self.every is not None:
            return np.unique(np.concatenate([np.arange(0.0, t_end, self.every), [t_end]]))
        if np.any(self._listed() > t_end):
            raise InputError(f"expected times in [0, T={t_end:g}]", field="save_times")
        return np.unique(np.concatenate([[0.0], self.times]))


@dataclass(frozen=True)
class Stepping:
    """Euler–Maruyama steps: ``uniform`` (h <= dt between events) or ``intrinsic`` (steps
    uniform in s = ∫c dt: h = min(ds / c(t), h_max)); ``ds`` defaults to ``dt`` and
    ``h_max`` to max(1, 100·dt)."""

    kind: SteppingKind = "uniform"
    dt: float = 1e-3
    ds: float | None = None
    h_max: float | None = None
    scheme: Scheme = "explicit"  # or "implicit": (I + c h L_B) x_{k+1} = x_k + c h u + noise

    def __post_init__(self) -> None:
        if self.kind not in choices(SteppingKind):
            raise InputError(f"must be uniform or intrinsic, got {self.kind!r}", field="stepping")
        if self.scheme not in choices(Scheme):
            raise InputError(f"must be explicit or implicit, got {self.scheme!r}", field="scheme")
        if self.scheme == "implicit" and self.kind != "intrinsic":
            raise InputError(
                "implicit needs stepping: intrinsic (c·h constant, so (I + c h L_B) "
                "is factorised once per mode)",
                field="scheme",
            )
        require_positive("dt", self.dt)
        if self.ds is not None:
            require_positive("ds", self.ds)
        if self.h_max is not None:
            require_positive("h_max", self.h_max)

    @property
    def intrinsic_ds(self) -> float | None:
        """The intrinsic step ds (``dt`` when not given); None for uniform stepping."""
        if self.kind != "intrinsic":
            return None
        return float(self.ds if self.ds is not None else self.dt)

    @property
    def max_step(self) -> float | None:
        """The largest intrinsic step h_max; None for uniform stepping."""
        if self.kind != "intrinsic":
            return None
        return float(self.h_max if self.h_max is not None else max(1.0, 100 * self.dt))


#: The most paths (and paths per block, paths stored) a scenario may ask for: each path
#: takes a step at least, and the budget refuses more than 1e13 path-steps
#: (:data:`.budget.MAX_PATH_STEPS`); an integer beyond it (a 400-digit one, say) is no
#: float for the estimates either.
MAX_PATHS = 10**13


@dataclass(frozen=True)
class MonteCarlo:
    """Monte Carlo options: the number of sample ``paths``, the ``seed`` of the run's
    numpy SeedSequence, paths per ``block_size`` (a block is the unit of work and of
    randomness), how many paths to keep (``store_paths``), worker processes, the normals'
    generator (``rng``) and the ``device`` (``cpu``, or ``gpu``: the same paths on an
    NVIDIA GPU, :mod:`.gpu`)."""

    paths: int = 1000
    seed: int = 0
    block_size: int = 500
    store_paths: int = 10
    workers: int = 2
    rng: Rng = "xoshiro"  # xoshiro256** per path, drawn in the kernel; or numpy (PCG64)
    device: Device = "cpu"  # or "gpu": the same paths on an NVIDIA GPU (.gpu)

    def __post_init__(self) -> None:
        require_int("paths", self.paths, minimum=1, maximum=MAX_PATHS)
        require_int("seed", self.seed, minimum=0, maximum=MAX_SEED)
        require_int("block_size", self.block_size, minimum=1, maximum=MAX_PATHS)
        require_int("store_paths", self.store_paths, minimum=0, maximum=MAX_PATHS)
        check_workers(self.workers)
        if self.rng not in choices(Rng):
            raise InputError(f"expected xoshiro or numpy, got {self.rng!r}", field="rng")
        if self.device not in DEVICES:
            raise InputError(f"expected cpu or gpu, got {self.device!r}", field="device")
        if self.device == "gpu" and self.rng == "numpy":
            raise InputError(
                "numpy stays on the CPU (device: gpu draws xoshiro256** normals in the "
                "kernel); use ",
                Option("rng", "xoshiro", document=True),
                " or ",
                Option("device", "cpu", document=True),
                field="rng",
            )
        for f in fields(self):
            if f.name not in ("rng", "device"):
                object.__setattr__(self, f.name, int(getattr(self, f.name)))


@dataclass(frozen=True)
class UniformInitial:
    """x(0) with every entry uniform on [lo, hi], drawn from SeedSequence(seed)."""

    lo: float
    hi: float
    seed: int = 0

    def __post_init__(self) -> None:
        # bounded: rng.uniform needs hi - lo finite (±1e308 overflows it)
        lo = require_number("initial.uniform[0]", self.lo, bound=MAX_MAGNITUDE)
        hi = require_number("initial.uniform[1]", self.hi, bound=MAX_MAGNITUDE)
        if not lo < hi:
            raise InputError(f"need lo < hi, got [{lo:g}, {hi:g}]", field="initial.uniform")
        require_int("initial.seed", self.seed, minimum=0, maximum=MAX_SEED)
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)

    def draw(self, size: int) -> np.ndarray:
        """Draw x(0) (the same on every call).

        Parameters
        ----------
        size : int
            N·d.

        Returns
        -------
        numpy.ndarray
            ``size`` numbers uniform on [lo, hi].
        """
        rng = np.random.default_rng(np.random.SeedSequence(int(self.seed)))
        return rng.uniform(self.lo, self.hi, size=size)


__all__ = [
    "DEVICES",
    "MAX_PATHS",
    "MAX_VECTOR",
    "MAX_WORKERS",
    "MonteCarlo",
    "Noise",
    "SaveAt",
    "Stepping",
    "UniformInitial",
    "check_states",
    "check_vector",
    "check_workers",
]
