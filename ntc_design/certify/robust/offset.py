"""The robust consensus offset past the LMI's size: the S-procedure of :mod:`.robust` with
the equation eliminated, so that the SDP has one multiplier per edge and no Finsler
multiplier to search.

**Channels by a gain.** For each edge pick G_e with ``G_e G_eᵀ ⪰ W_e`` (here
``U diag(√(σ + ε))`` from W_e's eigenpairs, ε = 10⁻¹² of its largest eigenvalue; the
inequality is proven for the floats G_e). For a realisation ``Δ_e = F E F`` (F = W_e^{1/2},
‖E‖ <= ρ_e) write ``Δ_e D_eᵀx = G_e s_e``: then ``‖s_e‖² = vᵀΔ(GGᵀ)⁻¹Δv <= vᵀF E² F v
<= ρ_e² xᵀ D_e W_e D_eᵀ x`` because ``F (GGᵀ)⁻¹ F ⪯ I``. The channels are well
conditioned whatever W_e's conditioning (its identity block is exact), unlike the pivot
columns, whose ``VᵀWV`` is singular to rounding when a weight is nearly singular.

**The bound.** With z = x* − 1⊗θ, c = 1⊗θ and r0 = u − L_B c, every realisation gives
``L_B z + Σ_e E_i G_e s_e = r0`` and ``‖s_e‖² <= ρ_e² (z + c)ᵀ D_e W_e D_eᵀ (z + c)``. On
ξ = (z, s, 1),

    Γ = γ e eᵀ − [I_z] − Σ_e λ_e (ρ_e² (z + c)ᵀ D_e W_e D_eᵀ (z + c) − ‖s_e‖²) + sym(Aᵀ Y) ≻ 0,

with A = [L_B, E_i G_e, −r0] and λ_e >= 0, proves ``‖z‖² <= γ`` for every realisation (the
S-procedure and Finsler's lemma; Boyd, El Ghaoui, Feron & Balakrishnan, 1994, §2.6), given
that every L_B(A') is invertible (the decay proof at the same radii). γ and λ come from the
reduced SDP ``γ e eᵀ − Nᵀ(...)N ⪰ 0`` on the null space N of A (size Σ rank + 1, one
variable per edge; CVXOPT); Y is then built from L_B⁻¹ so that ``TᵀΓT`` is block diagonal
(T = [[L_B⁻¹, −L_B⁻¹[G, −r0]], [0, I]]), and the floating-point Γ is proven positive
definite with every rounding bounded, L_B's and u's own included (Rump's verified Cholesky
after an exact power-of-two equilibration). Y and G are witnesses, not claims: ``ntc
verify`` rebuilds them from γ, λ and the subject, and proves Γ ≻ 0 again.
"""

from __future__ import annotations

import functools

import numpy as np

from ...rigorous.exact import gamma as gamma_k
from ...rigorous.exact import verified_float_pd, within_span
from ..dense import lap_b_float
from .are import edge_sum
from .lmi import load_cvxpy, solve_sdp
from .problem import UncertainEdges, uncertain_edges

#: The reduced SDP's matrix is Σ d + 1 square with one variable per edge; past this many
#: rows the interior-point solve grows past half a minute (2.9 s at 166 rows, 8.5 s at
#: 223; its cost grows about as E·r³).
OFFSET_MAX_ROWS = 300
GAIN_EPS = 1e-12  # G Gᵀ = W + ε·λ_max(W)·I: a margin that survives the rounding
#: The z block after the congruence, tried in turn: small values keep Y's large entries
#: (which cancel against Φ) small, so the rounding bound stays below the margin.
C0 = (1e-4, 1e-2, 1e-6, 1.0)
#: A small price on Σλ_e in the SDP: multipliers of edges that barely matter would
#: otherwise drift to 10⁴–10⁵ at no cost and their cancellation swamp the rounding bound.
PENALTY = 1e-6

_U = 2.0**-53
_TINY = 2.0**-1074  # a power-of-two scaling is exact unless subnormal: then within this


def gains(w: np.ndarray) -> np.ndarray:
    """G_e with G_e G_eᵀ ≈ W_e + ε λ_max(W_e) I for each edge (the witness; see
    :func:`gains_proven`).

    Parameters
    ----------
    w : numpy.ndarray
        The edges' |A_e|, (m, d, d).

    Returns
    -------
    numpy.ndarray
        (m, d, d).
    """
    sg, u = np.linalg.eigh(w)
    top = np.maximum(sg[:, -1:], 1e-300)
    return u * np.sqrt(np.maximum(sg, 0.0) + GAIN_EPS * top)[:, None, :]


def gains_proven(g: np.ndarray, w: np.ndarray) -> bool:
    """Whether ``G_e G_eᵀ − W_e ≻ 0`` holds exactly for every edge (rounding bounded).

    Parameters
    ----------
    g : numpy.ndarray
        G_e, (m, d, d).
    w : numpy.ndarray
        W_e, (m, d, d).

    Returns
    -------
    bool
    """
    d = w.shape[1] if w.ndim == 3 else 0
    for ge, we in zip(g, w, strict=True):
        m = ge @ ge.T - we
        err = gamma_k(d + 1) * (np.abs(ge) @ np.abs(ge).T + np.abs(we))
        if not verified_float_pd(m, err).holds:
            return False
    return True


def input_float(
    top, b, delta: float, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """u = δ·blockdiag(B_i)(1⊗x0) with x0 = (1 + 2/δ)·θ as the design rounds it, an
    entrywise bound on its rounding, and c = 1⊗θ.

    Parameters
    ----------
    top : Topology
        The topology.
    b : mapping of int to numpy.ndarray
        B_i of the informed agents.
    delta : float
        δ.
    theta : numpy.ndarray
        θ.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        u, the bound on |u exact − u|, and 1⊗θ.
    """
    d, n = top.dim, top.n
    x0 = (1.0 + 2.0 / delta) * np.asarray(theta, dtype=float)
    u = np.zeros((n, d))
    err = np.zeros((n, d))
    for i, bi in b.items():
        bi = np.asarray(bi, dtype=float)
        u[i] = delta * (bi @ x0)
        err[i] = gamma_k(d + 1) * abs(delta) * (np.abs(bi) @ np.abs(x0))
    return u.reshape(-1), err.reshape(-1), np.tile(np.asarray(theta, dtype=float), n)


def offset_search(des, lap: tuple[np.ndarray, np.ndarray] | None = None) -> OffsetSearch:
    """The offset search for a design: L_B and u with their rounding bounds.

    Parameters
    ----------
    des : ProtocolDesign
        The nominal design.
    lap : (numpy.ndarray, numpy.ndarray), optional
        L_B and its bound (:func:`ntc_design.certify.dense.lap_b_float`), when the caller
        has them.

    Returns
    -------
    OffsetSearch
    """
    top = des.topology
    lap = lap or lap_b_float(top, des.B, des.delta)
    u = input_float(top, des.B, des.delta, des.theta)
    return OffsetSearch(*lap, *u, uncertain_edges(top), top.dim)


class OffsetSearch:
    """The reduced offset SDP and its rigorous check for one network (dense).

    Parameters
    ----------
    lap : numpy.ndarray
        L_B in floating point (:func:`ntc_design.certify.dense.lap_b_float`).
    lap_err : numpy.ndarray
        An entrywise bound on |L_B exact − lap|.
    u : numpy.ndarray
        The input vector u (:func:`input_float`).
    u_err : numpy.ndarray
        An entrywise bound on |u exact − u|.
    target : numpy.ndarray
        1⊗θ.
    edges : UncertainEdges
        The uncertain edges.
    dim : int
        d.
    """

    def __init__(self, lap, lap_err, u, u_err, target, edges: UncertainEdges, dim: int):
        self.lap, self.lap_err, self.d = lap, lap_err, dim
        self.target = target
        self.n, self.m = lap.shape[0], edges.m
        self.i = edges.dst.astype(int) * dim
        self.j = edges.src.astype(int) * dim
        self.s = edges.s.astype(float)
        self.w = edges.channel_w  # W̄_e (robust.channel_bound)
        self.g = gains(self.w) if edges.m else np.zeros((0, dim, dim))
        self.r0 = u - lap @ target
        ac = np.abs(target)
        self._memo: tuple | None = None
        self.r0_err = u_err + lap_err @ ac + gamma_k(self.n + 2) * (np.abs(lap) @ ac + np.abs(u))

    @property
    def rows(self) -> int:
        """Σ d + 1: the reduced SDP's size."""
        return self.m * self.d + 1

    @functools.cached_property
    def _a(self) -> np.ndarray:
        """A = [L_B, E_i G_e, −r0] (floats; only L_B and r0 carry rounding)."""
        n, d = self.n, self.d
        f = np.zeros((n, self.m * d))
        for e in range(self.m):
            f[self.i[e] : self.i[e] + d, e * d : (e + 1) * d] = self.g[e]
        return np.hstack([self.lap, f, -self.r0.reshape(n, 1)])

    @functools.cached_property
    def _lu(self):
        """L_B's LU factors, and L_B⁻¹[G, −r0] (the elimination), computed once."""
        import scipy.linalg as sla

        lu = sla.lu_factor(self.lap)
        return lu, sla.lu_solve(lu, self._a[:, self.n :])

    def _q(self, lam: np.ndarray, rad: np.ndarray, absolute: bool = False) -> np.ndarray:
        """Σ λ_e ρ_e² D_e W_e D_eᵀ (or its magnitude, for the error bound)."""
        return edge_sum(self.n, self.d, (self.i, self.j, self.s), self.w, lam * rad**2, absolute)

    def _phi(self, gamma: float, lam: np.ndarray, rad: np.ndarray):
        """Φ (everything in Γ but sym(AᵀY)) and an entrywise bound on its rounding."""
        n, d, m = self.n, self.d, self.m
        k = n + m * d + 1
        c = self.target
        q = self._q(lam, rad)
        e_q = gamma_k(m + 6) * self._q(lam, rad, absolute=True)
        qc = q @ c
        e_qc = gamma_k(n + 1) * (np.abs(q) @ np.abs(c)) + e_q @ np.abs(c)
        cqc = float(c @ qc)
        e_cqc = gamma_k(n + 1) * float(np.abs(c) @ np.abs(qc)) + float(np.abs(c) @ e_qc)
        phi = np.zeros((k, k))
        err = np.zeros((k, k))
        phi[:n, :n] = -np.eye(n) - q
        err[:n, :n] = e_q + _U * np.abs(phi[:n, :n])
        phi[:n, -1] = phi[-1, :n] = -qc
        err[:n, -1] = err[-1, :n] = e_qc
        phi[-1, -1] = gamma - cqc
        # cᵀQc multiplies six in-span factors: it may underflow (each term by <= 2⁻¹⁰⁷⁴)
        err[-1, -1] = e_cqc + _U * (abs(gamma) + abs(cqc)) + (n + 2) * _TINY
        idx = np.arange(n, n + m * d)
        phi[idx, idx] = np.repeat(lam, d)
        return phi, err

    def witness(self, gamma: float, lam: np.ndarray, rad: np.ndarray, c0: float) -> np.ndarray:
        """Finsler's Y making TᵀΓT = blockdiag(c0·I, NᵀΦN) (floats; module docstring).

        Parameters
        ----------
        gamma : float
            γ.
        lam : numpy.ndarray
            λ_e.
        rad : numpy.ndarray
            ρ_e.
        c0 : float
            The z block's value after the congruence.

        Returns
        -------
        numpy.ndarray
            Y, Nd × (Nd + Σ d + 1).
        """
        import scipy.linalg as sla

        n = self.n
        phi, _ = self._phi(gamma, lam, rad)
        lu, m1 = self._lu  # m1 = L⁻¹[G, −r0]
        gm = self._a[:, n:]
        pzz = phi[:n, :n]
        pzw = phi[:n, n:]
        y2 = -sla.lu_solve(lu, pzw - pzz @ m1, trans=1)
        li_pzz = sla.lu_solve(lu, pzz, trans=1)  # L⁻ᵀ Φzz
        y1 = -0.5 * sla.lu_solve(lu, li_pzz.T, trans=1).T + 0.5 * c0 * np.eye(n)
        return np.hstack([y1 @ self.lap, y1 @ gm + y2])

    def gamma_matrix(self, gamma: float, lam: np.ndarray, y: np.ndarray, rad: np.ndarray):
        """Γ in floating point and an entrywise bound on |Γ exact − Γ|.

        Parameters
        ----------
        gamma : float
            γ.
        lam : numpy.ndarray
            λ_e.
        y : numpy.ndarray
            Y.
        rad : numpy.ndarray
            ρ_e.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
        """
        n = self.n
        a = self._a
        a_err = np.zeros_like(a)
        a_err[:, :n] = self.lap_err
        a_err[:, -1] = self.r0_err
        phi, e_phi = self._phi(gamma, lam, rad)
        ay = a.T @ y
        x = gamma_k(n) * (np.abs(a).T @ np.abs(y)) + a_err.T @ np.abs(y)
        sym = ay + ay.T
        g = phi + sym
        err = e_phi + x + x.T + _U * np.abs(sym) + _U * np.abs(g)
        # the bound is itself computed in floating point: inflate it past its own rounding
        return g, err * (1.0 + 4.0 * gamma_k(g.shape[0] + 8))

    def proven(self, gamma: float, lam: np.ndarray, rad: np.ndarray) -> bool:
        """Whether γ and λ prove ``‖x*(A') − 1⊗θ‖² <= γ`` for every realisation with an
        invertible L_B(A'): G_e G_eᵀ ≻ W_e and Γ ≻ 0 exactly, with the witnesses G and Y
        rebuilt here (a few scalings of Y's free block are tried).

        Parameters
        ----------
        gamma : float
            γ.
        lam : numpy.ndarray
            λ_e >= 0.
        rad : numpy.ndarray
            ρ_e per edge.

        Returns
        -------
        bool
        """
        lam = np.asarray(lam, dtype=float)
        rad = np.asarray(rad, dtype=float)
        if lam.shape != (self.m,) or rad.shape != (self.m,):
            return False
        if not (np.all(np.isfinite(lam)) and np.all(lam >= 0) and np.isfinite(gamma)):
            return False
        if not (np.all(np.isfinite(rad)) and np.all(rad >= 0) and gamma > 0):
            return False
        if not within_span(lam, rad, np.array([gamma]), self.w, self.g, self.lap, self.lap_err):
            return False  # the relative rounding bounds assume no underflow or overflow
        if not within_span(self.target, self.r0, self.r0_err):
            return False
        if not gains_proven(self.g, self.w):
            return False
        for c0 in C0:
            try:
                y = self.witness(gamma, lam, rad, c0)
            except (np.linalg.LinAlgError, ValueError):
                return False
            if not within_span(y):
                continue
            g, err = self.gamma_matrix(gamma, lam, y, rad)
            dg = np.diag(g)
            if not np.all(dg > 0):
                continue
            # Γ ≻ 0 iff DΓD ≻ 0: D of powers of two equilibrates exactly (no rounding)
            dsc = np.exp2(-np.round(0.5 * np.log2(dg)))
            scale = np.outer(dsc, dsc)  # a product of powers of two: exact
            gs = g * scale  # one rounding each, only where the result is subnormal
            es = err * scale + 2.0 * _TINY
            if (
                np.all(np.isfinite(gs))
                and np.all(np.isfinite(es))
                and verified_float_pd(gs, es).holds
            ):
                return True
        return False

    def reduced(self, lam: np.ndarray, rad: np.ndarray) -> float:
        """γ(λ) = the least γ of the reduced matrix for these λ (∞ when its η block is not
        negative definite), in floating point.

        Parameters
        ----------
        lam : numpy.ndarray
            λ_e.
        rad : numpy.ndarray
            ρ_e.

        Returns
        -------
        float
        """
        import scipy.linalg as sla

        h = self._h(np.asarray(lam, dtype=float), rad)
        try:
            cf = sla.cho_factor(-h[:-1, :-1])
        except np.linalg.LinAlgError:
            return float("inf")
        y = sla.cho_solve(cf, h[:-1, -1])
        return float(h[-1, -1] + h[:-1, -1] @ y)

    def _pieces(self, rad: np.ndarray):
        """The reduced quadratic forms on ζ = (s, t): ZᵀZ, and per edge ρ²(DᵀX)ᵀW(DᵀX)
        (kept for the last radii: the bumps of one search reuse them)."""
        key = np.asarray(rad, dtype=float).tobytes()
        if self._memo is not None and self._memo[0] == key:
            return self._memo[1]
        d = self.d
        x = -self._lu[1]  # z = Zζ with Z = −L⁻¹[G, −r0]
        z = x.copy()
        x[:, -1] += self.target  # x = z + t c
        q = []
        for e in range(self.m):
            i, j = self.i[e], self.j[e]
            dx = x[i : i + d] - self.s[e] * x[j : j + d]
            q.append(rad[e] ** 2 * (dx.T @ self.w[e] @ dx))
        self._memo = (key, (z.T @ z, q))
        return self._memo[1]

    def _h(self, lam: np.ndarray, rad: np.ndarray) -> np.ndarray:
        zz, q = self._pieces(rad)
        h = zz
        d = self.d
        for e in range(self.m):
            h = h + lam[e] * q[e]
            h[e * d : (e + 1) * d, e * d : (e + 1) * d] -= lam[e] * np.eye(d)
        return h

    def __call__(self, radius) -> tuple[float, np.ndarray] | None:
        """γ and λ proving the offset bound √γ at the radii (rigorously checked), or None.

        Parameters
        ----------
        radius : float or numpy.ndarray
            ρ, or ρ_e per edge.

        Returns
        -------
        (float, numpy.ndarray) or None
        """

        rad = np.broadcast_to(np.asarray(radius, dtype=float), (self.m,)).copy()
        if self.rows > OFFSET_MAX_ROWS or self.m == 0:
            return None
        cp = load_cvxpy()
        zz, q = self._pieces(rad)
        k, d = self.rows, self.d
        scale = max(float(np.max(np.abs(zz))), 1e-300)
        lam = cp.Variable(self.m, nonneg=True)
        gam = cp.Variable()
        corner = np.zeros((k, k))
        corner[-1, -1] = 1.0
        expr = gam * corner - zz / scale
        for e in range(self.m):
            ge = q[e].copy()
            ge[e * d : (e + 1) * d, e * d : (e + 1) * d] -= np.eye(d)
            expr = expr - lam[e] * ge
        price = PENALTY * cp.sum(lam) / self.m
        prob = cp.Problem(cp.Minimize(gam + price), [0.5 * (expr + expr.T) >> 0])
        if not solve_sdp(prob) or lam.value is None:
            return None
        lv = np.maximum(np.asarray(lam.value, dtype=float).reshape(-1), 0.0) * scale
        for bump in (1e-6, 1e-4, 1e-3, 1e-2):
            lb = lv * (1 + bump) + bump * 1e-6 * float(np.max(lv, initial=1.0))
            g0 = self.reduced(lb, rad)
            if not np.isfinite(g0):
                continue
            gv = g0 * (1 + bump) + bump * 1e-6 * scale
            if self.proven(gv, lb, rad):
                return gv, lb
        return None


__all__ = [
    "GAIN_EPS",
    "OFFSET_MAX_ROWS",
    "OffsetSearch",
    "gains",
    "gains_proven",
    "input_float",
    "offset_search",
]
