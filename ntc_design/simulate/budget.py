"""Size before allocation: the memory and the work a simulation will need, estimated from
its input alone, and a refusal (one line naming the field and the size) when the memory
exceeds :data:`MEMORY_FRACTION` of the memory available or the work exceeds
:data:`MAX_PATH_STEPS`.

The estimate counts the arrays the simulation allocates (8-byte floats): the time grid
and its per-step gains (in each worker), the per-mode sparse L_B and edge arrays (with
the dense L_B and its eigenvalues at small Nd; in the driver and each worker), each
block's state and normals (at most XI_BYTES of normals), the statistics at the save times (per block in flight and merged), the stored
paths, the exact second moments (Nd × Nd, RK4 stages) and the written tables. It is an
estimate of the peak, within a small factor; what it guards against is a request that is
orders of magnitude too big (a save count of 10¹², 10⁹ stored paths), which used to end
in a MemoryError deep inside NumPy.

The exact moments take their own RK4 steps (h <= κ / (c ρ), :mod:`.moments`), as many as
∫ c (ρ_L + c ρ_Q) dt / κ plus one per save time and switch: :func:`estimate_exact_steps`
counts them from c(t) on samples of [0, T] (:func:`gain_samples`, the same samples as the
intrinsic step count) and :func:`check_exact_work` refuses a run that would take longer than
:data:`MAX_EXACT_SECONDS`, before the time grid is built and before any Monte Carlo runs
(a horizon of 10⁷ used to build its grid, run, and only then be refused or run out of
memory).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, format_bytes
from ..numerics.memory import available_memory
from .modes import BATCH, XI_BYTES
from .moments import KAPPA
from .system import DENSE_EIG_MAX_ND, DENSE_LB_MAX_ND

MEMORY_FRACTION = 0.5  # refuse a run that needs more than this share of available memory
MAX_PATH_STEPS = 1e13  # paths × steps: ~ weeks of computation at 10⁷ path-steps per second
# The exact moments' RK4 time, estimated as steps × (5e-5 s + 8·(Nd)³ flops at 1 GFLOP/s):
# refused above this many seconds (the paper's runs: ~1 000 steps at N·d = 21, < 1 s)
MAX_EXACT_SECONDS = 300.0
GAIN_SAMPLES = 2049  # linear and as many logarithmic samples of [0, T]
F8 = 8.0


@dataclass(frozen=True)
class Estimate:
    """Estimated peak bytes by part: ``parts[name] = (field to change, bytes)``; and the
    number of time steps and of path-steps."""

    parts: dict[str, tuple[str, float]]
    steps: float
    path_steps: float

    @property
    def total(self) -> float:
        """The estimated peak, bytes."""
        return float(sum(b for _, b in self.parts.values()))

    def largest(self) -> tuple[str, str, float]:
        """The part that takes the most memory.

        Returns
        -------
        tuple of (str, str, float)
            Its name, the field that changes it, and its bytes.
        """
        name, (fld, b) = max(self.parts.items(), key=lambda kv: kv[1][1])
        return name, fld, b


def gain_samples(t_end: float) -> np.ndarray:
    """Times on [0, T] at which the estimates evaluate c(t): linear and logarithmic
    samples (the logarithmic ones resolve a gain that changes fast near t = 0).

    Parameters
    ----------
    t_end : float
        The horizon T.

    Returns
    -------
    numpy.ndarray
        Sorted times, 0 and T included.
    """
    return np.unique(
        np.concatenate(
            [
                np.linspace(0.0, t_end, GAIN_SAMPLES),
                np.geomspace(min(1e-6, t_end / 2), t_end, GAIN_SAMPLES),
            ]
        )
    )


def check_gain(gain: Callable[[np.ndarray], np.ndarray], text: str, ts: np.ndarray) -> np.ndarray:
    """c(t) at the times ``ts``, refused when it is not finite or negative there: on the
    samples of [0, T] before an estimate integrates it, and on the time grid before a
    run uses it.

    Parameters
    ----------
    gain : callable
        Vectorised c(t).
    text : str
        The gain as written (named in the message).
    ts : numpy.ndarray
        The times.

    Returns
    -------
    numpy.ndarray
        c at ``ts``.

    Raises
    ------
    InputError
        c is not finite, or negative, at one of the times.
    """
    c = gain(ts)
    if c.shape != ts.shape or not np.all(np.isfinite(c)):
        raise InputError(f"{text!r} is not finite on [0, T]", field="gain")
    if np.any(c < 0):
        k = int(np.argmax(c < 0))
        raise InputError(
            f"{text!r} is negative at t = {ts[k]:.6g}; c(t) must be >= 0", field="gain"
        )
    return c


def _integral(ts: np.ndarray, y: np.ndarray) -> float:
    """Trapezoid rule (inf on overflow: the estimates refuse it)."""
    with np.errstate(all="ignore"):
        return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(ts)))


def estimate_steps(
    t_end: float,
    dt: float,
    intrinsic_ds: float | None,
    h_max: float | None,
    gain: Callable[[np.ndarray], np.ndarray],
    events: float,
) -> float:
    """Number of Euler–Maruyama steps: T/dt (uniform) or ∫c dt / ds + T/h_max (intrinsic),
    plus one per event (save time or switch). ∫c is a trapezoid on linear and
    logarithmic samples of [0, T] (an estimate: it only has to get the magnitude).

    Parameters
    ----------
    t_end : float
        The horizon T.
    dt : float
        The uniform step.
    intrinsic_ds : float or None
        The intrinsic step ds; None for uniform stepping.
    h_max : float or None
        The largest intrinsic step.
    gain : callable
        Vectorised c(t).
    events : float
        The number of save times and switches.

    Returns
    -------
    float
        The estimated number of steps.
    """
    if intrinsic_ds is None:
        return t_end / dt + events
    ts = gain_samples(t_end)
    with np.errstate(all="ignore"):
        try:
            c = np.asarray(gain(ts), dtype=float) * np.ones(ts.shape)
        except Exception:  # noqa: BLE001 - user code; the driver reports it properly
            c = np.ones(ts.shape)
        c = np.nan_to_num(np.abs(c), nan=0.0, posinf=1e300)
    return _integral(ts, c) / intrinsic_ds + t_end / (h_max or t_end) + events


def estimate_exact_steps(
    ts: np.ndarray, c: np.ndarray, rho_l: float, rho_q: float, events: float
) -> float:
    """RK4 steps of the exact moments: steps h <= κ / (c ρ) with ρ = ρ_L + c·ρ_Q (the
    generator's spectral radius bound, :func:`.moments.generator_radius`) make about
    ∫ c (ρ_L + c ρ_Q) dt / κ steps, plus one per event (save time or switch).

    Parameters
    ----------
    ts, c : numpy.ndarray
        Samples of [0, T] (:func:`gain_samples`) and c(t) there (:func:`check_gain`).
    rho_l, rho_q : float
        ρ_L and ρ_Q, the largest over the modes.
    events : float
        Save times and switching segments.

    Returns
    -------
    float
        The estimated number of steps (inf when it overflows).
    """

    with np.errstate(all="ignore"):
        y = c * (rho_l + c * rho_q)
    return _integral(ts, y) / KAPPA + events


#: The extra time of one exact-moment step of a topology given as expressions of t, per
#: agent: A(t) and Lemma 1 re-evaluated at the step (0.6 to 0.8 ms a step on the
#: time-varying G1, 7 agents, on a loaded 2-core machine).
TV_STEP_SECONDS_PER_AGENT = 1.2e-4


def exact_seconds(steps: float, nd: int, agents_per_step: int = 0) -> float:
    """The time the exact moments take: ``steps`` × (5e-5 s + 8·(Nd)³ flops at 1 GFLOP/s),
    plus :data:`TV_STEP_SECONDS_PER_AGENT` per agent and step where A(t) is re-evaluated.

    Parameters
    ----------
    steps : float
        RK4 steps (:func:`estimate_exact_steps`).
    nd : int
        N·d.
    agents_per_step : int, optional
        N for a topology given as expressions of t (its design is made at every step).

    Returns
    -------
    float
        Seconds (within a factor of a few).
    """
    return steps * (5e-5 + 8e-9 * float(nd) ** 3 + TV_STEP_SECONDS_PER_AGENT * agents_per_step)


def check_exact_work(steps: float, nd: int) -> None:
    """Refuse exact moments that would take longer than :data:`MAX_EXACT_SECONDS`
    (:func:`exact_seconds`).

    Parameters
    ----------
    steps : float
        RK4 steps (:func:`estimate_exact_steps`).
    nd : int
        N·d.

    Raises
    ------
    InputError
        Naming ``method``, the steps and the time.
    """
    seconds = exact_seconds(steps, nd)
    if not math.isfinite(seconds) or seconds > MAX_EXACT_SECONDS:
        raise InputError(
            f"the exact moments would take about {steps:.3g} RK4 steps on N·d = {nd} "
            f"(~{seconds:.3g} s, more than {MAX_EXACT_SECONDS:g} s); use method: mc, fewer "
            "save times, a smaller gain or a shorter T",
            field="method",
        )


def estimate(
    *,
    n: int,
    d: int,
    edges: int,
    modes: int,
    segments: float,
    saves: float,
    steps: float,
    paths: int,
    block_size: int,
    store_paths: int,
    workers: int,
    mc: bool,
    exact: bool,
    mode_field: str = "topology",
    delay: int = 0,
) -> Estimate:
    """Peak memory by part (see the module docstring) for the sizes given.

    Parameters
    ----------
    n, d, edges : int
        Agents, state dimension, most edges in a mode.
    modes : int
        Distinct mode systems (modes of a switching file, or re-designs).
    segments : float
        Switching segments on [0, T].
    saves, steps : float
        Save times and time steps.
    paths, block_size, store_paths, workers : int
        Monte Carlo sizes.
    mc, exact : bool
        Which methods run.
    mode_field : str
        The field that sets ``modes`` (named in a refusal).
    delay : int, optional
        The sampled protocol's delay D: every path holds D + 1 states, and the exact
        moments ((D+1)·Nd)² numbers (:mod:`.digital`).

    Returns
    -------
    Estimate
    """
    nd_ = float(n * d)
    ed = float(edges * d)
    w = float(max(1, workers)) if mc else 1.0
    nnz = (n + edges) * d * d
    dense = min(nd_, DENSE_LB_MAX_ND) ** 2 + 3 * min(nd_, DENSE_EIG_MAX_ND) ** 2
    # the design's dense L, D and L_B (3 Nd² per mode) exist only up to DENSE_LB_MAX_ND;
    # above it the design and the simulation's own matrices are sparse
    per_system = F8 * (
        4 * nnz + edges * (2 * d * d + d + 3) + 6 * nd_ + dense + 3 * min(nd_, DENSE_LB_MAX_ND) ** 2
    )
    parts: dict[str, tuple[str, float]] = {
        "time grid": ("dt", F8 * steps * (10 + 4 * w) + 64.0 * segments),
        "mode systems": (mode_field, per_system * modes * (1 + (w if mc else 0))),
    }
    if mc:
        b = float(min(block_size, paths))
        stats = F8 * saves * (3 * n + nd_)  # Σ, spread and centre per agent; Σx
        k = float(min(store_paths, paths))
        parts["Monte Carlo blocks"] = (
            "block_size",
            w * (F8 * b * (4 * nd_ + 3 * ed) + min(F8 * b * BATCH * 2 * edges, XI_BYTES)),
        )
        if delay:
            parts["delayed states"] = ("digital.delay", w * F8 * b * 2 * delay * nd_)
        parts["statistics at the save times"] = (
            "save_every",
            stats * (2 * w + 2) + F8 * saves * 3 * n,
        )
        # k stored paths × S save times × Nd: name the factor that is out of scale
        parts["stored paths"] = (
            "store_paths" if k >= saves else "save_every",
            3 * F8 * k * saves * nd_,
        )
    if exact and delay:
        wd = (delay + 1) * nd_
        parts["exact moments"] = ("digital.delay", F8 * (4 * wd * wd + saves * (nd_ + n)))
    elif exact:
        parts["exact moments"] = ("method", F8 * (12 * nd_ * nd_ + saves * (nd_ + n)))
    parts["output tables"] = ("save_every", 30.0 * saves * (4 * n + 1))
    return Estimate(parts, float(steps), float(steps) * paths if mc else 0.0)


# Monte Carlo throughput per worker, state entries × steps per second: ~8·10⁸ explicit
# (G1: 1.3·10⁷ path-steps/s of 21 + 8·9 entries per worker of a 2-core reference machine,
# normals drawn in the kernel), about 5x less with the drift-implicit scheme's sparse
# solves. Only for the estimate a long run prints before it starts (:func:`mc_seconds`).
MC_ENTRIES_PER_SECOND = 8e8
IMPLICIT_SLOWDOWN = 5.0


def mc_seconds(est: Estimate, nd: int, edge_entries: int, workers: int, implicit: bool) -> float:
    """Rough wall time of the Monte Carlo part of a run: path-steps × (N·d + E·d²) state
    and weight entries, at :data:`MC_ENTRIES_PER_SECOND` per worker.

    Parameters
    ----------
    est : Estimate
        The run's estimate (its path-steps).
    nd : int
        N·d.
    edge_entries : int
        E·d².
    workers : int
        Processes.
    implicit : bool
        The drift-implicit scheme.

    Returns
    -------
    float
        Seconds (within a factor of a few on a current CPU).
    """
    rate = MC_ENTRIES_PER_SECOND / (IMPLICIT_SLOWDOWN if implicit else 1.0)
    return est.path_steps * (nd + edge_entries) / (rate * max(workers, 1))


_HINTS = {
    "method": "use method: mc (the exact second moments are N·d × N·d)",
    "topology": "the topology is too large for this machine's memory",
    "dt": "raise dt (or ds), or shorten T",
    "save_every": "save less often (save_every) or fewer save_times",
    "digital.delay": "lower the delay D (every path and the exact moments hold D + 1 states)",
}


def check_budget(est: Estimate, available: float | None = None) -> None:
    """Refuse (InputError naming the field and the size) a run whose estimated peak
    memory exceeds :data:`MEMORY_FRACTION` of ``available`` (default: what the machine
    has available now) or whose work exceeds :data:`MAX_PATH_STEPS`.

    Parameters
    ----------
    est : Estimate
        The run's estimate.
    available : float, optional
        Bytes available.

    Raises
    ------
    InputError
        The estimate is above the limits (naming the field to change and the size).
    """
    avail = available_memory() if available is None else available
    total = est.total
    if not math.isfinite(total) or total > MEMORY_FRACTION * avail:
        name, fld, b = est.largest()
        raise InputError(
            f"the run would need about {format_bytes(total)} of memory "
            f"({name}: {format_bytes(b)}), more than {MEMORY_FRACTION:.0%} of the "
            f"{format_bytes(avail)} available; {_HINTS.get(fld, f'reduce {fld}')}",
            field=fld,
        )
    if est.path_steps > MAX_PATH_STEPS:
        raise InputError(
            f"{est.path_steps:.3g} path-steps (paths × {est.steps:.3g} steps) exceed "
            f"the limit {MAX_PATH_STEPS:.0e}; reduce paths or T, or raise dt",
            field="paths",
        )
