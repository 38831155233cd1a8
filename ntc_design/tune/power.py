"""Tune the gain c(t) = a·(b + t)^(−γ) (and optionally δ) of a scenario for a deadline T.

The question: which admissible gain brings the agents closest to θ by time T, measured by
E Σ_i ‖x_i(T) − θ‖², under the scenario's own noise, initial state and topology (fixed,
switching or A(t))? The objective comes from :mod:`.objective` (exact moments, or Monte
Carlo with common random numbers), the search from :mod:`.search`. The optimum is written
with 4 significant digits and its numbers are recomputed for the written gain at the
reported accuracy; its theorem conditions are analysed (:func:`ntc_design.gain.conditions.analyse_gain`)
and the tuned design is certified (:func:`ntc_design.certify.certify`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping

import numpy as np

from ..choices import Require
from ..errors import (
    InputError,
    Option,
    check_work,
    format_seconds,
    require_horizon,
)
from ..gain.conditions import analyse_gain
from ..model import SwitchingTopology, Topology
from ..protocol import design_topology
from ..simulate import SimulationSpec
from ..simulate.prepare import AnyTopology
from .evidence import certify_tuned, stable_stepping
from .family import A_RANGE, B_RANGE, BASELINE, PowerGain, gamma_range
from .objective import Objective, objective_for
from .options import PowerOptions
from .power_result import Landscape, TuneResult
from .search import Dimension, search

#: δ is searched in [max(1.05·δ_crit, 0.05·δ_Lemma1), 4·δ_Lemma1] (δ_crit: δ_H for one
#: topology, the largest δ_S of the modes for a switching set).
DELTA_UPPER = 4.0
DELTA_LOWER_FRACTION = 0.05
DELTA_CRIT_FACTOR = 1.05
#: The contour map's grid (a × γ), and its size when each point is a Monte Carlo run.
LANDSCAPE_SHAPE = (13, 9)
LANDSCAPE_SHAPE_MC = (5, 4)
LANDSCAPE_SPAN = 8.0
#: A tuning run estimated to take longer than this is refused before it starts (one
#: longer than ``errors.LONG_WORK_SECONDS`` says how long, and goes on).
MAX_TUNE_SECONDS = 3600.0


def delta_range(topology: AnyTopology, theta) -> tuple[float, float, float]:
    """The δ range searched by ``tune_delta`` and Lemma 1's δ: −L_B Hurwitz (one
    topology) or L_B + L_Bᵀ ≻ 0 in every mode (switching) holds on all of it.

    Parameters
    ----------
    topology : Topology or SwitchingTopology
        The network.
    theta : sequence of float
        θ.

    Returns
    -------
    (float, float, float)
        Lower limit, upper limit, Lemma 1's δ (the largest over the modes).

    Raises
    ------
    InputError
        A topology given as functions of t, or no δ with the property.
    """
    if isinstance(topology, SwitchingTopology):
        designs = [design_topology(m, theta, thresholds=True) for m in topology.modes.values()]
        crits = [d.thresholds.symmetric if d.thresholds else None for d in designs]
        what = "L_B + L_Bᵀ ≻ 0 in every mode"
    elif isinstance(topology, Topology):
        designs = [design_topology(topology, theta, thresholds=True)]
        crits = [designs[0].thresholds.hurwitz if designs[0].thresholds else None]
        what = "−L_B Hurwitz"
    else:
        raise InputError(
            "a topology given as functions of t takes Lemma 1's δ(t) at every t",
            field="tune_delta",
        )
    if any(c is None for c in crits):
        raise InputError(f"no δ gives {what} for every larger δ", field="tune_delta")
    lemma = max(d.delta for d in designs)
    crit = max(float(c) for c in crits if c is not None)
    lo = max(DELTA_CRIT_FACTOR * crit, DELTA_LOWER_FRACTION * lemma)
    hi = DELTA_UPPER * lemma
    if not lo < hi:
        raise InputError(
            f"the critical δ {crit:.4g} leaves no room below {hi:.4g} "
            f"({DELTA_UPPER:g} × Lemma 1's δ)",
            field="tune_delta",
        )
    return lo, hi, lemma


def _dimensions(
    require: Require,
    delta: tuple[float, float] | None,
    bounds: Mapping[str, tuple[float, float]] | None,
) -> list[Dimension]:
    """The searched box: the defaults, narrowed by ``bounds`` (lo = hi fixes a parameter)."""
    g_lo, g_hi = gamma_range(require)
    box = {"a": A_RANGE, "b": B_RANGE, "gamma": (g_lo, g_hi)}
    if delta is not None:
        box["delta"] = delta
    for name, rng in (bounds or {}).items():
        if name not in box:
            raise InputError(
                f"unknown parameter {name!r} (known: {', '.join(box)})", field="bounds"
            )
        lo, hi = (float(v) for v in rng)
        allowed = box[name] if name in ("gamma", "delta") else (0.0, math.inf)
        if not (math.isfinite(lo) and math.isfinite(hi) and allowed[0] <= lo <= hi <= allowed[1]):
            raise InputError(
                f"{name} range [{lo:g}, {hi:g}] is not inside [{allowed[0]:g}, "
                f"{allowed[1]:g}]" + (" (the required theorems)" if name == "gamma" else ""),
                field="bounds",
            )
        if name in ("a", "b") and lo <= 0:
            raise InputError(f"{name} must be > 0", field="bounds")
        box[name] = (lo, hi)
    points = {"a": 5, "b": 3, "gamma": 4, "delta": 3}
    logs = {"a", "b", "delta"}
    return [Dimension(k, lo, hi, log=k in logs, points=points[k]) for k, (lo, hi) in box.items()]


def tune_seconds(
    obj: Objective, dims: list[Dimension], evaluations: int, landscape: bool
) -> tuple[float, int, float] | None:
    """The estimated time of a tuning run before it starts: the mean cost of an evaluation
    over the search's coarse grid (:meth:`.objective.Objective.seconds`, closed-form
    integrals of each candidate) times the evaluations of the search and the landscape,
    plus the two curves at the reported accuracy.

    Parameters
    ----------
    obj : Objective
        The objective.
    dims : list of Dimension
        The searched box.
    evaluations : int
        The search's budget.
    landscape : bool
        Whether the contour map is evaluated too.

    Returns
    -------
    (float, int, float) or None
        Seconds in all, evaluations, seconds of a mean evaluation; None when the
        objective gives no estimate.
    """
    box = {d.name: d.grid() for d in dims}
    costs = [
        obj.seconds(PowerGain(float(a), float(b), float(g)))
        for a in box["a"]
        for b in box["b"]
        for g in box["gamma"]
    ]
    accurate = obj.seconds(BASELINE, accurate=True)
    if accurate is None or any(c is None for c in costs):
        return None
    per = float(np.mean([c for c in costs if c is not None]))
    shape = LANDSCAPE_SHAPE_MC if obj.statistical else LANDSCAPE_SHAPE
    n = evaluations + (shape[0] * shape[1] if landscape else 0)
    return n * per + 2 * accurate, n, per


def _check_tune_work(
    obj: Objective, dims: list[Dimension], evaluations: int, landscape: bool, horizon: float
) -> None:
    """Refuse a run estimated above :data:`MAX_TUNE_SECONDS`; warn with the estimate
    above ``errors.LONG_WORK_SECONDS``."""
    got = tune_seconds(obj, dims, evaluations, landscape)
    if got is None:
        return
    total, n, per = got
    what = (
        f"tuning for T = {horizon:g} takes roughly {format_seconds(total)} ({n} evaluations "
        f"of {obj.name}, about {per:.3g} s each)"
    )
    instead = f"a shorter {Option('horizon')} or fewer {Option('max_evaluations')}"
    check_work(total, what, MAX_TUNE_SECONDS, instead, field="horizon", option=True)


def tune_power(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    options: PowerOptions | None = None,
    progress: Callable[..., None] | None = None,
) -> TuneResult:
    """Tune c(t) = a·(b + t)^(−γ) (and δ) to minimise E Σ_i ‖x_i(T) − θ‖² (what
    :func:`ntc_design.tune.tune` runs for :class:`.options.PowerOptions`).

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario: θ, noise, x(0), δ or ΔC, and for Monte Carlo the paths, seed, dt.
    horizon : float
        The deadline T.
    options : PowerOptions, optional
        The theorems required, δ, ε, the objective, the budget, the landscape, the
        certificate and narrower ranges (default: ``PowerOptions()``).
    progress : callable, optional
        Called with a line of text at each stage, and with ``transient=True`` for each
        evaluation (done, the time left in the search).

    Returns
    -------
    TuneResult

    Raises
    ------
    InputError
        A bad horizon or δ range; a scenario the objective refuses.
    """
    require_horizon("horizon", horizon)
    o = options if options is not None else PowerOptions()
    require, tune_delta, eps, method = o.require, o.tune_delta, o.eps, o.method
    max_evaluations, landscape, certificate, bounds = (
        o.max_evaluations,
        o.landscape,
        o.certificate,
        o.bounds,
    )
    t0 = time.perf_counter()
    notes: list[str] = []
    drange = delta_range(topology, spec.theta) if tune_delta else None
    obj = objective_for(topology, spec, horizon, method)
    dims = _dimensions(require, drange[:2] if drange else None, bounds)
    _check_tune_work(obj, dims, max_evaluations, landscape, horizon)

    done = [0]

    def fun(p: Mapping[str, float]) -> float:
        done[0] += 1
        if progress is not None:
            el = time.perf_counter() - t0
            left = el * (max_evaluations - done[0]) / done[0]
            progress(
                f"evaluation {done[0]} of at most {max_evaluations} "
                f"(about {format_seconds(left)} left in the search)",
                transient=True,
            )
        return obj.value(PowerGain(p["a"], p["b"], p["gamma"]), p.get("delta"))

    base = {"a": BASELINE.a, "b": BASELINE.b, "gamma": BASELINE.gamma}
    if drange:
        base["delta"] = min(max(drange[2], drange[0]), drange[1])
    inside = all(d.lo <= base[d.name] <= d.hi for d in dims)
    trace = search(fun, dims, [base] if inside else [], max_evaluations=max_evaluations)
    stages = {"search": time.perf_counter() - t0}  # what took the time, said in the note
    (best, value) = trace.best
    if not math.isfinite(value):
        raise InputError(
            f"no candidate could be evaluated ({next(iter(obj.skipped.values()), '')})",
            field="tune",
        )
    p = dict(zip(trace.names, best, strict=True))
    for d in dims:
        if d.hi > d.lo and min(d.to_unit(p[d.name]), 1 - d.to_unit(p[d.name])) < 1e-3:
            why = (
                "the limit the required theorems allow"
                if d.name == "gamma"
                else "a wider range may do better"
            )
            notes.append(
                f"{d.name} = {p[d.name]:.4g} is at the edge of the searched range "
                f"[{d.lo:.4g}, {d.hi:.4g}]: {why}"
            )
    tuned = PowerGain(p["a"], p["b"], p["gamma"]).rounded()
    delta = float(f"{p['delta']:.4g}") if "delta" in p else None
    say = progress or (lambda text, transient=False: None)

    def stage(name: str, since: float) -> None:
        stages[name] = time.perf_counter() - since

    t1 = time.perf_counter()
    say("the tuned and baseline curves at the reported accuracy")
    curves = {
        "tuned": obj.curve(tuned, delta),
        "baseline": obj.curve(BASELINE, None),
    }
    stage("final curves", t1)
    if curves["tuned"].final > curves["baseline"].final:
        notes.append(
            "the baseline is better than every candidate found at T (a flat or noisy objective)"
        )
    if obj.skipped:
        notes.append(f"{len(obj.skipped)} candidate(s) scored +∞ (too stiff or overflowing)")
    t1 = time.perf_counter()
    say("a stable Euler–Maruyama step for the tuned gain")
    stepping = stable_stepping(topology, spec, tuned, delta, horizon, notes)
    stage("step check", t1)
    t1 = time.perf_counter()
    if landscape:
        say("the landscape around the optimum (the contour map)")
    land = _landscape(obj, tuned, delta, dims) if landscape else None
    if landscape:
        stage("landscape", t1)
    t1 = time.perf_counter()
    say("the theorem conditions and the certificate of the tuned design")
    analysis = analyse_gain(tuned.text)
    cert = certify_tuned(topology, spec, tuned, delta, notes, horizon) if certificate else None
    stage("theorems and certificate", t1)
    return TuneResult(
        tuned=tuned,
        baseline=BASELINE,
        delta=delta,
        horizon=float(horizon),
        require=require,
        method=obj.describe(),
        statistical=obj.statistical,
        curves=curves,
        eps=eps,
        gain_analysis=analysis,
        certificate=cert,
        evaluations=len(trace.values),
        seconds=time.perf_counter() - t0,
        landscape=land,
        notes=tuple(notes),
        stepping=stepping,
        stage_seconds=stages,
    )


def _landscape(
    obj: Objective, best: PowerGain, delta: float | None, dims: list[Dimension]
) -> Landscape:
    """The objective over (a, γ) at the optimum's b and δ (search accuracy): a within a
    factor ``LANDSCAPE_SPAN`` of the optimum (inside the searched range), all of γ's."""
    na, ng = LANDSCAPE_SHAPE_MC if obj.statistical else LANDSCAPE_SHAPE
    box = {d.name: d for d in dims}
    a_lo = max(box["a"].lo, best.a / LANDSCAPE_SPAN)
    a_hi = min(box["a"].hi, best.a * LANDSCAPE_SPAN)
    a = np.geomspace(a_lo, a_hi, na) if a_hi > a_lo else np.array([best.a])
    g = box["gamma"]
    gam = np.linspace(g.lo, g.hi, ng) if g.hi > g.lo else np.array([g.lo])
    vals = np.array([[obj.value(PowerGain(x, best.b, y), delta) for x in a] for y in gam])
    return Landscape(a, gam, best.b, vals)
