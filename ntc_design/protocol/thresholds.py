"""Exact critical couplings of the Lemma 1 design family (beyond the paper).

The family is ``L_B(δ) = L + δ·D`` with ``D = blockdiag(B_i)`` (``B_i = 0`` for naive
agents): informed agents V_I = U and the B_i are fixed, the common coupling δ > 0 varies.

* ``δ_H = inf{δ0 >= 0 : -L_B(δ) is Hurwitz for every δ > δ0}``. Candidate crossing points
  are the δ at which ``L + δD`` has an eigenvalue on the imaginary axis, i.e. the real
  positive roots of ``det((L⊕L) + δ(D⊕D)) = 0`` (λ_i + λ_j = 0 covers both 0 and ±iω);
  the Hurwitz property is constant between consecutive candidates. Each boundary is then
  refined by Brent's method on the spectral abscissa ``α(δ) = max Re λ(-L_B(δ))``, which
  is continuous in δ. Above ``KRON_MAX`` (Nd) the Kronecker pencil is too large and a
  logarithmic scan of α(δ) is used instead (stated in ``method``).
* ``δ_S = inf{δ : L_B + L_Bᵀ ≻ 0}``: ``λ_min((L+Lᵀ) + 2δD)`` is concave and
  non-decreasing in δ (D ⪰ 0), so the set is one ray; found by Brent's method.
* ``best_rate = max_δ -α(δ)`` and the δ reaching it (grid + bounded refinement in log δ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..numerics.linalg import DenseRefused, SPDFamily, require_sparse_factor
from ..numerics.roots import brent_root
from ..present.rows import counted

KRON_MAX = 40
REL = 1e-12


@dataclass(frozen=True)
class CriticalCouplings:
    """The critical couplings of the design family L + δD: δ_H with the Hurwitz set, δ_S,
    the best decay rate and its δ, and how they were computed."""

    hurwitz: float | None  # δ_H; None when no δ makes -L_B Hurwitz for all larger δ
    hurwitz_intervals: tuple[tuple[float, float], ...]  # the Hurwitz set, (lo, hi) with hi=inf
    symmetric: float | None  # δ_S; None when no δ gives L_B + L_Bᵀ ≻ 0
    best_rate: float
    best_rate_delta: float | None  # None: approached as δ → ∞, not attained (or no δ acts)
    method: str
    notes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        """The couplings as a JSON-ready mapping.

        Returns
        -------
        dict
            ``hurwitz``, ``hurwitz_intervals`` (an open end as None), ``symmetric``,
            ``best_rate``, ``best_rate_delta``, ``method`` and ``notes``.
        """
        return {
            "hurwitz": self.hurwitz,
            "hurwitz_intervals": [
                [lo, None if math.isinf(hi) else hi] for lo, hi in self.hurwitz_intervals
            ],
            "symmetric": self.symmetric,
            "best_rate": self.best_rate,
            "best_rate_delta": self.best_rate_delta,
            "method": self.method,
            "notes": list(self.notes),
        }


def spectral_abscissa(lap: np.ndarray, d: np.ndarray, delta: float) -> float:
    """The spectral abscissa of −L_B(δ).

    Parameters
    ----------
    lap : numpy.ndarray
        L, Nd×Nd.
    d : numpy.ndarray
        D = blockdiag(B_i), Nd×Nd.
    delta : float
        δ.

    Returns
    -------
    float
        ``α(δ) = max Re λ(-(L + δD))``; −L_B(δ) is Hurwitz iff α(δ) < 0.
    """
    return float(-np.min(np.linalg.eigvals(lap + delta * d).real))


def _kron_candidates(lap: np.ndarray, d: np.ndarray) -> np.ndarray:
    n = lap.shape[0]
    eye = np.eye(n)
    k = np.kron(lap, eye) + np.kron(eye, lap)
    m = np.kron(d, eye) + np.kron(eye, d)
    # det(K + δM) = 0  <=>  K v = δ (-M) v
    ab = sla.eigvals(k, -m, homogeneous_eigvals=True)
    alpha, beta = ab[0], ab[1]
    scale = np.linalg.norm(k, 1) + np.linalg.norm(m, 1)
    ok = np.abs(beta) > 1e-13 * np.maximum(np.abs(alpha), 1e-300)
    ok &= ~((np.abs(alpha) < 1e-12 * scale) & (np.abs(beta) < 1e-12 * scale))
    w = alpha[ok] / beta[ok]
    w = np.sort(w[np.abs(w.imag) <= 1e-6 * np.maximum(1.0, np.abs(w))].real)
    w = w[w > 0]
    # λ_i + λ_j = 0 and λ_j + λ_i = 0 give the same root twice: merge near-equal roots.
    keep = np.concatenate([[True], np.diff(w) > 1e-8 * w[1:]]) if w.size else w.astype(bool)
    return w[keep]


def hurwitz_set(
    lap: np.ndarray, d: np.ndarray, notes: list[str], kron: bool = True
) -> tuple[list[tuple[float, float]], float | None, str]:
    """The Hurwitz set {δ > 0 : −(L + δD) Hurwitz} as intervals, δ_H and the method (see
    the module docstring); ``D ≠ 0``. Notes are appended to ``notes``. ``kron=False``
    uses the logarithmic scan at every size (cheaper for many small components).

    Parameters
    ----------
    lap : numpy.ndarray
        L, Nd×Nd.
    d : numpy.ndarray
        D = blockdiag(B_i), non-zero.
    notes : list of str
        Receives notes on the computation.
    kron : bool, optional
        Use the Kronecker pencil up to ``KRON_MAX``.

    Returns
    -------
    tuple
        (intervals (lo, hi) with hi = inf for the last, δ_H or None, method).
    """
    n = lap.shape[0]
    nl = max(float(np.linalg.norm(lap, 2)), 1e-300)
    ndn = np.linalg.norm(d, 2)
    scale = float(nl / ndn)
    alpha = lambda x: spectral_abscissa(lap, d, x)  # noqa: E731
    if kron and n <= KRON_MAX:
        # Roots at δ ≈ 0 are the singular L itself, perturbed by rounding: not crossings.
        cands = _kron_candidates(lap, d)
        cands = cands[cands > 1e-9 * scale]
        method = "kronecker-pencil"
        edges = np.concatenate([[0.0], cands, [2.0 * cands[-1] if cands.size else 2.0 * scale]])
        test = 0.5 * (edges[:-1] + edges[1:])
    else:
        method = "log-scan"
        if kron:
            notes.append(f"Nd={n} > {KRON_MAX}: crossings found by a logarithmic scan of α(δ)")
        test = scale * np.logspace(-6, 4, 161)
    alphas = np.array([alpha(x) for x in test])
    hurw = alphas < -REL * (nl + test * ndn)

    def root(a: float, b: float) -> float:
        fa, fb = alpha(a), alpha(b)
        if fa * fb > 0:
            return b
        return brent_root(alpha, a, b, xtol=1e-15 * b, rtol=4 * np.finfo(float).eps, maxiter=200)

    intervals: list[tuple[float, float]] = []
    k = 0
    while k < len(test):
        if not hurw[k]:
            k += 1
            continue
        lo = 0.0 if k == 0 else root(test[k - 1], test[k])
        m = k
        while m + 1 < len(test) and hurw[m + 1]:
            m += 1
        hi = math.inf if m == len(test) - 1 else root(test[m], test[m + 1])
        intervals.append((lo, hi))
        k = m + 1
    if intervals and math.isinf(intervals[-1][1]):
        delta_h: float | None = intervals[-1][0]
    else:
        delta_h = None
        notes.append("-L_B is not Hurwitz for large δ: no δ_H exists")
    if len(intervals) > 1:
        notes.append(
            "the Hurwitz set is not one interval: "
            + ", ".join(f"({lo:.6g}, {hi:.6g})" for lo, hi in intervals)
        )

    return intervals, delta_h, method


def critical_couplings(lap: np.ndarray, d: np.ndarray) -> CriticalCouplings:
    """Critical couplings of ``L + δD`` over δ > 0 (see the module docstring).

    Parameters
    ----------
    lap : numpy.ndarray
        L, Nd×Nd, dense.
    d : numpy.ndarray
        D = blockdiag(B_i), Nd×Nd.

    Returns
    -------
    CriticalCouplings
        δ_H, δ_S and the best rate.
    """
    notes: list[str] = []
    nl = max(float(np.linalg.norm(lap, 2)), 1e-300)
    ndn = np.linalg.norm(d, 2)
    if ndn == 0.0:
        a0 = spectral_abscissa(lap, d, 1.0)
        hur = a0 < -REL * nl
        if abs(a0) <= REL * nl:  # no informed agent: L(1⊗v) = 0, the rate is 0 (not ±1e-16)
            a0 = 0.0
        notes.append(
            "no informed agent: L_B = L does not depend on δ, so no δ changes the decay "
            "rate; an antagonistic edge (A_ij negative definite) into an agent makes it "
            "informed"
        )
        return CriticalCouplings(
            0.0 if hur else None,
            ((0.0, math.inf),) if hur else (),
            0.0 if np.linalg.eigvalsh(lap + lap.T)[0] > REL * nl else None,
            -a0,
            None,
            "constant",
            tuple(notes),
        )
    scale = float(nl / ndn)
    alpha = lambda x: spectral_abscissa(lap, d, x)  # noqa: E731
    intervals, delta_h, method = hurwitz_set(lap, d, notes)

    # δ_S: λ_min((L+Lᵀ) + 2δD) is non-decreasing in δ.
    s0 = lap + lap.T
    g = lambda x: float(np.linalg.eigvalsh(s0 + 2 * x * d)[0])  # noqa: E731
    stol = REL * np.linalg.norm(s0, 2)
    if g(0.0) > stol:
        delta_s: float | None = 0.0
    else:
        w, v = np.linalg.eigh(d)
        z = v[:, w <= 1e-10 * ndn]
        if z.shape[1] and np.linalg.eigvalsh(z.T @ s0 @ z)[0] <= stol:
            delta_s = None
            notes.append("L_B + L_Bᵀ is not positive definite for any δ")
        else:
            hi = scale
            while g(hi) <= 0 and hi < 1e300:
                hi *= 2
            delta_s = brent_root(
                g, 0.0, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps, maxiter=100
            )

    best_rate, best_delta = _best_rate(alpha, scale, notes, rate_limit(lap, d))
    return CriticalCouplings(
        delta_h, tuple(intervals), delta_s, best_rate, best_delta, method, tuple(notes)
    )


def rate_limit(lap: np.ndarray, d: np.ndarray) -> float:
    """The decay rate's limit as δ → ∞: the eigenvalues of L + δD that stay bounded tend
    to those of ZᵀLZ, Z an orthonormal basis of ker D (first-order perturbation of the
    semisimple zero eigenvalue of the symmetric D ⪰ 0), the others to +∞.

    Parameters
    ----------
    lap : numpy.ndarray
        L, Nd×Nd.
    d : numpy.ndarray
        D = blockdiag(B_i) ⪰ 0, Nd×Nd.

    Returns
    -------
    float
        ``min Re λ(ZᵀLZ)``; +∞ when D ≻ 0 (every direction is coupled: the rate grows
        without bound).
    """
    w, v = np.linalg.eigh(0.5 * (d + d.T))
    z = v[:, w <= 1e-10 * max(float(np.abs(w).max(initial=0.0)), 1e-300)]
    if not z.shape[1]:
        return math.inf
    return float(np.min(np.linalg.eigvals(z.T @ lap @ z).real))


def _best_rate(
    alpha, scale: float, notes: list[str], limit: float = math.inf
) -> tuple[float, float | None]:
    """max over δ > 0 of the decay rate r(δ) = -α(δ), and the smallest δ reaching it.

    r is evaluated on a log grid; a maximum at the grid's end means r still grows (its
    supremum is approached as δ → ∞), as is a maximum below the limit ``limit`` of r as
    δ → ∞ (:func:`rate_limit`); a plateau (r within 1e-9 of its maximum on neighbouring
    points) is reported at its start, found by bisection in log δ, unless r still rises
    towards its limit beyond that start: then the supremum is the limit, approached as
    δ → ∞ and not attained (reported with no δ)."""
    grid = scale * np.logspace(-6, 4, 161)
    rates = np.array([-alpha(x) for x in grid])
    rmax = float(rates.max())
    tol = 1e-9 * max(1.0, abs(rmax))
    k = int(np.argmax(rates >= rmax - tol))

    def asymptote() -> tuple[float, None]:
        if math.isfinite(limit):
            sup = max(limit, rmax)
            notes.append(
                f"the decay rate approaches {sup:.6g} as δ → ∞ (not attained: "
                f"{sup - float(rates[-1]):.2g} below it at δ = {grid[-1]:.3g})"
            )
            return sup, None
        notes.append(
            f"the decay rate grows without bound as δ → ∞ (every direction is coupled); "
            f"at δ = {grid[-1]:.3g} it is {float(rates[-1]):.6g}"
        )
        return rmax, None

    if k == len(grid) - 1 or limit > rmax + tol:  # still rising, or heading higher
        return asymptote()
    if k > 0 and rates[k + 1] >= rmax - tol:
        lo, hi = math.log(grid[k - 1]), math.log(grid[k])
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if -alpha(math.exp(mid)) >= rmax - tol else (mid, hi)
        start = math.exp(hi)
        # a plateau stays at its value past its start; an asymptote still rises there
        # (by about tol/2 at twice the start for a 1/δ approach, tol/8 for 1/δ³)
        if -alpha(2.0 * start) < limit - tol / 16:
            return asymptote()
        notes.append(
            f"the decay rate reaches its maximum {rmax:.6g} at δ ≈ {start:.6g} and stays there"
        )
        return rmax, start
    if k == 0:
        return rmax, float(grid[0])
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(
        lambda u: alpha(math.exp(u)),
        bounds=(math.log(grid[k - 1]), math.log(grid[k + 1])),
        method="bounded",
        options={"xatol": 1e-10},
    )
    if -res.fun >= rmax:
        return float(-res.fun), math.exp(res.x)
    return rmax, float(grid[k])


#: A strongly connected component up to this Nd gets its Hurwitz set from the dense
#: method (:func:`hurwitz_set`); larger components are reported as not computed.
COMPONENT_DENSE_MAX_ND = 120
#: δ_S by bisection stops at this relative bracket width.
BISECT_RTOL = 1e-4


def _intersect(a: list[tuple[float, float]], b: list[tuple[float, float]]):
    out = []
    for lo1, hi1 in a:
        for lo2, hi2 in b:
            lo, hi = max(lo1, lo2), min(hi1, hi2)
            if lo < hi:
                out.append((lo, hi))
    return sorted(out)


def strong_components(lap, dim: int) -> tuple[int, np.ndarray]:
    """Strongly connected components of the agent graph of a block matrix (an agent
    edge j -> i wherever the block (i, j) is non-zero): ``(count, label per agent)``,
    labels numbered in a topological order of the condensation (sources first).

    Parameters
    ----------
    lap : scipy.sparse matrix
        A block matrix, Nd×Nd.
    dim : int
        The block size d.

    Returns
    -------
    tuple of (int, numpy.ndarray)
        The number of components and each agent's component.
    """
    from scipy.sparse import csgraph, csr_matrix

    n = lap.shape[0] // dim
    c = lap.tocoo()
    r, k = c.row // dim, c.col // dim
    off = (r != k) & (c.data != 0)
    g = csr_matrix((np.ones(int(off.sum()), dtype=np.int8), (k[off], r[off])), shape=(n, n))
    ncomp, lab = csgraph.connected_components(g, directed=True, connection="strong")
    # order the condensation topologically (Kahn on the component DAG)
    cr, cc = lab[k[off]], lab[r[off]]
    keep = cr != cc
    dag = csr_matrix(
        (np.ones(int(keep.sum()), dtype=np.int8), (cr[keep], cc[keep])), shape=(ncomp, ncomp)
    )
    dag.sum_duplicates()
    indeg = np.diff(dag.tocsc().indptr)
    order = np.empty(ncomp, dtype=np.int64)
    front = list(np.flatnonzero(indeg == 0))
    indeg = indeg.copy()
    pos = 0
    indptr, indices = dag.indptr, dag.indices
    while front:
        nxt = []
        for u in front:
            order[pos] = u
            pos += 1
            for w in indices[indptr[u] : indptr[u + 1]]:
                indeg[w] -= 1
                if indeg[w] == 0:
                    nxt.append(w)
        front = nxt
    rank = np.empty(ncomp, dtype=np.int64)
    rank[order] = np.arange(ncomp)
    return ncomp, rank[lab]


def diagonal_blocks(a, dim: int) -> np.ndarray:
    """The d×d diagonal blocks of a sparse block matrix.

    Parameters
    ----------
    a : scipy.sparse matrix
        Nd×Nd.
    dim : int
        The block size d.

    Returns
    -------
    numpy.ndarray
        Shape (N, d, d).
    """
    n = a.shape[0] // dim
    c = a.tocoo()
    m = c.row // dim == c.col // dim
    out = np.zeros((n, dim, dim))
    np.add.at(out, (c.row[m] // dim, c.row[m] % dim, c.col[m] % dim), c.data[m])
    return out


def critical_couplings_sparse(lap, d, dim: int) -> CriticalCouplings:
    """Critical couplings of ``L + δD`` for big networks (sparse L, D), saying what was
    computed and how (``method``, ``notes``).

    * δ_H per strongly connected component: in a topological order of the condensation
      L + δD is block triangular, so −(L + δD) is Hurwitz iff every diagonal block is,
      and the Hurwitz set is the intersection of the blocks' sets. A one-agent block
      ``L_ii + δB_i`` is symmetric with ``L_ii, B_i ⪰ 0``: it is PD for every δ > 0 iff
      ``L_ii + B_i ≻ 0`` and for none otherwise (batched eigenvalues). Components up to
      ``COMPONENT_DENSE_MAX_ND`` use :func:`hurwitz_set` (log-scan); a larger one is not computed
      (δ_H is then None and a note says so).
    * δ_S by bisection on the monotone ``λ_min(L + Lᵀ + 2δD)``: each step is one sparse
      Cholesky factorisation (CHOLMOD) of ``L + Lᵀ + 2δD − τI`` with τ = 1e-12·‖·‖_∞;
      bracket width ``BISECT_RTOL`` (δ_S is the upper end: L_B + L_Bᵀ ≻ 0 there).
    * The best decay rate is not computed (it needs the whole spectrum): NaN, with a note.

    Parameters
    ----------
    lap : scipy.sparse matrix
        L, Nd×Nd.
    d : scipy.sparse matrix
        D = blockdiag(B_i), Nd×Nd.
    dim : int
        The block size d.

    Returns
    -------
    CriticalCouplings
        δ_H (None when a component is too large), δ_S and the notes.
    """
    notes: list[str] = []
    ncomp, comp = strong_components(lap, dim)
    sizes = np.bincount(comp, minlength=ncomp)
    intervals, skipped = _component_hurwitz_sets(lap, d, dim, comp, sizes, notes)
    method = (
        f"per strongly connected component ({counted(ncomp, 'component')}, largest "
        f"{counted(int(sizes.max()), 'agent')}; one-agent blocks exact, others by a dense log-scan of α(δ) "
        f"up to Nd = {COMPONENT_DENSE_MAX_ND}); δ_S by sparse-Cholesky bisection"
    )
    if skipped:
        delta_h: float | None = None
        notes.append(
            f"δ_H not computed: {len(skipped)} component(s) above Nd = "
            f"{COMPONENT_DENSE_MAX_ND} (largest Nd = {max(skipped)})"
        )
        intervals_out: tuple = ()
    else:
        intervals_out = tuple(intervals)
        if intervals and math.isinf(intervals[-1][1]):
            delta_h = intervals[-1][0]
        else:
            delta_h = None
            notes.append("-L_B is not Hurwitz for large δ: no δ_H exists")
    delta_s = _delta_s_sparse(lap, d, notes)
    notes.append("best decay rate not computed at this size (needs the whole spectrum)")
    return CriticalCouplings(delta_h, intervals_out, delta_s, math.nan, None, method, tuple(notes))


def _component_hurwitz_sets(lap, d, dim, comp, sizes, notes) -> tuple[list, list[int]]:
    """The δ for which −(L + δD) is Hurwitz, intersected over the strongly connected
    components (exact for one-agent blocks, a dense log-scan for components up to
    COMPONENT_DENSE_MAX_ND), and the Nd of the components too large to scan."""
    single = sizes[comp] == 1
    lb = diagonal_blocks(lap, dim)
    db = diagonal_blocks(d, dim)
    intervals: list[tuple[float, float]] = [(0.0, math.inf)]
    idx = np.flatnonzero(single)
    if idx.size:
        s = lb[idx] + db[idx]
        lam = np.linalg.eigvalsh(0.5 * (s + s.transpose(0, 2, 1)))
        tol = REL * np.maximum(np.abs(lam).max(axis=1), 1e-300)
        if np.any(lam[:, 0] <= tol):
            intervals = []
            bad = idx[np.argmax(lam[:, 0] <= tol)]
            notes.append(
                f"agent index {bad}: its diagonal block L_ii + δB_i is singular for every δ "
                "(nothing reaches it and it is not informed): −L_B is never Hurwitz"
            )
    skipped: list[int] = []
    lap_c, d_c = lap.tocsr(), d.tocsr()
    for c in np.flatnonzero(sizes > 1).tolist():
        if not intervals:
            break
        agents = np.flatnonzero(comp == c)
        nd_c = agents.size * dim
        if nd_c > COMPONENT_DENSE_MAX_ND:
            skipped.append(nd_c)
            continue
        ix = (agents[:, None] * dim + np.arange(dim)).ravel()
        lb_c = lap_c[ix][:, ix].toarray()
        db_c = d_c[ix][:, ix].toarray()
        sub_notes: list[str] = []
        if not np.any(db_c):
            hur = spectral_abscissa(lb_c, db_c, 1.0) < -REL * max(
                float(np.linalg.norm(lb_c, 2)), 1e-300
            )
            iv = [(0.0, math.inf)] if hur else []
        else:
            iv, _, _ = hurwitz_set(lb_c, db_c, sub_notes, kron=False)
        intervals = _intersect(intervals, iv)
    return intervals, skipped


def _delta_s_sparse(lap, d, notes: list[str]) -> float | None:
    """δ_S by bisection on λ_min(L + Lᵀ + 2δD), one sparse Cholesky per step; None (with a
    note) when it does not exist or would not fit."""
    s0 = (lap + lap.T).tocsr()
    dd = d.tocsr()
    ninf = float(abs(s0).sum(axis=1).max()) if s0.nnz else 0.0
    ndn = float(abs(dd).sum(axis=1).max()) if dd.nnz else 0.0
    tau = REL * max(ninf, 1e-300)
    fam = SPDFamily([s0, dd])

    def pos(x: float) -> bool:
        return fam.factor([1.0, 2.0 * x], tau)[0]

    try:  # about 50 factorisations: skipped with the reason rather than refusing the design
        require_sparse_factor(fam.fill, "δ_S", factorisations=50)
    except DenseRefused as exc:
        notes.append(f"δ_S not computed: the bisection needs about 50 factorisations; {exc}")
        return None
    if pos(0.0):
        return 0.0
    if ndn == 0.0:
        notes.append("no informed agent and L + Lᵀ is not positive definite: no δ_S")
        return None
    hi = ninf / ndn
    steps = 0
    while not pos(hi) and steps < 40:
        hi *= 4.0
        steps += 1
    if steps == 40:
        notes.append(f"L_B + L_Bᵀ is not positive definite for any δ up to {hi:.3g}")
        return None
    lo = hi / 4.0 if steps else 0.0
    while hi - lo > BISECT_RTOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if pos(mid) else (mid, hi)
    return hi
