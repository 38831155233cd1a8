"""The lossy-link certificate with a delay D >= 1: the delay line's functional
(:mod:`.delayline`) with the expectation taken over the arrivals (:mod:`.loss`), and the
lossy mean-square limit c_true it is measured against.

*Model* (notation of :mod:`.loss` and :mod:`.delayline`; e = x − 1⊗θ, τ = h c_k,
y_k = e_{k−D}, m_e = χ_e (skip) or χ_e/q_e (rescale), δ_e = m_e − E m_e with variance v_e,
w_e = E[m_e²]). The lost or received terms act on the delayed state, as the noise does:

    e_{k+1} = e_k − τ L_χ y_k − τ Σ_e (E m_e − m_e)·P_i b_e + c √h Σ_e m_e (g_e ξ₁ + G_e y_k ξ₂).

The mean's fixed point e* (L̄ e* = Σ_e p_e L_e(1⊗θ) under skip, e* = 0 under rescale) is
the same as for D = 0. With w = e − e* and y = w_{k−D} (y is w's delayed value from here on)

    w_{k+1} = w_k − τ L̄ y + ζ_k,
    ζ_k = −τ Σ_e δ_e L_e y + τ Σ_e δ_e u_e + c √h Σ_e m_e (g_e ξ₁ + G_e (y + e*) ξ₂),

u_e = P_i b_e − L_e e* as in :mod:`.loss`. ζ_k has mean zero given the past (δ_e and the ξ
are independent of it and of each other), and for X ⪰ 0, *exactly*,

    E[ζᵀXζ | past] = yᵀ Q_c(X) y + ℓ_X(y) + h c² Γ(X),
    Q_c(X) = τ² Λ(X) + h c² N_w(X),  Λ(X) = Σ_e v_e L_eᵀXL_e,  N_w(X) = Σ_e w_e G_eᵀXG_e,
    ℓ_X(y) = 2τ² Σ_e v_e (−u_eᵀXL_e y) + 2h c² Σ_e w_e e*ᵀG_eᵀXG_e y,
    Γ(X) = h Σ_e v_e u_eᵀXu_e + Σ_e w_e (g_eᵀXg_e + e*ᵀG_eᵀXG_e e*).

No Young's inequality is used (unlike D = 0's μ = 2): the cross terms between the state and
the arrivals' forcing or the offset's noise are *linear* in y, so their expectation is
linear in the mean E y, which stays bounded (below).

*The functional.* With S, R_j, T_j as in :mod:`.delayline` (δ_{k,j} = w_{k−j} − w_{k−j−1})

    V_k = w_kᵀSw_k + (1/τ_k) Σ_j δ_{k,j}ᵀR_jδ_{k,j},
    Ṽ_k = E V_k − (1/τ_k) Σ_j F_{k−1−j}(R_j),  F_i(X) = h c_i² Γ(X) + ℓ_X(E y_i) at step i.

δ_{k,j} was made at step i = k−1−j: δ = −τ_i L̄ y_i + ζ_i, so E[δᵀXδ] = E[(τ_iL̄y_i)ᵀX(τ_iL̄y_i)]
+ E[y_iᵀQ(X)y_i] + F_i(X): the excess E[δᵀXδ] − F_i(X) is >= 0 and monotone in X, so
Ṽ_k >= E w_kᵀSw_k. Expanding E V_{k+1} as in :mod:`.delayline`, every term of the
lossless proof is there with L → L̄ and N → N_w + hΛ (τ²Λ = h c²·hΛ), plus the floors and
ℓ. The new increment's floor F_k(R_0)/τ_{k+1} is the one Ṽ_{k+1} subtracts; the
quadratic part is bounded with 1/τ_{k+1} <= 1/τ_k + g, which gives *the same step
condition*

    G(c) = F₁ + c F₂ + c² F₃ ⪰ 0 for c in (0, κ]  (G(0) = F₁ ⪰ 0, F₃ ⪯ 0: G(κ) ⪰ 0 suffices),
    K(c) = c·(h L̄ᵀR_0L̄ + N'(R_0)) + c²·(h² L̄ᵀ(S + gR_0)L̄ + h N'(S + gR_0)),
    N'(X) = N_w(X) + h Λ(X),

with L̄ for L_B in G's blocks, and the same decrease conditions on R_j, T_j
(:func:`.delayline.form_matrices`). What is left over per step is

    h c_k² Γ(S) + ℓ_S(E y_k) + Σ_j [F_{k−1−j}(T_j) + (g − g_k) F_{k−1−j}(R_{j+1})],

each term O(c̄_k²)·(1 + ‖E y‖) with c̄_k = max(c_k, …, c_{k−D}). The mean follows the
noiseless recursion m_{k+1} = m_k − τ L̄ m_{k−D}, whose own functional (V with E, no floors)
satisfies the same step with K replaced by its L̄ part alone, which G's K bounds: so from
k₀ on the mean's functional does not grow, and ‖E y‖ is bounded. Hence

    Ṽ_{k+1} <= (1 − α h c_k) Ṽ_k + h c_k·b_k,  b_k = O(c̄_k²/c_k) → 0,

and with Σ τ_k = ∞ and c_k → 0 (the sampled gain conditions; c̄_k/c_k → 1 by the growth
bound) limsup Ṽ_k <= 0, so E‖x_k − x*‖²_S <= Ṽ_k → 0: the agents go to x* under skip, to
1⊗θ under rescale. Nothing of the constants (Γ, ℓ) is stated, so nothing of them is
claimed; what the certificate proves is G(κ) ⪰ 0 with L̄ and N' (exactly, or in verified
floats), the decrease conditions, (1/c)' < g and c < κ from t₀ on, and the offset.

The factors v_e, w_e enter as doubles at or above their exact values
(:func:`.loss.factors`): they multiply positive semidefinite terms that G subtracts, so a
larger factor proves more. L̄ = L_B − Σ_e p_e L_e is exact (p_e is a double).

*c_true on lossy links.* The homogeneous part of the augmented second-moment map (the
moments of :mod:`ntc_design.simulate.loss` without the constant input):
Z ↦ A_c Z A_cᵀ + h c² Σ Ĝ Z_yy Ĝᵀ in the first block, with A_c built on L̄ and the Ĝ the
√w_e G_e and √(h v_e) L_e; the largest constant c with spectral radius < 1
(:func:`.ctrue.ms_limit`). Informational, not a claim.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..rigorous.exact import Dyadic
from ..rigorous.floatmat import FloatMat
from .ctrue import ms_limit
from .delayline import (
    DelayLinePlan,
    form_matrices,
    growth_bound,
    plan_delay_line,
    step_matrix,
)
from .digital import EdgeNoise, noise_matrix, noise_operator, scaled
from .loss import LossEdge, edge_laplacian, factors, mean_laplacian

#: The largest (D+1)·Nd for which the lossy delay line's SDP is tried at issue.
LOSS_DELAY_MAX_ORDER = 200


def arrival_noise(
    x: Any,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    h: float,
    policy: str,
    exact: bool,
) -> Any:
    """N'(X) = Σ_e w_e G_eᵀXG_e + h Σ_e v_e L_eᵀXL_e (module docstring), exactly or in
    verified floats (w_e, v_e at or above their exact values).

    Parameters
    ----------
    x : Dyadic or FloatMat
        X.
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise, in the same order.
    d : int
        The state dimension.
    h : float
        The period.
    policy : str
        ``skip`` or ``rescale``.
    exact : bool
        Dyadic (True) or FloatMat.

    Returns
    -------
    Dyadic or FloatMat
    """
    n = x.num.shape[0] if exact else x.val.shape[0]
    out: Any = None
    for e, ne in zip(edges, noises, strict=True):
        var, sq = factors(e.p, policy)
        term = scaled(noise_matrix(x, [ne], d, exact), sq)
        if var:
            le = (
                Dyadic.of(edge_laplacian(e, n, d))
                if exact
                else FloatMat.of(edge_laplacian(e, n, d))
            )
            term = term + scaled(scaled(le.T @ (x @ le), var), h)
        out = term if out is None else out + term
    if out is None:
        z = np.zeros((n, n))
        return Dyadic.of(z) if exact else FloatMat.of(z)
    return out


def arrival_operator(
    edges: Sequence[LossEdge], noises: Sequence[EdgeNoise], n: int, d: int, h: float, policy: str
) -> sp.csr_matrix:
    """X ↦ N'(X) on row-major vec(X) in floats (the SDP's map).

    Parameters
    ----------
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    n : int
        N·d.
    d : int
        The state dimension.
    h : float
        The period.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    scipy.sparse.csr_matrix
        (n², n²).
    """
    op = sp.csr_matrix((n * n, n * n))
    for e, ne in zip(edges, noises, strict=True):
        var, sq = factors(e.p, policy)
        op = op + sq * noise_operator([ne], n, d)
        if var:
            lt = sp.csr_matrix(edge_laplacian(e, n, d).T)
            op = op + (h * var) * sp.kron(lt, lt, format="csr")  # vec(AXB) = (A ⊗ Bᵀ)vec X
    return sp.csr_matrix(op)


def arrival_gs(
    edges: Sequence[LossEdge], noises: Sequence[EdgeNoise], n: int, d: int, h: float, policy: str
) -> list[np.ndarray]:
    """The Ĝ of the lossy second-moment map: √w_e G_e and √(h v_e) L_e per edge.

    Parameters
    ----------
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    n : int
        N·d.
    d : int
        The state dimension.
    h : float
        The period.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    list of numpy.ndarray
    """
    out = []
    for e, ne in zip(edges, noises, strict=True):
        var, sq = factors(e.p, policy)
        gm = np.zeros((n, n))
        gm[ne.i * d : ne.i * d + d, ne.j * d : ne.j * d + d] += ne.k
        gm[ne.i * d : ne.i * d + d, ne.i * d : ne.i * d + d] -= ne.k
        out.append(math.sqrt(sq) * gm)
        if var:
            out.append(math.sqrt(h * var) * edge_laplacian(e, n, d))
    return out


def loss_ms_limit(
    lap: np.ndarray,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    h: float,
    delay: int,
    policy: str,
) -> tuple[float | None, str]:
    """c_true on lossy links: the largest constant gain at which the homogeneous lossy
    second-moment map contracts (module docstring).

    Parameters
    ----------
    lap : numpy.ndarray
        L_B.
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    h : float
        The period.
    delay : int
        D.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    (float or None, str)
    """
    n = lap.shape[0]
    lbar = mean_laplacian(lap, edges, n, d, policy)
    gs = arrival_gs(edges, noises, n, d, h, policy)
    c, how = ms_limit([lbar], [noises], d, h, delay, [gs])
    return c, how.replace("second-moment map", "lossy second-moment map (mean L̄, arrivals)")


def loss_step_matrix(
    s: np.ndarray,
    rs: Sequence[np.ndarray],
    ts: Sequence[np.ndarray],
    lap: Any,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    alpha: float,
    kappa: float,
    g: float,
    h: float,
    policy: str,
    exact: bool,
) -> Any:
    """G(κ) with L̄ and N' (module docstring), exactly (Dyadic) or in verified floats.

    Parameters
    ----------
    s : numpy.ndarray
        S.
    rs, ts : sequence of numpy.ndarray
        R_j and T_j.
    lap : Dyadic or FloatMat
        L_B (L̄ is formed from it in the same arithmetic).
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    alpha, kappa, g, h : float
        α, κ, the growth bound of 1/c and the period.
    policy : str
        ``skip`` or ``rescale``.
    exact : bool
        Dyadic (True) or FloatMat.

    Returns
    -------
    Dyadic or FloatMat
        ((D+1)·Nd)², to be proven ⪰ 0.
    """
    n = s.shape[0]
    lbar = mean_laplacian(lap, edges, n, d, policy)
    return step_matrix(
        s,
        rs,
        ts,
        lbar,
        noises,
        d,
        alpha,
        kappa,
        g,
        h,
        exact,
        lambda x: arrival_noise(x, edges, noises, d, h, policy, exact),
    )


def loss_holds_in_floats(
    pl: DelayLinePlan,
    lap: np.ndarray,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    h: float,
    policy: str,
) -> bool:
    """Whether the plan's decrease conditions and G(κ) pass the verified-float test.

    Parameters
    ----------
    pl : DelayLinePlan
        The plan.
    lap : numpy.ndarray
        L_B.
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    h : float
        The period.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    bool
    """
    mats = [m for _, m in form_matrices(pl.s, pl.rs, pl.ts, pl.alpha, pl.kappa, pl.g, h, False)]
    mats.append(
        loss_step_matrix(
            pl.s,
            pl.rs,
            pl.ts,
            FloatMat.of(lap),
            edges,
            noises,
            d,
            pl.alpha,
            pl.kappa,
            pl.g,
            h,
            policy,
            False,
        )
    )
    return all(m.positive_definite().holds for m in mats)


def plan_loss_delay(
    lap: np.ndarray,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    h: float,
    delay: int,
    policy: str,
    gain: Any,
) -> tuple[DelayLinePlan | None, float | None, str]:
    """S, R_j, T_j, α and κ of the lossy delay line (the SDP of
    :func:`.delayline.plan_delay_line` on L̄ and N', searched up to c_true on lossy links),
    checked in verified floats.

    Parameters
    ----------
    lap : numpy.ndarray
        L_B.
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    h : float
        The period.
    delay : int
        D >= 1.
    policy : str
        ``skip`` or ``rescale``.
    gain : str or dict
        c(t) (a schedule gives no plan: the growth bound needs an expression).

    Returns
    -------
    (DelayLinePlan or None, float or None, str)
        The plan (None and why in the text when there is none), c_true on lossy links
        and how it was computed.
    """
    n = lap.shape[0]
    if n * (delay + 1) > LOSS_DELAY_MAX_ORDER:
        why = f"(D+1)·Nd = {n * (delay + 1)} > {LOSS_DELAY_MAX_ORDER} for the delay line's SDP"
        return None, None, why
    c_true, how = loss_ms_limit(lap, edges, noises, d, h, delay, policy)
    g = growth_bound(gain)
    if c_true is None or g is None:
        return None, c_true, how if c_true is None else "the delay line needs c(t) as an expression"
    lbar = mean_laplacian(lap, edges, n, d, policy)
    ops = [arrival_operator(edges, noises, n, d, h, policy)]

    def holds(pl: DelayLinePlan) -> bool:
        return loss_holds_in_floats(pl, lap, edges, noises, d, h, policy)

    pl = plan_delay_line([lbar], [noises], d, h, delay, g, c_true, ops, holds)
    if pl is None:
        return None, c_true, "the delay line's SDP found no κ > 0 for the mean matrix"
    return pl, c_true, how


__all__ = [
    "LOSS_DELAY_MAX_ORDER",
    "arrival_gs",
    "arrival_noise",
    "arrival_operator",
    "loss_holds_in_floats",
    "loss_ms_limit",
    "loss_step_matrix",
    "plan_loss_delay",
]
