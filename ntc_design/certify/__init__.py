"""Certificates layer: Lyapunov equations, LMIs, exact re-check, gain conditions and the
theorem verdict."""

from ..gain import GainAnalysis, analyse_gain
from .certificate import (
    DIGEST_NOTE,
    About,
    Check,
    Verification,
    hurwitz_certificate,
    switching_certificate,
    topology_hash,
    verify,
    verify_file,
    write_certificate,
)
from .claims import KINDS, Claim, ClaimKind, KindSpec, Property
from .result import CertifyResult, certify
from .scale import scale_certificate, verify_scale
from .theorems import Premise, TheoremVerdict

__all__ = [
    "scale_certificate",
    "verify_scale",
    "DIGEST_NOTE",
    "GainAnalysis",
    "analyse_gain",
    "KINDS",
    "About",
    "CertifyResult",
    "Check",
    "Claim",
    "ClaimKind",
    "KindSpec",
    "Premise",
    "Property",
    "TheoremVerdict",
    "Verification",
    "certify",
    "hurwitz_certificate",
    "switching_certificate",
    "topology_hash",
    "verify",
    "verify_file",
    "write_certificate",
]
