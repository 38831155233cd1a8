"""``certify``: design (Lemma 1), certify, re-verify and give the theorem verdict."""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..choices import RateMethod
from ..errors import InputError
from ..gain.conditions import GainAnalysis
from ..gain.schedule import ScheduleGain, analyse_any_gain
from ..model import SwitchingTopology, Topology
from ..model.paper import F_SCALE, SIGMA
from ..model.timevarying import ExpressionTopology
from ..numerics.linalg import RANGE_TEXT, out_of_range
from ..present.rows import Table
from ..protocol import ProtocolDesign, SwitchingDesign, design
from ..protocol.agents import require_sampled
from ..protocol.digital import Digital, DigitalDesign
from ..protocol.timevarying import TimeVaryingDesign
from .checks import Check, Verification
from .deadline_subject import deadline_text
from .dense import DENSE_CERT_MAX_ND
from .format import digest
from .kinds import KINDS, IssueOptions, ResultRow, kind_for
from .robust import (
    DEFAULT_RADIUS,
    RobustDesign,
    RobustReport,
    check_radius,
    check_robust_work,
    robust,
)
from .theorems import GUARANTEE_WORD, TheoremVerdict, assumption_notes, theorem_table
from .verify import verify


@dataclass(frozen=True)
class CertifyResult:
    """A design, its certificate and verification, the gain analysis and the verdicts."""

    design: ProtocolDesign | SwitchingDesign | TimeVaryingDesign
    certificate: dict
    verification: Verification
    gain: GainAnalysis | None
    theorems: tuple[TheoremVerdict, ...]

    @property
    def proven(self) -> bool:
        """What ``ntc certify`` exits 0 on: a theorem is guaranteed, or no gain was given
        and the certificate is valid (the theorems then wait only for a gain)."""
        theorems = [t for t in self.theorems if t.sampled] or list(self.theorems)
        if any(t.guaranteed is True for t in theorems):  # the sampled ones when asked for
            return True
        return self.gain is None and self.verification.valid

    @property
    def rows(self) -> tuple[ResultRow, ...]:
        """What the certificate reports, as rows (the same on every face)."""
        results = self.certificate["results"]
        line = deadline_text(results)  # the figures at the deadline, when stated
        extra = (ResultRow("proven at the deadline", line),) if line is not None else ()
        return (*KINDS[self.certificate["kind"]].rows(results), *extra)

    def results_table(self) -> Table:
        """What the certificate reports (its kind's rows), as every face shows it.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows = [
            (row.label + (" (estimate)" if row.estimate else ""), row.value) for row in self.rows
        ]
        kind = self.certificate["kind"]
        title = (
            f"certificate ({kind})"
            if self.verification.valid
            else f"attempted certificate ({kind}): not valid, nothing below is proven"
        )
        return Table.build(title, ("property", "result"), rows, layout="list")

    def tables(self, gain: bool = True) -> tuple[Table, ...]:
        """Everything the result shows: the certificate's checks and results, the gain
        conditions (when a gain was given) and the theorem verdicts.

        Parameters
        ----------
        gain : bool, optional
            Include the gain conditions (False for a page that shows them in a section of
            their own, as the tune report).

        Returns
        -------
        tuple of ntc_design.present.rows.Table
        """
        conditions = (self.gain.table(),) if gain and self.gain is not None else ()
        return (
            self.verification.table(),
            self.results_table(),
            *conditions,
            self.theorems_table(),
        )

    def theorems_table(self) -> Table:
        """The theorem verdicts, with Assumption 2's violations and their fixes said once
        below them (not in every theorem that names the premise).

        Returns
        -------
        ntc_design.present.rows.Table
        """
        return theorem_table(self.theorems, assumption_notes(self.design))

    def _repr_html_(self) -> str:
        return "".join(t.html() for t in (self.design.table(), *self.tables()))

    def __repr__(self) -> str:
        ver = "valid" if self.verification.valid else "INVALID"
        verdicts = ", ".join(
            f"Theorem {t.theorem}: {GUARANTEE_WORD[t.guaranteed]}" for t in self.theorems
        )
        return f"CertifyResult({self.certificate['kind']}, {ver}; {verdicts or 'no gain given'})"

    def to_dict(self) -> dict:
        """The result as a JSON-ready mapping (what ``ntc certify`` prints as JSON).

        Returns
        -------
        dict
            The design, the certificate's kind, subject, digest, checks, results and rows, the
            gain analysis, the theorem verdicts and ``proven``.
        """
        ver = self.verification
        return {
            "design": self.design.to_dict(),
            "certificate": {
                "kind": self.certificate["kind"],
                "certifies": self.certificate["certifies"],
                "digest": self.certificate["digest"],
                "valid": ver.valid,
                "method": ver.method,
                "checks": [c.to_dict() for c in ver.checks],
                "results": self.certificate["results"],
                "rows": [row.to_dict() for row in self.rows],
            },
            "gain": self.gain.to_dict() if self.gain is not None else None,
            "theorems": [t.to_dict() for t in self.theorems],
            "proven": self.proven,
        }


def _verify_own(cert: dict) -> Verification:
    """Verify a certificate just issued; numbers that make no checkable certificate (a
    Lyapunov equation without a finite solution) make it invalid, not bad input."""
    try:
        return verify(cert)
    except InputError as exc:
        return Verification(False, "none", (Check("certificate well-formed", False, str(exc)),))


def with_schedule(cert: dict, gain: ScheduleGain) -> dict:
    """The certificate with the gain schedule in its ``gain`` field, digest re-sealed.

    Parameters
    ----------
    cert : dict
        A certificate of a fixed or switching kind.
    gain : ScheduleGain
        The schedule.

    Returns
    -------
    dict
    """
    out = dict(cert)
    out["gain"] = gain.to_document()
    out["digest"] = digest(out)
    return out


def certify(
    topology: Topology | SwitchingTopology | ExpressionTopology,
    theta,
    margin: float = 0.1,
    gain: str | ScheduleGain | None = None,
    delta: float | None = None,
    noise_sigma: float = SIGMA,
    noise_f=F_SCALE,
    rate_method: RateMethod = "lyapunov",
    digital: Digital | None = None,
    sigma_edges: Mapping | None = None,
) -> CertifyResult:
    """Design (Lemma 1), certify (Lyapunov + LMI, or per-mode L_B + L_Bᵀ ≻ 0 and a common
    P), re-verify the certificate exactly, analyse the gain and give the theorem verdict.
    Above Nd = ``DENSE_CERT_MAX_ND`` no step is dense: component by component for one
    topology (:mod:`.scale`), a sparse Cholesky per mode for a switching set
    (:mod:`.switching_scale`).

    Parameters
    ----------
    topology : Topology or SwitchingTopology or ExpressionTopology
        The network: fixed, switching, or with weights that are expressions of t.
    theta : sequence of float
        The target consensus state θ ≠ 0.
    margin : float
        ΔC > 0: δ = C + ΔC.
    gain : str or ScheduleGain, optional
        c(t), e.g. ``"1/(1+t)"``, or a tabulated schedule with an analytic tail (stored
        in the certificate's ``gain`` field, re-checked by ``verify``).
    delta : float, optional
        An explicit δ instead of C + ΔC.
    noise_sigma, noise_f : float
        σ_ji and f(x) = f·x (f may be a d×d matrix for the digital certificate): the
        time-varying certificate (p̄, σ̄, t₀) and the digital one (γ, N) use them.
    rate_method : {"lyapunov", "lmi"}
        How one topology's decay rate is found: the shifted Lyapunov equation (no SDP
        solver) or the LMI bisection (Clarabel). The certificate is checked the same way.
    digital : Digital, optional
        Certify the sampled protocol too (period h, delay D: kinds ``digital`` and
        ``digital_switching``); needs ``gain``.
    sigma_edges : mapping of (str, str) to float, optional
        Per-edge σ by (from, to) labels (the digital certificate).

    Returns
    -------
    CertifyResult
        ``verification.valid`` says whether the certificate proves what its kind says;
        ``proven`` whether a theorem is guaranteed.

    Raises
    ------
    InputError
        For a bad θ, margin, δ or gain.

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.certify import certify
    >>> certify(nd.load("examples/g1.yaml"), [1, 2, -1], gain="1/(1+t)")
    CertifyResult(hurwitz, valid; Theorem 1: guaranteed, Theorem 2: guaranteed)
    """
    g = analyse_any_gain(gain) if gain is not None else None
    if isinstance(topology, ExpressionTopology):
        if isinstance(gain, ScheduleGain):
            raise InputError(
                "a schedule with a topology given as expressions of t: the time-varying "
                "certificate needs c(t) as one expression (its t₀ of μ₂ is symbolic)",
                field="gain",
            )
        if delta is not None:
            raise InputError(
                "a time-varying topology uses δ(t) = C(t) + ΔC (Lemma 1)", field="delta"
            )
        des: Any = TimeVaryingDesign(topology, np.asarray(theta, dtype=float), margin)
    else:
        big = topology.n * topology.dim > DENSE_CERT_MAX_ND
        # at scale the critical couplings are not needed by the certificate (design notes it)
        des = design(topology, theta, margin, delta, thresholds=False if big else None)
    if digital is not None:
        des = _digital_design(topology, des, digital, gain, noise_sigma, noise_f, sigma_edges)
    kind = kind_for(des)
    options = IssueOptions(
        gain=g, noise_sigma=noise_sigma, noise_f=noise_f, rate_method=rate_method
    )
    cert = kind.issue(des, options)
    if isinstance(gain, ScheduleGain):
        cert = with_schedule(cert, gain)
    ver = _verify_own(cert)
    return CertifyResult(des, cert, ver, g, kind.verdicts(des, cert, ver, g))


def _digital_design(
    topology: object, des: Any, digital: Digital, gain, sigma, f, sigma_edges
) -> DigitalDesign:
    """The design wrapped for a digital kind, or one line saying why it cannot be."""
    if gain is None:
        raise InputError("the digital certificate needs the gain c(t)", field="gain", option=True)
    require_sampled(topology, "digital", option=True)
    # a value no certificate can state (the subnormal 5e-324) is refused before any work
    for name, value in (
        ("noise_sigma", sigma),
        ("noise_f", f),
        *(("sigma_edges", v) for v in (sigma_edges or {}).values()),
    ):
        if not callable(value) and out_of_range(np.asarray(value, dtype=float)):
            option = name != "sigma_edges"
            raise InputError(f"{value!r} has {RANGE_TEXT}"[:180], field=name, option=option)
    out = DigitalDesign(des, digital, gain, float(sigma), f, dict(sigma_edges or {}))
    if not any(k.accepts(out) for k in KINDS.values()):
        nd_ = (
            next(iter(des.modes.values())).topology.nd
            if isinstance(des, SwitchingDesign)
            else des.topology.nd
        )
        raise InputError(
            f"the digital certificate needs a dense Lyapunov matrix: N·d <= "
            f"{DENSE_CERT_MAX_ND}, this network has N·d = {nd_}",
            field="digital",
            option=True,
        )
    return out


@dataclass(frozen=True)
class RobustResult:
    """The brackets of :func:`certify_robust` with their certificate, issued through the
    registry like every kind, and its verification; both None where no certificate is
    issued (past the dense proofs' reach, or no margin radius proven: the sparse bounds
    are then proven in this process only).

    Parameters
    ----------
    report : RobustReport
        The three brackets.
    certificate : dict or None
        The ``robust`` certificate.
    verification : Verification or None
        Its verification (exact or verified-float arithmetic).
    """

    report: RobustReport
    certificate: dict | None
    verification: Verification | None

    @property
    def valid(self) -> bool:
        """The certificate verifies; without one, whether a margin radius is proven."""
        if self.verification is not None:
            return self.verification.valid
        return self.report.margin.lower is not None


def certify_robust(
    topology: Topology | SwitchingTopology | ExpressionTopology,
    theta,
    radius: float = DEFAULT_RADIUS,
    margin: float = 0.1,
    starts: int = 6,
    seed: int = 0,
) -> RobustResult:
    """Design (Lemma 1), bracket the decay, offset and margin when every weight is known
    only within its relative radius (:func:`ntc_design.certify.robust.robust`), issue the
    ``robust`` certificate through the registry and re-verify it, as :func:`certify` does
    for the nominal kinds.

    Parameters
    ----------
    topology : Topology
        One fixed topology (its ``uncertainty:`` radii per edge, where given); another kind
        is refused.
    theta : sequence of float
        The target consensus state θ ≠ 0.
    radius : float, optional
        ρ in [0, 1) for every edge without a radius of its own.
    margin : float, optional
        ΔC > 0: δ = C + ΔC.
    starts, seed : int, optional
        The realisation searches' random starts and their seed.

    Returns
    -------
    RobustResult

    Raises
    ------
    InputError
        A bad θ, radius or margin (named as the field: ``radius: ...``), a topology that is
        not one fixed network, or work estimated past an hour.

    Examples
    --------
    >>> import ntc_design as nd
    >>> res = certify_robust(nd.load("examples/g1.yaml"), [1, 2, -1], radius=0.02, starts=1)
    >>> res.valid, res.certificate["kind"]
    (True, 'robust')
    """
    rho = check_radius(radius, "radius")
    if not isinstance(topology, Topology):
        raise InputError(
            "robust needs one fixed topology (not a switching or time-varying one)",
            field="topology",
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the certificate says whether Assumption 2 holds
        des = design(topology, theta, margin, thresholds=False)
    assert isinstance(des, ProtocolDesign)  # a fixed topology's design
    check_robust_work(des)  # the estimate, before the work (a warning line past a minute)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solver chatter; the verification decides
        rd = RobustDesign(robust(des, rho, starts=starts, seed=seed))
        try:
            kind = kind_for(rd)
        except TypeError:  # no kind issues it (past the dense size, or no margin proven)
            return RobustResult(rd.report, None, None)
        cert = kind.issue(rd)
        ver = verify(json.loads(json.dumps(cert)), "the robust certificate")
    return RobustResult(rd.report, cert, ver)


__all__ = [
    "CertifyResult",
    "RobustResult",
    "certify",
    "certify_robust",
]
