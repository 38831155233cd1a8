"""The signed matrix-weighted network model (Niu & Wu, Sec. 2).

Conventions: ``A_ij`` is the d×d symmetric weight of the directed edge from agent j to
agent i (i listens to j). Agents are indexed 0..N-1 internally and shown by their labels.
The algorithms are plain functions over a :class:`Topology`, each stating the definition
it implements.

Modules: :mod:`.topology` (:class:`Topology`), :mod:`.graph` (graph functions over it; the signed Laplacian is with the class),
:mod:`.switching` (:class:`SwitchingTopology`, :class:`TimeVaryingTopology`).
"""

from .graph import (
    antagonistic_in_weight,
    in_degree_dominated,
    in_degree_dominated_all,
    in_out_difference,
    positive_negative_reachable,
)
from .switching import ExpressionFamily, SwitchingTopology, TimeVaryingTopology
from .topology import (
    EdgeArrays,
    Label,
    Topology,
    block_coo,
    signed_laplacian,
    signed_laplacian_sparse,
)

__all__ = [
    "ExpressionFamily",
    "EdgeArrays",
    "Label",
    "SwitchingTopology",
    "TimeVaryingTopology",
    "Topology",
    "antagonistic_in_weight",
    "block_coo",
    "in_degree_dominated",
    "in_degree_dominated_all",
    "in_out_difference",
    "positive_negative_reachable",
    "signed_laplacian",
    "signed_laplacian_sparse",
]
