"""The digital certificate's mathematics: from a Lyapunov matrix P of the continuous design,
the gains for which the sampled (and delayed) recursion contracts in mean square, and the
first step k₀ from which it does (:mod:`ntc_design.protocol.digital` states the recursion).

Notation: ‖x‖²_P = xᵀPx, M = P L + Lᵀ P, Q = Lᵀ P L, N = Σ_e G_eᵀ P G_e and
γ = Σ_e g_eᵀ P g_e (every mode's L = L_B and edges), τ_k = h c_k, v_k = E‖e_k‖²_P.

*No delay (D = 0).* E[e_{k+1}ᵀPe_{k+1} | e_k] = e_kᵀ(P − τ_k(M − τ_kQ − c_kN))e_k + τ_kc_kγ, so
(M − αP) − κ·(hQ + N) ⪰ 0 gives v_{k+1} <= (1 − ατ_k) v_k + τ_k c_k γ whenever c_k <= κ
(the matrix is affine in c and hQ + N ⪰ 0): from the first step on which c <= κ forever,
v contracts by (1 − ατ_k) up to the additive noise.

*Which P.* The continuous design's Lyapunov matrices ignore the noise and can make N ⪯ βP
need a huge β. The certificate also tries P solving LᵀP + PL − c₁·N(P) = I (the mean-square
Lyapunov equation of the frozen-gain SDE, PD exactly while c₁ is below its mean-square
stability limit), for a few c₁ below that limit, and keeps the P with the largest κ.

*Delay D > 0 (a Razumikhin functional).* Write e_{k−D} = e_k − p_k with
p_k = Σ_{i=k−D}^{k−1} (−τ_iLe_{i−D} + n_i), so e_{k+1} = (I − τ_kL)e_k + τ_kLp_k + n_k and

    E[‖e_{k+1}‖²_P | F_k] = e_kᵀ(AᵀPA + hc²N)e_k + 2e_kᵀ(τAᵀPL − hc²N)p_k
                           + p_kᵀ(τ²Q + hc²N)p_k + hc²γ.

The first term is bounded by the D = 0 inequality at κ; with Q ⪯ ℓ²P, N ⪯ βP, Young's
inequality (weight ατ_k/2) and Cauchy–Schwarz over the D terms of p_k,

    v_{k+1} <= (1 − a_k) v_k + a_k ρ(c̄) W_k + b_k,   a_k = ατ_k/2,
    W_k = max_{k−2D <= j <= k} v_j,
    ρ(c̄) = (2/α)·[(2/α)(ℓ + c̄β)² + hc̄ℓ² + c̄β]·D²·h c̄²·(hℓ² + β),

where c̄ bounds c on the steps k−D … k and b_k = O(τ_k c̄) is the additive noise. With
ρ(κ) <= 1/2 and c(t) < κ for every t >= t₀, from k₀ = ⌈t₀/h⌉ + D on every step satisfies
v_{k+1} <= (1 − a_k/2)·W_k + b_k: the functional W does not grow except by the additive
noise, and with Σ τ_k = ∞ and c_k → 0 (the sampled gain conditions) E‖e_k‖² → 0 (a
discrete Halanay argument); with Σ c_k² < ∞ too, e_k → 0 almost surely (Robbins–Siegmund on
the Krasovskii functional ‖e_k‖²_P plus the weighted sum of the last D increments, whose
cross terms cancel exactly). The bound is norm-based: ρ ~ (2/α)²ℓ²D²hc̄²(hℓ² + β) makes κ
of the order of α/(ℓ·D·√(h(hℓ² + β))), conservative where L_B is stiff (ℓ ≫ α).

Every inequality is proven from the certificate's numbers exactly (dyadic rationals,
:class:`~ntc_design.rigorous.exact.Dyadic`) while affordable, else in verified floating
point (:class:`~ntc_design.rigorous.floatmat.FloatMat`); the level ρ(κ) <= 1/2 in exact
fractions; c(t) < κ beyond t₀ in ball arithmetic (:func:`.mu2.prove_below`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import InputError
from ..expr.symbolic import parse_expression
from ..rigorous.exact import Dyadic, PDProof, exact_affordable, exact_pd
from ..rigorous.floatmat import FloatMat
from .mu2 import T0_SCAN_END, mu2_t0, prove_below

#: Relative back-off of the stated constants from the computed ones, so that the stated
#: inequalities hold strictly and survive the exact re-check.
BACKOFF = 1e-4
#: The Razumikhin factor the level κ keeps ρ(κ) below (D > 0): the functional then
#: decreases by at least a_k/2 per step.
RHO_TARGET = Fraction(1, 2)


@dataclass(frozen=True)
class EdgeNoise:
    """One edge j → i's noise: K_e = |A_ij|·F multiplies e_j − e_i (the multiplicative
    term, in agent i's rows) and g_e = σ_e·|A_ij|·1_d is the additive one."""

    i: int
    j: int
    absw: np.ndarray  # |A_ij|, d×d
    f: np.ndarray  # F, d×d
    sigma: float

    @property
    def k(self) -> np.ndarray:
        """K_e = |A_ij| F in floating point."""
        return self.absw @ self.f

    @property
    def g(self) -> np.ndarray:
        """g_e = σ_e |A_ij| 1_d in floating point."""
        return self.sigma * self.absw.sum(axis=1)


def edge_noises(top: Any, f: np.ndarray, sigma: float, sigma_edges: Any = None) -> list[EdgeNoise]:
    """Every edge's noise terms for a topology, in its (sorted) edge order.

    Parameters
    ----------
    top : Topology
        The mode.
    f : numpy.ndarray
        F, d×d.
    sigma : float
        σ of an edge without its own.
    sigma_edges : mapping of (str, str) to float, optional
        Per-edge σ by (from, to) labels.

    Returns
    -------
    list of EdgeNoise
    """
    lab = [str(x) for x in top.labels]
    own = {(str(a), str(b)): float(v) for (a, b), v in (sigma_edges or {}).items()}
    return [
        EdgeNoise(
            i, j, np.asarray(top.abs_weight(i, j), dtype=float), f, own.get((lab[j], lab[i]), sigma)
        )
        for i, j in top.edges
    ]


@dataclass(frozen=True)
class DigitalPlan:
    """What a digital certificate states: P and α, the level κ, the constants of the
    delayed bound (D > 0) and the additive noise energy γ (module docstring)."""

    p: np.ndarray
    alpha: float
    kappa: float
    gamma: float
    beta: float | None = None  # D > 0
    ell2: float | None = None
    source: str = ""  # which P


def scaled(m: Any, s: float) -> Any:
    """``s·m`` for a Dyadic (exactly) or a FloatMat.

    Parameters
    ----------
    m : Dyadic or FloatMat
        The matrix.
    s : float
        The factor.

    Returns
    -------
    Dyadic or FloatMat
    """
    return m.scale(Dyadic.of(s)) if isinstance(m, Dyadic) else m.scale(s)


def _lift(a: np.ndarray, exact: bool) -> Any:
    return Dyadic.of(a) if exact else FloatMat.of(a)


def lipschitz_matrix(p: Any, lap: Any, ell2: float) -> Any:
    """ℓ²P − Lᵀ P L.

    Parameters
    ----------
    p, lap : Dyadic or FloatMat
        P and L_B.
    ell2 : float
        ℓ².

    Returns
    -------
    Dyadic or FloatMat
    """
    return scaled(p, ell2) - lap.T @ (p @ lap)


def noise_matrix(p: Any, edges: Sequence[EdgeNoise], d: int, exact: bool) -> Any:
    """N = Σ_e G_eᵀ P G_e with G_e e = e_i ⊗ K_e (e_j − e_i): each edge adds ±K_eᵀ P_ii K_e
    to the blocks (j, j), (j, i), (i, j), (i, i).

    Parameters
    ----------
    p : Dyadic or FloatMat
        P.
    edges : sequence of EdgeNoise
        The mode's edges.
    d : int
        The state dimension.
    exact : bool
        Build it exactly (Dyadic) or in verified floats.

    Returns
    -------
    Dyadic or FloatMat
    """
    n = p.val.shape[0] if isinstance(p, FloatMat) else p.num.shape[0]
    total: Any = None
    for e in edges:
        sel = np.zeros((d, n))  # K_e (e_j − e_i) = (K_e S_e) e with S_e = [.. I_j .. −I_i ..]
        sel[:, e.j * d : e.j * d + d] += np.eye(d)
        sel[:, e.i * d : e.i * d + d] -= np.eye(d)
        rows = np.zeros((n, d))
        rows[e.i * d : e.i * d + d, :] = np.eye(d)
        ks = (_lift(e.absw, exact) @ _lift(e.f, exact)) @ _lift(sel, exact)  # d × n
        g = _lift(rows, exact) @ ks  # n × n
        term = g.T @ (p @ g)
        total = term if total is None else total + term
    if total is None:
        z = np.zeros((n, n))
        return _lift(z, exact) if exact else FloatMat.of(z)
    return total


def additive_energy(p: np.ndarray, edges: Sequence[EdgeNoise], d: int) -> Fraction:
    """γ = Σ_e g_eᵀ P g_e exactly (each g_e = σ_e|A_ij|1_d lives in agent i's block).

    Parameters
    ----------
    p : numpy.ndarray
        P.
    edges : sequence of EdgeNoise
        The mode's edges.
    d : int
        The state dimension.

    Returns
    -------
    fractions.Fraction
    """
    total = Fraction(0)
    for e in edges:
        blk = p[e.i * d : e.i * d + d, e.i * d : e.i * d + d]
        sig = Fraction(float(e.sigma))
        g = [sig * sum((Fraction(float(x)) for x in row), Fraction(0)) for row in e.absw]
        for a in range(d):
            for b in range(d):
                total += g[a] * Fraction(float(blk[a, b])) * g[b]
    return total


def prove_psd(m: Any) -> PDProof:
    """m ≻ 0 exactly (Sylvester, while affordable) or by the verified-float test.

    Parameters
    ----------
    m : Dyadic or FloatMat
        A symmetric matrix expression.

    Returns
    -------
    PDProof
    """
    if isinstance(m, Dyadic):
        return exact_pd(m)
    return m.positive_definite()


def use_exact(n: int, *mats: np.ndarray) -> bool:
    """Whether the exact test is affordable for these inputs (their bit lengths).

    Parameters
    ----------
    n : int
        The matrix order.
    *mats : numpy.ndarray
        The inputs.

    Returns
    -------
    bool
    """
    bits = max((Dyadic.of(m).bits for m in mats if np.size(m)), default=1)
    return exact_affordable(n, 4 * bits)


def _gen_max(a: np.ndarray, b: np.ndarray) -> float:
    """λ_max of the pencil (a, b), b ≻ 0 (symmetric parts); inf when b is not PD."""
    try:
        return float(sla.eigh(0.5 * (a + a.T), 0.5 * (b + b.T), eigvals_only=True)[-1])
    except (np.linalg.LinAlgError, ValueError):
        return math.inf


def noise_operator(edges: Sequence[EdgeNoise], n: int, d: int) -> sp.csr_matrix:
    """The map P ↦ N(P) = Σ_e G_eᵀ P G_e on row-major vec(P), sparse (each edge reads
    agent i's d×d block of P and writes the (2d)² entries of blocks i and j).

    Parameters
    ----------
    edges : sequence of EdgeNoise
        The mode's edges.
    n : int
        N·d.
    d : int
        The state dimension.

    Returns
    -------
    scipy.sparse.csr_matrix
        (n², n²).
    """
    rows, cols, vals = [], [], []
    for e in edges:
        w = np.zeros((d, n))  # W = K_e S_e: K_e on block j, −K_e on block i
        w[:, e.j * d : e.j * d + d] += e.k
        w[:, e.i * d : e.i * d + d] -= e.k
        idx = np.unique(
            np.concatenate([np.arange(e.j * d, e.j * d + d), np.arange(e.i * d, e.i * d + d)])
        )
        for a in range(d):
            for b in range(d):
                coef = np.outer(w[a, idx], w[b, idx])  # entries (r, s) of the output
                r, c = np.meshgrid(idx, idx, indexing="ij")
                rows.append((r * n + c).ravel())
                cols.append(np.full(r.size, (e.i * d + a) * n + (e.i * d + b)))
                vals.append(coef.ravel())
    if not rows:
        return sp.csr_matrix((n * n, n * n))
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n * n, n * n)
    )


def ms_lyapunov(
    laps: Sequence[np.ndarray], ops: Sequence[sp.csr_matrix], c: float
) -> np.ndarray | None:
    """P solving Σ_m (L_mᵀP + PL_m − c·N_m(P)) = (number of modes)·I (the mean-square
    Lyapunov equation of the frozen-gain SDE, averaged over the modes).

    Parameters
    ----------
    laps : sequence of numpy.ndarray
        L_B of every mode.
    ops : sequence of scipy.sparse.csr_matrix
        Their :func:`noise_operator`.
    c : float
        The frozen gain c₁.

    Returns
    -------
    numpy.ndarray or None
        P, or None when it is not positive definite (c₁ at or beyond the mean-square
        stability limit).
    """
    n = laps[0].shape[0]
    eye = sp.identity(n, format="csr")
    op = sum(
        sp.kron(sp.csr_matrix(lap.T), eye) + sp.kron(eye, sp.csr_matrix(lap.T)) - c * o
        for lap, o in zip(laps, ops, strict=True)
    )
    try:
        x = spla.spsolve(sp.csc_matrix(op), len(laps) * np.eye(n).ravel())
    except (RuntimeError, ValueError):
        return None
    p = np.asarray(x, dtype=float).reshape(n, n)
    p = 0.5 * (p + p.T)
    if not np.all(np.isfinite(p)):
        return None
    try:
        np.linalg.cholesky(p)
    except np.linalg.LinAlgError:
        return None
    return p


def candidate_ps(
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    fixed: np.ndarray | None,
) -> list[tuple[str, np.ndarray]]:
    """Lyapunov matrices to try: the continuous design's own (``fixed``; the identity for a
    switching set), and the mean-square Lyapunov equation's solution at 1/4, 1/2 and 3/4
    of its stability limit c_ms (found by bisection).

    Parameters
    ----------
    laps : sequence of numpy.ndarray
        L_B of every mode used.
    noises : sequence of sequence of EdgeNoise
        Every mode's edges.
    d : int
        The state dimension.
    fixed : numpy.ndarray or None
        A Lyapunov matrix of the continuous design (None: the identity).

    Returns
    -------
    list of (str, numpy.ndarray)
    """
    n = laps[0].shape[0]
    out = [
        (
            "the continuous design's Lyapunov matrix" if fixed is not None else "the identity",
            fixed if fixed is not None else np.eye(n),
        )
    ]
    ops = [noise_operator(e, n, d) for e in noises]
    if not any(o.nnz for o in ops) or ms_lyapunov(laps, ops, 0.0) is None:
        return out
    hi = 1.0
    while ms_lyapunov(laps, ops, hi) is not None and hi < 1e12:
        hi *= 4.0
    lo = 0.0 if ms_lyapunov(laps, ops, hi / 4) is None else hi / 4
    hi = hi if lo else hi / 4
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if ms_lyapunov(laps, ops, mid) is not None:
            lo = mid
        else:
            hi = mid
    for frac in (0.25, 0.5, 0.75):
        p = ms_lyapunov(laps, ops, frac * lo)
        if p is not None:
            out.append(
                (f"the mean-square Lyapunov equation at c₁ = {frac:g}·c_ms (c_ms ≈ {lo:.4g})", p)
            )
    return out


def plan(
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
    delay: int,
    fixed: np.ndarray | None = None,
) -> DigitalPlan | None:
    """The digital certificate's P, α, κ and constants, the candidate P with the largest κ
    (:func:`candidate_ps`); each stated number backed off by :data:`BACKOFF`.

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
        D.
    fixed : numpy.ndarray, optional
        The continuous design's Lyapunov matrix.

    Returns
    -------
    DigitalPlan or None
        None when no candidate gives α > 0.
    """
    best: DigitalPlan | None = None
    n = laps[0].shape[0]
    for source, p in candidate_ps(laps, noises, d, fixed):
        ms = [p @ lap + lap.T @ p for lap in laps]
        qs = [lap.T @ p @ lap for lap in laps]
        ns = [noise_matrix(FloatMat.of(p), e, d, exact=False).val for e in noises]
        lam = min(-_gen_max(-m, p) for m in ms)  # λ_min of (M, P)
        if not lam > 0:
            continue
        alpha = 0.5 * lam
        gamma = max(float(additive_energy(p, e, d)) for e in noises) * (1 + 1e-12)
        up = 1 + BACKOFF
        worst = max(
            _gen_max(h * q + nm, m - alpha * p) for m, q, nm in zip(ms, qs, ns, strict=True)
        )
        kappa0 = 1.0 / (worst * up) if worst > 0 else 1e300
        if delay == 0:
            cand = DigitalPlan(p, alpha, kappa0, gamma, source=source)
        else:
            beta = max(max(_gen_max(nm, p) for nm in ns), 0.0) * up + 1e-300
            ell2 = max(_gen_max(q, p) for q in qs) * up + 1e-300
            kappa = level(alpha, kappa0, beta, ell2, h, delay)
            cand = DigitalPlan(p, alpha, kappa, gamma, beta, ell2, source)
        if best is None or cand.kappa > best.kappa:
            best = cand
    del n
    return best


def sqrt_up(x: Fraction) -> Fraction:
    """A rational upper bound on √x (x >= 0), within a relative 2⁻⁵⁰.

    Parameters
    ----------
    x : fractions.Fraction
        x >= 0.

    Returns
    -------
    fractions.Fraction
    """
    if x <= 0:
        return Fraction(0)
    scale = 1 << 120
    r = math.isqrt(x.numerator * scale * scale // x.denominator) + 1
    return Fraction(r, scale)


def rho(
    c: Fraction, alpha: Fraction, beta: Fraction, ell2: Fraction, h: Fraction, delay: int
) -> Fraction:
    """The Razumikhin factor ρ(c̄) of the module docstring, exactly (ℓ bounded above by
    :func:`sqrt_up`, so the value bounds the true ρ from above).

    Parameters
    ----------
    c, alpha, beta, ell2, h : fractions.Fraction
        c̄, α, β, ℓ², h.
    delay : int
        D > 0.

    Returns
    -------
    fractions.Fraction
    """
    ell = sqrt_up(ell2)
    inner = 2 / alpha * (ell + c * beta) ** 2 + h * c * ell2 + c * beta
    return 2 / alpha * inner * delay * delay * h * c * c * (h * ell2 + beta)


def level(alpha: float, kappa0: float, beta: float, ell2: float, h: float, delay: int) -> float:
    """κ for D > 0: the largest gain level <= κ₀ (the D = 0 level) with ρ(κ) <= 1/2
    (bisection, checked in exact fractions).

    Parameters
    ----------
    alpha, kappa0, beta, ell2 : float
        α, the level of the no-delay inequality, β and ℓ².
    h : float
        The period.
    delay : int
        D > 0.

    Returns
    -------
    float
        κ > 0.
    """
    fa, fb, fl, fh = (Fraction(x) for x in (alpha, beta, ell2, h))

    def ok(c: float) -> bool:
        return rho(Fraction(c), fa, fb, fl, fh, delay) <= RHO_TARGET

    if ok(kappa0):
        return kappa0
    lo, hi = 0.0, kappa0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * hi:
            break
    return lo


def ms_matrix(p: Any, lap: Any, noise: Any, alpha: float, kappa: float, h: float) -> Any:
    """(P L + Lᵀ P − αP) − κ·(h·Lᵀ P L + N) (D = 0), exactly or in verified floats.

    Parameters
    ----------
    p, lap, noise : Dyadic or FloatMat
        P, L_B and N = Σ_e G_eᵀ P G_e.
    alpha, kappa, h : float
        α, κ and the period.

    Returns
    -------
    Dyadic or FloatMat
    """
    pl = p @ lap
    return (pl + pl.T) - scaled(p, alpha) - scaled(scaled(lap.T @ pl, h) + noise, kappa)


def level_holds(
    kappa: float, alpha: float, beta: float, ell2: float, h: float, delay: int
) -> tuple[bool, str]:
    """Check a delayed certificate's level exactly: κ > 0, α > 0 and ρ(κ) <= 1/2.

    Parameters
    ----------
    kappa, alpha, beta, ell2 : float
        The stated numbers.
    h : float
        The period.
    delay : int
        D > 0.

    Returns
    -------
    (bool, str)
    """
    if not (kappa > 0 and alpha > 0 and beta >= 0 and ell2 >= 0):
        return False, "κ, α must be > 0 and β, ℓ² >= 0"
    r = rho(Fraction(kappa), Fraction(alpha), Fraction(beta), Fraction(ell2), Fraction(h), delay)
    if r > RHO_TARGET:
        return False, f"ρ(κ) = {float(r):.6g} > 1/2"
    return True, f"exact fractions: ρ(κ) = {float(r):.6g} <= 1/2"


def first_step(t0: float, h: float, delay: int) -> int:
    """k₀ = ⌈t₀/h⌉ + D, exactly (t₀ and h are dyadic rationals).

    Parameters
    ----------
    t0, h : float
        t₀ and the period.
    delay : int
        D.

    Returns
    -------
    int
    """
    q = Fraction(t0) / Fraction(h)
    return int(-((-q.numerator) // q.denominator)) + delay


# -- the gain beyond t₀ ----------------------------------------------------------------


def _tail_expr(gain: Any):
    """The gain's expression (an expression's text, or a schedule document's tail)."""
    text = gain["tail"] if isinstance(gain, dict) else gain
    return parse_expression(text, "gain")


def gain_t0(gain: Any, kappa: float) -> tuple[float | None, str]:
    """The least t₀ found with c(t) < κ for every t >= t₀, and how it was proven.

    Parameters
    ----------
    gain : str or dict
        c(t) as text, or a schedule document (``t``, ``c``, ``interpolation``, ``tail``).
    kappa : float
        The level.

    Returns
    -------
    (float or None, str)
        None when no t₀ was found.

    Raises
    ------
    InputError
        The gain is not an allowed expression.
    """
    if not isinstance(gain, dict):
        return mu2_t0(gain, kappa)
    t, c = np.asarray(gain["t"], dtype=float), np.asarray(gain["c"], dtype=float)
    above = np.flatnonzero(c >= kappa)  # the table is below κ after its last such knot
    t0 = 0.0 if above.size == 0 else float(t[min(int(above[-1]) + 1, t.size - 1)])
    t_tail, how = mu2_t0(_tail_expr(gain), kappa)
    if t_tail is None:
        return None, how
    if t_tail > float(t[-1]):  # the tail is used from the table's end on
        t0 = max(t0, t_tail)
    ok, how = prove_gain_below(gain, kappa, t0)
    return (t0, how) if ok else (None, how)


def prove_gain_below(gain: Any, kappa: float, t0: float) -> tuple[bool | None, str]:
    """Prove c(t) < κ for every t >= t₀: an expression by ball arithmetic and monotonicity
    (:func:`.mu2.prove_below`); a schedule by its table (linear interpolation stays between
    the values at the knots) and its tail from the table's end on.

    Parameters
    ----------
    gain : str or dict
        c(t) as text, or a schedule document.
    kappa : float
        The level.
    t0 : float
        From where.

    Returns
    -------
    (bool or None, str)
        True when proven, False when refuted, None when undecided.

    Raises
    ------
    InputError
        The gain is not an allowed expression, or a malformed schedule.
    """
    if not (isinstance(t0, float) and math.isfinite(t0) and t0 >= 0):
        return False, f"t₀ = {t0!r} is not a finite time >= 0"
    if not isinstance(gain, dict):
        return prove_below(_tail_expr(gain), kappa, t0)
    try:
        t = np.asarray(gain["t"], dtype=float)
        c = np.asarray(gain["c"], dtype=float)
        interp = gain["interpolation"]
    except (KeyError, TypeError, ValueError):
        raise InputError("expected a schedule {t, c, interpolation, tail}", field="gain") from None
    end = float(t[-1])
    if t0 < end:
        # the knots bracketing [t0, end]: linear or previous interpolation stays within them
        k = max(int(np.searchsorted(t, t0, side="right")) - 1, 0)
        top = float(np.max(c[k:]))
        if not top < kappa:
            return False if float(c[-1]) >= kappa else None, (
                f"the table reaches {top:.6g} >= κ = {kappa:.6g} after t₀ = {t0:g}"
            )
        if interp not in ("linear", "previous"):
            return None, f"interpolation {interp!r} is not bounded by its knots"
    ok, how = prove_below(_tail_expr(gain), kappa, max(t0, end))
    return ok, ("table below κ from t₀ on; tail: " + how) if t0 < end else "tail: " + how


__all__ = [
    "BACKOFF",
    "RHO_TARGET",
    "T0_SCAN_END",
    "DigitalPlan",
    "EdgeNoise",
    "additive_energy",
    "edge_noises",
    "candidate_ps",
    "ms_lyapunov",
    "ms_matrix",
    "noise_operator",
    "plan",
    "first_step",
    "gain_t0",
    "level",
    "level_holds",
    "lipschitz_matrix",
    "noise_matrix",
    "prove_gain_below",
    "prove_psd",
    "rho",
    "scaled",
    "sqrt_up",
    "use_exact",
]
