"""Kind ``switching``: L_B(k) + L_B(k)ᵀ ≻ 0 in every scheduled mode (Theorems 3-4), and a
common Lyapunov P for every scheduled mode when one was found."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...design import SwitchingDesign
from ..certificate import DENSE_CERT_MAX_ND, _min_eig, switching_certificate
from ..claims import Claim, Property, derive_claims
from ..lyapunov import verified_margin
from ..theorems import TheoremVerdict, switching_verdicts
from .base import CertificateKind, Reading, ResultsAudit, Subject
from .dense import dense_method, prove_dense, read_dense


def switching_nd(design: SwitchingDesign) -> int:
    """N·d of a switching design's modes.

    Parameters
    ----------
    design : SwitchingDesign
        The design.

    Returns
    -------
    int
    """
    return design.switching.n * design.switching.dim


def weight_bound(design: SwitchingDesign) -> float:
    """max |entry| over every weight of every mode (Assumption 3's bound).

    Parameters
    ----------
    design : SwitchingDesign
        The design.

    Returns
    -------
    float
    """
    return max(
        (
            float(np.max(np.abs(a)))
            for top in design.switching.modes.values()
            for a in top.weights.values()
        ),
        default=0.0,
    )


class SwitchingKind(CertificateKind):
    """A switching set up to Nd = ``DENSE_CERT_MAX_ND``: dense matrices, exact re-check."""

    name = "switching"
    description = "a switching topology: every mode its schedule uses"
    properties = (Property.SYMMETRIC_PART, Property.COMMON_LYAPUNOV)
    required = frozenset({Property.SYMMETRIC_PART})
    switching = True
    method = "exact-rational"

    def accepts(self, design: Any) -> bool:
        return isinstance(design, SwitchingDesign) and switching_nd(design) <= DENSE_CERT_MAX_ND

    def issue(self, design: Any, **options: Any) -> dict:
        return switching_certificate(design)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        est = certificate["results"]["symmetric_part_min_eig"]
        return switching_verdicts(design, verification, gain, weight_bound(design), est)

    def read(self, doc: dict, source: str) -> Reading:
        return read_dense(doc, source)

    def verification_method(self, reading: Reading) -> str:
        return dense_method(reading)

    def claims(
        self, properties, subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        return derive_claims(properties, subject.scheduled, alpha)

    def prove(self, claim: Claim, subject: Subject, reading: Reading):
        return prove_dense(claim, subject, reading)

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # λ_min(L_B(k) + L_B(k)ᵀ) of every mode and the common P's verified margin
        # recomputed; the solver's run times are informational.
        ctx = reading.state
        for k, m in ctx.modes.items():
            s = m.lap + m.lap.T
            audit.recomputed(("symmetric_part_min_eig", k), _min_eig(s), float(np.max(np.abs(s))))
        got = audit.get("symmetric_part_min_eig")
        if not isinstance(got, dict):
            audit.fail("symmetric_part_min_eig: expected an object mode -> number")
        cl = audit.get("common_lyapunov")
        if isinstance(cl, dict):
            for i in range(
                len(cl.get("attempts", []) if isinstance(cl.get("attempts"), list) else [])
            ):
                audit.informational(("common_lyapunov", "attempts", i, "seconds"))
            if cl.get("margin") is not None:
                p = ctx.p("common") if "common" in ctx.ps else None
                if p is None:
                    audit.fail("common_lyapunov.margin: reported, but there is no common P")
                else:
                    used = [ctx.modes[k].lap for k in subject.scheduled if k in ctx.modes]
                    audit.recomputed(
                        ("common_lyapunov", "margin"), verified_margin(used, p, 0.0), 1.0
                    )
