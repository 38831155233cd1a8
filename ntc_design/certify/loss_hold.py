"""The mean-square certificate of the ``hold`` policy on lossy links (D = 0): a quadratic
functional of the error and of the held measurements' lag, whose step inequality is a
matrix inequality concave in the gain, so that one check at κ proves every c in (0, κ].

*Model* (:mod:`ntc_design.simulate.loss`, e = x − 1⊗θ, τ = h c_k, χ_e ~ Bernoulli(q_e),
q_e = 1 − p_e > 0). Edge e = (j -> i) measures a_e(e) = Γ_e e + b_e (Γ_e: A_ij at j,
−|A_ij| at i) with noise n_e = (g_e ξ₁ + K_e Δ_e e ξ₂)/√h (Δ_e e = e_j − e_i); the agent
holds y_e ← y_e + χ_e (a_e + n_e − y_e) and steps with it. Stack the edges (Π: Nd×Ed puts
an edge into agent i's rows, Γ: Ed×Nd the rows Γ_e, X = diag(χ_e I_d), Q_d = diag(q_e I_d),
P_d = I − Q_d) and write η = y − a(e) for the held minus the fresh noiseless measurement.
Since Σ_e P_i (a_e − b_e) − L_δ e = −L_B e = −L e,

    e' = (I − τL) e + τΠζ,      ζ = (I − X)η + Xn,
    η' = ζ − Γ(e' − e) = (I − τΓΠ)ζ + τΓL e.

η is not small (it carries the raw noise n, of size 1/√h) but it enters e only through τ.
The state of the functional is therefore the lag scaled by the step, u = τ Q_d⁻¹ η: on a
step with τ' = τ,

    e' = (I − τL)e + Π(I − X)Q_d u + τΠXn,
    u' = Q_d⁻¹(I − τΓΠ)(I − X)Q_d u + τ² Q_d⁻¹ΓL e + τ Q_d⁻¹(I − τΓΠ)Xn.

*The functional.* V(e, u) = zᵀQz, z = (e, u), Q = [[S, C], [Cᵀ, R]] with C = SΠP_d. At
c = 0 the step is e' = e + Π(I − X)Q_d u, u' = (I − X)u, and this C makes ê = e + Π P_d u
a martingale in the mean: Q − E[B₀ᵀQB₀] has zero e-rows (ee: S − S; eu: C − (SΠP_dQ_d +
CP_d) = 0 as Q_d + P_d = I). This is what lets the held lag and the error live in one
functional: without C the cross term 2eᵀSΠP_d u is O(1) at c → 0 while e's decrease is
O(c) (the weights constant, ∝ τ or ∝ 1/τ on ‖η‖² were tried: each leaves either an O(c)
additive term from the held noise or an O(1)·c cross term that no c-independent inequality
dominates).

*The step.* Write B(c, X) for the affine part (everything except the τ² e-term and the
noise), B̂(c) = [ΠQ_d; Q_d⁻¹(I − hcΓΠ)Q_d] (W×Ed), so that B = Ā(c) + Σ_e (χ_e − q_e)H_e
with Ā(c) = [[I − hcL; 0], B̂(c)P_d] and H_e = −B̂(c)E_e (E_e: edge e's columns in the u
block). The arrivals are independent, so E[BᵀQB] = ĀᵀQĀ + Σ_e p_e q_e H_eᵀQH_e. The τ²
term δ = c²h² (0, Q_d⁻¹ΓL e) is split off by Young with a weight ρc: V(x + δ) <=
(1 + ρc)V(x) + (1 + 1/(ρc))V(δ) and c⁴ + c³/ρ <= c²(κ² + κ/ρ) for c <= κ. The noise enters
as hc·B_n(c)Xn with B_n(c) = B₀ + hcB₁, B₀ = [Π; Q_d⁻¹], B₁ = [0; −Q_d⁻¹ΓΠ], and B_nᵀQB_n
⪯ M := (1 + hκ)(B₀ᵀQB₀ + hκ B₁ᵀQB₁) for c <= κ (Young with weight hκ). Hence with

    G(c) = (1 − (α'h + ρ)c) Q − ĀᵀQĀ − Σ_e p_e q_e H_eᵀQH_e
           − c² (κ² + κ/ρ) h⁴ (LᵀΓᵀQ_d⁻¹RQ_d⁻¹ΓL ⊕ 0) − h c² (Σ_e q_e Δ_eᵀK_eᵀM_eeK_eΔ_e ⊕ 0),

G(c) ⪰ 0 gives (the factor (1 + ρc) divided out, (1 + ρc)(1 − (α'h + ρ)c) <= 1 − α'hc)

    E[V(e', u')] <= (1 − α' h c) V(e, u) + h c² γ,     γ = Σ_e q_e g_eᵀ M_ee g_e.

G is concave in c (Ā and H_e are affine in c, the other terms c² times a PSD matrix) and
G(0) = 0 ⊕ G₀ with G₀ = R − 𝔈(ΠᵀSΠ − P_dΠᵀSΠP_d + R) (𝔈(Y) = P_d Y P_d + diag_e(p_e q_e
Y_ee)), so G₀ ⪰ 0 and G(κ) ⪰ 0 prove G(c) ⪰ (1 − c/κ)G(0) + (c/κ)G(κ) ⪰ 0 for every c in
(0, κ].

*The gain's change.* The next step's state is (e', r u') with r = τ_{k+1}/τ_k. If c is
non-increasing from t₀ and (1/c)' < g there, r ∈ [1/(1 + ghc), 1]. With
[[βS, C], [Cᵀ, R]] ⪰ 0 (β ∈ (0, 1)): CᵀS⁻¹C ⪯ βR, so V(e, ru) − V(e, u) = −2(1 − r)eᵀCu −
(1 − r²)uᵀRu <= (1 − r)β eᵀSe, and eᵀSe <= V/(1 − β) (Q − (1 − β)(S ⊕ 0) is that matrix).
So V(e', ru') <= (1 + ghcβ/(1 − β)) V(e', u') and, for every k >= k₀ (c_k <= κ),

    E V_{k+1} <= (1 − α h c_k) E V_k + 2 h c_k² γ,      α = α' − gβ/(1 − β) > 0,

(when ghκβ/(1 − β) <= 1) with V_k >= (1 − β) E‖e_k‖²_S. The additive term is O(h c²):
with Σ c_k = ∞ and c_k → 0, E‖x_k − 1⊗θ‖² → 0: hold converges to θ. (The mean's limit
is 1⊗θ as for rescale: its mean drift is L_B's.)

*What is checked.* S ≻ 0 and [[βS, SΠP_d], [·, R]] ≻ 0 and G₀ ≻ 0 exactly (dyadic
rationals: no Q_d⁻¹ enters them), G(κ) ≻ 0 in verified floats (Q_d⁻¹'s entries enclosed
from their exact rational values), c(t) < κ, (1/c)' < g and c non-increasing from t₀, and
α <= α' − gβ/(1 − β), ghκβ/(1 − β) <= 1 in exact rationals.

*c_true(hold).* The largest constant gain below which the spectral radius of the second
moment map of z = (e, η) (the homogeneous part: Ā, the arrivals' variance and the
multiplicative noise) is < 1 (bisection); informational.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from ..rigorous.exact import Dyadic
from ..rigorous.floatmat import FloatMat
from .digital import EdgeNoise
from .loss import LossEdge

# -- the model's constant matrices, exactly -------------------------------------------


def _fr(a: np.ndarray) -> np.ndarray:
    return np.vectorize(Fraction, otypes=[object])(np.asarray(a, dtype=float))


def _zeros(r: int, c: int) -> np.ndarray:
    return np.full((r, c), Fraction(0), dtype=object)


def _eye(n: int) -> np.ndarray:
    out = _zeros(n, n)
    for k in range(n):
        out[k, k] = Fraction(1)
    return out


@dataclass(frozen=True)
class HoldModel:
    """The structure of the held measurements, in exact rationals (object arrays).

    Attributes
    ----------
    n, m, d : int
        Nd, Ed and the state dimension.
    pi : numpy.ndarray
        Π, Nd×Ed (edge e into agent i's rows).
    gam : numpy.ndarray
        Γ, Ed×Nd (A_ij at j, −|A_ij| at i).
    lap : numpy.ndarray
        L_B, Nd×Nd.
    q, p : tuple of Fraction
        q_e and p_e per row of the u block (each edge's value repeated d times).
    kd : tuple of numpy.ndarray
        K_eΔ_e per edge, d×Nd.
    g : tuple of numpy.ndarray
        g_e per edge, length d.
    """

    n: int
    m: int
    d: int
    pi: np.ndarray
    gam: np.ndarray
    lap: np.ndarray
    q: tuple
    p: tuple
    kd: tuple
    g: tuple


def hold_model(
    lap: Any, edges: Sequence[LossEdge], noises: Sequence[EdgeNoise], d: int
) -> HoldModel:
    """The model's matrices from the edges, their losses and noise, exactly.

    Parameters
    ----------
    lap : numpy.ndarray
        L_B: doubles, or an object array of exact rationals.
    edges : sequence of LossEdge
        The edges with their losses (p_e < 1).
    noises : sequence of EdgeNoise
        Their noise, in the same order.
    d : int
        The state dimension.

    Returns
    -------
    HoldModel
    """
    lap_a = np.asarray(lap)
    lapf = lap_a if lap_a.dtype == object else _fr(lap_a)
    n, m = lapf.shape[0], len(edges) * d
    pi, gam = _zeros(n, m), _zeros(m, n)
    q, p, kd, g = [], [], [], []
    for k, (e, ne) in enumerate(zip(edges, noises, strict=True)):
        rows = slice(k * d, (k + 1) * d)
        pi[e.i * d : (e.i + 1) * d, rows] = _eye(d)
        gam[rows, e.j * d : (e.j + 1) * d] += _fr(e.signed)
        gam[rows, e.i * d : (e.i + 1) * d] -= _fr(e.absw)
        pe = Fraction(e.p)
        q += [1 - pe] * d
        p += [pe] * d
        kmat = _fr(ne.absw) @ _fr(ne.f)
        sel = _zeros(d, n)
        sel[:, e.j * d : (e.j + 1) * d] += _eye(d)
        sel[:, e.i * d : (e.i + 1) * d] -= _eye(d)
        kd.append(kmat @ sel)
        sig = Fraction(float(ne.sigma))
        g.append(np.array([sig * sum(r, Fraction(0)) for r in _fr(ne.absw)], dtype=object))
    return HoldModel(n, m, d, pi, gam, lapf, tuple(q), tuple(p), tuple(kd), tuple(g))


@dataclass(frozen=True)
class StepConstants:
    """The constant matrices of G(c) at one c (exact rationals): Ā(c) (W×W), B̂(c) (W×Ed),
    B₀, B₁ (W×Ed), the τ² map F = h²Q_d⁻¹ΓL (Ed×Nd) and the scalars."""

    abar: np.ndarray
    bhat: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    f: np.ndarray


def step_constants(mo: HoldModel, h: float, c: float) -> StepConstants:
    """Ā(c), B̂(c), B₀, B₁ and h²Q_d⁻¹ΓL of the module docstring, exactly.

    Parameters
    ----------
    mo : HoldModel
        The model.
    h, c : float
        The period and the gain.

    Returns
    -------
    StepConstants
    """
    n, m = mo.n, mo.m
    hc = Fraction(h) * Fraction(c)
    qv = np.array(mo.q, dtype=object)
    pv = np.array(mo.p, dtype=object)
    qinv = np.array([1 / x for x in mo.q], dtype=object)
    gp = mo.gam @ mo.pi  # Ed×Ed
    inner = _eye(m) - hc * gp
    lower = qinv[:, None] * inner * qv[None, :]  # Q_d⁻¹(I − hcΓΠ)Q_d
    bhat = np.vstack([mo.pi * qv[None, :], lower])
    top = np.vstack([_eye(n) - hc * mo.lap, _zeros(m, n)])
    abar = np.hstack([top, bhat * pv[None, :]])
    b0 = np.vstack([mo.pi, np.diag(qinv).astype(object)])
    b0[n:, :] = _zeros(m, m)
    for k in range(m):
        b0[n + k, k] = qinv[k]
    b1 = np.vstack([_zeros(n, m), -(qinv[:, None] * gp)])
    hh = Fraction(h) * Fraction(h)
    f = hh * (qinv[:, None] * (mo.gam @ mo.lap))
    return StepConstants(abar, bhat, b0, b1, f)


# -- one builder for every arithmetic --------------------------------------------------


def _enclose(a: np.ndarray) -> FloatMat:
    """Exact rationals as the nearest doubles with a bound on their distance."""
    val = np.array([[float(x) for x in row] for row in a], dtype=float).reshape(a.shape)
    err = np.array(
        [
            [abs(Fraction(v) - x) for v, x in zip(vr, xr, strict=True)]
            for vr, xr in zip(val, a, strict=True)
        ],
        dtype=object,
    )
    rad = np.array([[float(x) for x in row] for row in err], dtype=float).reshape(a.shape)
    return FloatMat.of(val, rad * (1 + 1e-15) + np.where(rad > 0, 5e-324, 0.0))


def _dyadic_exact(a: np.ndarray) -> Dyadic:
    """Exact rationals with power-of-two denominators as a Dyadic (ValueError otherwise)."""
    flat = [Fraction(x) for x in np.asarray(a, dtype=object).ravel()]
    dens = [x.denominator for x in flat]
    if any(dd & (dd - 1) for dd in dens):
        raise ValueError("not dyadic")
    exp = max((dd.bit_length() - 1 for dd in dens), default=0)
    num = np.array([x.numerator << (exp - (x.denominator.bit_length() - 1)) for x in flat])
    return Dyadic(num.astype(object).reshape(np.asarray(a).shape), exp)


class HoldOps:
    """Products and scalings in floats, cvxpy, Dyadic or FloatMat (one formula for the
    SDP, the float checks and the proof).

    Parameters
    ----------
    kind : str
        ``float``, ``cvxpy``, ``dyadic`` or ``floatmat``.
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind

    def const(self, a: np.ndarray) -> Any:
        """An exact rational matrix in this arithmetic.

        Parameters
        ----------
        a : numpy.ndarray
            Object array of Fractions.

        Returns
        -------
        matrix
        """
        if self.kind == "dyadic":
            return _dyadic_exact(a)
        if self.kind == "floatmat":
            return _enclose(a)
        return np.array([[float(x) for x in row] for row in a], dtype=float).reshape(a.shape)

    def matrix(self, a: Any) -> Any:
        """A stated double matrix (or a cvxpy expression) in this arithmetic.

        Parameters
        ----------
        a : numpy.ndarray or cvxpy expression
            The matrix.

        Returns
        -------
        matrix
        """
        if self.kind == "dyadic":
            return Dyadic.of(a)
        if self.kind == "floatmat":
            return FloatMat.of(a)
        return a

    def mul(self, s: float, x: Any) -> Any:
        """s·x for an exact double s.

        Parameters
        ----------
        s : float
            The factor.
        x : matrix
            The matrix.

        Returns
        -------
        matrix
        """
        if self.kind == "dyadic":
            return x.scale(Dyadic.of(float(s)))
        if self.kind == "floatmat":
            return x.scale(float(s))
        return s * x

    def mask(self, x: Any, keep: np.ndarray) -> Any:
        """x with the entries outside ``keep`` (0/1) set to zero.

        Parameters
        ----------
        x : matrix
            The matrix.
        keep : numpy.ndarray
            0/1 of the same shape.

        Returns
        -------
        matrix
        """
        if self.kind == "dyadic":
            return Dyadic(x.num * keep.astype(int).astype(object), x.exp)
        if self.kind == "floatmat":
            return FloatMat(x.val * keep, x.rad * keep)
        if self.kind == "cvxpy":
            import cvxpy as cp

            return cp.multiply(keep, x)
        return x * keep

    def block(self, grid: list[list[Any]]) -> Any:
        """A block matrix.

        Parameters
        ----------
        grid : list of list of matrix
            The blocks.

        Returns
        -------
        matrix
        """
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


def _blockmask(m: int, d: int) -> np.ndarray:
    return np.kron(np.eye(m // d), np.ones((d, d))) if m else np.zeros((0, 0))


def functional(ops: HoldOps, mo: HoldModel, s: Any, r: Any) -> Any:
    """Q = [[S, SΠP_d], [(SΠP_d)ᵀ, R]].

    Parameters
    ----------
    ops : HoldOps
        The arithmetic.
    mo : HoldModel
        The model.
    s, r : matrix
        S (Nd×Nd) and R (Ed×Ed) in that arithmetic.

    Returns
    -------
    matrix
    """
    pv = np.array(mo.p, dtype=object)
    c = s @ ops.const(mo.pi * pv[None, :])
    return ops.block([[s, c], [c.T, r]])


def coupling(ops: HoldOps, mo: HoldModel, s: Any, r: Any, beta: float) -> Any:
    """[[βS, SΠP_d], [(SΠP_d)ᵀ, R]]: ⪰ 0 bounds the cross term when the gain changes.

    Parameters
    ----------
    ops : HoldOps
        The arithmetic.
    mo : HoldModel
        The model.
    s, r : matrix
        S and R.
    beta : float
        β.

    Returns
    -------
    matrix
    """
    pv = np.array(mo.p, dtype=object)
    c = s @ ops.const(mo.pi * pv[None, :])
    return ops.block([[ops.mul(beta, s), c], [c.T, r]])


def inverse_up(x: float) -> float:
    """The smallest double >= 1/x (x > 0), from the exact rational 1/x.

    Parameters
    ----------
    x : float
        x > 0.

    Returns
    -------
    float
    """
    want = 1 / Fraction(x)
    f = float(want)
    return f if Fraction(f) >= want else math.nextafter(f, math.inf)


def step_matrix(
    ops: HoldOps,
    mo: HoldModel,
    s: Any,
    r: Any,
    alpha1: float,
    rho: float,
    kappa: float,
    h: float,
    c: float,
) -> Any:
    """G(c) of the module docstring (the level κ enters the noise and τ² bounds).

    Parameters
    ----------
    ops : HoldOps
        The arithmetic.
    mo : HoldModel
        The model.
    s, r : matrix
        S and R.
    alpha1, rho, kappa, h, c : float
        α', ρ, κ, the period and the gain (1/ρ enters rounded up: a larger factor on
        the PSD term it multiplies proves more).

    Returns
    -------
    matrix
        W×W, W = Nd + Ed.
    """
    n, m, d = mo.n, mo.m, mo.d
    k = step_constants(mo, h, c)
    q = functional(ops, mo, s, r)
    ab = ops.const(k.abar)
    bh = ops.const(k.bhat)
    pq = np.array([a * b for a, b in zip(mo.p, mo.q, strict=True)], dtype=object)
    y = ops.mask(bh.T @ (q @ bh), _blockmask(m, d))
    var = ops.const(np.diag(pq).astype(object)) @ y  # Σ_e p_e q_e H_eᵀ Q H_e (u block)
    zn = ops.const(_zeros(n, n))
    znm = ops.const(_zeros(n, m))
    g = q - ab.T @ (q @ ab) - ops.block([[zn, znm], [znm.T, var]])
    if c == 0:
        return g
    g = g - ops.mul(alpha1, ops.mul(h, ops.mul(c, q))) - ops.mul(rho, ops.mul(c, q))
    f = ops.const(k.f)
    young = f.T @ (r @ f)
    ee = ops.mul(c, ops.mul(c, ops.mul(kappa, ops.mul(kappa, young))))
    ee = ee + ops.mul(c, ops.mul(c, ops.mul(kappa, ops.mul(inverse_up(rho), young))))
    b0, b1 = ops.const(k.b0), ops.const(k.b1)
    m1 = b0.T @ (q @ b0) + ops.mul(h, ops.mul(kappa, b1.T @ (q @ b1)))
    mm = ops.mask(m1 + ops.mul(h, ops.mul(kappa, m1)), _blockmask(m, d))
    kd = np.vstack(mo.kd) if mo.kd else _zeros(0, n)
    qv = np.array(mo.q, dtype=object)
    kdq = ops.const(qv[:, None] * kd)
    noise = ops.const(kd).T @ (mm @ kdq)
    ee = ee + ops.mul(h, ops.mul(c, ops.mul(c, noise)))
    ee = ops.mul(0.5, ee + ee.T)
    zm = ops.const(_zeros(m, m))
    return g - ops.block([[ee, znm], [znm.T, zm]])


@dataclass(frozen=True)
class HoldPlan:
    """A hold certificate's numbers: S, R, α' (the step's rate), ρ, β, the growth bound g
    of 1/c, the level κ and the proven rate α = α' − gβ/(1 − β) (rounded down)."""

    s: np.ndarray
    r: np.ndarray
    alpha1: float
    rho: float
    beta: float
    g: float
    kappa: float
    alpha: float


def hold_rate(alpha1: float, beta: float, g: float) -> Fraction:
    """α' − gβ/(1 − β) exactly.

    Parameters
    ----------
    alpha1, beta, g : float
        α', β and g.

    Returns
    -------
    fractions.Fraction
    """
    b = Fraction(beta)
    return Fraction(alpha1) - Fraction(g) * b / (1 - b)


def holds_in_floats(mo: HoldModel, pl: HoldPlan, h: float) -> bool:
    """Whether every stated inequality passes the verified-float test (G(κ) in verified
    floats; S, the coupling and G₀ too, though the proof takes them exactly).

    Parameters
    ----------
    mo : HoldModel
        The model.
    pl : HoldPlan
        The plan.
    h : float
        The period.

    Returns
    -------
    bool
    """
    return all(m.positive_definite().holds for _, m in hold_matrices(mo, pl.s, pl.r, pl, h, False))


def hold_matrices(
    mo: HoldModel, s: np.ndarray, r: np.ndarray, pl: Any, h: float, exact: bool
) -> list[tuple[str, Any]]:
    """The matrices to prove ≻ 0: S, the coupling and G₀ (exactly when ``exact``, else in
    verified floats) and G(κ) (verified floats: Q_d⁻¹ is not dyadic).

    Parameters
    ----------
    mo : HoldModel
        The model.
    s, r : numpy.ndarray
        S and R.
    pl : HoldPlan or similar
        α' (``alpha1``), ρ, β and κ.
    h : float
        The period.
    exact : bool
        Dyadic or FloatMat for the first three.

    Returns
    -------
    list of (str, Dyadic or FloatMat)
    """
    n = mo.n
    ops = HoldOps("dyadic" if exact else "floatmat")
    sm, rm = ops.matrix(s), ops.matrix(r)
    g0 = step_matrix(ops, mo, sm, rm, pl.alpha1, pl.rho, pl.kappa, h, 0.0)
    g0u: Any
    if exact:  # the e-rows of G(0) vanish by the identity C = SΠP_d; checked here too
        g0u = Dyadic(g0.num[n:, n:].copy(), g0.exp)
        zero = bool(np.all(g0.num[:n, :] == 0)) and bool(np.all(g0.num[:, :n] == 0))
        if not zero:  # the identity C = SΠP_d failed: nothing to prove with
            g0u = Dyadic(np.full_like(g0u.num, 0), 0)
    else:
        g0u = FloatMat(g0.val[n:, n:].copy(), g0.rad[n:, n:].copy())
    fm = HoldOps("floatmat")
    gk = step_matrix(
        fm, mo, FloatMat.of(s), FloatMat.of(r), pl.alpha1, pl.rho, pl.kappa, h, pl.kappa
    )
    return [
        ("S", sm),
        ("[[βS, SΠP_d], [·, R]]", coupling(ops, mo, sm, rm, pl.beta)),
        ("G₀", g0u),
        ("G(κ)", fm.mul(0.5, gk + gk.T)),
    ]


__all__ = [
    "HoldModel",
    "HoldOps",
    "HoldPlan",
    "StepConstants",
    "coupling",
    "functional",
    "hold_matrices",
    "hold_model",
    "hold_rate",
    "inverse_up",
    "holds_in_floats",
    "step_constants",
    "step_matrix",
]
