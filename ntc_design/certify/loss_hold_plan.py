"""Finding the hold certificate's S and R (an SDP, Clarabel) and c_true(hold), the
mean-square limit its κ is measured against (:mod:`.loss_hold` states the mathematics).

c_true(hold) is the largest constant gain below which the spectral radius of the second
moment map of z = (e, η) (its homogeneous part: the mean matrix, the arrivals' variance and
the multiplicative noise, written out from the model) is < 1, by bisection; informational.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np

from .delayline import SOLVER_OPTIONS, largest_level
from .loss_hold import (
    HoldModel,
    HoldOps,
    HoldPlan,
    coupling,
    hold_rate,
    holds_in_floats,
    step_matrix,
)

#: The largest order Nd + Ed of the functional the SDP is attempted for.
HOLD_MAX_ORDER = 160
#: The Young weight ρ of the τ² term as a share of h·min Re λ(L_B) (it costs ρc of the
#: e-block's decay h c (SL + LᵀS)).
RHO_SHARE = 0.75
#: The share of α' that the gain's change may cost: β solves gβ/(1 − β) = share·α'.
BETA_SHARE = 0.5
#: α' as a share of the slowest continuous decay min Re λ(L_B).
ALPHA_SHARE = 0.4
#: The SDP's margin in every inequality.
MARGIN = 1e-7


# -- c_true(hold) ------------------------------------------------------------------------


def _float_model(mo: HoldModel) -> dict:
    f = HoldOps("float").const
    return {
        "pi": f(mo.pi),
        "gam": f(mo.gam),
        "lap": f(mo.lap),
        "q": np.array([float(x) for x in mo.q]),
        "p": np.array([float(x) for x in mo.p]),
        "kd": [f(k) for k in mo.kd],
    }


def hold_ms_map(mo: HoldModel, h: float, c: float) -> Callable[[np.ndarray], np.ndarray]:
    """The homogeneous second-moment map of z = (e, η) at the constant gain c: Z ↦ ĀZĀᵀ +
    Σ_e p_e q_e H_eZH_eᵀ + Σ_e q_e b_e (K_eΔ_e Z_ee Δ_eᵀK_eᵀ / h) b_eᵀ (written out from
    the model in the module docstring, in (e, η) coordinates).

    Parameters
    ----------
    mo : HoldModel
        The model.
    h, c : float
        The period and the gain.

    Returns
    -------
    callable
        On a flattened W×W matrix.
    """
    fm = _float_model(mo)
    n, m, d = mo.n, mo.m, mo.d
    tau = h * c
    pi, gam, lap, q, p = fm["pi"], fm["gam"], fm["lap"], fm["q"], fm["p"]
    gp = gam @ pi
    a = np.block(
        [[np.eye(n) - tau * lap, tau * pi * p], [tau * gam @ lap, (np.eye(m) - tau * gp) * p]]
    )
    bn = np.vstack([tau * pi, np.eye(m) - tau * gp])
    ne = m // d

    def apply(v: np.ndarray) -> np.ndarray:
        z = v.reshape(n + m, n + m)
        out = a @ z @ a.T
        zee = z[:n, :n]
        for e in range(ne):
            b = bn[:, e * d : (e + 1) * d]
            out += (
                p[e * d]
                * q[e * d]
                * (b @ z[n:, n:][e * d : (e + 1) * d, e * d : (e + 1) * d] @ b.T)
            )
            kd = fm["kd"][e]
            out += q[e * d] * (b @ (kd @ zee @ kd.T) @ b.T) / h
        return out.ravel()

    return apply


def hold_spectral_radius(mo: HoldModel, h: float, c: float) -> float:
    """The spectral radius of :func:`hold_ms_map` (ARPACK; dense for tiny orders).

    Parameters
    ----------
    mo : HoldModel
        The model.
    h, c : float
        The period and the gain.

    Returns
    -------
    float
    """
    import scipy.sparse.linalg as spla

    w = mo.n + mo.m
    apply = hold_ms_map(mo, h, c)
    if w * w <= 400:
        mat = np.column_stack([apply(col) for col in np.eye(w * w)])
        return float(np.max(np.abs(np.linalg.eigvals(mat))))
    op = spla.LinearOperator((w * w, w * w), matvec=apply, dtype=float)
    v0 = np.eye(w).ravel()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        vals = spla.eigs(op, k=1, which="LM", v0=v0, return_eigenvectors=False, tol=1e-10)
    return float(np.max(np.abs(vals)))


def hold_ctrue(mo: HoldModel, h: float) -> float | None:
    """c_true(hold): the largest constant gain with spectral radius < 1 (bisection to
    1e-4 relative); None when none is found below 2/(h·max|λ(L_B)|)·16.

    Parameters
    ----------
    mo : HoldModel
        The model.
    h : float
        The period.

    Returns
    -------
    float or None
    """
    lap = _float_model(mo)["lap"]
    hi = 32.0 / (h * max(float(np.max(np.abs(np.linalg.eigvals(lap)))), 1e-12))
    lo = 0.0
    if hold_spectral_radius(mo, h, hi) < 1:
        return None
    for _ in range(60):
        if hi - lo <= 1e-4 * hi:
            break
        mid = 0.5 * (lo + hi)
        if hold_spectral_radius(mo, h, mid) < 1:
            lo = mid
        else:
            hi = mid
    return lo if lo > 0 else None


# -- finding S and R ---------------------------------------------------------------------


def _down(x: Fraction) -> float:
    f = float(x)
    return f if Fraction(f) <= x else math.nextafter(f, -math.inf)


def _sym(a: Any) -> np.ndarray:
    x = np.array(a, dtype=float)
    return 0.5 * (x + x.T)


def lowest(mo: HoldModel, pl: HoldPlan, h: float, c: float) -> float:
    """The least eigenvalue (floats) over S − I, the coupling, G₀ and G(c) at level c (less
    the SDP's margins): >= 0 when S and R hold at level c.

    Parameters
    ----------
    mo : HoldModel
        The model.
    pl : HoldPlan
        S, R, α', ρ, β (κ is taken as c).
    h, c : float
        The period and the level.

    Returns
    -------
    float
    """
    ops = HoldOps("float")
    n, m = mo.n, mo.m
    out = float(np.linalg.eigvalsh(pl.s)[0]) - 1.0 + MARGIN
    out = min(out, float(np.linalg.eigvalsh(_sym(coupling(ops, mo, pl.s, pl.r, pl.beta)))[0]))
    g0 = step_matrix(ops, mo, pl.s, pl.r, pl.alpha1, pl.rho, c, h, 0.0)
    out = min(out, float(np.linalg.eigvalsh(_sym(g0[n:, n:]))[0]) - MARGIN)
    gk = _sym(step_matrix(ops, mo, pl.s, pl.r, pl.alpha1, pl.rho, c, h, c))
    scale = np.concatenate([np.full(n, h * c), np.ones(m)]) * MARGIN
    return min(out, float(np.linalg.eigvalsh(gk - np.diag(scale))[0]))


def plan_hold(mo: HoldModel, h: float, g: float, c_hi: float, decay: float) -> HoldPlan | None:
    """S, R and the largest κ <= c_hi found (:func:`.delayline.largest_level`, Clarabel,
    a margin :data:`MARGIN` in every inequality), then checked in verified floats.

    Parameters
    ----------
    mo : HoldModel
        The model.
    h : float
        The period.
    g : float
        The growth bound of 1/c (>= 0).
    c_hi : float
        The top of the search (c_true(hold)).
    decay : float
        min Re λ(L_B) (> 0).

    Returns
    -------
    HoldPlan or None
    """
    import cvxpy as cp

    n, m = mo.n, mo.m
    if not (decay > 0 and c_hi > 0 and g >= 0) or n + m > HOLD_MAX_ORDER:
        return None
    alpha1 = ALPHA_SHARE * decay
    want = BETA_SHARE * alpha1  # gβ/(1 − β)
    beta = float(want / (g + want)) if g > 0 else 0.5
    rho = RHO_SHARE * h * decay
    ops = HoldOps("cvxpy")
    s = cp.Variable((n, n), symmetric=True)
    r = cp.Variable((m, m), symmetric=True)
    lev = {"k": 0.0}

    def problem(kv: float) -> Any:
        cons = [s >> np.eye(n)]
        cp_ = coupling(ops, mo, s, r, beta)
        cons.append(0.5 * (cp_ + cp_.T) >> MARGIN * np.eye(n + m))
        g0 = step_matrix(ops, mo, s, r, alpha1, rho, kv, h, 0.0)[n:, n:]
        cons.append(0.5 * (g0 + g0.T) >> MARGIN * np.eye(m))
        gk = step_matrix(ops, mo, s, r, alpha1, rho, kv, h, kv)
        scale = np.concatenate([np.full(n, h * kv), np.ones(m)]) * MARGIN
        cons.append(0.5 * (gk + gk.T) >> np.diag(scale))
        return cp.Problem(cp.Minimize(cp.trace(s) / n), cons)

    def as_plan(sv: np.ndarray, rv: np.ndarray, kv: float) -> HoldPlan:
        alpha = _down(hold_rate(alpha1, beta, g))
        return HoldPlan(sv, rv, alpha1, rho, beta, g, kv, alpha)

    def solve(kv: float) -> Any:
        lev["k"] = kv
        prob = problem(kv)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                prob.solve(solver=cp.CLARABEL, **SOLVER_OPTIONS)
        except (cp.SolverError, ArithmeticError, ValueError):
            return None
        if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            return None
        pl = as_plan(_sym(s.value), _sym(r.value), kv)
        return pl if lowest(mo, pl, h, kv) >= 0 else None

    def reach(pl: HoldPlan, c0: float) -> float:
        lo, hi = c0, c_hi
        if lowest(mo, pl, h, hi) >= 0:
            return hi
        for _ in range(40):
            if hi - lo <= 1e-6 * hi:
                break
            mid = 0.5 * (lo + hi)
            if lowest(mo, pl, h, mid) >= 0:
                lo = mid
            else:
                hi = mid
        return lo

    lo, best = largest_level(solve, reach, c_hi)
    if best is None or not lo > 0:
        return None
    pl = as_plan(best.s, best.r, lo)
    if not pl.alpha > 0 or not Fraction(g) * Fraction(h) * Fraction(lo) * Fraction(
        beta
    ) <= 1 - Fraction(beta):
        return None
    return pl if holds_in_floats(mo, pl, h) else None


__all__ = [
    "ALPHA_SHARE",
    "BETA_SHARE",
    "HOLD_MAX_ORDER",
    "MARGIN",
    "RHO_SHARE",
    "hold_ctrue",
    "hold_ms_map",
    "hold_spectral_radius",
    "lowest",
    "plan_hold",
]
