"""``tune(..., ScheduleOptions())``: the best gain schedule for a deadline, with the
evidence a user needs to trust it.

Steps: the best power law a·(b + t)^(−γ) (:func:`.power.tune_power`, polished by exact gradients; the schedule starts
from and is compared with); the optimal schedule (:mod:`.optimal`); the schedule written
as a :class:`~ntc_design.gain.schedule.ScheduleGain` whose tail a·(1 + t)^(−1) meets it at T,
so Theorems 1 and 2 hold; every number re-evaluated independently by the tuner's exact
objective (RK4 at κ = 0.2 or Crank–Nicolson, on its own grid); the three gains by Monte
Carlo with common random numbers; the theorem conditions and the certificate of the
design with the schedule.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace
from functools import partial

import numpy as np

from ..choices import Require
from ..errors import InputError, Option, require_horizon
from ..gain.schedule import ScheduleGain, analyse_schedule, join_tail
from ..model import TimeVaryingTopology
from ..model.timevarying import ExpressionTopology
from ..simulate import SimulationSpec, simulate
from ..simulate.options import SaveAt
from ..simulate.prepare import AnyTopology, sampled_grid
from ..simulate.result import Z95
from .evidence import certify_tuned, checked_spec, stable_stepping
from .family import A_RANGE, B_RANGE, BASELINE, PowerGain, gamma_range
from .objective import AnyGain, ExactObjective, objective_for
from .optimal import fit_power, optimise_schedule
from .options import CHECK_PATHS, PowerOptions, ScheduleOptions
from .power import delta_range, tune_power
from .sampled import SampledScheduleProblem
from .schedule_problem import MomentProblem, ScheduleProblem
from .schedule_result import (
    AGREE_RTOL,
    MonteCarloCheck,
    ScheduleTuneResult,
    relative_gap,
)

#: The coarse power-law search's budget before the gradient polish.
POWER_EVALUATIONS = 40
#: Pieces of the schedule that scores each δ of the δ search (``tune_delta``).
DELTA_PIECES = 10
#: z of the 99 % band of the evidence.
Z99 = 2.5758293035489004


def check_schedule_scenario(topology: AnyTopology, spec: SimulationSpec) -> None:
    """Refuse, in one line, what the optimal schedule cannot do: a non-linear f (no exact
    moments) or N·d above the limit.

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario.

    Raises
    ------
    InputError
        What is missing, and what to use instead.
    """
    if not spec.noise.linear:
        raise InputError(
            "exact moments exist only for a linear f(x) = F·x; use ",
            Option("schedule", "power"),
            " ",
            Option("method", "mc"),
            " (Monte Carlo with common random numbers)",
            field="schedule",
            value="optimal",
        )
    ScheduleProblem.check_size(topology.n * topology.dim)


def sampled_topology(topology: ExpressionTopology) -> TimeVaryingTopology:
    """A(t) given as expressions of t, as functions of t: what the schedule optimises on,
    re-designed (Lemma 1) every ``spec.resample`` (default 0.1) time units as the
    simulator does for functions of t; the numbers reported are re-evaluated on the
    continuous A(t).

    Parameters
    ----------
    topology : ExpressionTopology
        The network.

    Returns
    -------
    TimeVaryingTopology
    """
    labels = topology.labels
    weights = {
        (labels[e.j], labels[e.i]): partial(_edge_weight, topology, k)
        for k, e in enumerate(topology.edges)
    }
    return TimeVaryingTopology(labels, topology.dim, weights, topology.name)


def _edge_weight(topology: ExpressionTopology, k: int, t: float) -> np.ndarray:
    return topology.weights_at([t])[0, k]


def _monte_carlo(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    gains: dict[str, tuple[AnyGain, float | None]],
    exact: dict[str, float],
    paths: int,
    notes: list[str],
) -> dict[str, MonteCarloCheck]:
    """The gains (each with its δ) by Monte Carlo, the scenario's seed for each, so the
    same Brownian increments (common random numbers); the drift-implicit scheme where the
    explicit one is unstable (:func:`.evidence.checked_spec`)."""
    out: dict[str, MonteCarloCheck] = {}
    base = spec.replace(
        T=horizon,
        method="mc",
        save=SaveAt(times=np.array([0.0, horizon])),
        mc=replace(spec.mc, paths=paths, store_paths=0),
    )
    for key, (g, delta) in gains.items():
        run_spec, why = checked_spec(
            topology, base.replace(gain=g, delta=delta if delta is not None else spec.delta)
        )
        if why is not None:
            notes.append(f"Monte Carlo of {key}: the drift-implicit scheme (explicit unstable)")
        mc = simulate(topology, spec=run_spec).mc
        assert mc is not None
        mean = float(mc.mean[-1].sum())
        # the sum's standard error is at most the agents' added: a conservative band
        half = float(np.sum(mc.hi[-1] - mc.mean[-1])) * Z99 / Z95
        out[key] = MonteCarloCheck(mean, mean - half, mean + half, exact[key], mc.count)
    return out


def problem_for(obj: ExactObjective, delta: float | None, model: AnyTopology) -> MomentProblem:
    """The optimal-control problem of a scenario: the sampled recursion's when it has a
    ``digital`` block (:class:`.sampled.SampledScheduleProblem`), else the moment
    equations' (:class:`.optimal.ScheduleProblem`).

    Parameters
    ----------
    obj : ExactObjective
        The scenario's exact objective (its designs per δ).
    delta : float or None
        The δ.
    model : Topology, SwitchingTopology or TimeVaryingTopology
        The network the objective was built on.

    Returns
    -------
    MomentProblem
    """
    pm = obj.prepared(delta)[0]
    dg = obj.spec.digital
    if dg is None:
        return ScheduleProblem(pm, obj.horizon)
    grid = sampled_grid(model, pm, dg, obj.horizon, np.array([obj.horizon]))
    return SampledScheduleProblem(pm, grid, dg)


def sampled_levels(prob: MomentProblem, levels: tuple[int, ...]) -> tuple[int, ...]:
    """The refinement levels of a problem: for the sampled recursion no finer than one
    node per sample (the last level then is the sampled schedule itself).

    Parameters
    ----------
    prob : MomentProblem
        The problem.
    levels : tuple of int
        The levels asked for.

    Returns
    -------
    tuple of int
    """
    if not isinstance(prob, SampledScheduleProblem):
        return levels
    k = prob.grid.n_steps
    out = tuple(x for x in levels if x < k)
    return (*out, k) if k <= max(levels) else out


def _polish(
    prob: MomentProblem,
    found: PowerGain,
    require: Require,
    obj: ExactObjective,
    delta: float | None,
) -> PowerGain:
    """The coarse search's power law polished by exact gradients (:func:`.optimal.fit_power`),
    rounded as written; the better of the two by the independent objective."""
    polished = fit_power(prob, found, gamma_range(require), A_RANGE, B_RANGE).rounded()
    if obj.value(polished, delta) <= obj.value(found, delta):
        return polished
    return found


def _schedule_delta(
    obj: ExactObjective,
    model: AnyTopology,
    topology: AnyTopology,
    theta,
    start: PowerGain,
    max_gain: float,
    max_peak: float | None,
    notes: list[str],
) -> float:
    """The common δ for the schedule: bounded Brent search of log δ over
    :func:`.power.delta_range`, each δ scored by the optimal schedule on ``DELTA_PIECES``
    pieces (started from the schedule of the nearest δ scored so far); δ written to 4
    significant digits."""
    from scipy.optimize import minimize_scalar

    lo, hi, _ = delta_range(topology, theta)
    seen: dict[float, Callable] = {}

    def score(log_delta: float) -> float:
        near = min(seen, key=lambda v: abs(v - log_delta)) if seen else None
        prob = problem_for(obj, math.exp(log_delta), model)
        sol = optimise_schedule(
            prob,
            seen[near] if near is not None else start,
            max_gain=max_gain,
            max_peak=max_peak,
            levels=(DELTA_PIECES,),
        )
        seen[log_delta] = partial(np.interp, xp=sol.t, fp=sol.c)
        return sol.value

    r = minimize_scalar(
        score, bounds=(math.log(lo), math.log(hi)), method="bounded", options={"xatol": 1e-3}
    )
    delta = float(f"{math.exp(r.x):.4g}")
    if min(r.x - math.log(lo), math.log(hi) - r.x) < 1e-2:
        notes.append(
            f"δ = {delta:.4g} is at the edge of the searched range [{lo:.4g}, {hi:.4g}]: a "
            "wider range may do better"
        )
    return delta


def _additive_noise(spec: SimulationSpec) -> bool:
    """Whether any σ_ji is non-zero (Q ≠ 0: the error grows from ε = 0)."""
    return bool(spec.noise.sigma) or any(spec.noise.sigma_edges.values())


def tune_schedule(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    options: ScheduleOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> ScheduleTuneResult:
    """The optimal c(t) on [0, T] (see :mod:`.optimal`) with its tail, beside the best
    power law and 1/(1 + t).

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.
    spec : SimulationSpec
        The scenario (θ, noise with a linear f, x(0), δ or ΔC, Monte Carlo seed).
    horizon : float
        T.
    options : ScheduleOptions, optional
        The theorems the power law must satisfy (the schedule's tail satisfies both), δ
        (the power law's with its search, the schedule's by a bounded search of log δ
        scored by the schedule optimised on ``DELTA_PIECES`` pieces), ε, the bounds on c
        and on the peak, the certificate, the evidence's paths and the refinement's
        pieces (default: ``ScheduleOptions()``).
    progress : callable, optional
        Called with a line per stage.

    Returns
    -------
    ScheduleTuneResult

    Raises
    ------
    InputError
        A bad horizon or scenario (see :func:`check_schedule_scenario`).
    """
    t0 = time.perf_counter()
    require_horizon("horizon", horizon)
    o = options if options is not None else ScheduleOptions()
    require, tune_delta, eps, certificate = o.require, o.tune_delta, o.eps, o.certificate
    max_gain, max_peak, check_paths, levels = o.max_gain, o.max_peak, o.check_paths, o.levels
    check_schedule_scenario(topology, spec)
    notes: list[str] = []
    say = progress or (lambda _m: None)
    # the optimiser's model (A(t) expressions sampled) and the independent judge of every
    # reported number (the continuous A(t) for expressions)
    model = sampled_topology(topology) if isinstance(topology, ExpressionTopology) else topology
    obj = ExactObjective(model, spec, horizon)
    judge = objective_for(topology, spec, horizon, "exact")
    eps0 = obj.prepared(None)[0].eps0
    initial = float(eps0 @ eps0)
    if initial == 0 and not _additive_noise(spec):
        raise InputError(
            "x(0) = 1⊗θ and noise.sigma = 0: E Σ‖x_i(t) − θ‖² = 0 at every t for "
            "every gain (the multiplicative noise vanishes at consensus); nothing to tune",
            field="initial",
        )
    if max_peak is not None and not max_peak > initial:
        raise InputError(
            f"{max_peak:g} is not above the initial error E Σ‖x_i(0) − θ‖² = "
            f"{initial:.6g}; no gain can keep below it",
            field="max_peak",
        )

    say("the best power law a·(b + t)^(−γ)")
    pw = tune_power(
        model,
        spec,
        horizon,
        PowerOptions(
            require,
            tune_delta,
            max_evaluations=POWER_EVALUATIONS,
            landscape=False,
            certificate=False,
        ),
    )
    prob = problem_for(obj, pw.delta, model)
    levels = sampled_levels(prob, levels)
    power = _polish(prob, pw.tuned, require, obj, pw.delta)
    delta = pw.delta
    if tune_delta:
        say("δ for the schedule")
        delta = _schedule_delta(obj, model, topology, spec.theta, power, max_gain, max_peak, notes)
        prob = problem_for(obj, delta, model)
    say("the optimal schedule")
    sol = optimise_schedule(
        prob, power, max_gain=max_gain, max_peak=max_peak, levels=levels, progress=say
    )
    notes.extend(sol.notes)
    if sol.binds:
        notes.append(
            f"{Option('max_gain', max_gain)} binds on {len(sol.binds)} node(s) from t = {sol.binds[0]:g}: "
            "a larger bound would do better"
        )
    if max_peak is not None and sol.peak[0] > max_peak * (1 + AGREE_RTOL):
        notes.append(
            f"the peak bound could not be met: the best found peaks at {sol.peak[0]:.6g} "
            f"(t = {sol.peak[1]:g})"
        )
    schedule = ScheduleGain(sol.t, sol.c, "linear", join_tail(float(horizon), float(sol.c[-1])))

    say("independent re-evaluation of the three gains")
    gains: dict[str, tuple[AnyGain, float | None]] = {
        "optimal": (schedule, delta),
        "power": (power, pw.delta),
        "baseline": (BASELINE, None),
    }
    curves = {k: judge.curve(g, d, points=401) for k, (g, d) in gains.items()}
    gap = relative_gap(sol.value, curves["optimal"].final)
    if gap > AGREE_RTOL:
        notes.append(
            f"the optimiser's value {sol.value:.6g} and the independent re-evaluation "
            f"{curves['optimal'].final:.6g} differ by {gap:.1e} relative"
        )
    mc: dict[str, MonteCarloCheck] = {}
    if check_paths:
        say(f"Monte Carlo of the three gains ({check_paths} paths, common random numbers)")
        exact = {k: c.final for k, c in curves.items()}
        mc = _monte_carlo(topology, spec, horizon, gains, exact, check_paths, notes)
        missed = [k for k, m in mc.items() if not m.inside]
        if missed:
            notes.append(
                "Monte Carlo misses the exact value for " + ", ".join(missed) + " (Euler–"
                "Maruyama bias at the scenario's dt, or a 1 % chance per gain)"
            )
    cert = certify_tuned(topology, spec, schedule, delta, notes, horizon) if certificate else None
    dg = spec.digital
    method = (
        (
            "optimal control: piecewise-linear c on K pieces sampled every h = "
            f"{dg.period:g} (delay D = {dg.delay}), the sampled recursion's exact second "
            "moments with their exact discrete adjoint, "
            if dg is not None
            else "optimal control: piecewise-linear c on K pieces, exact second-moment "
            "equations by RK4 with their exact discrete adjoint, "
        )
        + ("SLSQP with the peak bound" if max_peak is not None else "L-BFGS-B")
        + ("; A(t) sampled every 0.1 for the optimiser" if model is not topology else "")
        + f"; re-evaluated by {judge.describe()}"
    )
    return ScheduleTuneResult(
        schedule=schedule,
        power=power,
        baseline=BASELINE,
        delta=delta,
        power_delta=pw.delta,
        horizon=float(horizon),
        require=require,
        method=method,
        curves=curves,
        solution=sol,
        max_peak=max_peak,
        gain_analysis=analyse_schedule(schedule),
        certificate=cert,
        monte_carlo=mc,
        seconds=time.perf_counter() - t0,
        notes=tuple(notes),
        stepping=stable_stepping(topology, spec, schedule, delta, horizon, []),
        eps=eps,
    )


__all__ = [
    "CHECK_PATHS",
    "check_schedule_scenario",
    "tune_schedule",
]
