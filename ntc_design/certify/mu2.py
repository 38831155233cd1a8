"""μ₂(t) = c(t)[Λ₂ − 2σ̄Λ₁N c(t)] > 0 after t₀ (Niu & Wu, proof of Theorem 3): the level
κ that c(t) must stay below, σ̄ of the noise, and t₀ for a gain, proven in ball arithmetic.
Used by the time-varying certificate (:mod:`.time_varying`) and its verification."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import sympy as sp

from ..expr.symbolic import compile_expression, parse_expression, symbol
from ..rigorous.interval import bounds, enclose, t_ball

T0_SCAN_END = 1e9


def mu2_threshold(lambda2: float, lambda1: float, sigma_bar: float, n: int) -> float:
    """The gain level below which μ₂(t) = c(t)[Λ₂ − 2σ̄Λ₁N c(t)] > 0 (Niu & Wu, proof of
    Theorem 3).

    Parameters
    ----------
    lambda2 : float
        Λ₂, the uniform lower bound on λ_min(L_B(t) + L_B(t)ᵀ).
    lambda1 : float
        Λ₁ >= λ_max²(|A_ij(t)|).
    sigma_bar : float
        σ̄ of Assumption 1 (eq. (4)).
    n : int
        The number of agents N.

    Returns
    -------
    float
        κ = Λ₂ / (2σ̄Λ₁N) (inf when the denominator is 0): μ₂(t) > 0 exactly when
        0 < c(t) < κ.
    """
    den = 2.0 * sigma_bar * lambda1 * n
    return math.inf if den == 0 else lambda2 / den


def mu2_t0(gain: Any, kappa: float) -> tuple[float | None, str]:
    """The time t₀ after which c(t) < κ, and how it was proven.

    Parameters
    ----------
    gain : str or sympy.Expr
        c(t): text (parsed safely, :mod:`ntc_design.expr.symbolic`), or a GainAnalysis's expression.
    kappa : float
        The level from :func:`mu2_threshold`.

    Returns
    -------
    tuple of (float or None, str)
        The least t₀ on a fine scan with c(t) < κ for every t >= t₀ (None if c is still
        >= κ at 10⁹), and how it was proven: ball arithmetic on [t₀, 10⁹] and sympy's
        monotonicity of c beyond.

    Raises
    ------
    InputError
        The gain is not an allowed expression of t.
    """
    c = parse_expression(gain, "gain") if isinstance(gain, str) else gain
    t = symbol("t")
    if not c.has(t):
        v = float(c)
        return (
            (0.0, "constant gain below κ") if v < kappa else (None, f"constant gain {v:.4g} >= κ")
        )
    fn = compile_expression(c)
    grid = np.concatenate([[0.0], np.geomspace(1e-6, T0_SCAN_END, 4000)])
    vals = fn(grid)
    above = np.nonzero(~(vals < kappa))[0]
    if above.size == 0:
        t0 = 0.0
    elif above[-1] == grid.size - 1:
        return None, f"c(t) >= κ = {kappa:.4g} still at t = {T0_SCAN_END:g}"
    else:
        lo, hi = grid[above[-1]], grid[above[-1] + 1]
        for _ in range(60):
            m = 0.5 * (lo + hi)
            if fn(np.array([m]))[0] < kappa:
                hi = m
            else:
                lo = m
        # a little above the crossing (6 significant digits, rounded up) so that the
        # ball-arithmetic proof below closes
        e10 = 10 ** (math.floor(math.log10(hi)) - 5) if hi > 0 else 1e-6
        t0 = float(math.ceil(hi * (1 + 1e-7) / e10) * e10)
    return t0, prove_below(c, kappa, t0)[1]


def prove_below(c: sp.Expr, kappa: float, t0: float) -> tuple[bool | None, str]:
    """Prove c(t) < κ for every t >= t₀: ball arithmetic on [t₀, 10⁹] (bisection), and
    sympy's monotonicity of c beyond.

    Parameters
    ----------
    c : sympy.Expr
        c(t) (a constant is decided at once).
    kappa : float
        The level.
    t0 : float
        From where.

    Returns
    -------
    (bool or None, str)
        True when proven; False when c >= κ somewhere was found; None when the proof did
        not close (undecided); and how.
    """
    if not c.has(symbol("t")):
        v = float(c)
        return (
            (True, "constant gain below κ") if v < kappa else (False, f"constant gain {v:.4g} >= κ")
        )
    stack = [(t0, max(T0_SCAN_END, t0))]
    n_ev = 0
    while stack:
        a, b = stack.pop()
        n_ev += 1
        hi_c = bounds(enclose(c, t_ball(a, b)))[1]
        if hi_c < kappa:
            continue
        if b - a < 1e-9 * max(1.0, a) or n_ev > 20000:
            lo_c = bounds(enclose(c, t_ball(a, a)))[0]
            if lo_c >= kappa:
                return False, f"c({a:.6g}) >= κ = {kappa:.6g}"
            return None, "numerical (the ball-arithmetic proof did not close)"
        # [a, 2a] bisects (splitting it at 2a would give it back); longer ones split at 2a
        m = 0.5 * (a + b) if b <= 2 * max(a, 1.0) else max(2 * a, a + 1.0)
        stack += [(a, m), (m, b)]
    try:
        dec = sp.is_decreasing(c, sp.Interval(max(T0_SCAN_END, t0), sp.oo))
    except Exception:  # noqa: BLE001 - sympy may fail on anything
        dec = None
    if dec:
        return True, "ball arithmetic on t0 <= t <= 1e9, c decreasing beyond (sympy)"
    return None, "ball arithmetic on t0 <= t <= 1e9; beyond 1e9 not proven"


def noise_sigma_bar(f: Any) -> float:
    """σ̄ of Assumption 1 for f(x) = s·x (|s|) or f(x) = F x (‖F‖₂).

    Parameters
    ----------
    f : float or array_like
        s or F.

    Returns
    -------
    float
    """
    arr = np.asarray(f, dtype=float)
    return float(abs(arr)) if arr.ndim == 0 else float(np.linalg.norm(arr, 2))


__all__ = ["T0_SCAN_END", "mu2_t0", "mu2_threshold", "noise_sigma_bar", "prove_below"]
