"""Certificate kinds: a base class, one module per kind, and the registry."""

from .base import (
    CertificateKind,
    IssueOptions,
    ModeReading,
    Reading,
    ResultRow,
    ResultsAudit,
    Subject,
)
from .registry import KINDS, kind_for

__all__ = [
    "KINDS",
    "CertificateKind",
    "IssueOptions",
    "ModeReading",
    "Reading",
    "ResultRow",
    "ResultsAudit",
    "Subject",
    "kind_for",
]
