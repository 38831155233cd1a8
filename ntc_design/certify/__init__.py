"""Certificates layer: Lyapunov equations, LMIs, exact re-check, gain conditions and the
theorem verdict. Certificate kinds live in :mod:`ntc_design.certify.kinds` (a base class,
one module per kind, and the registry :data:`KINDS`); :func:`verify` re-checks any kind
through one path."""

from ..gain.conditions import GainAnalysis, analyse_gain
from .checks import About, Check, Verification
from .claims import Claim, ClaimKind, Property
from .format import DIGEST_NOTE, topology_hash, write_certificate
from .kinds import KINDS, CertificateKind, kind_for
from .kinds.hurwitz import hurwitz_certificate
from .kinds.hurwitz_scale import scale_certificate
from .kinds.switching import switching_certificate
from .result import CertifyResult, RobustResult, certify, certify_robust
from .theorems import Premise, TheoremVerdict
from .verify import verify, verify_file

__all__ = [
    "DIGEST_NOTE",
    "KINDS",
    "About",
    "CertificateKind",
    "CertifyResult",
    "RobustResult",
    "Check",
    "Claim",
    "ClaimKind",
    "GainAnalysis",
    "Premise",
    "Property",
    "TheoremVerdict",
    "Verification",
    "analyse_gain",
    "certify",
    "certify_robust",
    "hurwitz_certificate",
    "kind_for",
    "scale_certificate",
    "switching_certificate",
    "topology_hash",
    "verify",
    "verify_file",
    "write_certificate",
]
