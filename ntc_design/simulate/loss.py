"""Exact first and second moments of the digital protocol on lossy links
(:mod:`ntc_design.protocol.loss`), and the mean offset that skipping lost terms causes.

In error coordinates e = x − 1⊗θ, edge e = (j -> i) measures, D samples late,

    a_e = A_ij e_j − |A_ij| e_i + b_e,   b_e = (A_ij − |A_ij|) θ,
    n_e = (g_e ξ_{k,e,1} + K_e (e_j − e_i) ξ_{k,e,2}) / √h,

(b_e ≠ 0 only on an antagonistic edge) and the informed agents' term, never lost, is the
constant u − L_δ(1⊗θ) = −Σ_e P_i b_e (L_δ = L_B − Σ_e L_e, the grounding). With τ = h c_k
and χ_{k,e} ~ Bernoulli(q_e), q_e = 1 − p_e, independent of everything else:

    skip:     e_{k+1} = e_k − τ L_δ e_{k−D} − τ Σ_e P_i b_e + τ Σ_e χ_e P_i (a_e + n_e)
    rescale:  the same with χ_e / q_e in place of χ_e
    hold:     y_e ← y_e + χ_e (a_e + n_e − y_e),  then
              e_{k+1} = e_k − τ L_δ e_{k−D} − τ Σ_e P_i b_e + τ Σ_e P_i y_e

(y_e starts at the noiseless a_e of the initial state). Without loss each is the lossless
recursion of :mod:`.digital`. On the augmented state z = (e_k, …, e_{k−D}, 1, y_1 … y_E)
(the held y only for hold) a step is z' = M₀ z + Σ_e χ_e R_e (r_e z + n_e) with r_e the
d×W row block of a_e (minus y_e for hold) and R_e its placement (τ P_i for skip and
rescale, with the y_e rows for hold). With μ_e, v_e, w_e the mean and the variance of the
edge's multiplier and the mean of its square (q, q(1 − q), q for skip and hold; 1,
(1 − q)/q, 1/q for rescale), and M̄ = M₀ + Σ_e μ_e R_e r_e:

    m'  = M̄ m
    Z'  = M̄ Z M̄ᵀ + Σ_e R_e ( v_e r_e Z r_eᵀ + w_e N_e ) R_eᵀ,
    N_e = E[n_e n_eᵀ] = (g_e g_eᵀ + K_e Δ_e Z Δ_eᵀ K_eᵀ) / h,

exactly (the arrivals are independent across edges, so their cross terms vanish; the
noise is independent of the arrivals and of z). Under skip the mean converges, where it
converges, to x* with (L_δ + Σ_e q_e L_e) x* = u: the offset ‖x* − 1⊗θ‖
(:func:`mean_offset`); rescale and hold keep 1⊗θ.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, format_bytes
from ..numerics.memory import available_memory
from ..protocol.loss import loss_width
from .digital import MEMORY_SHARE
from .grid import TimeGrid
from .moments import MOMENTS_MAX_ND, MomentRecorder, Moments
from .system import ModeSystem

#: Dense W×W matrices alive during a step of the lossy moments (W: the augmented state).
LOSS_COPIES = 6


@dataclass(frozen=True)
class EdgeTerms:
    """One mode's edges in the form the lossy recursion takes them.

    Attributes
    ----------
    signed : numpy.ndarray
        (E, d, d) A_ij.
    absw : numpy.ndarray
        (E, d, d) |A_ij|.
    offset : numpy.ndarray
        (E, d) b_e = (A_ij − |A_ij|) θ.
    grounding : numpy.ndarray
        (Nd, Nd) L_δ = L_B − Σ_e L_e, dense.
    """

    signed: np.ndarray
    absw: np.ndarray
    offset: np.ndarray
    grounding: np.ndarray


def edge_terms(s: ModeSystem, theta: np.ndarray) -> EdgeTerms:
    """A_ij (the negated off-diagonal blocks of L_B), |A_ij|, b_e and L_δ of a mode.

    Parameters
    ----------
    s : ModeSystem
        The mode.
    theta : numpy.ndarray
        θ, length d.

    Returns
    -------
    EdgeTerms
    """
    d, ne = s.dim, s.n_edges
    lap = s.lap_b_dense()
    signed = np.empty((ne, d, d))
    ground = lap.copy()
    for e in range(ne):
        i, j = int(s.dst[e]), int(s.src[e])
        signed[e] = -lap[i * d : (i + 1) * d, j * d : (j + 1) * d]
        ground[i * d : (i + 1) * d, j * d : (j + 1) * d] += signed[e]
        ground[i * d : (i + 1) * d, i * d : (i + 1) * d] -= s.abs_w[e]
    th = np.asarray(theta, dtype=float)
    return EdgeTerms(signed, s.abs_w, (signed - s.abs_w) @ th, ground)


def multipliers(q: np.ndarray, policy: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mean, the variance and the mean square of each edge's multiplier χ_e (skip,
    hold) or χ_e / q_e (rescale), χ_e ~ Bernoulli(q_e).

    Parameters
    ----------
    q : numpy.ndarray
        (E,) arrival probabilities 1 − p_e.
    policy : str
        ``skip``, ``rescale`` or ``hold``.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        μ_e, v_e, w_e.

    Examples
    --------
    >>> [float(a[0]) for a in multipliers(np.array([0.5]), "rescale")]
    [1.0, 1.0, 2.0]
    """
    q = np.asarray(q, dtype=float)
    if policy == "rescale":
        return np.ones_like(q), (1.0 - q) / q, 1.0 / q
    return q.copy(), q * (1.0 - q), q.copy()


def mean_offset(s: ModeSystem, theta: np.ndarray, loss: np.ndarray, policy: str) -> np.ndarray:
    """lim E[x] − 1⊗θ of the lossy protocol when its mean converges: under skip the
    solution e* of (L_δ + Σ_e q_e L_e) e* = −Σ_e p_e P_i b_e (so x* = 1⊗θ + e* solves
    (L_δ + Σ_e q_e L_e) x* = u); zero for rescale and hold, whose mean drift is L_B's.

    Parameters
    ----------
    s : ModeSystem
        The mode.
    theta : numpy.ndarray
        θ.
    loss : numpy.ndarray
        (E,) p_e.
    policy : str
        The policy.

    Returns
    -------
    numpy.ndarray
        e*, length Nd.

    Raises
    ------
    InputError
        The mean matrix is singular (no unique limit).
    """
    nd_, d = s.nd, s.dim
    if policy != "skip":
        return np.zeros(nd_)
    et = edge_terms(s, theta)
    q = 1.0 - np.asarray(loss, dtype=float)
    mat = et.grounding.copy()
    rhs = np.zeros(nd_)
    for e in range(s.n_edges):
        i, j = int(s.dst[e]), int(s.src[e])
        mat[i * d : (i + 1) * d, i * d : (i + 1) * d] += q[e] * et.absw[e]
        mat[i * d : (i + 1) * d, j * d : (j + 1) * d] -= q[e] * et.signed[e]
        rhs[i * d : (i + 1) * d] -= (1.0 - q[e]) * et.offset[e]
    try:
        return np.linalg.solve(mat, rhs)
    except np.linalg.LinAlgError:
        raise InputError(
            "L_δ + Σ_e (1 − p_e) L_e is singular; the mean has no unique limit",
            field="digital.loss",
        ) from None


def check_loss_moments(nd_: int, delay: int, n_edges: int, d: int, policy: str) -> None:
    """Refuse, before anything is allocated, lossy moments that would not fit in memory.

    Parameters
    ----------
    nd_ : int
        N·d.
    delay : int
        D.
    n_edges : int
        E.
    d : int
        The state dimension.
    policy : str
        The policy.

    Raises
    ------
    InputError
        Naming ``method`` or ``digital.loss``.
    """
    if nd_ > MOMENTS_MAX_ND:
        raise InputError(
            f"exact moments at Nd = {nd_} exceed the limit Nd <= {MOMENTS_MAX_ND}; use method: mc",
            field="method",
        )
    w = loss_width(nd_, delay, n_edges, d, policy)
    need = LOSS_COPIES * 8.0 * (w * w + (n_edges * d) ** 2)
    avail = MEMORY_SHARE * available_memory()
    if need > avail:
        raise InputError(
            f"the exact moments with lossy links hold W² = {w}² numbers, about "
            f"{format_bytes(need)}, more than {format_bytes(avail)}; use method: mc",
            field="digital.loss",
        )


@dataclass(frozen=True)
class LossMoments:
    """The lossy recursion's exact moments at the save times, the peak of E‖e_k‖² over
    every step and when it happened, and the mean's limit offset."""

    moments: Moments
    peak: float
    peak_time: float
    offset: float


def _structure(s: ModeSystem, et: EdgeTerms, delay: int, policy: str):
    """S (the shift and the identities), T₀ (the τ part of M₀), the stacked r_e (Ed×W),
    the top placement (W×Ed, P_i per edge) and the y placement (W×Ed, hold only)."""
    nd_, d, ne = s.nd, s.dim, s.n_edges
    hold = policy == "hold"
    w = loss_width(nd_, delay, ne, d, policy)
    one = (delay + 1) * nd_  # the constant's index
    lo = delay * nd_  # the block of e_{k−D}
    shift = np.zeros((w, w))
    shift[:nd_, :nd_] = np.eye(nd_)
    for b in range(1, delay + 1):
        shift[b * nd_ : (b + 1) * nd_, (b - 1) * nd_ : b * nd_] = np.eye(nd_)
    shift[one, one] = 1.0
    t0 = np.zeros((w, w))
    t0[:nd_, lo : lo + nd_] = -et.grounding
    for e in range(ne):
        i = int(s.dst[e])
        t0[i * d : (i + 1) * d, one] -= et.offset[e]
    r = np.zeros((ne * d, w))
    top = np.zeros((w, ne * d))
    ypl = np.zeros((w, ne * d))
    for e in range(ne):
        i, j = int(s.dst[e]), int(s.src[e])
        rows = slice(e * d, (e + 1) * d)
        r[rows, lo + j * d : lo + (j + 1) * d] += et.signed[e]
        r[rows, lo + i * d : lo + (i + 1) * d] -= et.absw[e]
        r[rows, one] = et.offset[e]
        top[i * d : (i + 1) * d, rows] = np.eye(d)
        if hold:
            y0 = one + 1 + e * d
            r[rows, y0 : y0 + d] -= np.eye(d)
            ypl[y0 : y0 + d, rows] = np.eye(d)
            shift[y0 : y0 + d, y0 : y0 + d] = np.eye(d)
            t0[i * d : (i + 1) * d, y0 : y0 + d] += np.eye(d)
    return shift, t0, r, top, ypl


def loss_moments(
    s: ModeSystem,
    grid: TimeGrid,
    gain: Callable[[np.ndarray], np.ndarray],
    eps0: np.ndarray,
    theta: np.ndarray,
    delay: int,
    loss: np.ndarray,
    policy: str,
) -> LossMoments:
    """Exact moments of the sampled, delayed recursion on lossy links from a deterministic
    start (the initial state held for k < 0, the held measurements at their noiseless
    initial values).

    Parameters
    ----------
    s : ModeSystem
        The mode (one topology; a linear f).
    grid : TimeGrid
        The sampling grid (:func:`.digital.digital_grid`).
    gain : callable
        Vectorised c(t).
    eps0 : numpy.ndarray
        e_0 = x(0) − 1⊗θ.
    theta : numpy.ndarray
        θ.
    delay : int
        D.
    loss : numpy.ndarray
        (E,) p_e.
    policy : str
        ``skip``, ``rescale`` or ``hold``.

    Returns
    -------
    LossMoments

    Raises
    ------
    InputError
        Too large (:func:`check_loss_moments`).
    """
    n, d, nd_, ne = s.n_agents, s.dim, s.nd, s.n_edges
    check_loss_moments(nd_, delay, ne, d, policy)
    k_steps = grid.n_steps
    et = edge_terms(s, theta)
    q = 1.0 - np.asarray(loss, dtype=float)
    mu, var, sq = multipliers(q, policy)
    shift, t0, r, top, ypl = _structure(s, et, delay, policy)
    mu_d = np.repeat(mu, d)
    m_top = t0 + top @ (mu_d[:, None] * r)  # the τ part of M̄
    m_y = shift + ypl @ (mu_d[:, None] * r)  # the rest
    lo = delay * nd_
    one = (delay + 1) * nd_
    z0 = np.concatenate([np.tile(np.asarray(eps0, dtype=float), delay + 1), [1.0]])
    if policy == "hold":
        z0 = np.concatenate([z0, np.zeros(ne * d)])
        z0[one + 1 :] = r[:, : one + 1] @ z0[: one + 1]  # y_e = the noiseless a_e
    m, zz = z0.copy(), np.outer(z0, z0)
    ai = np.arange(d)
    rows_i = lo + s.dst[:, None] * d + ai  # (E, d) e_{k−D,i}
    rows_j = lo + s.src[:, None] * d + ai
    gg = np.einsum("ea,eb->eab", s.g_edge, s.g_edge)
    kb = s.k_blocks
    c_all = np.asarray(gain(grid.t[:-1]), dtype=float) * np.ones(k_steps)
    h_all = np.diff(grid.t)
    # the period whose held noise a step carries: h, also on a last partial step s
    # (its noise factor is s²/h, :meth:`.grid.TimeGrid.noise_h`)
    period_all = h_all**2 / grid.noise_h()
    rec = MomentRecorder(grid.save_times, n, d)
    save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
    if 0 in save_at:
        rec.put(save_at[0], m[:nd_], zz[:nd_, :nd_])
    peak, peak_k = float(np.trace(zz[:nd_, :nd_])), 0
    blocks = np.zeros((ne * d, ne * d))
    bi = np.arange(ne)[:, None, None] * d + ai[None, :, None]
    bj = np.arange(ne)[:, None, None] * d + ai[None, None, :]
    for k in range(k_steps):
        tau, h = float(c_all[k] * h_all[k]), float(period_all[k])
        mbar = m_y + tau * m_top
        place = ypl + tau * top
        rz = (r @ zz).reshape(ne, d, -1)
        rzr = np.einsum("eaw,ebw->eab", rz, r.reshape(ne, d, -1))
        dz = (
            zz[rows_j[:, :, None], rows_j[:, None, :]]
            - zz[rows_j[:, :, None], rows_i[:, None, :]]
            - zz[rows_i[:, :, None], rows_j[:, None, :]]
            + zz[rows_i[:, :, None], rows_i[:, None, :]]
        )
        noise = (gg + kb @ dz @ kb.transpose(0, 2, 1)) / h
        blocks[bi, bj] = var[:, None, None] * rzr + sq[:, None, None] * noise
        new = mbar @ zz @ mbar.T + place @ blocks @ place.T
        zz = 0.5 * (new + new.T)
        m = mbar @ m
        tr = float(np.trace(zz[:nd_, :nd_]))
        if not tr <= peak:
            peak, peak_k = tr, k + 1
        if k + 1 in save_at:
            rec.put(save_at[k + 1], m[:nd_], zz[:nd_, :nd_])
            rec.k = save_at[k + 1] + 1
    offset = float(np.linalg.norm(mean_offset(s, theta, loss, policy)))
    moments = rec.result(zz[:nd_, :nd_].copy(), k_steps)
    return LossMoments(moments, peak, float(grid.t[peak_k]), offset)


def loss_note(policy: str, loss: np.ndarray, offset: float, theta_norm: float) -> str:
    """What a run on lossy links says about where its mean goes.

    Parameters
    ----------
    policy : str
        The policy.
    loss : numpy.ndarray
        (E,) p_e.
    offset : float
        ‖lim E x − 1⊗θ‖.
    theta_norm : float
        ‖1⊗θ‖.

    Returns
    -------
    str
    """
    arr = np.asarray(loss, dtype=float)
    lo, hi = (float(arr.min()), float(arr.max())) if arr.size else (0.0, 0.0)
    p = f"p = {hi:g}" if lo == hi else f"p_e in [{lo:g}, {hi:g}]"
    if policy != "skip":
        return f"lossy links ({p}, {policy}): the mean drift is L_B's, the mean goes to 1⊗θ"
    share = offset / theta_norm if theta_norm > 0 else math.inf
    return (
        f"lossy links ({p}, skip): the mean goes to x* with ‖x* − 1⊗θ‖ = {offset:.4g} "
        f"({share:.1%} of ‖1⊗θ‖), not to 1⊗θ"
    )


__all__ = [
    "LOSS_COPIES",
    "EdgeTerms",
    "LossMoments",
    "check_loss_moments",
    "edge_terms",
    "loss_moments",
    "loss_note",
    "loss_width",
    "mean_offset",
    "multipliers",
]
