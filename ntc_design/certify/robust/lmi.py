"""The LMIs of :mod:`.robust`, in floating point for the solvers: the channels of the
uncertain edges, the decay S-procedure matrix Ψ (P, τ; α, ρ) and the offset S-procedure
matrix Γ (γ, λ, Y; ρ), their solves (cvxpy with CVXOPT, Clarabel as fallback), and the
descent that finds the best verified value of a bound. ``ntc verify`` rebuilds the same
matrices exactly (:mod:`.kinds.robust`)."""

from __future__ import annotations

import numpy as np

from .problem import Problem


def load_cvxpy():
    """cvxpy, imported on first use (heavy: only the robust SDPs need it).

    Returns
    -------
    module
    """
    import cvxpy as cp

    return cp


#: Interior-point solvers tried in turn: CVXOPT was 3× faster than Clarabel on these LMIs
#: (G1's decay LMI 0.19 s against 0.64 s); Clarabel takes over when CVXOPT fails.
SOLVERS = ("CVXOPT", "CLARABEL")


def solve_sdp(prob) -> bool:
    """Solve with CVXOPT, then Clarabel (:data:`SOLVERS`) until one reports optimal.

    Parameters
    ----------
    prob : cvxpy.Problem
        The problem.

    Returns
    -------
    bool
        Whether a solver reached an optimal (possibly inaccurate) point.
    """
    cp = load_cvxpy()
    for name in SOLVERS:
        try:
            prob.solve(solver=getattr(cp, name))
        except (cp.error.SolverError, ArithmeticError, ValueError):
            continue
        if prob.status in ("optimal", "optimal_inaccurate"):
            return True
        if prob.status in ("infeasible", "infeasible_inaccurate"):
            return False  # a solver's certificate of infeasibility: the next would agree
    return False


def channels(
    p: Problem, scale: float = 1.0, normalise: bool = False
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per edge: (E_i W V as Nd×r, D W Dᵀ as Nd×Nd, Vᵀ W V as r×r), with W divided by
    ``scale`` and V the pivot columns (normalised to unit length if asked). Any basis of range(W)
    gives a congruent Ψ (diag(I, D) with D diagonal), so ``ntc verify``'s unnormalised
    pivot columns accept the same P and τ; and Ψ of (L_B, W)/s is Ψ/s for the same P, τ."""
    d, n, ed = p.d, p.n, p.edges
    out = []
    for e in range(ed.m):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        w, v = ed.channel_w[e] / scale, ed.basis(e)  # W̄_e (robust.channel_bound)
        if normalise:
            v = v / np.linalg.norm(v, axis=0)
        ewv = np.zeros((n, v.shape[1]))
        ewv[i : i + d] = w @ v
        dm = np.zeros((n, d))
        dm[i : i + d] += np.eye(d)
        dm[j : j + d] -= ed.s[e] * np.eye(d)
        out.append((ewv, dm @ w @ dm.T, v.T @ w @ v))
    return out


def decay_matrix(
    lap_b: np.ndarray,
    channels: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
    p: np.ndarray,
    tau: np.ndarray,
    alpha: float,
    radius: float | np.ndarray,
) -> np.ndarray:
    """Ψ of the decay S-procedure (module docstring) in floating point.

    Parameters
    ----------
    lap_b : numpy.ndarray
        Nominal L_B.
    channels : list
        Per edge (E_i W V, D W Dᵀ, Vᵀ W V).
    p : numpy.ndarray
        P.
    tau : numpy.ndarray
        The multipliers τ_e.
    alpha : float
        The rate α.
    radius : float or numpy.ndarray
        ρ, or ρ_e per edge.

    Returns
    -------
    numpy.ndarray
        Ψ, symmetric, on the edges of radius ρ_e > 0 (:func:`perturbed`).
    """
    n = lap_b.shape[0]
    sh = lap_b - alpha * np.eye(n)
    top = p @ sh + sh.T @ p
    cols, diag = [], []
    r2 = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, (len(channels),))
    for t, q, (ewv, dwd, vwv) in zip(tau, r2, channels, strict=True):
        if not q > 0:
            continue  # an edge of radius 0 is not perturbed: no channel
        top = top - t * q * dwd
        cols.append(p @ ewv)
        diag.append(t * vwv)
    import scipy.linalg as sla

    off = np.hstack(cols) if cols else np.zeros((n, 0))
    return np.block([[top, off], [off.T, sla.block_diag(*diag) if diag else np.zeros((0, 0))]])


def active_columns(n: int, sizes: list[int], active: tuple[int, ...]) -> list[int]:
    """The columns of ξ = (z, η_1, …, η_m, 1) that remain when only the channels of the
    ``active`` edges are kept (a certificate's Y has every channel's columns).

    Parameters
    ----------
    n : int
        Nd (the columns of z).
    sizes : list of int
        Each channel's columns (rank of W̄_e).
    active : tuple of int
        The edges kept (:func:`perturbed`).

    Returns
    -------
    list of int
    """
    starts = np.cumsum([n, *sizes])
    cols = list(range(n))
    for e in active:
        cols += list(range(int(starts[e]), int(starts[e]) + sizes[e]))
    return [*cols, int(starts[-1])]


def perturbed(radius: float | np.ndarray, m: int) -> tuple[int, ...]:
    """The edges with ρ_e > 0: the only ones with a channel in Ψ and Γ. An edge of radius
    0 is not perturbed (its interval is its nominal weight), so it needs no channel; with
    none, Ψ is the nominal Lyapunov inequality P(L_B − αI) + (L_B − αI)ᵀP ≻ 0 and Γ the
    nominal equilibrium's bound.

    Parameters
    ----------
    radius : float or numpy.ndarray
        ρ, or ρ_e per edge.
    m : int
        The number of edges.

    Returns
    -------
    tuple of int
    """
    r = np.broadcast_to(np.asarray(radius, dtype=float), (m,))
    return tuple(int(e) for e in np.flatnonzero(r > 0))


class DecayLMI:
    """The decay LMI with α and ρ² as parameters (cvxpy DPP), built once for each set of
    perturbed edges (:func:`perturbed`): each bisection step only re-solves."""

    def __init__(self, p: Problem, ch) -> None:
        self.p, self.ch = p, ch
        # solved on (L_B, W)/s with s = max|L_B|: the same P, τ prove the unscaled LMI
        self.scale = float(np.max(np.abs(p.lap_b))) or 1.0
        self.ch_s = channels(p, self.scale, normalise=True)
        self._built: dict[tuple[int, ...], tuple] = {}

    def _build(self, active: tuple[int, ...]) -> tuple:
        cp = load_cvxpy()
        n = self.p.n
        lap_s = self.p.lap_b / self.scale
        ch_s = [self.ch_s[e] for e in active]
        pv = cp.Variable((n, n), symmetric=True)
        tv = cp.Variable(max(len(ch_s), 1), nonneg=True)
        alpha = cp.Parameter(nonneg=True)
        rho2 = cp.Parameter(max(len(ch_s), 1), nonneg=True)
        top = pv @ lap_s + lap_s.T @ pv - 2 * alpha * pv
        rows_off, diag = [], []
        r = sum(c[0].shape[1] for c in ch_s)
        col = 0
        for k, (ewv, dwd, vwv) in enumerate(ch_s):
            top = top - rho2[k] * (tv[k] * dwd)
            rows_off.append(pv @ ewv)
            m = vwv.shape[0]
            row = [np.zeros((m, col))] if col else []
            row.append(tv[k] * vwv)
            if r - col - m:
                row.append(np.zeros((m, r - col - m)))
            diag.append(cp.hstack(row) if len(row) > 1 else row[0])
            col += m
        if r:
            off = cp.hstack(rows_off)
            psi = cp.bmat([[top, off], [off.T, cp.vstack(diag)]])
        else:
            psi = top
        prob = cp.Problem(
            cp.Minimize(0), [pv >> np.eye(n), 0.5 * (psi + psi.T) >> 1e-7 * np.eye(n + r)]
        )
        return prob, pv, tv, alpha, rho2

    def __call__(
        self, alpha: float, radius: float | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """P, τ with Ψ ≻ 0 at ρ (or ρ_e per edge), checked in floats with a strict margin;
        or None. τ_e = 0 on an edge of radius 0 (it has no channel)."""
        m = len(self.ch)
        active = perturbed(radius, m)
        if active not in self._built:
            self._built[active] = self._build(active)
        prob, pv, tv, alpha_p, rho2 = self._built[active]
        r2 = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, (m,))
        alpha_p.value = alpha / self.scale
        rho2.value = np.array([r2[e] for e in active]) if active else np.zeros(1)
        if not solve_sdp(prob) or pv.value is None:
            return None
        pm = 0.5 * (pv.value + pv.value.T)
        tau = np.zeros(m)
        if active:
            tau[list(active)] = np.maximum(np.asarray(tv.value, dtype=float).reshape(-1), 0.0)
        psi_f = decay_matrix(self.p.lap_b, self.ch, pm, tau, alpha, radius)
        if np.linalg.eigvalsh(0.5 * (psi_f + psi_f.T))[0] <= 1e-10 * np.linalg.norm(psi_f, 2):
            return None
        return pm, tau


def offset_matrix(
    lap_b: np.ndarray,
    channels: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
    target: np.ndarray,
    r0: np.ndarray,
    gamma: float,
    lam: np.ndarray,
    y: np.ndarray,
    radius: float | np.ndarray,
) -> np.ndarray:
    """Γ of the offset S-procedure (module docstring), floating point, on ξ = (z, η, 1).

    Parameters
    ----------
    lap_b : numpy.ndarray
        Nominal L_B.
    channels : list
        Per edge (E_i W V, D W Dᵀ, Vᵀ W V).
    target : numpy.ndarray
        1⊗θ.
    r0 : numpy.ndarray
        u − L_B(1⊗θ) (the equation is L_B z + Σ E_i W_e V_e η_e = r0).
    gamma : float
        The bound γ on ‖z‖².
    lam : numpy.ndarray
        The multipliers λ_e.
    y : numpy.ndarray
        Finsler's multiplier (Nd × dim ξ).
    radius : float or numpy.ndarray
        ρ, or ρ_e per edge.

    Returns
    -------
    numpy.ndarray
        Γ, symmetric, on ξ = (z, η_e of the edges of radius ρ_e > 0, 1): an edge of
        radius 0 has no channel (:func:`perturbed`; its columns of Y are not used).
    """
    n, m = lap_b.shape[0], len(channels)
    rad = np.broadcast_to(np.asarray(radius, dtype=float), (m,))
    active = perturbed(rad, m)
    y = y[:, active_columns(n, [c[0].shape[1] for c in channels], active)]
    channels = [channels[e] for e in active]
    lam = np.asarray(lam, dtype=float)[list(active)]
    radius = rad[list(active)]
    r = sum(c[0].shape[1] for c in channels)
    k = n + r + 1
    g = np.zeros((k, k))
    g[-1, -1] = gamma
    g[:n, :n] -= np.eye(n)
    col = n
    r2 = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, (len(channels),))
    for le, q2, (_ewv, dwd, vwv) in zip(lam, r2, channels, strict=True):
        # −λ(ρ² (z+c)ᵀ DWDᵀ (z+c) − ηᵀ VᵀWV η)
        q = q2 * dwd
        qc = q @ target
        g[:n, :n] -= le * q
        g[:n, -1] -= le * qc
        g[-1, :n] -= le * qc
        g[-1, -1] -= le * float(target @ qc)
        m = vwv.shape[0]
        g[col : col + m, col : col + m] += le * vwv
        col += m
    a = np.hstack([lap_b] + [c[0] for c in channels] + [-r0.reshape(n, 1)])
    g += a.T @ y + y.T @ a
    return g


def offset_sdp(p: Problem, ch_all, radius) -> tuple[float, np.ndarray, np.ndarray] | None:
    """γ, λ, Y with Γ ≻ 0 (floats, a strict margin), or None; the channels of the edges
    of radius 0 are left out (:func:`perturbed`): their λ_e and columns of Y are 0."""
    cp = load_cvxpy()
    n, m_all = p.n, len(ch_all)
    rad_all = np.broadcast_to(np.asarray(radius, dtype=float), (m_all,))
    active = perturbed(rad_all, m_all)
    ch = [ch_all[e] for e in active]
    radius = rad_all[list(active)]
    r = sum(c[0].shape[1] for c in ch)
    k = n + r + 1
    gam = cp.Variable()
    lam = cp.Variable(max(len(ch), 1), nonneg=True)
    y = cp.Variable((n, k))
    a = np.hstack([p.lap_b] + [c[0] for c in ch] + [-p.r0.reshape(n, 1)])
    e_last = np.zeros((k, 1))
    e_last[-1, 0] = 1.0
    sel_z = np.zeros((n, k))
    sel_z[:, :n] = np.eye(n)
    expr = gam * (e_last @ e_last.T) - sel_z.T @ sel_z
    col = n
    r2 = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, (len(ch),))
    for kk, (_ewv, dwd, vwv) in enumerate(ch):
        q = r2[kk] * dwd
        # the quadratic form of ρ²(z+c)ᵀDWDᵀ(z+c) on ξ = (z, η, 1)
        qa = np.zeros((k, k))
        qa[:n, :n] = q
        qc = q @ p.target
        qa[:n, -1] = qc
        qa[-1, :n] = qc
        qa[-1, -1] = float(p.target @ qc)
        m = vwv.shape[0]
        qa[col : col + m, col : col + m] = -vwv
        expr = expr - lam[kk] * qa
        col += m
    expr = expr + a.T @ y + y.T @ a
    scale = 1.0 + float(np.linalg.norm(p.target)) ** 2
    prob = cp.Problem(cp.Minimize(gam), [0.5 * (expr + expr.T) >> 1e-9 * scale * np.eye(k)])
    if not solve_sdp(prob) or gam.value is None:
        return None
    lam_v = np.zeros(m_all)
    if active:
        lam_v[list(active)] = np.maximum(np.asarray(lam.value, dtype=float).reshape(-1), 0.0)
    sizes = [c[0].shape[1] for c in ch_all]
    y_v = np.zeros((n, n + sum(sizes) + 1))  # every channel's columns, as verify reads Y
    y_v[:, active_columns(n, sizes, active)] = np.asarray(y.value, dtype=float)
    g0 = float(gam.value)
    for bump in (1e-7, 1e-5, 1e-3, 1e-2):  # back off until the float test is strict
        gv = g0 * (1 + bump) + bump * 1e-6 * scale
        gm = offset_matrix(p.lap_b, ch_all, p.target, p.r0, gv, lam_v, y_v, rad_all)
        if np.linalg.eigvalsh(0.5 * (gm + gm.T))[0] > 1e-12 * np.linalg.norm(gm, 2):
            return gv, lam_v, y_v
    return None


#: Tried from the top: the first fraction of the attained end whose LMI verifies, then a
#: few bisection steps between it and the last fraction that failed (few solves when the
#: bracket is tight, as it usually is).
FRACTIONS = (0.995, 0.97, 0.9, 0.75, 0.5, 0.25, 0.0)


def descend(test, top: float, steps: int, floor: float = 0.0):
    """The largest value in [floor, top] found to pass ``test`` (None: not even floor)."""
    hi = top
    for f in FRACTIONS:
        v = floor + f * (top - floor)
        got = test(v)
        if got is not None:
            lo, best = v, got
            break
        hi = v
    else:
        return floor, None
    for _ in range(steps if hi > lo else 0):
        mid = 0.5 * (lo + hi)
        got = test(mid)
        if got is None:
            hi = mid
        else:
            lo, best = mid, got
    return lo, best


__all__ = [
    "FRACTIONS",
    "SOLVERS",
    "active_columns",
    "decay_matrix",
    "load_cvxpy",
    "offset_matrix",
    "perturbed",
    "solve_sdp",
]
