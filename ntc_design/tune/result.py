"""The typed result of a tuning run, its table (every face renders it) and its JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..certify import CertifyResult
from ..gain.conditions import GainAnalysis
from ..present.rows import Table, fmt, verdict
from .evidence import proven_text
from .family import BASELINE, PowerGain
from .objective import Curve


@dataclass(frozen=True, eq=False)
class Landscape:
    """The objective over (a, γ) at the optimum's b (and δ): what the contour map shows.
    ``values[i, j]`` is at ``gamma[i]``, ``a[j]``; +∞ where a candidate was out of reach."""

    a: np.ndarray
    gamma: np.ndarray
    b: float
    values: np.ndarray


@dataclass(frozen=True, eq=False)
class TuneResult:
    """A tuned gain c(t) = a·(b + t)^(−γ) (and δ) for a scenario and horizon T.

    Attributes
    ----------
    tuned, baseline : PowerGain
        The optimum (rounded to the digits it is written with) and 1/(1 + t).
    delta : float or None
        The tuned common δ (``tune_delta``), else None (the scenario's δ).
    horizon : float
        T.
    require : str
        ``both`` or ``mean-square``.
    method : str
        How the objective was computed (exact moments, or Monte Carlo: statistical).
    statistical : bool
        Monte Carlo: the optimum and the numbers carry sampling error (bands).
    curves : dict of str to Curve
        ``tuned`` and ``baseline``: E Σ‖x_i − θ‖² over [0, T] (RK4 κ = 0.2 for exact).
    eps : float or None
        The tolerance ε of ``time_to_eps``.
    gain_analysis : GainAnalysis
        The theorem conditions of the tuned gain.
    certificate : CertifyResult or None
        The certificate of the tuned design (None when none could be issued; see notes).
    evaluations : int
        Objective evaluations of the search.
    seconds : float
        Wall time of the search and the final curves.
    landscape : Landscape or None
        The objective over (a, γ) for the contour map.
    notes : tuple of str
        What the run says besides its numbers.
    stepping : dict of str to str
        Scenario keys the written scenario needs for a stable Monte Carlo check (empty:
        the scenario's own stepping is stable under the tuned gain).
    stage_seconds : dict of str to float
        Wall time of each stage: ``search`` (the evaluations), then ``final curves``,
        ``step check``, ``landscape`` (when drawn), ``theorems and certificate``.
    """

    tuned: PowerGain
    baseline: PowerGain
    delta: float | None
    horizon: float
    require: str
    method: str
    statistical: bool
    curves: dict[str, Curve]
    eps: float | None
    gain_analysis: GainAnalysis
    certificate: CertifyResult | None
    evaluations: int
    seconds: float
    landscape: Landscape | None = None
    notes: tuple[str, ...] = field(default=())
    stepping: dict[str, str] = field(default_factory=dict)
    stage_seconds: dict[str, float] = field(default_factory=dict)

    @property
    def ms_error_T(self) -> dict[str, float]:  # noqa: N802 - T is the paper's horizon
        """E Σ‖x_i(T) − θ‖² of the tuned and the baseline gain."""
        return {k: c.final for k, c in self.curves.items()}

    @property
    def gains(self) -> dict[str, PowerGain]:
        """The two gains, by key."""
        return {"tuned": self.tuned, "baseline": self.baseline}

    @property
    def headline(self) -> tuple[float, str]:
        """E Σ‖x_i(T) − θ‖² of the tuned gain and how it was computed (the written
        scenario's description)."""
        return self.ms_error_T["tuned"], self.method

    def scenario_gain(self) -> str:
        """The written scenario's ``gain``: the tuned expression.

        Returns
        -------
        str
        """
        return self.tuned.text

    @property
    def ms_error_peak(self) -> dict[str, dict[str, float]]:
        """sup_t E Σ‖x_i(t) − θ‖² on [0, T] of the tuned and the baseline gain, and where
        (``{value, t}`` each, over the curves' save times)."""
        return {k: c.peak for k, c in self.curves.items()}

    @property
    def time_to_eps(self) -> dict[str, float | None]:
        """The first time each gain's curve reaches ε (None: not by T, or no ε)."""
        if self.eps is None:
            return {k: None for k in self.curves}
        return {k: c.first_below(self.eps) for k, c in self.curves.items()}

    @property
    def required_holds(self) -> bool | None:
        """Whether the tuned gain satisfies the theorems required (``ntc gain``'s verdict)."""
        g = self.gain_analysis
        return g.mean_square if self.require == "mean-square" else g.almost_sure

    @property
    def certified(self) -> bool:
        """The tuned design's certificate verifies and a required theorem is guaranteed."""
        c = self.certificate
        return bool(c is not None and c.verification.valid and self.required_holds)

    def _band(self, key: str) -> str:
        c = self.curves[key]
        if c.lo is None or c.hi is None:
            return ""
        return f" (95 % band {fmt(float(c.lo[-1]))} to {fmt(float(c.hi[-1]))})"

    def table(self) -> Table:
        """The tuned gain beside the baseline: the table every face shows.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        t, b, ms, te = self.tuned, self.baseline, self.ms_error_T, self.time_to_eps
        rows: list[tuple[Any, ...]] = [
            ("gain c(t)", t.text, b.text),
            ("a", t.a, b.a),
            ("b", t.b, b.b),
            ("γ", t.gamma, b.gamma),
        ]
        if self.delta is not None:
            rows.append(("δ (tuned)", self.delta, "scenario's"))
        rows.append(
            (
                f"E Σ‖x_i(T) − θ‖², T = {fmt(self.horizon)}",
                fmt(ms["tuned"]) + self._band("tuned") + proven_text(self.certificate),
                fmt(ms["baseline"]) + self._band("baseline"),
            )
        )
        pk = self.ms_error_peak
        rows.append(
            (
                "peak sup_t E Σ‖x_i(t) − θ‖² (at t)",
                *(f"{fmt(pk[k]['value'])} (t = {fmt(pk[k]['t'])})" for k in ("tuned", "baseline")),
            )
        )
        if self.eps is not None:
            rows.append((f"first time ≤ ε = {fmt(self.eps)}", te["tuned"], te["baseline"]))
        req = "mean square" if self.require == "mean-square" else "mean square and almost sure"
        rows.append(("theorems required: " + req, verdict(self.required_holds), ""))
        cert = self.certificate
        rows.append(
            (
                "certificate of the tuned design",
                verdict(cert.verification.valid if cert is not None else None),
                "",
            )
        )
        notes = (f"objective: {self.method}; {self.time_note()}", *self.notes)
        return Table.build(
            f"gain tuned for T = {fmt(self.horizon)}: a·(b + t)^(−γ)",
            ("", "tuned", "baseline"),
            rows,
            notes,
        )

    def time_note(self) -> str:
        """Where the time went: the evaluations of the search, then each later stage.

        Returns
        -------
        str
            E.g. ``158 evaluations in 30.2 s; then 3.1 s: final curves 0.3 s, step check
            0.1 s, theorems and certificate 2.7 s``.
        """
        st = dict(self.stage_seconds)
        search = st.pop("search", None)
        if search is None:  # no stage timings (a result built by hand)
            return f"{self.evaluations} evaluations in {self.seconds:.1f} s"
        rest = ", ".join(f"{k} {v:.1f} s" for k, v in st.items())
        after = max(self.seconds - search, 0.0)
        return f"{self.evaluations} evaluations in {search:.1f} s; then {after:.1f} s: {rest}"

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        ms = self.ms_error_T
        return (
            f"TuneResult(c(t) = {self.tuned.text}, E Σ‖x_i(T) − θ‖² = {fmt(ms['tuned'])} "
            f"(baseline {fmt(ms['baseline'])}), T = {fmt(self.horizon)})"
        )

    def to_dict(self) -> dict[str, Any]:
        """The result as a JSON-ready mapping (what ``ntc tune`` prints as JSON).

        Returns
        -------
        dict
            ``gain`` (text), ``a``, ``b``, ``gamma``, ``delta``, ``horizon``, ``require``,
            ``method``, ``statistical``, ``ms_error_T``, ``ms_error_peak`` (``{value, t}``)
            and ``time_to_eps`` (``tuned``, ``baseline``), ``eps``, ``theorems`` (the tuned gain's analysis),
            ``certificate_valid``, ``evaluations``, ``seconds``, ``stage_seconds``, ``notes``.
        """
        bands = {
            k: [float(c.lo[-1]), float(c.hi[-1])]
            for k, c in self.curves.items()
            if c.lo is not None and c.hi is not None
        }
        out: dict[str, Any] = {
            "gain": self.tuned.text,
            "a": self.tuned.a,
            "b": self.tuned.b,
            "gamma": self.tuned.gamma,
            "delta": self.delta,
            "baseline_gain": BASELINE.text,
            "horizon": self.horizon,
            "require": self.require,
            "method": self.method,
            "statistical": self.statistical,
            "ms_error_T": self.ms_error_T,
            "ms_error_peak": self.ms_error_peak,
            "eps": self.eps,
            "time_to_eps": self.time_to_eps,
            "theorems": self.gain_analysis.to_dict(),
            "required_holds": self.required_holds,
            "certificate_valid": (
                self.certificate.verification.valid if self.certificate is not None else None
            ),
            "evaluations": self.evaluations,
            "seconds": self.seconds,
            "stage_seconds": dict(self.stage_seconds),
            "notes": list(self.notes),
            "stepping": dict(self.stepping),
        }
        if bands:
            out["ms_error_T_band"] = bands
        return out
