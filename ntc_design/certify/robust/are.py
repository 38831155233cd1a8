"""Robust decay and margin by a Riccati equation, for networks past the robust LMI's size.

The robust LMI of :mod:`.robust` (P and one multiplier τ_e per edge) costs 2.4 s at
Nd = 36 and 92 s at Nd = 75, and the sparse block dominance of :mod:`.robust_scale` is
conservative. Between the two (``ROBUST_MAX_ND < Nd <= RICCATI_MAX_ND``) the same
quadratic-stability argument is searched in another way. With F_e = W_e^{1/2} and
Δ_e = F_e E F_e, ‖E‖ <= ρ_e, Young's inequality gives for every realisation
``2xᵀP E_i Δ_e D_eᵀx >= −τ_e ρ_e² xᵀD_e W_e D_eᵀx − xᵀP E_i W_e E_iᵀ P x / τ_e``, so

    M(P, τ) = P S + Sᵀ P − Q(τ) − P R(τ) P ≻ 0,   S = L_B − αI,
    Q(τ) = Σ_e τ_e ρ_e² D_e W_e D_eᵀ,   R(τ) = Σ_e E_i W_e E_iᵀ / τ_e,

with P ≻ 0 and τ > 0 proves ``min Re λ(L_B(A')) > α`` for every A' in the set (the
Schur complement of the LMI's Ψ). For fixed τ, M ≻ 0 is a Riccati inequality, solvable iff
the Hamiltonian of ``AᵀP + PA + PRP + Q = 0`` (A = −S) has no imaginary eigenvalue (the
bounded-real lemma; Zhou, Doyle & Glover, *Robust and Optimal Control*, 1996, §13.2); its
stabilising solution with Q + εI is taken. τ is then re-balanced for that P (on the
eigenvectors of M's smallest eigenvalues each τ_e equalises its two terms), and the two
steps alternate, as in D–K iteration, until M ≻ 0 is found or the equation has no
solution. The proof is checked rigorously in the process: P ≻ 0 and M ≻ 0 by Rump's
verified Cholesky on the floating-point M with an entrywise bound on its rounding error
(Higham, *Accuracy and Stability of Numerical Algorithms*, 2002, §3.5), L_B's own
rounding included; ``ntc verify`` re-checks a certificate's (P, τ) the same way.
"""

from __future__ import annotations

import time

import numpy as np

from ...rigorous.exact import gamma, verified_float_pd, within_span
from .problem import UncertainEdges

#: Past the robust LMI's size and up to here, decay and margin are proven by the Riccati
#: search (each equation is a 2Nd-dimensional Schur decomposition: 0.6 s at Nd = 150).
RICCATI_MAX_ND = 200
ROUNDS = 8  # Riccati solves per tested α (most succeed in one or two)
EPS = 1e-4  # Q + ε·tr(Q)/n·I in the equation: a margin that survives the rounding

_U = 2.0**-53


def edge_sum(
    n: int,
    d: int,
    ends: tuple[np.ndarray, np.ndarray, np.ndarray],
    w: np.ndarray,
    coef: np.ndarray,
    absolute: bool = False,
) -> np.ndarray:
    """Σ_e coef_e D_e W_e D_eᵀ (D_e = E_i − s_e E_j); with ``absolute``, the same sum of
    |coef_e|·|D_e| |W_e| |D_e|ᵀ, the magnitude its rounding bound needs.

    Parameters
    ----------
    n : int
        Nd.
    d : int
        d.
    ends : (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        Row offsets i·d and j·d of each edge's ends, and its sign s_e (0 for an edge
        whose source lies outside the matrix: D_e = E_i).
    w : numpy.ndarray
        W_e, (m, d, d).
    coef : numpy.ndarray
        The coefficients.
    absolute : bool, optional
        The magnitude instead.

    Returns
    -------
    numpy.ndarray
    """
    i_, j_, s_ = ends
    q = np.zeros((n, n))
    for e in range(w.shape[0]):
        c = abs(coef[e]) * np.abs(w[e]) if absolute else coef[e] * w[e]
        i, j, se = i_[e], j_[e], float(s_[e])
        off = abs(se) * c if absolute else -se * c
        q[i : i + d, i : i + d] += c
        if se:  # s_e = 0: an edge from outside a block (D_e = E_i)
            q[j : j + d, j : j + d] += c
            q[i : i + d, j : j + d] += off
            q[j : j + d, i : i + d] += off
    return q


class RiccatiSearch:
    """The Riccati search and its rigorous check for one network (dense).

    Parameters
    ----------
    lap : numpy.ndarray
        L_B in floating point (:func:`ntc_design.certify.dense.lap_b_float`).
    lap_err : numpy.ndarray
        An entrywise bound on |L_B exact − lap|.
    edges : UncertainEdges
        The uncertain edges (|A_e|, signs, ends).
    dim : int
        d.
    """

    def __init__(self, lap: np.ndarray, lap_err: np.ndarray, edges: UncertainEdges, dim: int):
        self.lap, self.lap_err, self.d = lap, lap_err, dim
        self.n, self.m = lap.shape[0], edges.m
        self.i = edges.dst.astype(int) * dim
        self.j = edges.src.astype(int) * dim
        self.s = edges.s.astype(float)
        self.w = edges.channel_w  # W̄_e (robust.channel_bound)
        self.wabs = np.abs(self.w)

    def _q(self, tau: np.ndarray, rad2: np.ndarray, absolute: bool = False) -> np.ndarray:
        """Σ τ_e ρ_e² D_e W_e D_eᵀ; with ``absolute``, its magnitude (for the error bound)."""
        ends = (self.i, self.j, self.s)
        return edge_sum(self.n, self.d, ends, self.w, tau * rad2, absolute)

    def _r(self, tau: np.ndarray, w: np.ndarray, rad: np.ndarray) -> np.ndarray:
        """Σ E_i W_e E_iᵀ / τ_e (block diagonal) over the edges with ρ_e > 0, with W
        replaced by ``w`` (an edge of radius 0 is not perturbed: it needs no Young term)."""
        n, d = self.n, self.d
        r = np.zeros((n, n))
        for e in range(self.m):
            if rad[e] > 0:
                i = self.i[e]
                r[i : i + d, i : i + d] += w[e] / tau[e]
        return r

    def schur(self, pm: np.ndarray, tau: np.ndarray, alpha: float, rad: np.ndarray) -> np.ndarray:
        """M(P, τ) in floating point.

        Parameters
        ----------
        pm : numpy.ndarray
            P (symmetric).
        tau : numpy.ndarray
            τ_e > 0.
        alpha : float
            α.
        rad : numpy.ndarray
            ρ_e per edge.

        Returns
        -------
        numpy.ndarray
        """
        sh = self.lap - alpha * np.eye(self.n)
        ps = pm @ sh
        m = ps + ps.T - self._q(tau, rad**2) - pm @ self._r(tau, self.w, rad) @ pm
        return 0.5 * (m + m.T)

    def proven(self, pm: np.ndarray, tau: np.ndarray, alpha: float, rad: np.ndarray) -> bool:
        """Whether P ≻ 0, τ > 0 and M(P, τ) ≻ 0 hold exactly for these floats (the
        rounding of every product and sum bounded entrywise, then Rump's test).

        Parameters
        ----------
        pm : numpy.ndarray
            P; it must be exactly symmetric.
        tau : numpy.ndarray
            τ_e.
        alpha : float
            α.
        rad : numpy.ndarray
            ρ_e per edge.

        Returns
        -------
        bool
        """
        n = self.n
        if not (np.all(tau > 0) and np.all(np.isfinite(tau)) and np.array_equal(pm, pm.T)):
            return False
        if not np.all(np.asarray(rad) >= 0):
            return False
        if not within_span(pm, tau, rad, np.array([alpha]), self.w, self.lap, self.lap_err):
            return False  # the relative rounding bounds below assume no underflow/overflow
        if not verified_float_pd(pm, np.zeros_like(pm)).holds:
            return False
        sh = self.lap - alpha * np.eye(n)
        ash = np.abs(sh) * (1.0 + _U)  # the diagonal's subtraction rounded
        ap = np.abs(pm)
        ps = pm @ sh
        t1 = ps + ps.T
        e_l = ap @ self.lap_err  # L_B's own rounding (the exact L_B is the subject)
        x = ap @ ash  # not symmetric: the error of ps + psᵀ is bounded by x + xᵀ
        e_t1 = gamma(n + 2) * (x + x.T) + e_l + e_l.T + _U * np.abs(t1)
        rad2 = rad**2  # its rounding is inside e_q's γ
        q = self._q(tau, rad2)
        e_q = gamma(self.m + 6) * self._q(tau, rad2, absolute=True)
        r = self._r(tau, self.w, rad)
        e_r = gamma(self.m + 2) * self._r(tau, self.wabs, rad)
        prp = pm @ r @ pm
        e_prp = gamma(2 * n + 2) * (ap @ np.abs(r) @ ap) + ap @ e_r @ ap
        m = t1 - q - prp
        err = e_t1 + e_q + e_prp + 2.0 * _U * (np.abs(t1) + np.abs(q) + np.abs(prp))
        err = err * (1.0 + 4.0 * gamma(2 * n + 8))  # the bound's own rounding
        return bool(verified_float_pd(m, err).holds)

    def _rebalance(self, pm, tau, alpha, rad, iters: int = 10):
        """τ for this P: on the eigenvectors of M's two smallest eigenvalues, each τ_e
        equalises τ ρ² ‖D_eᵀv‖²_W and ‖E_iᵀPv‖²_W / τ (damped, in logarithms)."""
        d = self.d
        best, best_tau = -np.inf, tau
        rad2 = rad**2
        for _ in range(iters):
            lam, vec = np.linalg.eigh(self.schur(pm, tau, alpha, rad))
            score = lam[0] / np.trace(pm)
            if score > best:
                best, best_tau = score, tau.copy()
            v, wt = vec[:, :2], np.array([1.0, 0.5])
            pv = pm @ v
            va = np.zeros(self.m)
            vb = np.zeros(self.m)
            for e in range(self.m):
                i, j, s, w = self.i[e], self.j[e], self.s[e], self.w[e]
                dv = v[i : i + d] - s * v[j : j + d]
                a = pv[i : i + d]
                va[e] = rad2[e] * np.sum(wt * np.einsum("ak,ab,bk->k", dv, w, dv))
                vb[e] = np.sum(wt * np.einsum("ak,ab,bk->k", a, w, a))
            new = np.sqrt(np.maximum(vb, 1e-300) / np.maximum(va, 1e-300))
            new = np.where(rad2 > 0, new, tau)  # an unperturbed edge keeps its τ: unused
            tau = np.exp(0.5 * np.log(tau) + 0.5 * np.log(new))
        return best, best_tau

    def _riccati(self, tau, alpha, rad) -> np.ndarray | None:
        import scipy.linalg as sla

        n = self.n
        a = -(self.lap - alpha * np.eye(n))
        q = self._q(tau, rad**2)
        r = self._r(tau, self.w, rad)
        lam, u = np.linalg.eigh(r)
        keep = lam > 1e-12 * max(float(lam.max(initial=0.0)), 1e-300)
        b = u[:, keep] * np.sqrt(lam[keep])
        q = q + EPS * max(float(np.trace(q)), 1e-300) / n * np.eye(n)
        try:  # Aᵀ P + P A + P R P + Q = 0: scipy's form with B r⁻¹ Bᵀ = −R
            pm = sla.solve_continuous_are(a, b, q, -np.eye(b.shape[1]))
        except (np.linalg.LinAlgError, ValueError):
            return None  # imaginary Hamiltonian eigenvalues: no P for this τ
        pm = 0.5 * (pm + pm.T)
        return pm if np.all(np.isfinite(pm)) else None

    def __call__(
        self, alpha: float, radius, deadline: float | None = None
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """P, τ proving decay rate α at the radii (rigorously checked), or None.

        Parameters
        ----------
        alpha : float
            α (0 for Hurwitz alone).
        radius : float or numpy.ndarray
            ρ, or ρ_e per edge.
        deadline : float, optional
            A ``time.perf_counter()`` value: no new Riccati solve starts after it (None:
            the ROUNDS solves at most).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray) or None
        """
        import scipy.linalg as sla

        rad = np.broadcast_to(np.asarray(radius, dtype=float), (self.m,)).copy()
        n = self.n
        sh = self.lap - alpha * np.eye(n)
        if float(np.min(np.linalg.eigvals(sh).real)) <= 0:
            return None  # not even the nominal network decays at α
        pm = sla.solve_continuous_lyapunov(sh.T, np.eye(n))
        pm = 0.5 * (pm + pm.T)
        if self.m == 0:
            return (pm, np.zeros(0)) if self.proven(pm, np.zeros(0), alpha, rad) else None
        score, tau = self._rebalance(pm, np.ones(self.m), alpha, rad)
        for _ in range(ROUNDS):
            if score > 0 and self.proven(pm, tau, alpha, rad):
                return pm, tau
            if deadline is not None and time.perf_counter() > deadline:
                return None
            nxt = self._riccati(tau, alpha, rad)
            if nxt is None:
                return None
            pm = nxt
            score, tau = self._rebalance(pm, tau, alpha, rad)
        return (pm, tau) if score > 0 and self.proven(pm, tau, alpha, rad) else None


__all__ = ["RICCATI_MAX_ND", "RiccatiSearch", "edge_sum"]
