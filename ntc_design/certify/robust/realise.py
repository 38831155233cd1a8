"""The realisations of :mod:`.robust` that attain the brackets' other ends: the spectral
abscissa and the consensus offset of a realisation, their gradients in each edge's E
(symmetric, ‖E‖ <= ρ_e), and the projected-gradient climb from the nominal point, ±ρI and
random starts."""

from __future__ import annotations

import math

import numpy as np

from .problem import Problem

SHRINK = 1.0 - 1e-9  # realisations are drawn this far inside the set (rounding)


def _project(e: np.ndarray, radius: float) -> np.ndarray:
    """The nearest symmetric matrix with spectral norm <= radius (eigenvalues clipped)."""
    lam, q = np.linalg.eigh(0.5 * (e + e.T))
    return (q * np.clip(lam, -radius, radius)) @ q.T


def abscissa(lap: np.ndarray) -> float:
    """min Re λ(L_B(A')): the decay rate of ε̇ = −L_B(A')ε (> 0 iff −L_B(A') is Hurwitz).

    Parameters
    ----------
    lap : numpy.ndarray
        L_B(A').

    Returns
    -------
    float
    """
    return float(np.min(np.linalg.eigvals(lap).real))


def offset_of(p: Problem, lap: np.ndarray) -> float:
    """‖x* − 1⊗θ‖₂ for the realisation whose L_B is ``lap`` (∞ when it is singular).

    Parameters
    ----------
    p : Problem
        The nominal data.
    lap : numpy.ndarray
        L_B(A').

    Returns
    -------
    float
    """
    try:
        x = np.linalg.solve(lap, p.u)
    except np.linalg.LinAlgError:
        return math.inf
    return float(np.linalg.norm(x - p.target))


def _grad_decay(p: Problem, es: np.ndarray) -> tuple[float, np.ndarray]:
    """min Re λ and its gradient in each E_e (symmetric), from the eigenvector pair."""
    import scipy.linalg as sla

    lap = p.lap(es)
    lam, vl, vr = sla.eig(lap, left=True, right=True)
    k = int(np.argmin(lam.real))
    x, y = vr[:, k], vl[:, k]
    s = np.vdot(y, x)  # yᴴ x
    d, ed, g = p.d, p.edges, np.zeros_like(es)
    for e in range(ed.m):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        dx = x[i : i + d] - ed.s[e] * x[j : j + d]
        kk = p.f[e] @ np.outer(dx, np.conj(y[i : i + d])) @ p.f[e] / s
        kk = np.real(kk).T  # d Re λ = tr(dE · Re K) -> gradient Re Kᵀ
        g[e] = 0.5 * (kk + kk.T)
    return float(lam[k].real), g


def _grad_offset(p: Problem, es: np.ndarray) -> tuple[float, np.ndarray]:
    """½‖x* − 1⊗θ‖² and its gradient in each E_e."""
    lap = p.lap(es)
    xs = np.linalg.solve(lap, p.u)
    z = xs - p.target
    mu = np.linalg.solve(lap.T, z)
    d, ed, g = p.d, p.edges, np.zeros_like(es)
    for e in range(ed.m):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        dx = xs[i : i + d] - ed.s[e] * xs[j : j + d]
        kk = -(p.f[e] @ np.outer(dx, mu[i : i + d]) @ p.f[e]).T
        g[e] = 0.5 * (kk + kk.T)
    return 0.5 * float(z @ z), g


def climb(p: Problem, radii, objective: str, starts: int, seed: int) -> np.ndarray:
    """Projected gradient search for the worst E (decay: lowest abscissa; offset: largest
    offset), from the nominal point, ± vertices and random starts.

    Parameters
    ----------
    p : Problem
        The nominal data.
    radii : float or numpy.ndarray
        ρ, or ρ_e per edge.
    objective : str
        ``"decay"`` or ``"offset"``.
    starts : int
        Starts besides the nominal point (the first two are ±ρI).
    seed : int
        Their seed (SeedSequence).

    Returns
    -------
    numpy.ndarray
        The best E found (m, d, d), drawn SHRINK inside the set.
    """
    m, d = p.edges.m, p.d
    radii = np.broadcast_to(np.asarray(radii, dtype=float), (m,))
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    sign = -1.0 if objective == "decay" else 1.0  # maximise sign·value
    fn = _grad_decay if objective == "decay" else _grad_offset

    def value(es: np.ndarray) -> float:
        lap = p.lap(es)
        return -abscissa(lap) if objective == "decay" else 0.5 * offset_of(p, lap) ** 2

    inits = [np.zeros((m, d, d))]
    for k in range(starts):
        if k < 2:
            inits.append(((-1) ** k) * radii[:, None, None] * np.broadcast_to(np.eye(d), (m, d, d)))
        else:
            r = rng.normal(size=(m, d, d))
            inits.append(
                np.array([_project(q * (x + x.T), q) for x, q in zip(r, radii, strict=True)])
            )
    best, best_v = inits[0], -math.inf
    for es in inits:
        v = value(es)
        top = float(np.max(radii, initial=0.0))
        step = top
        for _ in range(60):
            try:
                _, g = fn(p, es)
            except (np.linalg.LinAlgError, ValueError):
                break
            gn = float(np.sqrt(np.sum(g * g)))
            if not math.isfinite(gn) or gn == 0:
                break
            moved = False
            while step > 1e-6 * max(top, 1e-12):
                moved_es = es + sign * step * g / gn
                trial = np.array([_project(x, q) for x, q in zip(moved_es, radii, strict=True)])
                tv = value(trial)
                if tv > v + 1e-13 * max(1.0, abs(v)):
                    es, v, moved = trial, tv, True
                    step *= 1.5
                    break
                step *= 0.5
            if not moved:
                break
        if v > best_v:
            best, best_v = es, v
    return best * SHRINK


__all__ = ["SHRINK", "abscissa", "climb", "offset_of"]
