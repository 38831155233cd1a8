"""Certificates layer: Lyapunov equations, LMIs, exact re-check, gain conditions and the
theorem verdict."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..design import ProtocolDesign, SwitchingDesign, design
from ..errors import InputError
from ..gain import GainAnalysis, analyse_gain
from ..model import SwitchingTopology, Topology
from ..timevarying import ExpressionTopology, TimeVaryingDesign
from .certificate import (
    Verification,
    hurwitz_certificate,
    switching_certificate,
    verify,
    verify_file,
    write_certificate,
)
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
    topology: Topology | SwitchingTopology | ExpressionTopology,
    theta,
    margin: float = 0.1,
    gain: str | None = None,
    delta: float | None = None,
    noise_sigma: float = 0.4,
    noise_f=0.3,
) -> CertifyResult:
    """Design (Lemma 1), certify (Lyapunov + LMI, or per-mode L_B + L_Bᵀ ≻ 0 and a common
    P, or for weights given as expressions of t the uniform bound Λ₂ of Theorems 3-4 by
    branch and bound), re-verify the certificate, analyse the gain and give the theorem
    verdict. ``noise_sigma`` and ``noise_f`` (σ_ji and f(x) = f·x) enter only the
    time-varying certificate's p̄, σ̄ and t₀."""
    g = analyse_gain(gain) if gain is not None else None
    if isinstance(topology, ExpressionTopology):
        from .time_varying import (
            time_varying_certificate,
            time_varying_verdicts,
            verify_time_varying,
        )

        if delta is not None:
            raise InputError("delta: a time-varying topology uses δ(t) = C(t) + ΔC (Lemma 1)")
        tdes = TimeVaryingDesign(topology, np.asarray(theta, dtype=float), margin)
        cert = time_varying_certificate(topology, theta, margin, gain, noise_sigma, noise_f)
        ver = verify_time_varying(cert)
        th = time_varying_verdicts(cert["results"]["time_varying"], ver, g)
        return CertifyResult(tdes, cert, ver, g, th)
    des = design(topology, theta, margin, delta)
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
    else:
        cert = hurwitz_certificate(des)
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
    "switching_certificate",
    "verify",
    "verify_file",
    "write_certificate",
]
