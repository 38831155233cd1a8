"""Assumption 2 and the Lemma 1 protocol design (Niu & Wu, Sec. 3), with the exact critical
couplings of the same design family (:mod:`ntc_design.protocol.thresholds`).

Modules: :mod:`.assumption` (Assumption 2, the C_i), :mod:`.lemma1` (the design, its
table and the critical couplings).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

# loaded on first use (PEP 562): `ntc check` needs Assumption 2, not Lemma 1's thresholds
_EXPORTS = {
    "SUMMARY_ABOVE": "assumption",
    "AssumptionWarning": "assumption",
    "Decomposition": "assumption",
    "Violation": "assumption",
    "assumption2": "assumption",
    "lemma1_coefficient": "assumption",
    "structure_report": "assumption",
    "structure_summary": "assumption",
    "structure_tables": "assumption",
    "summary_table": "assumption",
    "violation_fixes": "assumption",
    "fix_notes": "assumption",
    "ProtocolDesign": "lemma1",
    "SwitchingDesign": "lemma1",
    "design": "lemma1",
    "design_table": "lemma1",
    "design_topology": "lemma1",
    "lemma1_c": "lemma1",
    "lemma1_delta": "lemma1",
}

if TYPE_CHECKING:
    from .assumption import (
        SUMMARY_ABOVE,
        AssumptionWarning,
        Decomposition,
        Violation,
        assumption2,
        fix_notes,
        lemma1_coefficient,
        structure_report,
        structure_summary,
        structure_tables,
        summary_table,
        violation_fixes,
    )
    from .lemma1 import (
        ProtocolDesign,
        SwitchingDesign,
        design,
        design_table,
        design_topology,
        lemma1_c,
        lemma1_delta,
    )

__all__ = [
    "AssumptionWarning",
    "Decomposition",
    "ProtocolDesign",
    "SUMMARY_ABOVE",
    "SwitchingDesign",
    "Violation",
    "assumption2",
    "design",
    "design_table",
    "design_topology",
    "fix_notes",
    "lemma1_c",
    "lemma1_coefficient",
    "lemma1_delta",
    "structure_report",
    "structure_summary",
    "structure_tables",
    "summary_table",
    "violation_fixes",
]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'ntc_design.protocol' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
