"""The longest safe sampling period of the digital protocol (``ntc tune --period auto``):
the largest h such that every period in (0, h] keeps the exact E Σ_i ‖x_i(T) − θ‖² of the
sampled recursion within (1 + tolerance) of the continuous design's, and its peak
sup_k E Σ_i ‖x_i(kh) − θ‖² within ``max_peak`` (when given).

Search: the exact moments (:func:`ntc_design.simulate.digital.digital_moments`) at
``SCAN_POINTS`` periods spaced geometrically from T/``SCAN_STEPS`` up to T; the last period
before the first that fails is refined by bisection against that failure to a relative
``RTOL``. Every period of the scan below it passed: that is the evidence for "every
period in (0, h]" (between scan points the curve is not evaluated; the report shows it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from ..errors import InputError, require_horizon, require_int, require_number
from ..model import SwitchingTopology, TimeVaryingTopology, Topology
from ..present.rows import Table, fmt, verdict
from ..protocol.digital import Digital
from ..simulate import SimulationSpec
from ..simulate.digital import digital_moments
from ..simulate.driver import (
    AnyTopology,
    is_expression_topology,
    make_gain,
    prepare_modes,
    sampled_grid,
)

SCAN_POINTS = 36
#: The shortest period scanned is T / SCAN_STEPS (K = SCAN_STEPS steps).
SCAN_STEPS = 4000
RTOL = 1e-3
#: A candidate whose E‖e‖² passes this many times its start is stopped (it fails).
GROWTH_STOP = 1e8


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
        Every period evaluated, sorted.
    notes : tuple of str
        What the search says besides its numbers.
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
        notes = [
            f"bounds: E Σ‖x_i(T) − θ‖² <= (1 + {self.tolerance:g})·{fmt(self.continuous_final)} "
            f"(the continuous design's at T = {self.horizon:g})"
            + (f"; peak <= {fmt(self.max_peak)}" if self.max_peak is not None else ""),
            *self.notes,
        ]
        return Table.build(
            head, ("period h", "E Σ‖x_i(T) − θ‖²", "peak", "within the bounds"), rows, notes
        )

    def to_dict(self) -> dict:
        """What ``ntc tune --period auto --json`` prints.

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
            "notes": list(self.notes),
        }


def _prepared(topology: AnyTopology, spec: SimulationSpec, horizon: float):
    """The continuous design's modes and the gain, for every period."""
    if is_expression_topology(topology):
        raise InputError(
            "--period: a topology given as expressions of t is not sampled by the digital "
            "protocol; give it as a switching schedule or a fixed topology"
        )
    base = spec.replace(T=float(horizon), digital=None, method="exact")
    if not base.noise.linear:
        raise InputError("--period: the exact moments need a linear f (a scalar or a matrix)")
    gain = make_gain(base.gain)[0]
    fixed = cast("Topology | SwitchingTopology | TimeVaryingTopology", topology)
    return fixed, prepare_modes(fixed, base, gain), gain


def _run(fixed, pm, gain, horizon: float, delay: int, h: float, stop: float | None):
    grid = sampled_grid(fixed, pm, Digital(float(h), delay), float(horizon), np.array([horizon]))
    with np.errstate(all="ignore"):
        dm = digital_moments(pm.systems, grid, gain, pm.eps0, pm.n, pm.d, delay, abort_above=stop)
    return float(dm.moments.ms_error[-1].sum()), dm.peak


def period_curve(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    delay: int,
    periods: np.ndarray,
    stop_above: float | None = None,
) -> list[tuple[float, float]]:
    """(E Σ‖x_i(K h) − θ‖², peak) of the sampled recursion at each period, exactly.

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
    fixed, pm, gain = _prepared(topology, spec, horizon)
    return [_run(fixed, pm, gain, horizon, delay, float(h), stop_above) for h in periods]


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
        sup_k E Σ‖x_i(kh) − θ‖² <= max_peak.
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
    horizon = require_horizon("--horizon", horizon)
    delay = require_int("--delay", delay, minimum=0)
    tolerance = require_number("--tolerance", tolerance, minimum=0.0)
    if max_peak is not None and not require_number("--max-peak", max_peak) > 0:
        raise InputError(f"--max-peak: must be a positive number, got {max_peak!r}")
    points = require_int("points", points, minimum=2, maximum=1000)
    fixed, pm, gain = _prepared(topology, spec, horizon)
    t = np.linspace(0.0, horizon, 401)
    with np.errstate(all="ignore"):
        cont = pm.moments(gain, t).ms_error.sum(axis=1)
    c_final, c_peak = float(cont[-1]), float(np.max(cont))
    if not (math.isfinite(c_final) and math.isfinite(c_peak)):
        raise InputError("--period auto: the continuous design's moments overflow on [0, T]")
    start = float(pm.eps0 @ pm.eps0)
    stop = GROWTH_STOP * max(start, c_peak, 1.0)
    if max_peak is not None:
        stop = min(stop, max_peak * (1 + 1e-9))
    bound = (1 + tolerance) * c_final

    def evaluate(h: float) -> PeriodPoint:
        final, peak = _run(fixed, pm, gain, horizon, delay, h, stop)
        ok = final <= bound and (max_peak is None or peak <= max_peak)
        return PeriodPoint(h, final, peak, bool(ok))

    scan = np.geomspace(horizon / SCAN_STEPS, horizon, points)
    seen: list[PeriodPoint] = []
    notes: list[str] = []
    good: PeriodPoint | None = None
    bad: PeriodPoint | None = None
    for h in scan:
        p = evaluate(float(h))
        seen.append(p)
        if not p.ok:
            bad = p
            break
        good = p
    if good is None:
        notes.append(f"even h = T/{SCAN_STEPS} = {scan[0]:.3g} fails the bounds")
        period = None
    elif bad is None:
        period = good.period
        notes.append("every scanned period up to T passes: the longest safe period is T")
    else:
        lo, hi = good.period, bad.period
        while hi - lo > RTOL * lo:
            mid = math.sqrt(lo * hi)
            p = evaluate(mid)
            seen.append(p)
            lo, hi = (mid, hi) if p.ok else (lo, mid)
        period = lo
        notes.append(
            f"scanned {len(scan)} periods from {scan[0]:.3g} (geometric), every one below "
            f"h passes; the boundary refined by bisection to {RTOL:.0e} relative"
        )
    notes.append(f"K = round(T/h) steps of the sampled recursion (exact moments), T = {horizon:g}")
    return SafePeriod(
        period,
        delay,
        float(tolerance),
        float(max_peak) if max_peak is not None else None,
        horizon,
        c_final,
        c_peak,
        tuple(sorted(seen, key=lambda p: p.period)),
        tuple(notes),
    )


__all__ = ["PeriodPoint", "SafePeriod", "longest_safe_period", "period_curve"]
