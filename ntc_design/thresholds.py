"""Exact critical couplings of the Lemma 1 design family (beyond the paper).

The family is ``L_B(δ) = L + δ·D`` with ``D = blockdiag(B_i)`` (``B_i = 0`` for naive
agents): informed agents V_I = U and the B_i are fixed, the common coupling δ > 0 varies.

* ``δ_H = inf{δ0 >= 0 : -L_B(δ) is Hurwitz for every δ > δ0}``. Candidate crossing points
  are the δ at which ``L + δD`` has an eigenvalue on the imaginary axis, i.e. the real
  positive roots of ``det((L⊕L) + δ(D⊕D)) = 0`` (λ_i + λ_j = 0 covers both 0 and ±iω);
  the Hurwitz property is constant between consecutive candidates. Each boundary is then
  refined by Brent's method on the spectral abscissa ``α(δ) = max Re λ(-L_B(δ))``, which
  is continuous in δ. Above ``KRON_MAX`` (Nd) the Kronecker pencil is too large and a
  logarithmic scan of α(δ) is used instead (stated in ``method``).
* ``δ_S = inf{δ : L_B + L_Bᵀ ≻ 0}``: ``λ_min((L+Lᵀ) + 2δD)`` is concave and
  non-decreasing in δ (D ⪰ 0), so the set is one ray; found by Brent's method.
* ``best_rate = max_δ -α(δ)`` and the δ reaching it (grid + bounded refinement in log δ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq, minimize_scalar

KRON_MAX = 40
REL = 1e-12


@dataclass(frozen=True)
class CriticalCouplings:
    hurwitz: float | None  # δ_H; None when no δ makes -L_B Hurwitz for all larger δ
    hurwitz_intervals: tuple[tuple[float, float], ...]  # the Hurwitz set, (lo, hi) with hi=inf
    symmetric: float | None  # δ_S; None when no δ gives L_B + L_Bᵀ ≻ 0
    best_rate: float
    best_rate_delta: float | None  # None when the rate still grows at the largest δ tried
    method: str
    notes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        return {
            "hurwitz": self.hurwitz,
            "hurwitz_intervals": [
                [lo, None if math.isinf(hi) else hi] for lo, hi in self.hurwitz_intervals
            ],
            "symmetric": self.symmetric,
            "best_rate": self.best_rate,
            "best_rate_delta": self.best_rate_delta,
            "method": self.method,
            "notes": list(self.notes),
        }


def spectral_abscissa(lap: np.ndarray, d: np.ndarray, delta: float) -> float:
    """``α(δ) = max Re λ(-(L + δD))``; -L_B(δ) is Hurwitz iff α(δ) < 0."""
    return float(-np.min(np.linalg.eigvals(lap + delta * d).real))


def _kron_candidates(lap: np.ndarray, d: np.ndarray) -> np.ndarray:
    n = lap.shape[0]
    eye = np.eye(n)
    k = np.kron(lap, eye) + np.kron(eye, lap)
    m = np.kron(d, eye) + np.kron(eye, d)
    # det(K + δM) = 0  <=>  K v = δ (-M) v
    ab = sla.eigvals(k, -m, homogeneous_eigvals=True)
    alpha, beta = ab[0], ab[1]
    scale = np.linalg.norm(k, 1) + np.linalg.norm(m, 1)
    ok = np.abs(beta) > 1e-13 * np.maximum(np.abs(alpha), 1e-300)
    ok &= ~((np.abs(alpha) < 1e-12 * scale) & (np.abs(beta) < 1e-12 * scale))
    w = alpha[ok] / beta[ok]
    w = np.sort(w[np.abs(w.imag) <= 1e-6 * np.maximum(1.0, np.abs(w))].real)
    w = w[w > 0]
    # λ_i + λ_j = 0 and λ_j + λ_i = 0 give the same root twice: merge near-equal roots.
    keep = np.concatenate([[True], np.diff(w) > 1e-8 * w[1:]]) if w.size else w.astype(bool)
    return w[keep]


def critical_couplings(lap: np.ndarray, d: np.ndarray) -> CriticalCouplings:
    """Critical couplings of ``L + δD`` over δ > 0 (see the module docstring)."""
    n = lap.shape[0]
    notes: list[str] = []
    nl = max(np.linalg.norm(lap, 2), 1e-300)
    ndn = np.linalg.norm(d, 2)
    if ndn == 0.0:
        a0 = spectral_abscissa(lap, d, 1.0)
        hur = a0 < -REL * nl
        notes.append("no informed agent: L_B = L does not depend on δ")
        return CriticalCouplings(
            0.0 if hur else None,
            ((0.0, math.inf),) if hur else (),
            0.0 if np.linalg.eigvalsh(lap + lap.T)[0] > REL * nl else None,
            -a0,
            None,
            "constant",
            tuple(notes),
        )
    scale = nl / ndn
    alpha = lambda x: spectral_abscissa(lap, d, x)  # noqa: E731
    if n <= KRON_MAX:
        # Roots at δ ≈ 0 are the singular L itself, perturbed by rounding: not crossings.
        cands = _kron_candidates(lap, d)
        cands = cands[cands > 1e-9 * scale]
        method = "kronecker-pencil"
        edges = np.concatenate([[0.0], cands, [2.0 * cands[-1] if cands.size else 2.0 * scale]])
        test = 0.5 * (edges[:-1] + edges[1:])
    else:
        method = "log-scan"
        notes.append(f"Nd={n} > {KRON_MAX}: crossings found by a logarithmic scan of α(δ)")
        test = scale * np.logspace(-6, 4, 161)
    alphas = np.array([alpha(x) for x in test])
    hurw = alphas < -REL * (nl + test * ndn)

    def root(a: float, b: float) -> float:
        fa, fb = alpha(a), alpha(b)
        if fa * fb > 0:
            return b
        return brentq(alpha, a, b, xtol=1e-15 * b, rtol=4 * np.finfo(float).eps, maxiter=200)

    intervals: list[tuple[float, float]] = []
    k = 0
    while k < len(test):
        if not hurw[k]:
            k += 1
            continue
        lo = 0.0 if k == 0 else root(test[k - 1], test[k])
        m = k
        while m + 1 < len(test) and hurw[m + 1]:
            m += 1
        hi = math.inf if m == len(test) - 1 else root(test[m], test[m + 1])
        intervals.append((lo, hi))
        k = m + 1
    if intervals and math.isinf(intervals[-1][1]):
        delta_h: float | None = intervals[-1][0]
    else:
        delta_h = None
        notes.append("-L_B is not Hurwitz for large δ: no δ_H exists")
    if len(intervals) > 1:
        notes.append(
            "the Hurwitz set is not one interval: "
            + ", ".join(f"({lo:.6g}, {hi:.6g})" for lo, hi in intervals)
        )

    # δ_S: λ_min((L+Lᵀ) + 2δD) is non-decreasing in δ.
    s0 = lap + lap.T
    g = lambda x: float(np.linalg.eigvalsh(s0 + 2 * x * d)[0])  # noqa: E731
    stol = REL * np.linalg.norm(s0, 2)
    if g(0.0) > stol:
        delta_s: float | None = 0.0
    else:
        w, v = np.linalg.eigh(d)
        z = v[:, w <= 1e-10 * ndn]
        if z.shape[1] and np.linalg.eigvalsh(z.T @ s0 @ z)[0] <= stol:
            delta_s = None
            notes.append("L_B + L_Bᵀ is not positive definite for any δ")
        else:
            hi = scale
            while g(hi) <= 0 and hi < 1e300:
                hi *= 2
            delta_s = brentq(g, 0.0, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps)

    best_rate, best_delta = _best_rate(alpha, scale, notes)
    return CriticalCouplings(
        delta_h, tuple(intervals), delta_s, best_rate, best_delta, method, tuple(notes)
    )


def _best_rate(alpha, scale: float, notes: list[str]) -> tuple[float, float | None]:
    """max over δ > 0 of the decay rate r(δ) = -α(δ), and the smallest δ reaching it.

    r is evaluated on a log grid; a maximum at the grid's end means r still grows (its
    supremum is approached as δ → ∞); a plateau (r within 1e-9 of its maximum on
    neighbouring points) is reported at its start, found by bisection in log δ."""
    grid = scale * np.logspace(-6, 4, 161)
    rates = np.array([-alpha(x) for x in grid])
    rmax = float(rates.max())
    tol = 1e-9 * max(1.0, abs(rmax))
    k = int(np.argmax(rates >= rmax - tol))
    if k == len(grid) - 1:
        notes.append(
            f"the decay rate still grows at δ = {grid[-1]:.3g}; its supremum "
            f"≈ {rmax:.6g} is approached as δ → ∞"
        )
        return rmax, None
    if k > 0 and rates[k + 1] >= rmax - tol:
        lo, hi = math.log(grid[k - 1]), math.log(grid[k])
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if -alpha(math.exp(mid)) >= rmax - tol else (mid, hi)
        notes.append(
            f"the decay rate reaches its maximum {rmax:.6g} at δ ≈ {math.exp(hi):.6g} "
            "and stays there"
        )
        return rmax, math.exp(hi)
    if k == 0:
        return rmax, float(grid[0])
    res = minimize_scalar(
        lambda u: alpha(math.exp(u)),
        bounds=(math.log(grid[k - 1]), math.log(grid[k + 1])),
        method="bounded",
        options={"xatol": 1e-10},
    )
    if -res.fun >= rmax:
        return float(-res.fun), math.exp(res.x)
    return rmax, float(grid[k])
