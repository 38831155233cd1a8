"""The LMIs of :mod:`.robust`, in floating point for the solvers: the channels of the
uncertain edges, the decay S-procedure matrix Ψ (P, τ; α, ρ) and the offset S-procedure
matrix Γ (γ, λ, Y; ρ), their solves (cvxpy with CVXOPT, Clarabel as fallback), and the
descent that finds the best verified value of a bound. ``ntc verify`` rebuilds the same
matrices exactly (:mod:`.kinds.robust`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the problem data is built by .robust, which imports this module
    from .robust import _Problem


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


def _channels(
    p: _Problem, scale: float = 1.0, normalise: bool = False
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per edge: (E_i W V as Nd×r, D W Dᵀ as Nd×Nd, Vᵀ W V as r×r), with W divided by
    ``scale`` and V the pivot columns (normalised to unit length if asked). Any basis of range(W)
    gives a congruent Ψ (diag(I, D) with D diagonal), so ``ntc verify``'s unnormalised
    pivot columns accept the same P and τ; and Ψ of (L_B, W)/s is Ψ/s for the same P, τ."""
    d, n, ed = p.d, p.n, p.edges
    out = []
    for e in range(ed.m):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        w, v = ed.w[e] / scale, ed.basis(e)
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
        Ψ, symmetric.
    """
    n = lap_b.shape[0]
    sh = lap_b - alpha * np.eye(n)
    top = p @ sh + sh.T @ p
    cols, diag = [], []
    r2 = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, (len(channels),))
    for t, q, (ewv, dwd, vwv) in zip(tau, r2, channels, strict=True):
        top = top - t * q * dwd
        cols.append(p @ ewv)
        diag.append(t * vwv)
    import scipy.linalg as sla

    off = np.hstack(cols) if cols else np.zeros((n, 0))
    return np.block([[top, off], [off.T, sla.block_diag(*diag) if diag else np.zeros((0, 0))]])


class _DecayLMI:
    """The decay LMI built once with α and ρ² as parameters (cvxpy DPP): each bisection
    step only re-solves."""

    def __init__(self, p: _Problem, ch) -> None:
        cp = load_cvxpy()
        self.p, self.ch = p, ch
        n = p.n
        # solved on (L_B, W)/s with s = max|L_B|: the same P, τ prove the unscaled LMI
        self.scale = float(np.max(np.abs(p.lap_b))) or 1.0
        lap_s = p.lap_b / self.scale
        ch_s = _channels(p, self.scale, normalise=True)
        self.pv = cp.Variable((n, n), symmetric=True)
        self.tv = cp.Variable(len(ch), nonneg=True)
        self.alpha = cp.Parameter(nonneg=True)
        self.rho2 = cp.Parameter(max(len(ch), 1), nonneg=True)
        top = self.pv @ lap_s + lap_s.T @ self.pv - 2 * self.alpha * self.pv
        rows_off, diag = [], []
        r = sum(c[0].shape[1] for c in ch_s)
        col = 0
        for k, (ewv, dwd, vwv) in enumerate(ch_s):
            top = top - self.rho2[k] * (self.tv[k] * dwd)
            rows_off.append(self.pv @ ewv)
            m = vwv.shape[0]
            row = [np.zeros((m, col))] if col else []
            row.append(self.tv[k] * vwv)
            if r - col - m:
                row.append(np.zeros((m, r - col - m)))
            diag.append(cp.hstack(row) if len(row) > 1 else row[0])
            col += m
        if r:
            off = cp.hstack(rows_off)
            psi = cp.bmat([[top, off], [off.T, cp.vstack(diag)]])
        else:
            psi = top
        self.prob = cp.Problem(
            cp.Minimize(0),
            [self.pv >> np.eye(n), 0.5 * (psi + psi.T) >> 1e-7 * np.eye(n + r)],
        )

    def __call__(
        self, alpha: float, radius: float | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """P, τ with Ψ ≻ 0 at ρ (or ρ_e per edge), checked in floats with a strict margin;
        or None."""
        self.alpha.value = alpha / self.scale
        self.rho2.value = np.broadcast_to(np.asarray(radius, dtype=float) ** 2, self.rho2.shape)
        if not solve_sdp(self.prob) or self.pv.value is None:
            return None
        pm = 0.5 * (self.pv.value + self.pv.value.T)
        tau = np.maximum(np.asarray(self.tv.value, dtype=float).reshape(-1), 0.0)
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
        Γ, symmetric.
    """
    n = lap_b.shape[0]
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


def _offset_sdp(p: _Problem, ch, radius) -> tuple[float, np.ndarray, np.ndarray] | None:
    """γ, λ, Y with Γ ≻ 0 (floats, a strict margin), or None."""
    cp = load_cvxpy()
    n = p.n
    r = sum(c[0].shape[1] for c in ch)
    k = n + r + 1
    gam = cp.Variable()
    lam = cp.Variable(len(ch), nonneg=True)
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
    lam_v = np.maximum(np.asarray(lam.value, dtype=float).reshape(-1), 0.0)
    y_v = np.asarray(y.value, dtype=float)
    g0 = float(gam.value)
    for bump in (1e-7, 1e-5, 1e-3, 1e-2):  # back off until the float test is strict
        gv = g0 * (1 + bump) + bump * 1e-6 * scale
        gm = offset_matrix(p.lap_b, ch, p.target, p.r0, gv, lam_v, y_v, radius)
        if np.linalg.eigvalsh(0.5 * (gm + gm.T))[0] > 1e-12 * np.linalg.norm(gm, 2):
            return gv, lam_v, y_v
    return None


#: Tried from the top: the first fraction of the attained end whose LMI verifies, then a
#: few bisection steps between it and the last fraction that failed (few solves when the
#: bracket is tight, as it usually is).
FRACTIONS = (0.995, 0.97, 0.9, 0.75, 0.5, 0.25, 0.0)


def _descend(test, top: float, steps: int, floor: float = 0.0):
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


__all__ = ["FRACTIONS", "SOLVERS", "decay_matrix", "load_cvxpy", "offset_matrix", "solve_sdp"]
