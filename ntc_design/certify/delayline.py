"""A delayed digital certificate from a Lyapunov–Krasovskii functional of the whole delay
line (D >= 1), and the mean-square limit c_true it is measured against.

Notation as in :mod:`.digital`: τ_k = h c_k, e_{k+1} = e_k − τ_k L y_k + ν_k with
y_k = e_{k−D}, ν_k = c_k √h Σ_e (g_e ξ₁ + G_e y_k ξ₂), N(X) = Σ_e G_eᵀ X G_e and
γ(X) = Σ_e g_eᵀ X g_e. Write δ_{k,j} = e_{k−j} − e_{k−j−1} (j = 0 … D−1), so that
y_k = e_k − Σ_j δ_{k,j}.

*The functional.* With S ≻ 0, R_0 ⪰ R_1 ⪰ … ⪰ R_{D−1} ⪰ 0 and T_j ⪰ 0 (n×n),

    V_k = e_kᵀ S e_k + (1/τ_k) Σ_j δ_{k,j}ᵀ R_j δ_{k,j},
    Ṽ_k = E V_k − (h/τ_k) Σ_j c_{k−1−j}² γ(R_j)           (c_i = 0 for i < 0).

The subtracted term is the noise floor of the delay terms (the noise of step k−1−j sits in
δ_{k,j} and E[δᵀRδ] >= h c² γ(R)), so Ṽ_k >= E e_kᵀSe_k >= 0. The weight 1/τ_k on the
increments is what makes κ large: a constant weight is useless at small c or too stiff at
large c (/work notes, 1 % of c_true).

*The step.* Let g bound the growth of 1/c: (1/c)'(t) <= g for t >= t₀, so that
g_k = 1/τ_{k+1} − 1/τ_k <= g. The conditional expectation of V_{k+1} is a quadratic form
in x_k = (e_k, δ_{k,0}, …, δ_{k,D−1}); requiring it to be at most
diag((1 − ατ)S, (1/τ)R'_0, …, (1/τ)R'_{D−1}) with R'_j = (1 + gτ)R_{j+1} + τT_j
(R_D = 0) and multiplying by τ gives a matrix polynomial in c whose constant term vanishes.
Divided by τ it is G(c) = F₁ + c·F₂ + c²·F₃ with F₁ = diag(0, T_0, …, T_{D−1}),
F₃ ⪯ 0, i.e. (n×n blocks; s_0 = 1, s_{j+1} = −1)

    K(c)   = c·(h LᵀR_0L + N(R_0)) + c²·(h² Lᵀ(S + gR_0)L + h N(S + gR_0)),
    G_00   = c h (SL + LᵀS − αS) − K,     G_0b = K − c h SL,     G_ab = δ_ab T_{a−1} − K.

G is concave in c (F₃ ⪯ 0) and G(0) = F₁ ⪰ 0, so G(κ) ⪰ 0 proves G(c) ⪰ 0 for every
c in (0, κ]; G decreases in g, so the actual g_k <= g is covered. With the decrease
conditions (1 − ατ)R_j − (1 + gτ)R_{j+1} − τT_j ⪰ 0 (affine in τ: proven at τ = 0 and
τ = hκ), the floors telescope exactly and

    Ṽ_{k+1} <= (1 − α h c_k) Ṽ_k + h ( c_k² γ(S) + Σ_j c_{k−1−j}² γ(T_j) )
            <= (1 − α h c_k) Ṽ_k + h c̄_k² γ',      γ' = γ(S) + Σ_j γ(T_j),

c̄_k = max(c_k, …, c_{k−D}), for every k >= k₀ with c_k <= κ. With Σ τ_k = ∞ and
c_k → 0 (the sampled gain conditions; c̄_k/c_k → 1 by the growth bound) E‖e_k‖²_S <= Ṽ_k → 0.

*c_true.* The largest constant gain below which the spectral radius of the augmented
second-moment map Z ↦ A_c Z A_cᵀ + h c² Σ_e Ĝ_e Z Ĝ_eᵀ (z = (e_k, …, e_{k−D})) is < 1,
by bisection on c with ARPACK on the operator (dense for tiny orders); per mode (frozen),
the least over a schedule's modes. Informational: it is not a claim.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from ..expr.symbolic import parse_expression, symbol
from ..rigorous.exact import Dyadic
from ..rigorous.floatmat import FloatMat
from ..rigorous.interval import bounds, enclose, t_ball
from .ctrue import CTRUE_MAX_ORDER, ms_limit, spectral_radius
from .digital import (
    DigitalPlan,
    EdgeNoise,
    additive_energy,
    ms_matrix,
    noise_matrix,
    noise_operator,
)
from .mu2 import T0_SCAN_END, prove_below

#: The margin the SDP keeps in every inequality (relative to S ⪰ I), so that the stated
#: matrices pass the verified test.
MARGIN = 1e-6
#: The most SDP solves in the search for κ (each is most of a certificate's cost).
KAPPA_STEPS = 4
#: Where the search for κ starts, as a share of c_true (the functionals reach 55–70 %).
KAPPA_START = 0.55
#: The first step up from a feasible level, relative (halved after every infeasible one).
KAPPA_STEP_UP = 0.12
#: The search stops when the bracket is this narrow, relative to c_true.
KAPPA_RESOLUTION = 0.02
#: Clarabel's settings: infeasibility is declared at 1e-6 (half the iterations of the
#: default 1e-8 at the edge of feasibility); a feasible answer is judged by its own
#: matrices in floats (and the stated ones in verified floats), not by the status.
SOLVER_OPTIONS = {"tol_infeas_abs": 1e-6, "tol_infeas_rel": 1e-6}
#: α as a share of the slowest continuous decay min Re λ(L_B).
ALPHA_SHARE = 0.4


@dataclass(frozen=True)
class DelayLinePlan:
    """A delay-line certificate's numbers: S, R_0 … R_{D−1}, T_0 … T_{D−1}, α, κ, the
    growth bound g of 1/c and the additive constant γ' (module docstring)."""

    s: np.ndarray
    rs: tuple[np.ndarray, ...]
    ts: tuple[np.ndarray, ...]
    alpha: float
    kappa: float
    g: float
    gamma: float


# -- one builder for every arithmetic ---------------------------------------------------


class _Ops:
    """Scalar products and block matrices in floats, cvxpy, Dyadic or FloatMat."""

    def __init__(self, kind: str) -> None:
        self.kind = kind

    def lift(self, a: np.ndarray) -> Any:
        if self.kind == "dyadic":
            return Dyadic.of(a)
        if self.kind == "floatmat":
            return FloatMat.of(a)
        return a

    def mul(self, s: Any, x: Any) -> Any:
        if self.kind == "dyadic":
            return x.scale(Dyadic.of(float(s)))
        if self.kind == "floatmat":
            return x.scale(float(s))
        return s * x

    def block(self, grid: list[list[Any]]) -> Any:
        if self.kind == "cvxpy":
            import cvxpy as cp

            return cp.bmat(grid)
        if self.kind == "dyadic":
            e = max(b.exp for row in grid for b in row)
            num = np.block([[b.num * (1 << (e - b.exp)) for b in row] for row in grid])
            return Dyadic(num.astype(object), e)
        if self.kind == "floatmat":
            return FloatMat(
                np.block([[b.val for b in row] for row in grid]),
                np.block([[b.rad for b in row] for row in grid]),
            )
        return np.block(grid)


def step_blocks(
    ops: _Ops,
    s: Any,
    r0: Any,
    ts: Sequence[Any],
    lap: Any,
    noise: Callable[[Any], Any],
    alpha: float,
    c: Any,
    c2: Any,
    g: float,
    h: float,
    name: Callable[[Any], Any] | None = None,
) -> Any:
    """G(c) of the module docstring in the given arithmetic (c² passed separately so that
    cvxpy sees a parameter; in exact arithmetic c2 is None and c·c is used). ``name`` turns
    an expression used in many blocks into one (an SDP variable equal to it: K and SL
    appear (D+1)² times, and dense copies would make the solver's matrix dense).

    Parameters
    ----------
    ops : _Ops
        The arithmetic.
    s, r0 : matrix in that arithmetic
        S and R_0.
    ts : sequence of matrices
        T_0 … T_{D−1}.
    lap : matrix
        L_B.
    noise : callable
        X ↦ N(X) = Σ_e G_eᵀ X G_e in that arithmetic.
    alpha : float
        α.
    c, c2 : float, cvxpy parameter or None
        The gain and its square (None: c·c).
    g, h : float
        The growth bound of 1/c and the period.
    name : callable, optional
        Turns a repeated expression into one (cvxpy).

    Returns
    -------
    matrix
        G(c), ((D+1)·n)².
    """
    own = name or (lambda x: x)

    def cc(x: Any) -> Any:
        return ops.mul(c, ops.mul(c, x)) if c2 is None else ops.mul(c2, x)

    sg = s + ops.mul(g, r0)
    lt = lap.T
    k = ops.mul(c, ops.mul(h, lt @ (r0 @ lap)) + noise(r0))
    k = own(k + cc(ops.mul(h, ops.mul(h, lt @ (sg @ lap)) + noise(sg))))
    sl = own(s @ lap)
    chsl = ops.mul(c, ops.mul(h, sl))
    top = ops.mul(c, ops.mul(h, sl + sl.T - ops.mul(alpha, s))) - k
    cross = k - chsl
    dd = len(ts)
    zero = ops.mul(0.0, k)
    grid = [[top] + [cross] * dd]
    for a in range(dd):
        grid.append([cross.T] + [(ts[a] - k) if a == b else (zero - k) for b in range(dd)])
    return ops.block(grid)


def step_matrix(
    s: np.ndarray,
    rs: Sequence[np.ndarray],
    ts: Sequence[np.ndarray],
    lap: Any,
    edges: Sequence[EdgeNoise],
    d: int,
    alpha: float,
    kappa: float,
    g: float,
    h: float,
    exact: bool,
    noise: Callable[[Any], Any] | None = None,
) -> Any:
    """G(κ) for one mode, exactly (Dyadic) or in verified floats (FloatMat).

    Parameters
    ----------
    s : numpy.ndarray
        S.
    rs, ts : sequence of numpy.ndarray
        R_0 … R_{D−1} and T_0 … T_{D−1}.
    lap : numpy.ndarray, Dyadic or FloatMat
        L_B of the mode (a Dyadic or FloatMat is used as given).
    edges : sequence of EdgeNoise
        The mode's edges.
    d : int
        The state dimension.
    alpha, kappa, g, h : float
        α, κ, the growth bound of 1/c and the period.
    exact : bool
        Dyadic (True) or FloatMat.
    noise : callable, optional
        X ↦ the noise map in that arithmetic instead of N (:mod:`.loss_delay`).

    Returns
    -------
    Dyadic or FloatMat
        ((D+1)·n)², to be proven ⪰ 0.
    """
    ops = _Ops("dyadic" if exact else "floatmat")
    lp = lap if isinstance(lap, (Dyadic, FloatMat)) else ops.lift(lap)
    sm, r0 = ops.lift(s), ops.lift(rs[0])
    tl = [ops.lift(t) for t in ts]
    return step_blocks(
        ops,
        sm,
        r0,
        tl,
        lp,
        noise or (lambda x: noise_matrix(x, edges, d, exact)),
        alpha,
        kappa,
        None,
        g,
        h,
    )


def form_matrices(
    s: np.ndarray,
    rs: Sequence[np.ndarray],
    ts: Sequence[np.ndarray],
    alpha: float,
    kappa: float,
    g: float,
    h: float,
    exact: bool,
) -> list[tuple[str, Any]]:
    """The mode-free matrices to prove ≻ 0: S, every T_j, R_j − R_{j+1} (τ = 0) and
    (1 − αhκ)R_j − (1 + ghκ)R_{j+1} − hκT_j (τ = hκ), R_D = 0.

    Parameters
    ----------
    s : numpy.ndarray
        S.
    rs, ts : sequence of numpy.ndarray
        R_j and T_j.
    alpha, kappa, g, h : float
        α, κ, g and the period.
    exact : bool
        Dyadic (True) or FloatMat.

    Returns
    -------
    list of (str, Dyadic or FloatMat)
    """
    ops = _Ops("dyadic" if exact else "floatmat")
    out = [("S", ops.lift(s))]
    out += [(f"T_{j}", ops.lift(t)) for j, t in enumerate(ts)]
    rl = [ops.lift(r) for r in rs]
    dd = len(rs)
    for j in range(dd):
        nxt = rl[j + 1] if j + 1 < dd else ops.mul(0.0, rl[j])
        out.append((f"R_{j} − R_{j + 1}", rl[j] - nxt))

        def tau(x: Any) -> Any:
            return ops.mul(kappa, ops.mul(h, x))

        m = rl[j] - tau(ops.mul(alpha, rl[j])) - nxt - tau(ops.mul(g, nxt)) - tau(ops.lift(ts[j]))
        out.append((f"(1 − αhκ)R_{j} − (1 + ghκ)R_{j + 1} − hκT_{j}", m))
    return out


def delay_line_gamma(
    s: np.ndarray, ts: Sequence[np.ndarray], edges: Sequence[EdgeNoise], d: int
) -> Fraction:
    """γ' = γ(S) + Σ_j γ(T_j) exactly.

    Parameters
    ----------
    s : numpy.ndarray
        S.
    ts : sequence of numpy.ndarray
        T_j.
    edges : sequence of EdgeNoise
        The mode's edges.
    d : int
        The state dimension.

    Returns
    -------
    fractions.Fraction
    """
    return additive_energy(s, edges, d) + sum(
        (additive_energy(t, edges, d) for t in ts), Fraction(0)
    )


# -- the gain's growth ------------------------------------------------------------------


def _inverse_rate(gain: str) -> sp.Expr:
    c = parse_expression(gain, "gain")
    return sp.diff(1 / c, symbol("t"))


def growth_bound(gain: Any) -> float | None:
    """A numerical bound g on (1/c)'(t) over t >= 0 (sampled on a geometric grid, then
    raised by 1 %), to be proven from t₀ on by :func:`prove_growth`; None for a schedule
    or when 1/c is not finite.

    Parameters
    ----------
    gain : str or dict
        c(t) as text (a schedule document gives None).

    Returns
    -------
    float or None
    """
    if not isinstance(gain, str):
        return None
    f = _inverse_rate(gain)
    if not f.has(symbol("t")):
        v = float(f)
        return max(v, 0.0) * 1.01 + 1e-9 if math.isfinite(v) else None
    fn = sp.lambdify(symbol("t"), f, "numpy")
    ts = np.concatenate([[0.0], np.geomspace(1e-6, T0_SCAN_END, 4000)])
    with np.errstate(all="ignore"):
        v = np.asarray(fn(ts), dtype=float) * np.ones_like(ts)
    if not np.all(np.isfinite(v)):
        return None
    return max(float(np.max(v)), 0.0) * 1.01 + 1e-9


def prove_growth(gain: Any, g: float, t0: float) -> tuple[bool | None, str]:
    """Prove (1/c)'(t) < g for every t >= t₀ (ball arithmetic, as :func:`.mu2.prove_below`)
    and c(t₀) > 0 (then c > 0 on [t₀, ∞): 1/c is finite and continuous there).

    Parameters
    ----------
    gain : str or dict
        c(t).
    g : float
        The stated bound.
    t0 : float
        From where.

    Returns
    -------
    (bool or None, str)
    """
    if not isinstance(gain, str):
        return False, "the delay-line bound needs c(t) as an expression"
    if not (isinstance(g, float) and math.isfinite(g) and g >= 0):
        return False, f"g = {g!r} is not a finite number >= 0"
    if not (isinstance(t0, float) and math.isfinite(t0) and t0 >= 0):
        return False, f"t₀ = {t0!r} is not a finite time >= 0"
    c = parse_expression(gain, "gain")
    lo = bounds(enclose(c, t_ball(t0, t0)))[0]
    if not lo > 0:
        return False, f"c(t₀) > 0 not proven (lower bound {lo:.6g})"
    ok, how = prove_below(_inverse_rate(gain), g, t0)
    return ok, f"(1/c)' < g = {g!r} from t₀ on: {how}; c(t₀) > 0"


# -- finding S, R, T --------------------------------------------------------------------


def _decay(laps: Sequence[np.ndarray]) -> float:
    return min(float(np.min(np.linalg.eigvals(lap).real)) for lap in laps)


def _reach(lowest: Callable[[float], float], lo: float, hi: float) -> float:
    """The largest c in [lo, hi] with lowest(c) >= 0 (bisection to 1e-6 relative), for a
    check whose set of good c is an interval from 0 (concave in c); lo is known good."""
    if lowest(hi) >= 0:
        return hi
    for _ in range(40):
        if hi - lo <= 1e-6 * hi:
            break
        mid = 0.5 * (lo + hi)
        if lowest(mid) >= 0:
            lo = mid
        else:
            hi = mid
    return lo


def largest_level(
    solve: Callable[[float], Any],
    reach: Callable[[Any, float], float],
    c_hi: float,
    start: float = KAPPA_START,
    steps: int = KAPPA_STEPS,
    resolution: float = KAPPA_RESOLUTION,
) -> tuple[float, Any]:
    """The search for κ <= c_hi with few SDP solves: start at :data:`KAPPA_START`·c_hi;
    after a feasible solve the found matrices themselves are pushed as far as they hold
    (``reach``, cheap eigenvalues), then a step up (:data:`KAPPA_STEP_UP`, halved after
    every infeasible level); stop after :data:`KAPPA_STEPS` solves or when the bracket is
    narrower than :data:`KAPPA_RESOLUTION`·c_hi.

    Parameters
    ----------
    solve : callable
        c ↦ the SDP's matrices at level c, or None when infeasible.
    reach : callable
        (matrices, c) ↦ the largest level in [c, c_hi] at which those matrices hold.
    c_hi : float
        The top (c_true).
    start, steps, resolution : float, int, float
        The first level as a share of c_hi, the most solves, the bracket's width at
        which to stop (relative to c_hi).

    Returns
    -------
    (float, matrices or None)
        The level (0 and None when none was found) and its matrices.
    """
    lo, hi, best = 0.0, c_hi, None
    mid, step = start * c_hi, KAPPA_STEP_UP
    for _ in range(steps):
        sol = solve(mid)
        if sol is not None:
            lo, best = max(mid, min(reach(sol, mid), hi)), sol
        else:
            hi, step = mid, 0.5 * step
        if hi - lo <= resolution * c_hi:
            break
        mid = 0.5 * hi if best is None else min(lo * (1 + step), 0.5 * (lo + hi))
    return lo, best


def _sym(x: Any) -> np.ndarray:
    a = np.array(x, dtype=float)
    return 0.5 * (a + a.T)


def _lowest_step(
    sol: Any,
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
    alpha: float,
    g: float,
    c: float,
    ops: Sequence[Any] | None = None,
) -> float:
    """The least eigenvalue over the plan's inequalities for fixed S, R_j, T_j at level c
    (floats): S, T_j, R_j − R_{j+1}, and, less the SDP's margin, the decrease at τ = hc
    and G(c) per mode (``ops``: each mode's noise map on vec(X), default N)."""
    s, rs, ts = sol
    n = s.shape[0]
    dd = len(rs)
    rn = [*rs, np.zeros((n, n))]
    fixed = [s, *ts, *(rs[j] - rn[j + 1] for j in range(dd))]  # ≻ 0 is all the proof needs
    out = min(float(np.linalg.eigvalsh(m)[0]) for m in fixed)
    for j in range(dd):
        m = (1 - alpha * h * c) * rs[j] - (1 + g * h * c) * rn[j + 1] - h * c * ts[j]
        out = min(out, float(np.linalg.eigvalsh(m)[0]) - MARGIN)
    arith = _Ops("float")
    scale = np.concatenate([np.full(n, h * c), np.ones(n * dd)]) * MARGIN
    for k, (lap, edges) in enumerate(zip(laps, noises, strict=True)):
        op = noise_operator(edges, n, d) if ops is None else ops[k]

        def noise(x: Any, op: Any = op) -> Any:
            return (op @ np.ravel(x)).reshape(n, n)

        gm = step_blocks(arith, s, rs[0], list(ts), lap, noise, alpha, c, c * c, g, h)
        gm = 0.5 * (gm + gm.T) - np.diag(scale)
        out = min(out, float(np.linalg.eigvalsh(gm)[0]))
    return out


def plan_delay_line(
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
    delay: int,
    g: float,
    c_hi: float,
    ops: Sequence[Any] | None = None,
    holds: Callable[[DelayLinePlan], bool] | None = None,
) -> DelayLinePlan | None:
    """S, R_j, T_j and the largest κ <= c_hi found (:func:`largest_level`: a few Clarabel
    solves, a margin :data:`MARGIN` in every inequality, each found S, R_j, T_j pushed to the
    largest level at which they hold), then checked in verified floats.

    Parameters
    ----------
    laps : sequence of numpy.ndarray
        L_B of every mode used.
    noises : sequence of sequence of EdgeNoise
        Every mode's edges.
    d : int
        The state dimension.
    h : float
        The period.
    delay : int
        D >= 1.
    g : float
        The growth bound of 1/c.
    c_hi : float
        The top of the search (c_true).
    ops : sequence, optional
        Each mode's map X ↦ N(X) on row-major vec(X) (default :func:`.digital.noise_operator`;
        the lossy links' certificate passes its own, :mod:`.loss_delay`), and L_B the
        matrix the step uses.
    holds : callable, optional
        The verified-float test of a plan (default :func:`holds_in_floats`).

    Returns
    -------
    DelayLinePlan or None
        None when no κ > 0 was found or the stated matrices fail the verified test.
    """
    import cvxpy as cp

    mu = _decay(laps)
    if not (delay >= 1 and mu > 0 and c_hi > 0 and g >= 0):
        return None
    alpha = ALPHA_SHARE * mu
    n = laps[0].shape[0]
    eye = np.eye(n)
    s = cp.Variable((n, n), symmetric=True)
    rs = [cp.Variable((n, n), symmetric=True) for _ in range(delay)]
    ts = [cp.Variable((n, n), symmetric=True) for _ in range(delay)]
    c = cp.Parameter(nonneg=True)
    c2 = cp.Parameter(nonneg=True)
    cons = [s >> eye] + [t >> MARGIN * eye for t in ts]
    rn = [*rs, np.zeros((n, n))]
    for j in range(delay):
        cons.append(rs[j] - rn[j + 1] >> MARGIN * eye)
        cons.append(
            (1 - alpha * h * c) * rs[j] - (1 + g * h * c) * rn[j + 1] - h * c * ts[j]
            >> MARGIN * eye
        )
    arith = _Ops("cvxpy")
    m = n * (delay + 1)
    scale = np.ones(m)
    scale[:n] = 0.0
    for k, (lap, edges) in enumerate(zip(laps, noises, strict=True)):
        op = noise_operator(edges, n, d) if ops is None else ops[k]

        def noise(x: Any, op: Any = op) -> Any:
            return cp.reshape(op @ cp.vec(x, order="C"), (n, n), order="C")

        def name(x: Any) -> Any:
            v = cp.Variable(x.shape)
            cons.append(v == x)
            return v

        gm = step_blocks(arith, s, rs[0], ts, lap, noise, alpha, c, c2, g, h, name)
        margin = MARGIN * (np.diag(scale) + h * c * np.diag(1.0 - scale))
        cons.append(0.5 * (gm + gm.T) - margin >> 0)
    prob = cp.Problem(cp.Minimize(0), cons)

    def solve(cv: float) -> Any:
        c.value, c2.value = cv, cv * cv
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                prob.solve(solver=cp.CLARABEL, **SOLVER_OPTIONS)
        except (cp.SolverError, ArithmeticError, ValueError):
            return None
        if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            return None
        sol = (
            _sym(s.value),
            tuple(_sym(r.value) for r in rs),
            tuple(_sym(t.value) for t in ts),
        )
        # an inaccurate answer counts when its matrices hold at cv (floats)
        ok = prob.status == cp.OPTIMAL or low(sol, cv) >= 0
        return sol if ok else None

    def low(sol: Any, cv: float) -> float:
        return _lowest_step(sol, laps, noises, d, h, alpha, g, cv, ops)

    def reach(sol: Any, c0: float) -> float:
        return _reach(lambda cv: low(sol, cv), c0, c_hi)

    lo, best = largest_level(solve, reach, c_hi)
    if best is None:
        return None
    sv, rv, tv = best
    gamma = max(float(delay_line_gamma(sv, tv, e, d)) for e in noises) * (1 + 1e-12)
    pl = DelayLinePlan(sv, rv, tv, alpha, lo, g, gamma)
    ok = holds(pl) if holds is not None else holds_in_floats(pl, laps, noises, d, h)
    return pl if ok else None


def plan_no_delay(
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
    c_hi: float,
) -> DigitalPlan | None:
    """D = 0 with a free P: the largest κ <= c_hi found with (PL + LᵀP − αP) −
    κ(hLᵀPL + N(P)) ⪰ 0 for every mode (affine in κ with a PSD slope, so κ proves every
    c in (0, κ]); :func:`largest_level` from 0.9·c_hi with Clarabel, then checked in
    verified floats.

    Parameters
    ----------
    laps : sequence of numpy.ndarray
        L_B of every mode used.
    noises : sequence of sequence of EdgeNoise
        Every mode's edges.
    d : int
        The state dimension.
    h : float
        The period.
    c_hi : float
        The top of the search (c_true).

    Returns
    -------
    DigitalPlan or None
    """
    import cvxpy as cp

    mu = _decay(laps)
    if not (mu > 0 and c_hi > 0):
        return None
    alpha = ALPHA_SHARE * mu
    n = laps[0].shape[0]
    eye = np.eye(n)
    p = cp.Variable((n, n), symmetric=True)
    kap = cp.Parameter(nonneg=True)
    cons = [p >> eye]
    for lap, edges in zip(laps, noises, strict=True):
        op = noise_operator(edges, n, d)
        nm = cp.reshape(op @ cp.vec(p, order="C"), (n, n), order="C")
        m = p @ lap + lap.T @ p - alpha * p - kap * (h * lap.T @ p @ lap + nm)
        cons.append(0.5 * (m + m.T) >> MARGIN * eye)
    prob = cp.Problem(cp.Minimize(0), cons)

    def solve(kv: float) -> Any:
        kap.value = kv
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                prob.solve(solver=cp.CLARABEL, **SOLVER_OPTIONS)
        except (cp.SolverError, ArithmeticError, ValueError):
            return None
        if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            return None
        pv = _sym(p.value)
        return pv if prob.status == cp.OPTIMAL or reach(pv, 0.0) >= kv else None

    def reach(pv: np.ndarray, k0: float) -> float:
        parts = []
        for lap, edges in zip(laps, noises, strict=True):
            op = noise_operator(edges, n, d)
            nm = (op @ pv.ravel()).reshape(n, n)
            parts.append((pv @ lap + lap.T @ pv - alpha * pv, h * lap.T @ pv @ lap + nm))

        def lowest(kv: float) -> float:
            return min(float(np.linalg.eigvalsh(_sym(a - kv * b))[0]) - MARGIN for a, b in parts)

        return _reach(lowest, k0, c_hi)

    # small and cheap solves, and the free P reaches 90 % and more of c_true
    lo, best = largest_level(solve, reach, c_hi, 0.9, KAPPA_STEPS + 3, 0.004)
    if best is None:
        return None
    for lap, edges in zip(laps, noises, strict=True):
        pm = FloatMat.of(best)
        nm = noise_matrix(pm, edges, d, False)
        if not ms_matrix(pm, FloatMat.of(lap), nm, alpha, lo, h).positive_definite().holds:
            return None
    gamma = max(float(additive_energy(best, e, d)) for e in noises) * (1 + 1e-12)
    return DigitalPlan(best, alpha, lo, gamma, source="an SDP for P (Clarabel)")


def holds_in_floats(
    pl: DelayLinePlan,
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
) -> bool:
    """Whether every stated inequality passes the verified-float test.

    Parameters
    ----------
    pl : DelayLinePlan
        The plan.
    laps : sequence of numpy.ndarray
        L_B of every mode.
    noises : sequence of sequence of EdgeNoise
        Every mode's edges.
    d : int
        The state dimension.
    h : float
        The period.

    Returns
    -------
    bool
    """
    mats = [m for _, m in form_matrices(pl.s, pl.rs, pl.ts, pl.alpha, pl.kappa, pl.g, h, False)]
    mats += [
        step_matrix(pl.s, pl.rs, pl.ts, lap, e, d, pl.alpha, pl.kappa, pl.g, h, False)
        for lap, e in zip(laps, noises, strict=True)
    ]
    return all(m.positive_definite().holds for m in mats)


__all__ = [
    "ALPHA_SHARE",
    "CTRUE_MAX_ORDER",
    "KAPPA_RESOLUTION",
    "KAPPA_START",
    "KAPPA_STEPS",
    "KAPPA_STEP_UP",
    "MARGIN",
    "DelayLinePlan",
    "delay_line_gamma",
    "form_matrices",
    "growth_bound",
    "holds_in_floats",
    "largest_level",
    "ms_limit",
    "plan_delay_line",
    "plan_no_delay",
    "prove_growth",
    "SOLVER_OPTIONS",
    "spectral_radius",
    "step_blocks",
    "step_matrix",
]
