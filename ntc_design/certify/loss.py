"""The lossy-link certificate's mathematics (:mod:`ntc_design.protocol.loss`): the
mean-square contraction of the sampled recursion (D = 0) with the expectation taken over
the arrivals, and the offset that skipping lost terms causes, by an exact rational solve.

Model (e = x − 1⊗θ, τ = h c_k, χ_e ~ Bernoulli(q_e), q_e = 1 − p_e, independent): the
step uses L_χ = L_δ + Σ_e m_e L_e with m_e = χ_e (skip) or χ_e / q_e (rescale); L_e is
edge e's Laplacian block (|A_ij| at (i, i), −A_ij at (i, j)) and L_δ = L_B − Σ_e L_e. With
δ_e = m_e − E m_e (variance v_e), L̄ = E L_χ (L_B − Σ_e p_e L_e for skip, L_B for rescale):

    e_{k+1} = (I − τ L_χ) e_k + τ f_χ + c √h Σ_e m_e (g_e ξ1 + G_e e_k ξ2),

where f_χ = Σ_e δ_e u_e is the arrivals' zero-mean forcing (u_e = P_i b_e − L_e e* with
b_e = (A_ij − |A_ij|) θ; e* the fixed point of the mean, below). With w = e − e*,
‖·‖_P = ·ᵀP·, M̄ = P L̄ + L̄ᵀ P, S = Σ_e v_e L_eᵀ P L_e and N̄ = Σ_e E[m_e²] G_eᵀ P G_e,
Young's inequality on the cross term E[wᵀ(I − τL_χ)ᵀ P τ f_χ] = −τ² Σ_e v_e wᵀL_eᵀPu_e
gives

    E[‖w_{k+1}‖²_P | w_k] <= w_kᵀ(P − τ M̄ + τ²(L̄ᵀPL̄ + 2S) + h c² μ N̄)w_k + h c² Γ,

μ = 2 under skip (the noise is taken at e = w + e*: (w + e*)ᵀN̄(w + e*) <= 2wᵀN̄w +
2e*ᵀN̄e*), μ = 1 under rescale (e* = 0), and Γ a constant (the additive energy, the
forcing's variance and 2e*ᵀN̄e*). So

    (M̄ − αP) − κ·(h·(L̄ᵀPL̄ + 2S) + μ N̄) ⪰ 0

gives E‖w_{k+1}‖²_P <= (1 − ατ_k) E‖w_k‖²_P + h c_k² Γ whenever c_k <= κ: from the first
step on which c <= κ forever, E‖x − x*‖² contracts up to a term that vanishes with c_k;
with Σ τ_k = ∞ and c_k → 0, E‖x_k − x*‖² → 0. Under rescale x* = 1⊗θ; under skip x* = 1⊗θ
+ e* with L̄ e* = Σ_e p_e L_e (1⊗θ) (equivalently L̄ x* = u for u = L_B(1⊗θ), Lemma 1's
identity), solved here in exact rationals. hold keeps an augmented state: it is
certified by :mod:`.loss_hold`.

The scalar factors enter exactly (p_e is a dyadic rational, so are q_e and q_e(1 − q_e));
rescale's v_e = (1 − q_e)/q_e and E[m_e²] = 1/q_e enter as dyadic upper bounds (they
multiply positive semidefinite terms that the inequality subtracts, so a larger factor
proves more).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.linalg as sla

from ..rigorous.exact import Dyadic
from ..rigorous.floatmat import FloatMat
from .digital import BACKOFF, EdgeNoise, candidate_ps, noise_matrix, scaled

#: The largest N·d whose offset is solved in exact rationals.
EXACT_OFFSET_MAX_ND = 120


@dataclass(frozen=True)
class LossEdge:
    """One edge j -> i with its signed and absolute weight and its loss p_e."""

    i: int
    j: int
    signed: np.ndarray
    absw: np.ndarray
    p: float


def loss_edges(top: Any, losses: dict[tuple[int, int], float]) -> list[LossEdge]:
    """Every edge of a topology in its (sorted) edge order with its loss.

    Parameters
    ----------
    top : Topology
        The topology.
    losses : dict of (int, int) to float
        p_e by (i, j); an edge without one has p = 0.

    Returns
    -------
    list of LossEdge
    """
    return [
        LossEdge(
            i,
            j,
            np.asarray(top.weight(i, j), dtype=float),
            np.asarray(top.abs_weight(i, j), dtype=float),
            float(losses.get((i, j), 0.0)),
        )
        for i, j in top.edges
    ]


def edge_laplacian(e: LossEdge, n: int, d: int) -> np.ndarray:
    """L_e: |A_ij| at block (i, i), −A_ij at (i, j), zero elsewhere.

    Parameters
    ----------
    e : LossEdge
        The edge.
    n : int
        N·d.
    d : int
        The state dimension.

    Returns
    -------
    numpy.ndarray
    """
    out = np.zeros((n, n))
    out[e.i * d : e.i * d + d, e.i * d : e.i * d + d] = e.absw
    out[e.i * d : e.i * d + d, e.j * d : e.j * d + d] -= e.signed
    return out


def _up(x: Fraction) -> float:
    """The smallest double >= x."""
    f = float(x)
    return f if Fraction(f) >= x else math.nextafter(f, math.inf)


def factors(p: float, policy: str) -> tuple[float, float]:
    """(v_e, E[m_e²]) of one edge as doubles at or above their exact values.

    Parameters
    ----------
    p : float
        p_e.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    (float, float)

    Examples
    --------
    >>> factors(0.5, "skip"), factors(0.5, "rescale")
    ((0.25, 0.5), (1.0, 2.0))
    """
    q = 1 - Fraction(p)
    if policy == "rescale":
        return _up((1 - q) / q), _up(1 / q)
    return _up(q * (1 - q)), _up(q)


def _lift(a: np.ndarray, exact: bool) -> Any:
    return Dyadic.of(a) if exact else FloatMat.of(a)


def mean_laplacian(lap: Any, edges: Sequence[LossEdge], n: int, d: int, policy: str) -> Any:
    """L̄ = L_B − Σ_e p_e L_e (skip) or L_B (rescale), exactly for a Dyadic L_B.

    Parameters
    ----------
    lap : Dyadic or FloatMat or numpy.ndarray
        L_B.
    edges : sequence of LossEdge
        The edges.
    n : int
        N·d.
    d : int
        The state dimension.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    Dyadic, FloatMat or numpy.ndarray
    """
    if policy != "skip":
        return lap
    if isinstance(lap, np.ndarray):
        return lap - sum((e.p * edge_laplacian(e, n, d) for e in edges), np.zeros((n, n)))
    exact = isinstance(lap, Dyadic)
    out = lap
    for e in edges:
        if e.p:
            out = out - scaled(_lift(edge_laplacian(e, n, d), exact), e.p)
    return out


def loss_ms_matrix(
    p: Any,
    lap: Any,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    alpha: float,
    kappa: float,
    h: float,
    policy: str,
) -> Any:
    """(M̄ − αP) − κ·(h·(L̄ᵀPL̄ + 2S) + μ N̄) of the module docstring.

    Parameters
    ----------
    p : Dyadic or FloatMat
        P.
    lap : Dyadic or FloatMat
        L_B (of the same type).
    edges : sequence of LossEdge
        The edges with their losses.
    noises : sequence of EdgeNoise
        The edges' noise, in the same order.
    d : int
        The state dimension.
    alpha, kappa, h : float
        α, κ and the period.
    policy : str
        ``skip`` or ``rescale``.

    Returns
    -------
    Dyadic or FloatMat
    """
    exact = isinstance(p, Dyadic)
    n = p.num.shape[0] if exact else p.val.shape[0]
    lbar = mean_laplacian(lap, edges, n, d, policy)
    pl = p @ lbar
    quad = lbar.T @ pl
    noise: Any = None
    for e, ne in zip(edges, noises, strict=True):
        var, sq = factors(e.p, policy)
        le = _lift(edge_laplacian(e, n, d), exact)
        term = scaled(le.T @ (p @ le), 2.0 * var) if var else None
        if term is not None:
            quad = quad + term
        nt = scaled(noise_matrix(p, [ne], d, exact), sq * (2.0 if policy == "skip" else 1.0))
        noise = nt if noise is None else noise + nt
    rhs = scaled(quad, h) if noise is None else scaled(quad, h) + noise
    return (pl + pl.T) - scaled(p, alpha) - scaled(rhs, kappa)


def _gen_lmin(a: np.ndarray, b: np.ndarray) -> float:
    """λ_min of the symmetric pencil (a, b), b ≻ 0."""
    return float(sla.eigh(0.5 * (a + a.T), 0.5 * (b + b.T), eigvals_only=True)[0])


@dataclass(frozen=True)
class LossPlan:
    """What a lossy-link certificate states: P, α and the level κ."""

    p: np.ndarray
    alpha: float
    kappa: float
    source: str


def plan_loss(
    lap: np.ndarray,
    edges: Sequence[LossEdge],
    noises: Sequence[EdgeNoise],
    d: int,
    h: float,
    policy: str,
    fixed: np.ndarray | None = None,
) -> LossPlan | None:
    """P, α = λ_min(M̄, P)/2 and the largest κ of the inequality (backed off by
    :data:`.digital.BACKOFF`), over the digital kind's candidate P for L̄.

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
    policy : str
        ``skip`` or ``rescale``.
    fixed : numpy.ndarray, optional
        The continuous design's Lyapunov matrix.

    Returns
    -------
    LossPlan or None
        None when no candidate gives α > 0.
    """
    n = lap.shape[0]
    lbar = mean_laplacian(lap, edges, n, d, policy)
    best: LossPlan | None = None
    for source, p in candidate_ps([lbar], [noises], d, fixed):
        m = p @ lbar + lbar.T @ p
        try:
            lam = _gen_lmin(m, p)
        except (np.linalg.LinAlgError, ValueError):
            continue
        if not lam > 0:
            continue
        alpha = 0.5 * lam
        zero = loss_ms_matrix(
            FloatMat.of(p), FloatMat.of(lap), edges, noises, d, 0.0, 0.0, h, policy
        )
        one = loss_ms_matrix(
            FloatMat.of(p), FloatMat.of(lap), edges, noises, d, 0.0, 1.0, h, policy
        )
        r = zero.val - one.val  # h(L̄ᵀPL̄ + 2S) + μN̄
        try:
            worst = -_gen_lmin(-r, m - alpha * p)
        except (np.linalg.LinAlgError, ValueError):
            continue
        kappa = 1.0 / (worst * (1 + BACKOFF)) if worst > 0 else 1e300
        alpha *= 1 - BACKOFF
        if best is None or kappa > best.kappa:
            best = LossPlan(p, alpha, kappa, source)
    return best


def _solve(a: list[list[Fraction]], b: list[Fraction]) -> list[Fraction] | None:
    """a x = b in exact rationals (Gaussian elimination, pivot on a non-zero entry);
    None when a is singular."""
    n = len(b)
    m = [row[:] + [b[k]] for k, row in enumerate(a)]
    for c in range(n):
        piv = next((r for r in range(c, n) if m[r][c] != 0), None)
        if piv is None:
            return None
        m[c], m[piv] = m[piv], m[c]
        inv = 1 / m[c][c]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c] * inv
                m[r] = [x - f * y for x, y in zip(m[r], m[c], strict=True)]
    return [m[k][n] / m[k][k] for k in range(n)]


def exact_offset(
    lap: np.ndarray, edges: Sequence[LossEdge], theta: np.ndarray, d: int
) -> Fraction | None:
    """‖e*‖² for L̄ e* = Σ_e p_e L_e (1⊗θ) under skip, in exact rationals from the floats'
    exact values (None when L̄ is singular or N·d is past :data:`EXACT_OFFSET_MAX_ND`).

    Parameters
    ----------
    lap : numpy.ndarray
        L_B: doubles, or an object array of exact rationals.
    edges : sequence of LossEdge
        The edges with their losses.
    theta : numpy.ndarray
        θ, length d.
    d : int
        The state dimension.

    Returns
    -------
    fractions.Fraction or None
    """
    n = lap.shape[0]
    if n > EXACT_OFFSET_MAX_ND:
        return None
    fr = np.vectorize(Fraction, otypes=[object])
    lbar = fr(np.asarray(lap, dtype=object if np.asarray(lap).dtype == object else float))
    rhs = np.array([Fraction(0)] * n, dtype=object)
    target = fr(np.tile(np.asarray(theta, dtype=float), n // d))
    for e in edges:
        if not e.p:
            continue
        le = fr(edge_laplacian(e, n, d))
        pe = Fraction(e.p)
        lbar = lbar - pe * le
        rhs = rhs + pe * (le @ target)
    sol = _solve([list(r) for r in lbar], list(rhs))
    if sol is None:
        return None
    return sum((x * x for x in sol), Fraction(0))


def offset_value(norm2: Fraction) -> float:
    """‖e*‖ as a double from its exact square.

    Parameters
    ----------
    norm2 : fractions.Fraction
        ‖e*‖².

    Returns
    -------
    float
    """
    return math.sqrt(float(norm2))


__all__ = [
    "EXACT_OFFSET_MAX_ND",
    "LossEdge",
    "LossPlan",
    "edge_laplacian",
    "exact_offset",
    "factors",
    "loss_edges",
    "loss_ms_matrix",
    "mean_laplacian",
    "offset_value",
    "plan_loss",
]
