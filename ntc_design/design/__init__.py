"""Assumption 2 and the Lemma 1 protocol design (Niu & Wu, Sec. 3), with the exact critical
couplings of the same design family (:mod:`ntc_design.thresholds`).

Modules: :mod:`.assumption` (Assumption 2, the C_i), :mod:`.lemma1` (the design, its
table and the critical couplings).
"""

from .assumption import (
    AssumptionWarning,
    Decomposition,
    Violation,
    assumption2,
    lemma1_coefficient,
    lemma1_coefficients,
    structure_report,
)
from .lemma1 import (
    DENSE_DESIGN_MAX_ND,
    DESIGN_KEYS,
    THRESHOLDS_DEFAULT_MAX_ND,
    THRESHOLDS_MAX_ND,
    ProtocolDesign,
    SwitchingDesign,
    coupling_matrix,
    coupling_matrix_sparse,
    design,
    design_table,
    design_topology,
    identity_residual,
    input_vector,
)

__all__ = [
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
]
