"""The longest safe sampling period of the digital protocol (``ntc tune`` with the period ``auto``):
the largest h such that every period in (0, h] keeps the exact E Σ_i ‖x_i(T) − θ‖² of the
sampled protocol within (1 + tolerance) of the continuous design's, and its peak
sup_{t ≤ T} E Σ_i ‖x_i(t) − θ‖² within ``max_peak`` (when given). The protocol runs to T
itself (⌊T/h⌋ samples and the held input's partial step,
:mod:`ntc_design.protocol.digital`), so error(T; h) is continuous in h; it is not monotone:
it wiggles once per sample added (h = T/K, K whole), by about a percent on G1, and
windows a few tenths of a percent wide can fail between passing periods.

Search: the exact moments (:func:`ntc_design.simulate.digital.digital_moments`) at
``SCAN_POINTS`` periods spaced geometrically from T/``SCAN_STEPS`` up to T; the last period
before the first that fails is refined by bisection against that failure to a relative
``RTOL``. Then the answer is verified on a dense grid below it: the periods
T/(K + j/``PER_SAMPLE``) for every K from ⌊T/h⌋ up to ``VERIFY_SPAN``·T/h (at most
``VERIFY_SAMPLES`` samples: every sample added near the answer, and points between), the geometric scan below those, and, between two
neighbours where the curve may cross a bound (a margin under ``NEAR_FLOOR`` plus
``WIGGLE`` times their difference), up to ``REFINE_LEVELS`` bisections. A period
of the grid that fails shortens the answer to the largest period of the grid below it
that passes. The claim "every period up to h" is backed by that grid (reported in
``verification``), not by a bound between its points.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import InputError, require_horizon, require_int, require_number
from ..present.rows import Table, fmt, verdict
from ..protocol.agents import require_sampled
from ..protocol.digital import Digital
from ..simulate import SimulationSpec
from ..simulate.prepare import AnyTopology, make_gain
from .objective import DigitalObjective

SCAN_POINTS = 36
#: The shortest period scanned is T / SCAN_STEPS (K = SCAN_STEPS steps).
SCAN_STEPS = 4000
RTOL = 1e-3
#: A candidate whose E‖e‖² passes this many times its start is stopped (it fails); the
#: continuous design doing so diverges (no period is judged against it).
GROWTH_STOP = 1e8
#: The continuous design diverges, too, when E‖e(T)‖² ends this many times its start.
FINAL_GROWTH = 1e4
#: The verification: periods T/(K + j/PER_SAMPLE) for K from ⌊T/h⌋ to VERIFY_SPAN·T/h,
#: at most VERIFY_SAMPLES samples (each period costs K steps: the work grows as K²).
PER_SAMPLE = 4
VERIFY_SPAN = 1.5
VERIFY_SAMPLES = 40
#: Neighbours are bisected (up to REFINE_LEVELS times) where the curve may cross a bound
#: between them: a margin below NEAR_FLOOR plus WIGGLE times the change between them.
NEAR_FLOOR = 0.005
WIGGLE = 2.0
REFINE_LEVELS = 4
#: The most evaluations the verification makes (the rest of the refinement is dropped,
#: and the note says so).
MAX_VERIFY = 4000


@dataclass(frozen=True)
class PeriodPoint:
    """One evaluated period: the final error and the peak of the sampled recursion, and
    whether both bounds hold."""

    period: float
    final: float
    peak: float
    ok: bool

    def to_dict(self) -> dict:
        """The point as JSON data.

        Returns
        -------
        dict
        """
        return {
            "period": self.period,
            "final_ms_error": self.final,
            "peak": self.peak,
            "ok": self.ok,
        }


@dataclass(frozen=True)
class PeriodEvidence:
    """The grid that backs "every period up to h": how many periods of it lie in (0, h],
    from where, how it was built, and the one closest to a bound.

    Attributes
    ----------
    periods : int
        Periods evaluated in (0, h], every one within the bounds.
    k_from, k_to : int
        The dense part: T/(K + j/per_sample) for K = k_from … k_to (k_from = ⌊T/h⌋ of the
        bisected answer).
    lowest : float
        Its shortest period, T/(k_to + 1 − 1/per_sample); the geometric scan below it.
    per_sample : int
        Points per sample added.
    refine_levels : int
        Bisections between neighbours within ``near`` of a bound.
    near : float
        NEAR_FLOOR: the margin under which neighbours are always bisected (plus WIGGLE
        times their difference).
    worst : PeriodPoint or None
        The period in (0, h] closest to a bound.
    complete : bool
        False when the refinement stopped at its evaluation limit.
    """

    periods: int
    k_from: int
    k_to: int
    lowest: float
    per_sample: int
    refine_levels: int
    near: float
    worst: PeriodPoint | None
    complete: bool = True

    def to_dict(self) -> dict:
        """The evidence as JSON data.

        Returns
        -------
        dict
        """
        return {
            "periods": self.periods,
            "dense_samples": [self.k_from, self.k_to],
            "dense_from_period": self.lowest,
            "per_sample": self.per_sample,
            "refine_levels": self.refine_levels,
            "near": self.near,
            "worst": self.worst.to_dict() if self.worst is not None else None,
            "complete": self.complete,
        }

    def note(self) -> str:
        """One line for the table.

        Returns
        -------
        str
        """
        text = (
            f"verified at {self.periods} periods up to h, every one within the bounds: "
            f"T/(K + j/{self.per_sample}) for K = {self.k_from} … {self.k_to} (down to "
            f"h = {fmt(self.lowest)}), the geometric scan below, bisected "
            f"{self.refine_levels} times wherever the curve may cross a bound between "
            f"neighbours (a margin under {self.near:.1%} + {WIGGLE:g}× their difference)"
        )
        if self.worst is not None:
            text += f"; closest: h = {fmt(self.worst.period)}"
        if not self.complete:
            text += f" (the refinement stopped at {MAX_VERIFY} evaluations)"
        return text


@dataclass(frozen=True)
class SafePeriod:
    """The longest safe period and the curve error(h), peak(h) behind it.

    Attributes
    ----------
    period : float or None
        The largest safe h found (None: even the shortest scanned fails).
    delay : int
        D.
    tolerance : float
        The allowed relative excess of the final error.
    max_peak : float or None
        The bound on the peak.
    horizon : float
        T.
    continuous_final : float
        The continuous design's exact E Σ‖x_i(T) − θ‖².
    continuous_peak : float
        Its sup over [0, T] (401 save times).
    curve : tuple of PeriodPoint
        The periods scanned and bisected, sorted (the verification's are counted in
        ``evidence``).
    notes : tuple of str
        What the search says besides its numbers.
    evidence : PeriodEvidence or None
        The dense grid that backs the answer (None without an answer).
    diverged : str or None
        Why no period is judged: the continuous design itself diverges on [0, T].
    """

    period: float | None
    delay: int
    tolerance: float
    max_peak: float | None
    horizon: float
    continuous_final: float
    continuous_peak: float
    curve: tuple[PeriodPoint, ...]
    notes: tuple[str, ...] = field(default=())
    evidence: PeriodEvidence | None = None
    diverged: str | None = None

    @property
    def bound(self) -> float:
        """(1 + tolerance) times the continuous final error."""
        return (1 + self.tolerance) * self.continuous_final

    def table(self) -> Table:
        """The result and the scanned curve as every face shows it.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows: list[tuple[Any, ...]] = [
            (fmt(p.period), fmt(p.final), fmt(p.peak), verdict(p.ok)) for p in self.curve
        ]
        head = (
            f"longest safe period h = {fmt(self.period)} (delay D = {self.delay})"
            if self.period is not None
            else f"no safe period found (delay D = {self.delay})"
        )
        extra = [self.evidence.note()] if self.evidence is not None else []
        if self.diverged is not None:
            extra.append(self.diverged)
        notes = [
            f"bounds: E Σ‖x_i(T) − θ‖² <= (1 + {self.tolerance:g})·{fmt(self.continuous_final)} "
            f"(the continuous design's at T = {self.horizon:g})"
            + (f"; peak <= {fmt(self.max_peak)}" if self.max_peak is not None else ""),
            *self.notes,
            *extra,
        ]
        return Table.build(
            head, ("period h", "E Σ‖x_i(T) − θ‖²", "peak", "within the bounds"), rows, notes
        )

    def to_dict(self) -> dict:
        """What ``ntc tune`` prints as JSON for the period ``auto``.

        Returns
        -------
        dict
        """
        return {
            "period": self.period,
            "delay": self.delay,
            "tolerance": self.tolerance,
            "max_peak": self.max_peak,
            "horizon": self.horizon,
            "continuous_final_ms_error": self.continuous_final,
            "continuous_peak": self.continuous_peak,
            "bound": self.bound,
            "curve": [p.to_dict() for p in self.curve],
            "verification": self.evidence.to_dict() if self.evidence is not None else None,
            "diverged": self.diverged,
            "notes": list(self.notes),
        }


def _objective(
    topology: AnyTopology, spec: SimulationSpec, horizon: float, delay: int
) -> tuple[DigitalObjective, Digital, Callable]:
    """The objective every period is evaluated by (the continuous design's modes prepared
    once), the sampled protocol at h = T with the delay D (each period replaces h), and
    the scenario's gain."""
    require_sampled(topology, "period")
    base = spec.replace(T=float(horizon), digital=None, method="exact")
    if not base.noise.linear:
        raise InputError("the exact moments need a linear f (a scalar or a matrix)", field="period")
    return (
        DigitalObjective(topology, base, horizon),
        Digital(float(horizon), delay),
        make_gain(base.gain)[0],
    )


def _run(
    obj: DigitalObjective, dg: Digital, gain: Callable, h: float, stop: float | None
) -> tuple[float, float]:
    """E Σ‖x_i(T) − θ‖² and the peak of the sampled recursion at the period h."""
    dm = obj.moments(gain, np.array([obj.horizon]), replace(dg, period=float(h)), None, stop)
    return float(dm.moments.ms_error[-1].sum()), dm.peak


def period_curve(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    delay: int,
    periods: np.ndarray,
    stop_above: float | None = None,
) -> list[tuple[float, float]]:
    """(E Σ‖x_i(T) − θ‖², its peak over [0, T]) of the sampled protocol at each period, exactly.

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.
    spec : SimulationSpec
        The scenario (θ, noise with a linear f, x(0), gain, δ or ΔC).
    horizon : float
        T.
    delay : int
        D.
    periods : numpy.ndarray
        The periods h (each <= T).
    stop_above : float, optional
        A run whose E‖e_k‖² passes this stops early (both numbers +∞).

    Returns
    -------
    list of (float, float)

    Raises
    ------
    InputError
        A non-linear f, an A(t) topology, or a recursion too large for memory.
    """
    obj, dg, gain = _objective(topology, spec, horizon, delay)
    return [_run(obj, dg, gain, float(h), stop_above) for h in periods]


def longest_safe_period(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    *,
    delay: int = 0,
    tolerance: float = 0.1,
    max_peak: float | None = None,
    points: int = SCAN_POINTS,
) -> SafePeriod:
    """The largest h whose sampled recursion stays within the bounds, every period below
    it too (see the module).

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.
    spec : SimulationSpec
        The scenario.
    horizon : float
        T.
    delay : int, optional
        D.
    tolerance : float, optional
        E Σ‖x_i(T) − θ‖² <= (1 + tolerance)·(the continuous design's).
    max_peak : float, optional
        sup_{t <= T} E Σ‖x_i(t) − θ‖² <= max_peak.
    points : int, optional
        Periods scanned.

    Returns
    -------
    SafePeriod

    Raises
    ------
    InputError
        A bad option, a non-linear f, or moments too large.

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.simulate import NoiseModel, SimulationSpec
    >>> spec = SimulationSpec.build([1, 2, -1], noise=NoiseModel(0.4, 0.3), initial=[1.0] * 21)
    >>> r = longest_safe_period(nd.load("examples/g1.yaml"), spec, 2.0, points=8)
    >>> 0 < r.period < 2
    True
    """
    horizon = require_horizon("horizon", horizon)
    delay = require_int("delay", delay, minimum=0)
    tolerance = require_number("tolerance", tolerance, minimum=0.0)
    if max_peak is not None and not require_number("max_peak", max_peak) > 0:
        raise InputError(f"must be a positive number, got {max_peak!r}", field="max_peak")
    points = require_int("points", points, minimum=2, maximum=1000)
    obj, dg, gain = _objective(topology, spec, horizon, delay)
    pm = obj.prepared(None)[0]
    start = float(pm.eps0 @ pm.eps0)
    t = np.linspace(0.0, horizon, 401)
    with np.errstate(all="ignore"):
        cont = pm.moments(gain, t, abort_above=GROWTH_STOP * max(start, 1.0)).ms_error.sum(axis=1)
    c_final, c_peak = float(cont[-1]), float(np.max(cont))
    common = (
        delay,
        float(tolerance),
        float(max_peak) if max_peak is not None else None,
        horizon,
        c_final,
        c_peak,
    )
    diverged = _diverges(c_final, c_peak, start, horizon)
    if diverged is not None:
        return SafePeriod(None, *common, (), (), None, diverged)
    stop = GROWTH_STOP * max(start, c_peak, 1.0)
    if max_peak is not None:
        stop = min(stop, max_peak * (1 + 1e-9))
    bound = (1 + tolerance) * c_final
    seen: dict[float, PeriodPoint] = {}

    def evaluate(h: float) -> PeriodPoint:
        if h not in seen:
            final, peak = _run(obj, dg, gain, h, stop)
            ok = final <= bound and (max_peak is None or peak <= max_peak)
            seen[h] = PeriodPoint(h, final, peak, bool(ok))
        return seen[h]

    scan = np.geomspace(horizon / SCAN_STEPS, horizon, points)
    notes: list[str] = []
    good: PeriodPoint | None = None
    bad: PeriodPoint | None = None
    for h in scan:
        p = evaluate(float(h))
        if not p.ok:
            bad = p
            break
        good = p
    evidence = None
    if good is None:
        notes.append(f"even h = T/{SCAN_STEPS} = {scan[0]:.3g} fails the bounds")
        period = None
        searched = dict(seen)  # the scan and the bisection: the table's rows
    else:
        if bad is None:
            notes.append("every scanned period up to T passes")
            lo = good.period
        else:
            lo, hi = good.period, bad.period
            while hi - lo > RTOL * lo:
                mid = math.sqrt(lo * hi)
                lo, hi = (mid, hi) if evaluate(mid).ok else (lo, mid)
            notes.append(
                f"scanned {len(scan)} periods from {scan[0]:.3g} (geometric); the first "
                f"failure bracketed by bisection to {RTOL:.0e} relative, then verified below"
            )
        searched = dict(seen)
        period, evidence = _verify(evaluate, horizon, lo, scan, bound, max_peak, list(seen))
        if period is not None and period < lo:
            notes.append(
                f"the verification found a failing period below {fmt(lo)}: the answer is "
                "the largest verified period below it"
            )
    notes.append(
        f"K = ⌊T/h⌋ samples and the held input's partial step to T = {horizon:g} (exact moments)"
    )
    return SafePeriod(
        period,
        *common,
        tuple(sorted(searched.values(), key=lambda p: p.period)),
        tuple(notes),
        evidence,
    )


def _diverges(final: float, peak: float, start: float, horizon: float) -> str | None:
    """Why the continuous design diverges on [0, T] (None when it does not): its
    E‖e‖² overflows or passes GROWTH_STOP times its start, or ends at T FINAL_GROWTH times
    above it. A period within (1 + tolerance) of that would prove nothing."""
    scale = max(start, 1.0)
    if not (math.isfinite(final) and math.isfinite(peak)) or peak > GROWTH_STOP * scale:
        return (
            f"the continuous design diverges: E Σ‖x_i − θ‖² passes {GROWTH_STOP * scale:.3g} "
            f"({GROWTH_STOP:.0e} times its start) before T = {horizon:g}; no period is safe "
            "against it: lower the gain"
        )
    if final > FINAL_GROWTH * scale:
        return (
            f"the continuous design diverges: E Σ‖x_i(T) − θ‖² = {final:.3g} at "
            f"T = {horizon:g}, {final / scale:.3g} times its start; no period is safe "
            "against it: lower the gain"
        )
    return None


def _margin(p: PeriodPoint, bound: float, max_peak: float | None) -> float:
    """How far below its bounds a period is, relative (negative: it fails)."""
    r = p.final / bound if bound > 0 else (0.0 if p.final <= 0 else math.inf)
    if max_peak is not None:
        r = max(r, p.peak / max_peak)
    return 1.0 - r if math.isfinite(r) else -math.inf


def _verify(
    evaluate: Callable[[float], PeriodPoint],
    horizon: float,
    top: float,
    scan: np.ndarray,
    bound: float,
    max_peak: float | None,
    earlier: list[float],
) -> tuple[float | None, PeriodEvidence]:
    """The answer checked on the dense grid below ``top`` (see the module): the largest
    period of the grid below its first failure, and the grid's evidence."""
    k0 = max(1, math.floor(horizon / top * (1 + 1e-12)))
    k1 = min(math.ceil(VERIFY_SPAN * horizon / top), SCAN_STEPS, k0 + VERIFY_SAMPLES)
    k1 = max(k0 + 1, k1)
    dense = [horizon / (k + j / PER_SAMPLE) for k in range(k0, k1 + 1) for j in range(PER_SAMPLE)]
    lowest = min(dense)
    grid = sorted(
        {h for h in dense if h <= top}
        | {float(h) for h in scan if h <= top}
        | {h for h in earlier if h <= top}
        | {top}
    )
    pts: list[PeriodPoint] = []
    complete = True

    def close(a: PeriodPoint, b: PeriodPoint) -> bool:
        """Whether the curve may cross a bound between two passing neighbours: their
        margin is within NEAR_FLOOR plus WIGGLE times their difference."""
        ma, mb = _margin(a, bound, max_peak), _margin(b, bound, max_peak)
        return min(ma, mb) < NEAR_FLOOR + WIGGLE * abs(ma - mb)

    def refine(a: PeriodPoint, b: PeriodPoint, level: int) -> bool:
        """Bisect between a and b, lower half first; False at the first failure."""
        nonlocal complete
        if level >= REFINE_LEVELS or not close(a, b):
            return True
        if len(pts) >= MAX_VERIFY:
            complete = False
            return True
        m = evaluate(math.sqrt(a.period * b.period))
        pts.append(m)
        return refine(a, m, level + 1) and m.ok and refine(m, b, level + 1)

    # upwards, each neighbour pair refined as it comes: the first failure ends the search
    prev: PeriodPoint | None = None
    for h in grid:
        p = evaluate(h)
        pts.append(p)
        if (prev is not None and not refine(prev, p, 0)) or not p.ok:
            break
        prev = p
    pts.sort(key=lambda p: p.period)
    failing = [p.period for p in pts if not p.ok]
    cut = min(failing) if failing else math.inf
    passed = [p for p in pts if p.ok and p.period < cut]
    period = passed[-1].period if passed else None
    backing = [p for p in passed if period is not None and p.period <= period]
    worst = min(backing, key=lambda p: _margin(p, bound, max_peak)) if backing else None
    evidence = PeriodEvidence(
        len(backing), k0, k1, lowest, PER_SAMPLE, REFINE_LEVELS, NEAR_FLOOR, worst, complete
    )
    return period, evidence


__all__ = ["PeriodEvidence", "PeriodPoint", "SafePeriod", "longest_safe_period", "period_curve"]
