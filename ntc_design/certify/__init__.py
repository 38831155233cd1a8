"""Certificates layer: Lyapunov equations, LMIs, exact re-check, gain conditions and the
theorem verdict."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..design import ProtocolDesign, SwitchingDesign, design
from ..gain import GainAnalysis, analyse_gain
from ..model import SwitchingTopology, Topology
from .certificate import (
    DENSE_CERT_MAX_ND,
    Verification,
    hurwitz_certificate,
    switching_certificate,
    verify,
    verify_file,
    write_certificate,
)
from .scale import scale_certificate, verify_scale
from .theorems import fixed_verdicts, switching_verdicts


@dataclass(frozen=True)
class CertifyResult:
    design: ProtocolDesign | SwitchingDesign
    certificate: dict
    verification: Verification
    gain: GainAnalysis | None
    theorems: list[dict]

    def to_dict(self) -> dict:
        ver = self.verification
        return {
            "design": self.design.to_dict(),
            "certificate": {
                "kind": self.certificate["kind"],
                "digest": self.certificate["digest"],
                "valid": ver.valid,
                "method": ver.method,
                "checks": [{"name": c.name, "ok": c.ok, "detail": c.detail} for c in ver.checks],
                "results": self.certificate["results"],
            },
            "gain": self.gain.to_dict() if self.gain is not None else None,
            "theorems": self.theorems,
        }


def certify(
    topology: Topology | SwitchingTopology,
    theta,
    margin: float = 0.1,
    gain: str | None = None,
    delta: float | None = None,
) -> CertifyResult:
    """Design (Lemma 1), certify (Lyapunov + LMI up to Nd = DENSE_CERT_MAX_ND, the
    component-wise certificate of :mod:`.scale` above it, or per-mode L_B + L_Bᵀ ≻ 0 and
    a common P), re-verify the certificate, analyse the gain and give the theorem
    verdict."""
    g = analyse_gain(gain) if gain is not None else None
    big = isinstance(topology, Topology) and topology.nd > DENSE_CERT_MAX_ND
    # at scale the critical couplings are not needed by the certificate (design notes it)
    des = design(topology, theta, margin, delta, thresholds=False if big else None)
    if isinstance(des, SwitchingDesign):
        cert = switching_certificate(des)
        ver = verify(cert)
        bound = max(
            float(np.max(np.abs(a)))
            for top in des.switching.modes.values()
            for a in top.weights.values()
        )
        th = switching_verdicts(
            des.to_dict(), ver, g, bound, cert["results"]["symmetric_part_min_eig"]
        )
    elif des.topology.nd <= DENSE_CERT_MAX_ND:
        cert = hurwitz_certificate(des)
        ver = verify(cert)
        th = fixed_verdicts(des.to_dict(), ver, g)
    else:
        # big networks: component-wise certificate, no dense step (issue 9)
        cert = scale_certificate(des)
        ver = verify(cert)
        th = fixed_verdicts(des.to_dict(), ver, g)
    return CertifyResult(des, cert, ver, g, th)


__all__ = [
    "CertifyResult",
    "GainAnalysis",
    "Verification",
    "analyse_gain",
    "certify",
    "hurwitz_certificate",
    "scale_certificate",
    "switching_certificate",
    "verify",
    "verify_file",
    "verify_scale",
    "write_certificate",
]
