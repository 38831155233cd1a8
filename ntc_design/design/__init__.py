"""Assumption 2 and the Lemma 1 protocol design (Niu & Wu, Sec. 3), with the exact critical
couplings of the same design family (:mod:`ntc_design.thresholds`).

Modules: :mod:`.assumption` (Assumption 2, the C_i), :mod:`.lemma1` (the design, its
table and the critical couplings).
"""

from .assumption import (
    SUMMARY_ABOVE,
    AssumptionWarning,
    Decomposition,
    Violation,
    assumption2,
    lemma1_coefficient,
    structure_report,
    structure_summary,
    summary_table,
)
from .lemma1 import (
    ProtocolDesign,
    SwitchingDesign,
    design,
    design_table,
    design_topology,
)

__all__ = [
    "SUMMARY_ABOVE",
    "AssumptionWarning",
    "Decomposition",
    "ProtocolDesign",
    "SwitchingDesign",
    "Violation",
    "assumption2",
    "design",
    "design_table",
    "design_topology",
    "lemma1_coefficient",
    "structure_report",
    "structure_summary",
    "summary_table",
]
