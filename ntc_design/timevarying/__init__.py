"""Continuously time-varying topologies: weights A_ij(t) written as expressions of t, and the
Lemma 1 protocol evaluated at every instant (Niu & Wu, Lemma 1 and Sec. 4.2).

:class:`ExpressionTopology` holds the weights as parsed expressions
(:mod:`ntc_design.tvfiles`), compiled once to vectorised NumPy functions. Construction
*proves* that every weight keeps one sign class (PD, PSD, ND, NSD; for a semidefinite weight
with a fixed kernel) for every t of its domain — one period, [0, constant_after], or t >= 0
— by interval arithmetic on t-intervals (:mod:`ntc_design.rigorous.interval`), and refuses the file
naming the edge and the t where the proof fails. Because the classes are fixed, so are the
edges, U, Ω_i and the positive-negative paths; what moves with t is the weights, C(t),
δ(t) = C(t) + ΔC, B_i(t), x0(t) and L_B(t).

:func:`lemma1_batch` evaluates Lemma 1 at a batch of times at once (batched Cholesky and
symmetric eigenvalues), exactly as :func:`ntc_design.design.design_topology` does at one
time: V_I = U, B_i(t) = Σ_{Ω_i}|A_ij(t)|, C(t) = max over the C-minimising V1(t) of
C_i(t), δ(t) = C(t) + ΔC (δ = ΔC when C is undefined or C + ΔC <= 0), x0 = (1 + 2/δ)θ.

Modules: :mod:`.topology` (:class:`ExpressionTopology`, reading files), :mod:`.enclosure`
(interval proofs over t), :mod:`.design` (Lemma 1 at every instant).
"""

from .design import (
    DESIGN_SAMPLES,
    Lemma1Batch,
    Lemma1Structure,
    TimeVaryingDesign,
    grounded_laplacian_batch,
    lemma1_batch,
    lemma1_structure,
)
from .enclosure import SignProof, enclose_matrix, interval_mid_rad, sym_min_eig_lower
from .topology import ExprEdge, ExpressionTopology, from_document, load_time_varying

__all__ = [
    "DESIGN_SAMPLES",
    "ExprEdge",
    "ExpressionTopology",
    "Lemma1Batch",
    "Lemma1Structure",
    "SignProof",
    "TimeVaryingDesign",
    "enclose_matrix",
    "from_document",
    "grounded_laplacian_batch",
    "interval_mid_rad",
    "lemma1_batch",
    "lemma1_structure",
    "load_time_varying",
    "sym_min_eig_lower",
]
