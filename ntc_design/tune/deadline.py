"""``tune(..., schedule="optimal")``: the best gain schedule for a deadline, with the
evidence a user needs to trust it.

Steps: the best power law a·(b + t)^(−γ) (:func:`.run.tune_power`, polished by exact gradients; the schedule starts
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
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from ..errors import InputError, require_horizon, require_positive
from ..gain.conditions import GainAnalysis
from ..gain.schedule import ScheduleGain, analyse_schedule, join_tail
from ..model import TimeVaryingTopology
from ..model.timevarying import ExpressionTopology
from ..present.rows import Table, fmt, verdict
from ..simulate import SimulationSpec, simulate
from ..simulate.driver import AnyTopology, sampled_grid
from ..simulate.result import Z95
from ..simulate.spec import SaveAt
from .evidence import certify_tuned, checked_spec, stable_stepping
from .family import A_RANGE, B_RANGE, BASELINE, PowerGain, gamma_range
from .objective import AnyGain, Curve, ExactObjective, objective_for
from .optimal import (
    DEFAULT_MAX_GAIN,
    LEVELS,
    MomentProblem,
    ScheduleProblem,
    ScheduleSolution,
    check_max_gain,
    fit_power,
    optimise_schedule,
)
from .run import delta_range, tune_power
from .sampled import SampledScheduleProblem

#: The coarse power-law search's budget before the gradient polish.
POWER_EVALUATIONS = 40
#: Pieces of the schedule that scores each δ of the δ search (``tune_delta``).
DELTA_PIECES = 10
#: Monte Carlo paths of the evidence (0: none); z of the 99 % band.
CHECK_PATHS = 200
Z99 = 2.5758293035489004
#: Relative gap between the optimiser's value and the independent re-evaluation above
#: which the result says so.
AGREE_RTOL = 1e-3


@dataclass(frozen=True)
class MonteCarloCheck:
    """Σ_i E‖x_i(T) − θ‖² by Monte Carlo, its 99 % band (the per-agent bands' half-widths
    added, a conservative band of the sum) and the exact value it should contain."""

    mean: float
    lo: float
    hi: float
    exact: float
    paths: int

    @property
    def inside(self) -> bool:
        """The exact value lies in the band."""
        return self.lo <= self.exact <= self.hi


@dataclass(frozen=True, eq=False)
class ScheduleTuneResult:
    """The optimal schedule for a deadline beside the best power law and 1/(1 + t).

    Attributes
    ----------
    schedule : ScheduleGain
        The optimum on [0, T] (linear between nodes) and its tail.
    power, baseline : PowerGain
        The best a·(b + t)^(−γ) and 1/(1 + t).
    delta : float or None
        The schedule's common δ (``tune_delta``), else None (the scenario's).
    power_delta : float or None
        The power law's common δ (``tune_delta``), else None.
    horizon : float
        T.
    require : str
        The theorems required of the power law.
    method : str
        How the numbers were computed.
    curves : dict of str to Curve
        ``optimal``, ``power``, ``baseline``: exact E Σ‖x_i − θ‖² on [0, T], each
        computed independently of the optimiser.
    solution : ScheduleSolution
        The optimiser's record: refinement table, optimality, bound, peak.
    max_peak : float or None
        The peak bound M.
    gain_analysis : GainAnalysis
        The schedule's theorem conditions.
    certificate : CertifyResult or None
        The design certified with the schedule as its gain.
    monte_carlo : dict of str to MonteCarloCheck
        The three gains by Monte Carlo (empty when not asked).
    seconds : float
        Wall time.
    notes : tuple of str
        What the run says besides its numbers.
    stepping : dict of str to str
        Scenario keys the written scenario needs for a stable Monte Carlo check.
    """

    schedule: ScheduleGain
    power: PowerGain
    baseline: PowerGain
    delta: float | None
    power_delta: float | None
    horizon: float
    require: str
    method: str
    curves: dict[str, Curve]
    solution: ScheduleSolution
    max_peak: float | None
    gain_analysis: GainAnalysis
    certificate: Any
    monte_carlo: dict[str, MonteCarloCheck]
    seconds: float
    notes: tuple[str, ...] = field(default=())
    stepping: dict[str, str] = field(default_factory=dict)
    eps: float | None = None

    #: The file the written scenario reads the schedule from.
    SCHEDULE_FILE = "schedule.csv"

    @property
    def ms_error_T(self) -> dict[str, float]:  # noqa: N802 - T is the paper's horizon
        """E Σ‖x_i(T) − θ‖² of the three gains (independent exact re-evaluation)."""
        return {k: c.final for k, c in self.curves.items()}

    @property
    def ms_error_peak(self) -> dict[str, dict[str, float]]:
        """sup_t E Σ‖x_i(t) − θ‖² on [0, T] of each gain, and where."""
        return {k: c.peak for k, c in self.curves.items()}

    @property
    def time_to_eps(self) -> dict[str, float | None]:
        """The first time each gain's curve reaches ε (None: not by T, or no ε)."""
        return {
            k: None if self.eps is None else c.first_below(self.eps) for k, c in self.curves.items()
        }

    @property
    def headline(self) -> tuple[float, str]:
        """E Σ‖x_i(T) − θ‖² of the schedule and how it was computed (the written
        scenario's description)."""
        return self.ms_error_T["optimal"], "optimal schedule, exact moments"

    def scenario_gain(self) -> dict[str, str]:
        """The written scenario's ``gain``: the schedule file and its tail.

        Returns
        -------
        dict
        """
        return {
            "schedule": self.SCHEDULE_FILE,
            "tail": self.schedule.tail,
            "interpolation": self.schedule.interpolation,
        }

    @property
    def gains(self) -> dict[str, AnyGain]:
        """The three gains, by key."""
        return {"optimal": self.schedule, "power": self.power, "baseline": self.baseline}

    @property
    def required_holds(self) -> bool | None:
        """The schedule satisfies both theorems' conditions."""
        return self.gain_analysis.almost_sure

    @property
    def certified(self) -> bool:
        """The design's certificate verifies and the schedule's conditions hold."""
        c = self.certificate
        return bool(c is not None and c.verification.valid and self.required_holds)

    @property
    def agreement(self) -> float:
        """|optimiser's value − independent re-evaluation| / re-evaluation."""
        ind = self.ms_error_T["optimal"]
        return abs(self.solution.value - ind) / max(abs(ind), 1e-300)

    def table(self) -> Table:
        """The evidence: the three gains at T (exact and Monte Carlo), their peaks, the
        optimality measure and the verdicts.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        ms, pk, mc = self.ms_error_T, self.ms_error_peak, self.monte_carlo
        keys = ("optimal", "power", "baseline")
        rows: list[tuple[Any, ...]] = [
            ("gain c(t)", "schedule (see c(t))", self.power.text, self.baseline.text),
            (
                f"E Σ‖x_i(T) − θ‖², T = {fmt(self.horizon)} (exact)",
                *(fmt(ms[k]) for k in keys),
            ),
            (
                "ratio to the schedule",
                "1",
                *(_ratio(ms[k], ms["optimal"]) for k in keys[1:]),
            ),
        ]
        if mc:
            rows.append(
                (
                    f"Monte Carlo ({mc['optimal'].paths} paths, common random numbers), 99 % band",
                    *(
                        f"{fmt(mc[k].mean)} [{fmt(mc[k].lo)}, {fmt(mc[k].hi)}] "
                        + ("contains exact" if mc[k].inside else "MISSES exact")
                        for k in keys
                    ),
                )
            )
        rows.append(
            (
                "peak sup_t E Σ‖x_i(t) − θ‖² (at t)",
                *(f"{fmt(pk[k]['value'])} (t = {fmt(pk[k]['t'])})" for k in keys),
            )
        )
        if self.eps is not None:
            te = self.time_to_eps
            rows.append((f"first time ≤ ε = {fmt(self.eps)}", *(te[k] for k in keys)))
        if self.delta is not None or self.power_delta is not None:
            rows.append(("δ (tuned)", self.delta, self.power_delta, "scenario's"))
        sol = self.solution
        rows += [
            (
                "c(0) … c(T)",
                f"{fmt(float(self.schedule.c[0]))} … {fmt(float(self.schedule.c[-1]))}",
                "",
                "",
            ),
            ("tail after T", self.schedule.tail, "", ""),
            (
                "first-order optimality (projected gradient / J)",
                f"{sol.optimality:.2g}",
                "",
                "",
            ),
            (
                "optimiser's value vs independent re-evaluation",
                f"{fmt(sol.value)} vs {fmt(ms['optimal'])} ({self.agreement:.1e} relative)",
                "",
                "",
            ),
            (
                f"--max-gain {fmt(sol.max_gain)}",
                (
                    "binds at t = "
                    + ", ".join(fmt(t) for t in sol.binds[:6])
                    + (" …" if len(sol.binds) > 6 else "")
                )
                if sol.binds
                else "does not bind",
                "",
                "",
            ),
        ]
        if self.max_peak is not None:
            ok = pk["optimal"]["value"] <= self.max_peak * (1 + AGREE_RTOL)
            rows.append((f"--max-peak {fmt(self.max_peak)}", verdict(ok), "", ""))
        rows += [
            ("theorems 1 and 2 (schedule + tail)", verdict(self.required_holds), "", ""),
            (
                "certificate of the design",
                verdict(
                    self.certificate.verification.valid if self.certificate is not None else None
                ),
                "",
                "",
            ),
        ]
        notes = (
            f"{self.method}; {self.seconds:.1f} s",
            *self.notes,
        )
        return Table.build(
            f"best gain for T = {fmt(self.horizon)}: optimal schedule vs power law vs 1/(1 + t)",
            ("", "optimal schedule", "best power law", "1/(1 + t)"),
            rows,
            notes,
        )

    def refinement_table(self) -> Table:
        """Pieces → optimum: the grid refinement.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows = []
        prev = None
        for lv in self.solution.levels:
            change = "" if prev is None else f"{_relative(lv.value, prev):.2e}"
            rows.append(
                (lv.pieces, fmt(lv.value), change, lv.evaluations, lv.steps, f"{lv.seconds:.1f}")
            )
            prev = lv.value
        word = "settled" if self.solution.converged else "did not settle"
        return Table.build(
            "refinement: pieces of c(t) → optimum",
            ("pieces", "E Σ‖x_i(T) − θ‖²", "relative change", "evaluations", "RK4 steps", "s"),
            rows,
            (f"{word} to 0.1 % (the optimiser's own integration)",),
        )

    def tables(self) -> list[Table]:
        """Every table of the result, in the order the faces show them.

        Returns
        -------
        list of ntc_design.present.rows.Table
        """
        return [self.table(), self.refinement_table()]

    def _repr_html_(self) -> str:
        return "".join(t.html() for t in self.tables())

    def __repr__(self) -> str:
        ms = self.ms_error_T
        return (
            f"ScheduleTuneResult(E Σ‖x_i(T) − θ‖² = {fmt(ms['optimal'])} (power law "
            f"{fmt(ms['power'])}, 1/(1+t) {fmt(ms['baseline'])}), T = {fmt(self.horizon)})"
        )

    def to_dict(self) -> dict[str, Any]:
        """The result as a JSON-ready mapping (what ``ntc tune --json`` prints).

        Returns
        -------
        dict
            ``schedule`` ({t, c, interpolation, tail}), ``ms_error_T`` and
            ``ms_error_peak`` (optimal, power, baseline), ``power_gain``,
            ``baseline_gain``, ``delta`` and ``power_delta``, ``horizon``, ``eps`` and
            ``time_to_eps``, ``refinement``, ``optimality``,
            ``max_gain`` (and where it binds), ``max_peak``, ``monte_carlo``,
            ``theorems``, ``certificate_valid``, ``seconds``, ``notes``.
        """
        sol = self.solution
        return {
            "schedule": self.schedule.to_document(),
            "ms_error_T": self.ms_error_T,
            "ms_error_peak": self.ms_error_peak,
            "optimiser_value": sol.value,
            "power_gain": self.power.text,
            "baseline_gain": self.baseline.text,
            "delta": self.delta,
            "power_delta": self.power_delta,
            "horizon": self.horizon,
            "eps": self.eps,
            "time_to_eps": self.time_to_eps,
            "require": self.require,
            "method": self.method,
            "refinement": [
                {
                    "pieces": lv.pieces,
                    "value": lv.value,
                    "evaluations": lv.evaluations,
                    "rk4_steps": lv.steps,
                    "seconds": lv.seconds,
                }
                for lv in sol.levels
            ],
            "refinement_settled": sol.converged,
            "optimality": sol.optimality,
            "max_gain": sol.max_gain,
            "max_gain_binds_at": list(sol.binds),
            "max_peak": self.max_peak,
            "monte_carlo": {
                k: {
                    "mean": m.mean,
                    "band99": [m.lo, m.hi],
                    "exact": m.exact,
                    "inside": m.inside,
                    "paths": m.paths,
                }
                for k, m in self.monte_carlo.items()
            },
            "theorems": self.gain_analysis.to_dict(),
            "required_holds": self.required_holds,
            "certificate_valid": (
                self.certificate.verification.valid if self.certificate is not None else None
            ),
            "seconds": self.seconds,
            "notes": list(self.notes),
            "stepping": dict(self.stepping),
        }


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
            "--schedule optimal: exact moments exist only for a linear f(x) = F·x; use "
            "--schedule power --method mc (Monte Carlo with common random numbers)"
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
    require: str,
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
    :func:`.run.delta_range`, each δ scored by the optimal schedule on ``DELTA_PIECES``
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


def _relative(value: float, reference: float) -> float:
    """|value − reference| / |reference|, 0 when both are 0 (an error of 0 is reached)."""
    diff = abs(value - reference)
    return 0.0 if diff == 0 else diff / max(abs(reference), 1e-300)


def _ratio(value: float, reference: float) -> str:
    """value / reference for the table, "—" when the reference is 0."""
    return fmt(value / reference) if reference else "—"


def _additive_noise(spec: SimulationSpec) -> bool:
    """Whether any σ_ji is non-zero (Q ≠ 0: the error grows from ε = 0)."""
    return bool(spec.noise.sigma) or any(spec.noise.sigma_edges.values())


def tune_schedule(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    *,
    require: str = "both",
    tune_delta: bool = False,
    eps: float | None = None,
    max_gain: float = DEFAULT_MAX_GAIN,
    max_peak: float | None = None,
    certificate: bool = True,
    check_paths: int = CHECK_PATHS,
    levels: tuple[int, ...] = LEVELS,
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
    require : {"both", "mean-square"}, optional
        The theorems the power law must satisfy (the schedule's tail satisfies both).
    tune_delta : bool, optional
        Also choose δ: the power law's with its search, the schedule's by a bounded
        search of log δ scored by the schedule optimised on ``DELTA_PIECES`` pieces.
    eps : float, optional
        Report when each gain first reaches E Σ‖x_i − θ‖² ≤ ε.
    max_gain : float, optional
        Upper bound on c(t).
    max_peak : float, optional
        Bound M on sup_t E Σ‖x_i(t) − θ‖² (above the initial error).
    certificate : bool, optional
        Certify the design with the schedule.
    check_paths : int, optional
        Monte Carlo paths of the evidence (0: none).
    levels : tuple of int, optional
        The refinement's pieces.
    progress : callable, optional
        Called with a line per stage.

    Returns
    -------
    ScheduleTuneResult

    Raises
    ------
    InputError
        A bad horizon, bound or scenario (see :func:`check_schedule_scenario`).
    """
    t0 = time.perf_counter()
    require_horizon("horizon", horizon)
    check_max_gain(max_gain)
    if max_peak is not None:
        require_positive("--max-peak", max_peak)
    if eps is not None:
        require_positive("eps", eps)
    if not isinstance(check_paths, int) or not 0 <= check_paths <= 100_000:
        raise InputError(f"check_paths: expected an integer in [0, 100000], got {check_paths!r}")
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
            "initial: x(0) = 1⊗θ and noise.sigma = 0: E Σ‖x_i(t) − θ‖² = 0 at every t for "
            "every gain (the multiplicative noise vanishes at consensus); nothing to tune"
        )
    if max_peak is not None and not max_peak > initial:
        raise InputError(
            f"--max-peak: {max_peak:g} is not above the initial error E Σ‖x_i(0) − θ‖² = "
            f"{initial:.6g}; no gain can keep below it"
        )

    say("the best power law a·(b + t)^(−γ)")
    pw = tune_power(
        model,
        spec,
        horizon,
        require=require,
        tune_delta=tune_delta,
        max_evaluations=POWER_EVALUATIONS,
        landscape=False,
        certificate=False,
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
            f"--max-gain {max_gain:g} binds on {len(sol.binds)} node(s) from t = {sol.binds[0]:g}: "
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
    gap = _relative(sol.value, curves["optimal"].final)
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
    cert = certify_tuned(topology, spec, schedule, delta, notes) if certificate else None
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
    "MonteCarloCheck",
    "ScheduleTuneResult",
    "check_schedule_scenario",
    "tune_schedule",
]
