"""Kind ``hurwitz``: one topology, −L_B Hurwitz by a Lyapunov P (P ≻ 0, P L_B + L_Bᵀ P ≻ 0),
with a decay rate α when the LMI found one (P ≻ 0, P L_B + L_Bᵀ P − 2αP ≻ 0, α > 0)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...design import ProtocolDesign
from ..certificate import (
    DENSE_CERT_MAX_ND,
    _eig_bound,
    _min_eig,
    _need,
    _number,
    hurwitz_certificate,
)
from ..claims import Claim, Property, derive_claims
from ..theorems import TheoremVerdict, fixed_verdicts
from .base import CertificateKind, Reading, ResultsAudit, Subject
from .dense import dense_method, prove_dense, read_dense


class HurwitzKind(CertificateKind):
    """One topology up to Nd = ``DENSE_CERT_MAX_ND``: dense P, exact re-check."""

    name = "hurwitz"
    description = "one topology: −L_B Hurwitz, with a decay rate when one is proven"
    properties = (Property.HURWITZ, Property.DECAY_RATE)
    required = frozenset({Property.HURWITZ})
    switching = False
    method = "exact-rational"

    def accepts(self, design: Any) -> bool:
        return isinstance(design, ProtocolDesign) and design.topology.nd <= DENSE_CERT_MAX_ND

    def issue(self, design: Any, **options: Any) -> dict:
        return hurwitz_certificate(design)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        return fixed_verdicts(design, verification, gain)

    def read(self, doc: dict, source: str) -> Reading:
        return read_dense(doc, source)

    def verification_method(self, reading: Reading) -> str:
        return dense_method(reading)

    def rate(self, doc: dict, source: str) -> float:
        res = _need(doc, "results", dict, source)
        lmi = _need(res, "lmi", dict, f"{source}: results")
        return _number(_need(lmi, "alpha", (int, float), f"{source}: results.lmi"), "α")

    def claims(
        self, properties, subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        return derive_claims(properties, subject.scheduled, alpha)

    def prove(self, claim: Claim, subject: Subject, reading: Reading):
        return prove_dense(claim, subject, reading)

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # eig_bound = min Re λ(L_B), the Lyapunov residual and λ_min(P) recomputed; the
        # LMI's α is the proven one, below the eigenvalue bound, and its gap recomputed.
        ctx = reading.state
        (mode,) = ctx.modes.values()
        scale = float(np.max(np.abs(mode.lap))) if mode.in_range else 1.0
        eig = _eig_bound(mode.lap)
        audit.recomputed(("eig_bound",), eig, scale)
        if audit.has("lyapunov"):
            p = ctx.p("lyapunov") if "lyapunov" in ctx.ps else None
            if p is None:
                audit.fail("lyapunov: reported, but matrices.P.lyapunov is missing or out of range")
            else:
                r = p @ mode.lap + mode.lap.T @ p - np.eye(ctx.n)
                resid = float(np.linalg.norm(r) / np.sqrt(ctx.n))
                audit.recomputed(("lyapunov", "residual"), resid, 1.0)
                audit.recomputed(("lyapunov", "P_min_eig"), _min_eig(p), float(np.max(np.abs(p))))
        rated = alpha != 0.0 or Property.DECAY_RATE.value in doc.get("certifies", [])
        if audit.has("lmi"):
            audit.recomputed(("lmi", "eig_bound"), eig, scale)
            audit.recomputed(("lmi", "gap"), eig - alpha, scale)
            if rated:
                audit.estimate(("lmi", "alpha"), None, eig, " (α cannot exceed min Re λ(L_B))")
            else:  # no rate certified: the issuer reports α = 0
                audit.exact(("lmi", "alpha"), 0.0)
            audit.informational(("lmi", "bisection_steps"), integer=True)
