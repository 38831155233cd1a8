"""What :func:`ntc_design.tune.deadline.tune_schedule` returns: the optimal schedule, its
baseline and its independent Monte Carlo check, as every face shows them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..errors import Option
from ..gain.conditions import GainAnalysis
from ..gain.schedule import ScheduleGain
from ..present.rows import Table, fmt, verdict
from .evidence import proven_text
from .family import PowerGain
from .objective import AnyGain, Curve
from .optimal import ScheduleSolution

#: Relative gap between the optimiser's value and the independent re-evaluation above
#: which the result says so.
AGREE_RTOL = 1e-3


def relative_gap(value: float, reference: float) -> float:
    """|value − reference| / |reference|, 0 when both are 0 (an error of 0 is reached)."""
    diff = abs(value - reference)
    return 0.0 if diff == 0 else diff / max(abs(reference), 1e-300)


def ratio_text(value: float, reference: float) -> str:
    """value / reference for the table, "—" when the reference is 0."""
    return fmt(value / reference) if reference else "—"


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
                fmt(ms["optimal"]) + proven_text(self.certificate),
                *(fmt(ms[k]) for k in keys[1:]),
            ),
            (
                "ratio to the schedule",
                "1",
                *(ratio_text(ms[k], ms["optimal"]) for k in keys[1:]),
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
                str(Option("max_gain", fmt(sol.max_gain), quoted=False)),
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
            peak = Option("max_peak", fmt(self.max_peak), quoted=False)
            rows.append((str(peak), verdict(ok), "", ""))
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
            change = "" if prev is None else f"{relative_gap(lv.value, prev):.2e}"
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
        """The result as a JSON-ready mapping (what ``ntc tune`` prints as JSON).

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


__all__ = ["AGREE_RTOL", "MonteCarloCheck", "ScheduleTuneResult", "ratio_text", "relative_gap"]
