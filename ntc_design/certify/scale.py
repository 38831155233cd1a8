"""Certificates that scale: −L_B Hurwitz proven component by component, with no dense
step above documented sizes (issue 9).

**Block triangular structure.** Number the strongly connected components of the agent
graph in a topological order of the condensation. Every edge j -> i then runs from a
component numbered no later than i's, so L_B (block (i, j) = −A_ij, diagonal block
L_ii + δB_i) is block lower triangular in that order and its eigenvalues are those of
the diagonal component blocks L_B[C, C]: −L_B is Hurwitz iff every component block is.
``verify`` does not trust the numbering: it only checks that every edge goes forward
(any partition with a consistent order gives the same triangular form).

**Block generalised diagonal dominance** (Feingold & Varga, "Block diagonally dominant
matrices and generalizations of the Gerschgorin circle theorem", Pacific J. Math. 12,
1962). Inside a component C let μ_i ≤ λ_min(sym(L_B,ii)) and ν_ij ≥ ‖A_ij‖₂, and let
v > 0 with ``μ_i v_i > Σ_{j∈C, j≠i} ν_ij v_j`` for every i ∈ C (M v > 0 for the
comparison matrix M = [μ_i on the diagonal, −ν_ij off it]). Then every eigenvalue s of
L_B[C, C] has Re s > 0. Proof: let L_B x = s x with Re s ≤ 0 and x ≠ 0. For every i,
(L_ii − sI) x_i = −Σ_j L_ij x_j, and for any vector y,
‖(L_ii − sI) y‖‖y‖ ≥ Re y*(L_ii − sI) y ≥ (λ_min(sym L_ii) − Re s)‖y‖² ≥ μ_i ‖y‖², so
μ_i ‖x_i‖ ≤ Σ_j ν_ij ‖x_j‖. Take i maximising w_i = ‖x_i‖ / v_i (w_i > 0): then
μ_i v_i w_i ≤ Σ_j ν_ij v_j w_j ≤ w_i Σ_j ν_ij v_j < w_i μ_i v_i, a contradiction. A
one-agent component is the case v = 1 with no off-diagonal term (μ_i > 0).

**Fallbacks per component.** Where dominance does not apply: (a) the symmetric part
L_B[C,C] + L_B[C,C]ᵀ ≻ 0 (then Re x*L_B x > 0 for every x ≠ 0), proven by a sparse
Cholesky factorisation (CHOLMOD) of the shifted matrix with Rump's rounding bound
(Rump, BIT 46, 2006; :func:`rump_shift`); (b) the Lyapunov equation on that component only (dense,
Nd_C <= ``LYAPUNOV_COMPONENT_MAX_ND``), P stored and re-proven.

**Rigour.** ``verify`` rebuilds every number from the stated topology and δ: the
diagonal blocks in floating point with an entrywise error bound (γ_k, standard model),
the off-diagonal blocks exactly (−A_ij). μ_i is proven by a floating-point Cholesky of
``sym(L_ii) − μ_i I`` shifted by Rump's bound, ν_ij by two such proofs
(νI ∓ sym(A_ij) ≻ 0) plus the Frobenius norm of the skew part; ``M v > 0`` is checked
with the rounding of every sum bounded. No solver is used.

Sizes: the dense steps of the small certificate (decay-rate LMI, dense common P, exact
rational Sylvester) are not run here; the certificate says so and estimates the rate
with a sparse eigensolver.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sparse

from ..model import Topology, block_coo
from ..numerics.linalg import (
    CODE_SIGN,
    DENSE_MAX_BYTES,
    DenseRefused,
    SPDFamily,
    cholesky_fill,
    comparison_solve,
)
from ..protocol import ProtocolDesign
from ..protocol.thresholds import strong_components
from ..rigorous.exact import U, gamma, rump_shift_value
from .arrays import mode_subject, pack
from .dense import prove_pd_expr
from .format import FORMAT, VERSION, finish
from .lyapunov import hurwitz_by_lyapunov

#: Largest component (Nd) that may fall back to a dense Lyapunov equation.
LYAPUNOV_COMPONENT_MAX_ND = 600
#: Largest component (Nd) whose eigenvalues are computed densely for the rate estimate.
RATE_DENSE_MAX_ND = 1500
#: Largest component (Nd) given to ARPACK for the rate estimate.
RATE_ARPACK_MAX_ND = 20_000
#: ... and the largest factorisation work (flops of the Cholesky factor of its pattern, a
#: lower estimate of SuperLU's): SuperLU ran at about 2.5e9 flop/s, so about 10 s.
RATE_ARPACK_MAX_FLOPS = 2.5e10


# ----------------------------------------------------------------- rigorous helpers


def chol_ok_batch(a: np.ndarray) -> np.ndarray:
    """Floating-point Cholesky of every matrix of a stack (K, d, d), vectorised over K
    (the standard column algorithm).

    Parameters
    ----------
    a : numpy.ndarray
        Symmetric matrices, shape (K, d, d).

    Returns
    -------
    numpy.ndarray
        K booleans: True where every pivot is positive and finite.
    """
    k, d, _ = a.shape
    low = np.zeros_like(a)
    ok = np.ones(k, dtype=bool)
    for j in range(d):
        s = a[:, j, j] - np.sum(low[:, j, :j] ** 2, axis=1)
        ok &= s > 0
        ljj = np.sqrt(np.where(s > 0, s, 1.0))
        low[:, j, j] = ljj
        for i in range(j + 1, d):
            low[:, i, j] = (a[:, i, j] - np.sum(low[:, i, :j] * low[:, j, :j], axis=1)) / ljj
    return ok & np.all(np.isfinite(low), axis=(1, 2))


def verified_pd_batch(m: np.ndarray, err: np.ndarray) -> np.ndarray:
    """Rigorous ``M_exact ≻ 0`` for a stack of d×d matrices from float values ``m`` and
    entrywise bounds ``err >= |M_exact − m|``: the shifted-Cholesky test of
    :func:`ntc_design.rigorous.exact.verified_float_pd`, batched, with Rump's underflow
    term (:func:`rump_shift`).

    Parameters
    ----------
    m : numpy.ndarray
        Float values, shape (K, d, d).
    err : numpy.ndarray
        Entrywise error bounds, shape (K, d, d).

    Returns
    -------
    numpy.ndarray
        K booleans: True where positive definiteness is proven.
    """
    d = m.shape[1]
    mt = m.transpose(0, 2, 1)
    ms = 0.5 * (m + mt)
    err = err + 0.5 * np.abs(m - mt)
    em = np.max(np.abs(err), axis=(1, 2), initial=0.0)
    scale_ = np.where((em > 0) & np.isfinite(em), em, 1.0)
    e_f = em * np.sqrt(np.sum((err / scale_[:, None, None]) ** 2, axis=(1, 2)))
    dg = np.abs(np.diagonal(ms, axis1=1, axis2=2))
    c = rump_shift_value(d, dg.sum(axis=1), e_f, dg.max(axis=1, initial=0.0))
    return chol_ok_batch(ms - c[:, None, None] * np.eye(d))


@dataclass(frozen=True)
class BlockData:
    """L_B rebuilt from a topology and δ: ``diag`` (N, d, d) float diagonal blocks with
    entrywise error bounds ``diag_err``; off-diagonal blocks are −A_ij exactly (the
    topology's edge arrays)."""

    top: Topology
    delta: float
    diag: np.ndarray
    diag_err: np.ndarray


def lap_b_blocks(top: Topology, delta: float) -> BlockData:
    """Diagonal blocks ``L_ii + δB_i = Σ_{N_i}(1 + δ·[j∈Ω_i])|A_ij|`` with a rigorous
    entrywise error bound: each term carries at most two roundings (1 + δ, the
    product), the sum of m_i terms m_i − 1 more, so the error is at most
    γ_{m_i+3} times the sum of the absolute terms (taken ×(1 + 2u) for their own
    rounding).

    Parameters
    ----------
    top : Topology
        The topology.
    delta : float
        δ of the design.

    Returns
    -------
    BlockData
        The diagonal blocks with their error bounds.

    Raises
    ------
    DenseRefused
        The (N, d, d) blocks would exceed ``DENSE_MAX_BYTES`` (an InputError).
    """
    ea = top.edge_arrays
    n, d = top.n, top.dim
    need = 4 * 8.0 * n * d * d  # diag, err and their working copies, (N, d, d) each
    if need > DENSE_MAX_BYTES:
        raise DenseRefused(
            f"L_B's diagonal blocks: N = {n} agents of d = {d} need about "
            f"{need / 2**30:.1f} GiB (limit {DENSE_MAX_BYTES / 2**30:.1f} GiB); refused"
        )
    sg = CODE_SIGN[ea.codes].astype(float)
    neg = sg < 0
    fac = np.where(neg, 1.0 + delta, 1.0)
    terms = (sg * fac)[:, None, None] * ea.w
    diag = np.zeros((n, d, d))
    mag = np.zeros((n, d, d))
    np.add.at(diag, ea.rows, terms)
    np.add.at(mag, ea.rows, np.abs(terms))
    deg = np.bincount(ea.rows, minlength=n)
    gam = np.array([gamma(k + 3) for k in range(int(deg.max(initial=0)) + 1)])[deg]
    err = gam[:, None, None] * mag * (1 + 2 * U)
    return BlockData(top, float(delta), diag, err)


def edge_norm_bounds(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigorous upper bounds ν_k >= ‖w_k‖₂ for a stack of d×d weights: ν = ν_sym + ‖skew‖_F
    with ν_sym proven by νI ∓ sym(w) ≻ 0 (batched verified Cholesky).

    Parameters
    ----------
    w : numpy.ndarray
        Weights, shape (K, d, d).

    Returns
    -------
    tuple of numpy.ndarray
        ``(nu, proven)``: the bounds and where they are proven.
    """
    d = w.shape[1]
    sym = 0.5 * (w + w.transpose(0, 2, 1))
    skew = 0.5 * (w - w.transpose(0, 2, 1))
    lam = np.linalg.eigvalsh(sym)
    top_ = np.max(np.abs(lam), axis=1)
    nu_s = top_ * (1 + 1e-9) + 1e-300 + 1e-12 * top_
    eye = np.eye(d)
    ok = np.ones(w.shape[0], dtype=bool)
    for sgn in (1.0, -1.0):
        m = nu_s[:, None, None] * eye - sgn * sym
        ok &= verified_pd_batch(m, U * np.abs(m) + U * np.abs(sym))
    sk = np.sqrt(np.sum(skew**2, axis=(1, 2))) * (1 + 4 * d * d * U)
    return (nu_s + sk) * (1 + 4 * U), ok


def prove_mu(blocks: BlockData, idx: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Prove ``λ_min(sym(L_B,ii)) >= μ_i`` for some agents.

    Parameters
    ----------
    blocks : BlockData
        L_B's diagonal blocks with error bounds.
    idx : numpy.ndarray
        Agent indices.
    mu : numpy.ndarray
        The claimed μ_i, one per index.

    Returns
    -------
    numpy.ndarray
        True where proven.
    """
    d = blocks.top.dim
    m = blocks.diag[idx] - mu[:, None, None] * np.eye(d)
    err = blocks.diag_err[idx] + U * np.abs(m) + U * np.abs(mu)[:, None, None] * np.eye(d)
    return verified_pd_batch(m, err)


def dominance_holds(
    top: Topology,
    comp: np.ndarray,
    mu: np.ndarray,
    v: np.ndarray,
    nu: np.ndarray,
    agents: np.ndarray,
) -> np.ndarray:
    """Rigorous ``μ_i v_i > Σ_{j∈C(i), j≠i} ν_ij v_j`` for every agent of the boolean mask
    ``agents`` (rounding of products and sums bounded).

    Parameters
    ----------
    top : Topology
        The topology.
    comp : numpy.ndarray
        Each agent's dominance component C(i).
    mu : numpy.ndarray
        μ_i per agent.
    v : numpy.ndarray
        The positive weights v_i.
    nu : numpy.ndarray
        ν_ij >= ‖A_ij‖₂ per edge.
    agents : numpy.ndarray
        Boolean mask of the agents to check.

    Returns
    -------
    numpy.ndarray
        Per agent: True where the inequality is proven.
    """
    ea = top.edge_arrays
    n = top.n
    same = comp[ea.rows] == comp[ea.cols]
    inner = same & agents[ea.rows]
    rhs = np.zeros(n)
    np.add.at(rhs, ea.rows[inner], nu[inner] * v[ea.cols[inner]])
    cnt = np.bincount(ea.rows[inner], minlength=n)
    gam = np.array([gamma(int(k) + 2) for k in range(int(cnt.max(initial=0)) + 1)])[cnt]
    lhs = mu * v * (1 - 2 * U)
    return (v > 0) & (lhs > rhs * (1 + gam)) & np.isfinite(rhs)


def component_matrix(
    blocks: BlockData, agents: np.ndarray
) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
    """L_B restricted to some agents, with an error bound.

    Parameters
    ----------
    blocks : BlockData
        L_B's diagonal blocks with error bounds.
    agents : numpy.ndarray
        Agent indices C.

    Returns
    -------
    tuple of scipy.sparse.csr_matrix
        Float L_B[C, C] and an entrywise bound on its error.
    """
    top = blocks.top
    ea, d = top.edge_arrays, top.dim
    pos = np.full(top.n, -1, dtype=np.int64)
    pos[agents] = np.arange(agents.size)
    k = (pos[ea.rows] >= 0) & (pos[ea.cols] >= 0)

    m = agents.size
    rows = np.concatenate([pos[ea.rows[k]], np.arange(m)])
    cols = np.concatenate([pos[ea.cols[k]], np.arange(m)])
    vals = np.concatenate([-ea.w[k], blocks.diag[agents]])
    errs = np.concatenate([np.zeros_like(ea.w[k]), blocks.diag_err[agents]])
    return block_coo(m, d, rows, cols, vals), block_coo(m, d, rows, cols, errs)


@dataclass(frozen=True)
class SymmetricPartProof:
    """The outcome of :func:`symmetric_part_bound`: whether ``L + Lᵀ − shift·I ≻ 0`` is
    proven, with Rump's shift ``c`` that covered the rounding."""

    holds: bool
    shift: float
    c: float
    detail: str


def _frobenius(x: np.ndarray) -> float:
    """‖x‖₂ scaled by max|x| first, so the squares neither underflow nor overflow."""
    m = float(np.max(np.abs(x), initial=0.0))
    if m == 0.0 or not np.isfinite(m):
        return m
    return m * float(np.sqrt(np.sum((x / m) ** 2)))


def rump_shift(a: sparse.csr_matrix, e: sparse.csr_matrix) -> float:
    """Rump's shift (:func:`~ntc_design.rigorous.exact.rump_shift_value`) for a float
    symmetric sparse ``a`` within ``e`` (entrywise) of an exact matrix: the bound holds for
    any order of the inner products, so for CHOLMOD's supernodal blocked factorisation
    too, and its underflow term covers weights that are not range-checked.

    Parameters
    ----------
    a : scipy.sparse.csr_matrix
        The float matrix.
    e : scipy.sparse.csr_matrix
        An entrywise bound on its distance from the exact matrix.

    Returns
    -------
    float
        The shift c.
    """
    dg = np.abs(a.diagonal())
    return float(rump_shift_value(a.shape[0], dg.sum(), _frobenius(e.data), dg.max(initial=0.0)))


def shifted_symmetric_part(
    lap: sparse.csr_matrix, err: sparse.csr_matrix, shift: float = 0.0
) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
    """A = fl(L + Lᵀ − shift·I) and E = err + errᵀ + u|L + Lᵀ| + 2u(|diag| + shift), an
    entrywise bound on the distance of A from the exact L + Lᵀ − shift·I.

    Parameters
    ----------
    lap : scipy.sparse.csr_matrix
        The float matrix L.
    err : scipy.sparse.csr_matrix
        An entrywise bound on |L_exact − L|.
    shift : float, optional
        The shift.

    Returns
    -------
    tuple of scipy.sparse.csr_matrix
        A and E.
    """
    s = (lap + lap.T).tocsr()
    n = s.shape[0]
    a = (s - shift * sparse.identity(n, format="csr")).tocsr() if shift else s
    dg = np.abs(s.diagonal()) + shift
    e = (err + err.T + U * abs(s) + sparse.diags(2 * U * dg)).tocsr()
    return a, e


def symmetric_part_bound(
    lap: sparse.csr_matrix, err: sparse.csr_matrix, shift: float = 0.0
) -> SymmetricPartProof:
    """Rigorous ``λ_min(L + Lᵀ) > shift`` for the exact matrix within ``err`` of the float
    ``lap``: one sparse Cholesky factorisation (CHOLMOD) of ``A − cI`` succeeds, with A
    and E from :func:`shifted_symmetric_part` and c = :func:`rump_shift` (A, E). A
    success on the bit-identical A − cI earlier in the process is not factorised again
    (:meth:`~ntc_design.numerics.linalg.SPDFamily.factor`, ``reuse``).

    Parameters
    ----------
    lap : scipy.sparse.csr_matrix
        The float matrix L.
    err : scipy.sparse.csr_matrix
        An entrywise bound on |L_exact − L|.
    shift : float, optional
        The lower bound to prove (0: positive definiteness only).

    Returns
    -------
    SymmetricPartProof
        Whether it is proven, and how (or why not).

    Raises
    ------
    InputError
        The factorisation would not fit (:func:`~ntc_design.numerics.linalg.require_sparse_factor`).
    """
    return symmetric_part_factor(lap, err, shift, reuse=True)[0]


def symmetric_part_factor(
    lap: sparse.csr_matrix, err: sparse.csr_matrix, shift: float = 0.0, reuse: bool = False
) -> tuple[SymmetricPartProof, SPDFamily | None]:
    """:func:`symmetric_part_bound`, also returning the factorised family (its factor of
    ``A − cI`` solves with ``L + Lᵀ − (shift + c)·I`` up to rounding; None when nothing
    was factorised).

    Parameters
    ----------
    lap, err : scipy.sparse.csr_matrix
        The float matrix L and an entrywise bound on |L_exact − L|.
    shift : float, optional
        The lower bound to prove.
    reuse : bool, optional
        Reuse an earlier success on the identical matrix (no factor is then kept).

    Returns
    -------
    tuple of (SymmetricPartProof, SPDFamily or None)
    """
    a, e = shifted_symmetric_part(lap, err, shift)
    c = rump_shift(a, e)
    what = "L + Lᵀ" if not shift else f"L + Lᵀ − {shift:.6g}·I"
    if not (np.isfinite(c) and np.all(np.isfinite(a.data)) and np.all(np.isfinite(e.data))):
        return SymmetricPartProof(
            False, shift, c, f"{what} or its rounding bound overflows: nothing is proven"
        ), None
    fam = SPDFamily([a])
    ok, _ = fam.factor([1.0], c, reuse=reuse)
    if not ok:
        why = f"sparse Cholesky of {what} − {c:.3g}·I fails"
        return SymmetricPartProof(False, shift, c, why), fam
    how = f"sparse Cholesky of {what} − {c:.3g}·I succeeds (shift covers rounding)"
    return SymmetricPartProof(True, shift, c, how), fam


def prove_symmetric_part(lap: sparse.csr_matrix, err: sparse.csr_matrix) -> tuple[bool, str]:
    """Rigorous ``L + Lᵀ ≻ 0`` (:func:`symmetric_part_bound` with shift 0).

    Parameters
    ----------
    lap : scipy.sparse.csr_matrix
        The float matrix L.
    err : scipy.sparse.csr_matrix
        An entrywise bound on |L_exact − L|.

    Returns
    -------
    tuple of (bool, str)
        Whether it is proven, and how (or why not).

    Raises
    ------
    InputError
        The factorisation would not fit (:func:`~ntc_design.numerics.linalg.require_sparse_factor`).
    """
    p = symmetric_part_bound(lap, err)
    return p.holds, p.detail


# ----------------------------------------------------------------------- certify


def rate_estimate(blocks: BlockData, comp: np.ndarray, ncomp: int) -> tuple[float, str]:
    """min Re λ(L_B) estimated: eigenvalues of one-agent blocks, dense eigenvalues of
    components up to RATE_DENSE_MAX_ND, ARPACK (shift-invert at 0, the eigenvalue nearest
    0) up to RATE_ARPACK_MAX_ND and RATE_ARPACK_MAX_FLOPS; larger components are left to
    the proven lower bound.

    Parameters
    ----------
    blocks : BlockData
        L_B's blocks.
    comp : numpy.ndarray
        The component of each agent.
    ncomp : int
        The number of components.

    Returns
    -------
    tuple of (float, str)
        The estimate (inf when no component was estimated) and how it was made.
    """
    from scipy.sparse.linalg import eigs

    sizes = np.bincount(comp, minlength=ncomp)
    single = sizes[comp] == 1
    best = np.inf
    how = []
    if single.any():
        best = float(np.min(np.linalg.eigvals(blocks.diag[single]).real))
        how.append("one-agent blocks: dense d×d eigenvalues")
    big = np.flatnonzero(sizes > 1)
    arpack, left = 0, 0
    for c in big.tolist():
        agents = np.flatnonzero(comp == c)
        nd_c = agents.size * blocks.top.dim
        if nd_c > RATE_ARPACK_MAX_ND:
            left += 1
            continue
        lap, _ = component_matrix(blocks, agents)
        if nd_c <= RATE_DENSE_MAX_ND:
            val = float(np.min(np.linalg.eigvals(lap.toarray()).real))
        elif cholesky_fill(lap).flops > RATE_ARPACK_MAX_FLOPS:  # SuperLU would take minutes
            left += 1
            continue
        else:
            arpack += 1
            try:
                w = eigs(lap.tocsc(), k=1, sigma=0.0, which="LM", return_eigenvectors=False)
                val = float(np.min(w.real))
            except Exception:  # ARPACK did not converge: no estimate from this block
                val = np.nan
        best = min(best, val) if np.isfinite(val) else best
    if big.size:
        how.append(
            f"components up to Nd = {RATE_DENSE_MAX_ND}: dense eigenvalues"
            + (
                f"; {arpack} component(s) up to Nd = {RATE_ARPACK_MAX_ND}: ARPACK eigenvalue "
                "nearest 0"
                if arpack
                else ""
            )
            + (
                f"; {left} component(s) too large or filling in too much to estimate (see "
                "the proven lower bound)"
                if left
                else ""
            )
        )
    return best, "; ".join(how)


def dominance_rate_bound(mu: np.ndarray, v: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Per agent ``μ_i − (Σ_j ν_ij v_j)/v_i``: by the Feingold–Varga argument with μ_i
    replaced by μ_i − r, no eigenvalue of a dominance component has Re s <= r for any r
    below the minimum over its agents, so the minimum bounds the decay rate from below.

    Parameters
    ----------
    mu : numpy.ndarray
        μ_i per agent.
    v : numpy.ndarray
        The positive weights v_i.
    rhs : numpy.ndarray
        Σ_j ν_ij v_j per agent.

    Returns
    -------
    numpy.ndarray
        The per-agent bound.
    """
    return mu - rhs / v


def scale_document(des: ProtocolDesign, kind: str, name: str | None = None) -> dict:
    """Certify −L_B Hurwitz for a big network component by component (module docstring)
    and return the certificate document (compact: the topology as arrays, v and μ per
    agent, a dense P only for small fallback components).

    Parameters
    ----------
    des : ProtocolDesign
        The design whose L_B is certified.
    kind : str
        The kind's name, written into the document by the kind that issues it
        (:class:`ntc_design.certify.kinds.hurwitz_scale.HurwitzScaleKind`).
    name : str, optional
        Mode name used in claim ids (default: the topology's name).

    Returns
    -------
    dict
        The certificate, digest included; re-check it with
        :func:`ntc_design.certify.verify` / ``ntc verify``.
    """
    t0 = time.perf_counter()
    top = des.topology
    name = name or top.name or "topology"
    blocks = lap_b_blocks(top, des.delta)
    ncomp, comp = strong_components(des.grounded_laplacian_sparse(), top.dim)
    ea = top.edge_arrays
    n = top.n
    sizes = np.bincount(comp, minlength=ncomp)
    lam, mu = _agent_bounds(blocks, top.dim, n)
    nu, nu_ok = edge_norm_bounds(ea.w)
    same = comp[ea.rows] == comp[ea.cols]
    v = _comparison_vector(n, comp, sizes, ea, same, nu, mu)
    mu_proven = np.zeros(n, dtype=bool)
    pos_mu = mu > 0
    mu_proven[pos_mu] = prove_mu(blocks, np.flatnonzero(pos_mu), mu[pos_mu])
    # an edge bound that failed to prove sinks the dominance of its component
    bad_edge_comp = np.unique(comp[ea.rows[same & ~nu_ok]])
    dom = dominance_holds(top, comp, mu, v, nu, np.ones(n, dtype=bool)) & mu_proven
    comp_dom = np.ones(ncomp, dtype=bool)
    np.logical_and.at(comp_dom, comp, dom)
    comp_dom[bad_edge_comp] = False
    fb = _fallbacks(blocks, comp, sizes, comp_dom, lam)
    rate, rate_how = rate_estimate(blocks, comp, ncomp)
    rhs = np.zeros(n)
    np.add.at(rhs, ea.rows[same], nu[same] * v[ea.cols[same]])
    # a bound on min Re λ(L_B) only when every component is a dominance one
    lower = (
        float(np.min(dominance_rate_bound(mu, v, rhs))) * (1 - 1e-12)
        if n and comp_dom[comp].all()
        else None
    )
    methods = fb.methods
    counts = {m: int(np.sum(methods == m)) for m in ("dominance", "symmetric", "lyapunov", "none")}
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": kind,
        "certifies": ["hurwitz"],
        "size": int(top.nd),
        "subject": {"modes": {name: mode_subject(des)}},
        "components": {
            "label": pack(comp, "i8"),
            "method": [str(m) for m in methods.tolist()],
            "v": pack(v, "f8"),
            "mu": pack(mu, "f8"),
            "lyapunov": fb.extra,
        },
        "claims": [
            {
                "id": f"−L_B({name}) Hurwitz: every component block certified",
                "kind": "components",
                "mode": name,
            }
        ],
        "results": {
            "components": int(ncomp),
            "largest_component_agents": int(sizes.max(initial=0)),
            "methods": counts,
            "details": fb.details,
            "eig_bound": rate,
            "rate_estimate": {"value": rate, "method": rate_how},
            "rate_lower_bound": {
                "value": lower,
                "method": "min_i μ_i − (Σ_j ν_ij v_j)/v_i when every component is proven by "
                "dominance (Feingold–Varga with a shifted s; from the certified μ, ν, v; "
                "recomputed by verify), else None",
            },
            "skipped": [
                "decay-rate LMI, dense common P and exact rational Sylvester: not run "
                "above the dense sizes (memory grows as (Nd)^4 for the LMI); the rate is "
                "estimated instead",
                *fb.skipped,
            ],
            "seconds": time.perf_counter() - t0,
        },
        "solver": {"name": None, "status": None},
    }
    return finish(doc, "verified-float (component-wise)")


def _agent_bounds(blocks, d: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(eigenvalues of each symmetric diagonal block, μ_i): λ_min lowered so that the
    proof has room for the rounding of the blocks and of the eigenvalues."""
    sym = 0.5 * (blocks.diag + blocks.diag.transpose(0, 2, 1))
    lam = np.linalg.eigvalsh(sym) if n else np.zeros((0, d))
    scale = np.max(np.abs(lam), axis=1)
    errf = np.sqrt(np.sum(blocks.diag_err**2, axis=(1, 2)))
    return lam, lam[:, 0] - 1e-9 * scale - 4 * errf - 4 * gamma(d + 1) * scale


def _comparison_vector(n, comp, sizes, ea, same, nu, mu) -> np.ndarray:
    """v: 1 on one-agent components, M_C v = 1 on the others (−1 where M_C is singular
    or the solve is not finite: dominance then fails there)."""
    v = np.ones(n)
    if (sizes > 1).any():
        mm = sparse.csr_matrix(
            (-nu[same], (ea.rows[same], ea.cols[same])), shape=(n, n)
        ) + sparse.diags(mu)
        multi = np.flatnonzero(sizes[comp] > 1)
        v[multi] = comparison_solve(mm[multi][:, multi].tocsr())
    return v


@dataclass
class _Fallbacks:
    """The method per component and what the non-dominance proofs left."""

    methods: np.ndarray
    extra: dict[str, Any] = field(default_factory=dict)
    details: dict[str, str] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)


def _fallbacks(blocks, comp, sizes, comp_dom, lam) -> _Fallbacks:
    """The components dominance did not prove: the symmetric part, then a dense
    Lyapunov P for small ones."""
    fb = _Fallbacks(np.where(comp_dom, "dominance", "none").astype(object))
    # the agents of each component, grouped once (not a pass over all agents per component)
    order = np.argsort(comp, kind="stable")
    starts = np.concatenate([[0], np.cumsum(sizes)])
    # a one-agent block L_ii = Σ|A_ik| + δB_i is symmetric: when its λ_min is not positive
    # no method can prove it (an agent nothing reaches), so it is not tried one by one
    hopeless = (sizes == 1) & ~comp_dom
    hopeless[hopeless] = lam[order[starts[:-1][hopeless]], 0] <= 0
    if hopeless.any():
        fb.skipped.append(
            f"{int(hopeless.sum())} one-agent component(s) with λ_min(L_ii) <= 0 (e.g. an agent "
            "that no edge and no x0 reaches): −L_B is not Hurwitz there"
        )
    for c in np.flatnonzero(~comp_dom & ~hopeless).tolist():
        agents = order[starts[c] : starts[c + 1]]
        _prove_component(fb, c, *component_matrix(blocks, agents))
    return fb


def _prove_component(fb: _Fallbacks, c: int, lap_c, err_c) -> None:
    """Component c by its symmetric part, else (small enough) by a Lyapunov P."""
    try:
        ok, how = prove_symmetric_part(lap_c, err_c)
    except DenseRefused as exc:  # too much fill: the dense fallback below decides
        ok, how = False, str(exc)
    if ok:
        fb.methods[c] = "symmetric"
        fb.details[str(c)] = how
        return
    if lap_c.shape[0] > LYAPUNOV_COMPONENT_MAX_ND:
        fb.skipped.append(
            f"component {c} (Nd = {lap_c.shape[0]}): no dense Lyapunov fallback above "
            f"Nd = {LYAPUNOV_COMPONENT_MAX_ND}"
        )
        return
    dense = lap_c.toarray()
    try:
        p = hurwitz_by_lyapunov(dense).p
    except (np.linalg.LinAlgError, ValueError):
        return
    if p is None or not np.all(np.isfinite(p)):
        return
    p1 = prove_pd_expr(p, None, None, 0.0, None, False)
    p2 = prove_pd_expr(p, None, dense, 0.0, err_c.toarray(), False)
    if p1.holds and p2.holds:
        fb.methods[c] = "lyapunov"
        fb.extra[str(c)] = {"P": pack(p, "f8")}
        fb.details[str(c)] = f"{p1.detail}; {p2.detail}"
