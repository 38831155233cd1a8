"""Robust decay and margin bounds for big networks, sparse: cost O(E) per evaluation.

A realisation A' keeps the sparsity pattern, so L_B(A') has the nominal strongly connected
components and is block triangular in their order (:mod:`.scale`); its eigenvalues are
those of the component blocks. Inside a component, block generalised diagonal dominance
(Feingold & Varga, 1962) with

* ``μ_i^ρ``, a proven lower bound on λ_min(Σ_j (1 − ρ_e)|A_ij| + δB_i) <= λ_min(L_B(A')_ii)
  for every realisation (|A'_ij| ⪰ (1 − ρ_e)|A_ij|; B_i stays at its nominal value), and
* ``ν_ij^ρ = (1 + ρ_e)·ν_ij`` >= ‖A'_ij‖₂ (ν_ij >= ‖A_ij‖₂ proven),

and v > 0 with ``(μ_i^ρ − α)v_i > Σ_j ν_ij^ρ v_j`` proves Re λ(L_B(A')) > α for every
realisation (the rows of a component involve only its own v, so the test also says which
components it proves). α is the Collatz–Wielandt minimum of ``μ_i^ρ − (N^ρ v)_i / v_i`` for the v
that solves the comparison system; the margin radius is the largest uniform ρ for which
some α >= 0 is proven (bisection). A one-agent component is exact: its block is symmetric
and the realisation (1 − ρ_e)|A_ij| attains μ_i^ρ.

Where dominance proves a margin below 1/2 and Nd > RICCATI_MAX_ND, each component it
does not prove is given to the Riccati search of :mod:`.robust_are` on its own diagonal
block (up to COMPONENT_RICCATI_MAX_ND rows), the edges from other components perturbing
only that diagonal (D_e = E_i): the margin is then the largest ρ tried at which every
component is proven one way or the other.

The other ends are estimates on two realisations (every weight scaled by 1 − ρ_e, or by
1 + ρ_e) with :func:`.scale.rate_estimate`; the destabilising end is every weight vanishing
at ρ = 1 when an agent is not informed. The offset's upper end is the comparison bound of
:func:`proven_offset` (sound, loose); its lower end the larger offset of the antagonistic
weights scaled by 1 ∓ ρ_e (a sparse solve).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...numerics.linalg import comparison_solve
from ...protocol import ProtocolDesign
from ...rigorous.exact import U, gamma
from ..scale import BlockData, dominance_holds, edge_norm_bounds, prove_mu, rate_estimate
from .are import RICCATI_MAX_ND, RiccatiSearch
from .problem import Bracket, Realisation, UncertainEdges, channel_bound, uncertain_edges
from .report import RobustReport

MARGIN_STEPS = 12
#: A component that dominance does not prove is given to the Riccati search on its own
#: block up to this many rows (each solve is a 2·Nd Hamiltonian: 9 s at Nd = 534).
COMPONENT_RICCATI_MAX_ND = 600


def _components(top) -> tuple[int, np.ndarray]:
    import scipy.sparse as sparse
    from scipy.sparse.csgraph import connected_components

    ea = top.edge_arrays
    g = sparse.csr_matrix((np.ones(ea.rows.size), (ea.rows, ea.cols)), shape=(top.n, top.n))
    return connected_components(g, directed=True, connection="strong")


def _diag_blocks(des: ProtocolDesign, factor: np.ndarray) -> BlockData:
    """Σ_j factor_e·|A_ij| + δB_i per agent, with the entrywise error bound of
    :func:`.scale.lap_b_blocks` (B_i at its nominal value)."""
    top = des.topology
    ea = top.edge_arrays
    n, d = top.n, top.dim
    terms = (ea.sign * factor)[:, None, None] * ea.w
    diag = np.zeros((n, d, d))
    mag = np.zeros((n, d, d))
    np.add.at(diag, ea.rows, terms)
    np.add.at(mag, ea.rows, np.abs(terms))
    for i, b in des.B.items():
        diag[i] += des.delta * b
        mag[i] += np.abs(des.delta * b)
    deg = np.bincount(ea.rows, minlength=n) + 1
    gam = np.array([gamma(k + 4) for k in range(int(deg.max(initial=0)) + 1)])[deg]
    return BlockData(top, float(des.delta), diag, gam[:, None, None] * mag * (1 + 2 * U))


def _edge_radii(des: ProtocolDesign, radius: float) -> np.ndarray:
    """ρ_e per listed edge (edge-array order): the file's value, else ``radius``."""
    top = des.topology
    ea = top.edge_arrays
    unc = top.uncertainty
    rad = np.array(
        [unc.get((int(i), int(j)), radius) for i, j in zip(ea.rows, ea.cols, strict=True)]
    )
    return np.where(ea.sign != 0, rad, 0.0)


def _perron(mu: np.ndarray, off, v: np.ndarray, outer: int = 8, sweeps: int = 200) -> np.ndarray:
    """Inverse iteration v <- M⁻¹v (Jacobi sweeps, M = diag(μ) − N an M-matrix) towards the
    Perron vector of M, which makes the Collatz–Wielandt bound min μ_i − (Nv)_i/v_i
    approach the Perron root τ(M): the best rate dominance can prove. Any positive v is
    sound (it is checked afterwards); this only tightens the bound."""
    d = np.where(mu > 0, mu, 1.0)
    best, best_a = v, float(np.min(mu - (off @ v) / v))
    for _ in range(outer):
        b = v / np.max(v)
        x = b / d
        with np.errstate(over="ignore", invalid="ignore"):
            for _ in range(sweeps):
                new = (b + off @ x) / d
                if not np.all(np.isfinite(new)):
                    return best
                done = np.max(np.abs(new - x) / np.abs(new), initial=0.0) <= 1e-10
                x = new
                if done:
                    break
        if not np.all(x > 0):
            return best
        v = x
        a = float(np.min(mu - (off @ v) / v))
        if a > best_a:
            best, best_a = v, a
    return best


def _agent_bounds(
    des: ProtocolDesign, rad: np.ndarray, nu: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """(μ, ν^ρ): μ_i <= λ_min(Σ_j (1 − ρ_e)|A_ij| + δB_i) proven per agent, and
    ν^ρ_e = (1 + ρ_e)·ν_e >= ‖A'_e‖₂ per edge (``nu``: the proven ν_e, when the caller
    has them); None when a bound is not proven."""
    got = _agent_bounds_per_agent(des, rad, nu)
    if got is None or not np.all(got[2]):
        return None
    return got[0], got[1]


def _agent_bounds_per_agent(
    des: ProtocolDesign, rad: np.ndarray, nu: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """As :func:`_agent_bounds`, with the agents whose μ_i is proven (a mask) instead of
    all or nothing; None when a ν_e is not proven."""
    top = des.topology
    ea = top.edge_arrays
    low = _diag_blocks(des, np.maximum(1.0 - rad, 0.0) * (1 - 2 * U))
    lam = np.linalg.eigvalsh(0.5 * (low.diag + low.diag.transpose(0, 2, 1)))[:, 0]
    mu = lam - (1e-9 * np.abs(lam) + 1e-12 * np.max(np.abs(lam), initial=1.0))
    ok = prove_mu(low, np.arange(top.n), mu)
    if nu is None:
        nu, proven = edge_norm_bounds(ea.w)
        if not np.all(proven):
            return None
    return mu, (1.0 + rad) * nu * (1 + 2 * U), ok


def _norm_bounds(des: ProtocolDesign) -> np.ndarray | None:
    """The proven ν_e >= ‖A_e‖₂ of every listed edge (one batch, shared by every radius)."""
    nu, proven = edge_norm_bounds(des.topology.edge_arrays.w)
    return nu if np.all(proven) else None


def _dominance_weights(top, comp: np.ndarray, mu: np.ndarray, nu_r: np.ndarray):
    """The comparison matrix's off-diagonal part N (edges inside a component) and the
    weights v: M⁻¹1 for M = diag(μ) − N, moved towards the Perron vector when positive."""
    import scipy.sparse as sparse

    ea, n = top.edge_arrays, top.n
    same = comp[ea.rows] == comp[ea.cols]
    off = sparse.csr_matrix((nu_r[same], (ea.rows[same], ea.cols[same])), shape=(n, n)).tocsr()
    v = comparison_solve((sparse.diags(mu) - off).tocsr())
    return off, (_perron(mu, off, v) if np.all(v > 0) else v)


def proven_rate(
    des: ProtocolDesign, rad: np.ndarray, comp: np.ndarray, nu: np.ndarray | None = None
) -> float | None:
    """A proven α with Re λ(L_B(A')) > α for every realisation within ρ_e (per edge), or
    None when dominance does not hold with α >= 0.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    rad : numpy.ndarray
        ρ_e per listed edge (edge-array order).
    comp : numpy.ndarray
        The strongly connected component of each agent.
    nu : numpy.ndarray, optional
        Proven ν_e >= ‖A_e‖₂ per edge, when the caller has them.

    Returns
    -------
    float or None
    """

    top = des.topology
    n = top.n
    bounds = _agent_bounds(des, rad, nu)
    if bounds is None:
        return None
    mu, nu_r = bounds
    off, v = _dominance_weights(top, comp, mu, nu_r)
    if not np.all(v > 0):
        return None
    rhs = off @ v
    alpha = float(np.min(mu - rhs / v))
    alpha = alpha - 1e-9 * abs(alpha) - 1e-12 * float(np.max(np.abs(mu)))
    if alpha < 0:
        return None
    shifted = mu - alpha * (1 + 2 * U) - 4 * U * np.abs(mu)  # below μ_i − α despite rounding
    held = dominance_holds(top, comp, shifted, v, nu_r, np.ones(n, dtype=bool))
    return alpha if bool(np.all(held)) else None


def proven_offset(
    des: ProtocolDesign, rad: np.ndarray, nu: np.ndarray | None = None
) -> float | None:
    """An upper bound on ‖x*(A') − 1⊗θ‖₂ for every realisation within ρ_e, or None when
    the comparison argument does not apply.

    With z = x* − 1⊗θ, L_B(A')z = r where r_i = −2Σ_{antagonistic e into i} Δ_e θ (plus
    the rounding residue u − L_B(1⊗θ)), so ‖r_i‖ <= b_i = 2Σ ρ_e ‖|A_e|‖^{1/2}·(θᵀ|A_e|θ)^{1/2}.
    Each block row gives μ_i‖z_i‖ <= b_i + Σ_j ν_ij‖z_j‖ (μ_i, ν_ij as for the decay, over
    every edge), i.e. M ζ <= b for ζ_i = ‖z_i‖ and the comparison matrix M. When M is a
    non-singular M-matrix (M⁻¹ >= 0), any x >= 0 with M x >= b bounds ζ <= x, so
    ‖z‖₂ <= ‖x‖₂; M x >= b is checked with its rounding bounded.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    rad : numpy.ndarray
        ρ_e per listed edge (edge-array order).
    nu : numpy.ndarray, optional
        Proven ν_e >= ‖A_e‖₂ per edge, when the caller has them.

    Returns
    -------
    float or None
    """
    import scipy.sparse as sparse

    top = des.topology
    ea = top.edge_arrays
    n, d = top.n, top.dim
    bounds = _agent_bounds(des, rad, nu)
    if bounds is None or not np.all(bounds[0] > 0):
        return None
    mu, nu_r = bounds
    off = sparse.csr_matrix((nu_r, (ea.rows, ea.cols)), shape=(n, n)).tocsr()
    # b_i: the antagonistic in-weights' reach, bounded with eigenvalues ×(1 + 1e-9)
    absw = ea.sign[:, None, None] * ea.w
    lmax = np.linalg.eigvalsh(absw)[:, -1].clip(min=0.0) * (1 + 1e-9)
    th = des.theta
    quad = np.einsum("a,kab,b->k", th, absw, th).clip(min=0.0) * (1 + 1e-9) + 1e-300
    term = np.where(ea.sign < 0, 2.0 * rad * np.sqrt(lmax) * np.sqrt(quad), 0.0) * (1 + 8 * U)
    b = np.zeros(n)
    np.add.at(b, ea.rows, term)
    r0 = des.input_vector() - des.grounded_laplacian_sparse() @ np.tile(th, n)
    b += np.linalg.norm(r0.reshape(n, d), axis=1) * (1 + 1e-6) + 1e-300
    from scipy.sparse.linalg import spsolve

    m = (sparse.diags(mu) - off).tocsc()
    with np.errstate(over="ignore", invalid="ignore"):
        # M⁻¹(b + η) by sparse LU, checked below (not trusted): η leaves room for rounding
        x = spsolve(m, b + 1e-9 * float(np.max(b)) + 1e-300)
    if not np.all(np.isfinite(x)):
        return None
    cnt = np.bincount(ea.rows, minlength=n)
    gam = np.array([gamma(int(k) + 2) for k in range(int(cnt.max(initial=0)) + 1)])[cnt]
    lhs = mu * x * (1 - 2 * U) - (off @ x) * (1 + gam)
    if not np.all(lhs >= b) or not np.all(x >= 0):
        return None
    # the M-matrix property of M: the decay's dominance (every component) at α = 0
    return float(np.sqrt(np.sum(x * x)) * (1 + 4 * n * U))


def _offset_realisation(des: ProtocolDesign, rad: np.ndarray) -> tuple[float, np.ndarray] | None:
    """The larger offset of two realisations (antagonistic weights scaled by 1 − ρ_e, or by
    1 + ρ_e; cooperative ones do not move x*), by a sparse solve; with their factors."""
    from scipy.sparse.linalg import splu

    top = des.topology
    ea = top.edge_arrays
    n = top.n
    u = des.input_vector()
    target = np.tile(des.theta, n)
    best = None
    for sgn in (-1.0, 1.0):
        fac = np.where(ea.sign < 0, 1.0 + sgn * rad, 1.0)
        real = top.__class__.from_arrays(
            top.labels, top.dim, ea.rows, ea.cols, ea.w * fac[:, None, None]
        )
        from dataclasses import replace

        lap = replace(des, topology=real).grounded_laplacian_sparse().tocsc()
        try:
            z = splu(lap).solve(u) - target
        except RuntimeError:
            continue
        val = float(np.linalg.norm(z))
        if best is None or val > best[0]:
            best = (val, fac)
    return best


def dominance_failures(des: ProtocolDesign, rad: np.ndarray, comp: np.ndarray, nu) -> set | None:
    """The strongly connected components whose rows block dominance does not prove at
    α = 0 for the radii ``rad`` (rigorously, per agent; a component's rows involve only its
    own v), or None when the μ bounds themselves are not proven.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    rad : numpy.ndarray
        ρ_e per listed edge (edge-array order).
    comp : numpy.ndarray
        The strongly connected component of each agent.
    nu : numpy.ndarray or None
        Proven ν_e >= ‖A_e‖₂ per edge, when the caller has them.

    Returns
    -------
    set of int, or None
    """

    top = des.topology
    n = top.n
    bounds = _agent_bounds_per_agent(des, rad, nu)
    if bounds is None:
        return None
    mu, nu_r, ok = bounds
    mu = np.where(ok, mu, 1.0)  # an agent without a proven μ_i fails below in any case
    _, v = _dominance_weights(top, comp, mu, nu_r)
    held = dominance_holds(top, comp, mu - 4 * U * np.abs(mu), v, nu_r, np.ones(n, dtype=bool))
    return {int(c) for c in np.unique(comp[~(held & ok)])}


def component_riccati(des: ProtocolDesign, comp: np.ndarray, c: int):
    """The Riccati search (:mod:`.robust_are`) on one strongly connected component's
    block of L_B: its own edges, and the edges into it from other components as diagonal
    terms (D_e = E_i). Every realisation's L_B(A') is block triangular in the components'
    order, so the block's robust stability is the component's.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    comp : numpy.ndarray
        The strongly connected component of each agent.
    c : int
        The component.

    Returns
    -------
    (RiccatiSearch, int)
        The search on the block (L_B's block and its rounding bound built from the
        weights), and the number of uncertain edges into it.
    """

    top = des.topology
    ea, d = top.edge_arrays, top.dim
    agents = np.flatnonzero(comp == c)
    loc = np.full(top.n, -1)
    loc[agents] = np.arange(agents.size)
    k = agents.size * d
    lap = np.zeros((k, k))
    mag = np.zeros((k, k))
    into = (loc[ea.rows] >= 0) & (ea.sign != 0)
    for e in np.flatnonzero(into):
        i = int(loc[ea.rows[e]]) * d
        absw = ea.sign[e] * ea.w[e]
        lap[i : i + d, i : i + d] += absw
        mag[i : i + d, i : i + d] += np.abs(absw)
        j = int(loc[ea.cols[e]])
        if j >= 0:
            lap[i : i + d, j * d : j * d + d] -= ea.w[e]
            mag[i : i + d, j * d : j * d + d] += np.abs(ea.w[e])
    for a, b in des.B.items():
        if loc[a] >= 0:
            i = int(loc[a]) * d
            db = des.delta * np.asarray(b, dtype=float)
            lap[i : i + d, i : i + d] += db
            mag[i : i + d, i : i + d] += np.abs(db)
    err = gamma(top.n + 3) * mag  # each entry: at most N + 1 terms, and δ·B_i's product
    dst = loc[ea.rows[into]]
    src = loc[ea.cols[into]]
    inside = src >= 0
    absw = ea.sign[into][:, None, None] * ea.w[into]
    edges = UncertainEdges(
        dst,
        np.where(inside, src, dst),
        np.where(inside, ea.sign[into], 0).astype(float),
        absw,
        tuple(() for _ in range(int(into.sum()))),
        np.array([channel_bound(x)[0] for x in absw]).reshape(absw.shape),
    )
    return RiccatiSearch(lap, err, edges, d), int(into.sum())


def _riccati_margin(
    des, comp, nu, lo: float, hi: float, deadline: float, prove_lo: bool = False
) -> float | None:
    """A margin above ``lo`` (dominance's): the largest ρ in [lo, hi) tried (bisection,
    three steps) at which every component that dominance does not prove has at most
    COMPONENT_RICCATI_MAX_ND rows and a Riccati proof at α = 0; ``lo`` if none (with
    ``prove_lo``, ``lo`` itself is proven first, and None returned when it is not)."""
    top = des.topology
    sign = top.edge_arrays.sign
    searches: dict = {}

    def proven(r: float) -> bool:
        fails = dominance_failures(des, np.where(sign != 0, r, 0.0), comp, nu)
        if fails is None:
            return False
        if any(np.count_nonzero(comp == c) * top.dim > COMPONENT_RICCATI_MAX_ND for c in fails):
            return False
        for c in sorted(fails):
            if time.perf_counter() > deadline:
                return False
            if c not in searches:
                searches[c] = component_riccati(des, comp, c)
            search, m = searches[c]
            if search(0.0, np.full(m, r), deadline) is None:
                return False
        return True

    if prove_lo and not proven(lo):
        return None
    a, b = lo, hi
    for _ in range(3):
        if time.perf_counter() > deadline:
            break
        mid = 0.5 * (a + b)
        if proven(mid):
            a = mid
        else:
            b = mid
    return a


def robust_scale(des: ProtocolDesign, radius: float, seconds_budget: float = 60.0) -> RobustReport:
    """The decay and margin brackets of a big design (module docstring), sparse.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    radius : float
        ρ for every edge without an ``uncertainty:`` of its own.
    seconds_budget : float, optional
        The margin bisection stops past this time (the bracket is then wider).

    Returns
    -------
    RobustReport
        With ``proofs`` empty (nothing to re-check from a file at this size).
    """
    t0 = time.perf_counter()
    top = des.topology
    ncomp, comp = _components(top)
    rad = _edge_radii(des, radius)
    ea = top.edge_arrays
    nominal = rate_estimate(_diag_blocks(des, np.ones(rad.size)), comp, ncomp)[0]
    nu = _norm_bounds(des)  # ν_e do not depend on ρ: proven once for every radius below
    a_lo = proven_rate(des, rad, comp, nu)
    best: tuple[float, np.ndarray | None] = (math.inf, None)
    for sgn in (-1.0, 1.0):
        fac = 1.0 + sgn * rad
        est = rate_estimate(_diag_blocks(des, fac), comp, ncomp)[0]
        if est < best[0]:
            best = (est, fac)
    ed = uncertain_edges(top)
    order = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(ea.rows, ea.cols, strict=True))}
    real = None
    if best[1] is not None and math.isfinite(best[0]):
        fac = best[1]
        w = np.array(
            [
                fac[order[(int(i), int(j))]] * ea.w[order[(int(i), int(j))]]
                for i, j in zip(ed.dst, ed.src, strict=True)
            ]
        ).reshape(ed.w.shape)
        real = Realisation(float(np.max(rad, initial=0.0)), w, best[0])
    decay = Bracket(
        a_lo,
        None if real is None else real.value,
        real,
        "lower",
        "block diagonal dominance per strongly connected component (Feingold–Varga) with "
        "μ_i from (1 − ρ)|A| and ν from (1 + ρ)‖A‖; upper: ARPACK/dense estimate on every "
        "weight scaled by 1 ∓ ρ",
    )
    # margin: the largest uniform ρ with a proven α >= 0
    lo, hi = 0.0, 1.0
    proven0 = proven_rate(des, np.zeros_like(rad), comp, nu) is not None
    if proven0:
        for _ in range(MARGIN_STEPS):
            if time.perf_counter() - t0 > seconds_budget:
                break
            mid = 0.5 * (lo + hi)
            if proven_rate(des, np.where(ea.sign != 0, mid, 0.0), comp, nu) is not None:
                lo = mid
            else:
                hi = mid
    informed_all = len(des.B) == top.n
    destab = None
    if not informed_all:
        destab = Realisation(1.0, np.zeros_like(ed.w), 0.0)
    how = "block diagonal dominance at α = 0, bisection on ρ"
    if lo < 0.5 and top.nd > RICCATI_MAX_ND:  # more than 2× below ρ = 1, or none
        # the components dominance cannot prove, by the Riccati search on their own blocks
        better = _riccati_margin(des, comp, nu, lo, 1.0, t0 + seconds_budget, not proven0)
        if better is not None and (better > lo or not proven0):
            lo, proven0 = better, True
            how = (
                "block diagonal dominance at α = 0, and the Riccati search on the strongly "
                f"connected components it does not prove (up to Nd = {COMPONENT_RICCATI_MAX_ND} "
                "each; proven by verified Cholesky), bisection on ρ"
            )
    margin = Bracket(
        lo if proven0 else None,
        None if destab is None else 1.0,
        destab,
        "lower",
        how + "; upper: every weight vanishing at ρ = 1 (an uninformed agent then has a "
        "zero block)",
    )
    off_hi = proven_offset(des, rad, nu) if a_lo is not None else None
    got = _offset_realisation(des, rad)
    off_real = None
    if got is not None:
        val, fac = got
        w = np.array(
            [
                fac[order[(int(i), int(j))]] * ea.w[order[(int(i), int(j))]]
                for i, j in zip(ed.dst, ed.src, strict=True)
            ]
        ).reshape(ed.w.shape)
        off_real = Realisation(float(np.max(rad, initial=0.0)), w, val)
    offset = Bracket(
        None if off_real is None else off_real.value,
        off_hi,
        off_real,
        "upper",
        "comparison with the block dominance matrix (M⁻¹ >= 0) on the equilibrium "
        "equation; lower: antagonistic weights scaled by 1 ∓ ρ, sparse LU",
    )
    return RobustReport(
        des,
        float(np.max(rad, initial=0.0)),
        tuple(rad[ea.sign != 0][np.lexsort((ea.cols[ea.sign != 0], ea.rows[ea.sign != 0]))]),
        float(nominal),
        decay,
        offset,
        margin,
        {},
        time.perf_counter() - t0,
    )


__all__ = [
    "COMPONENT_RICCATI_MAX_ND",
    "component_riccati",
    "dominance_failures",
    "proven_rate",
    "robust_scale",
]
