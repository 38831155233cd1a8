"""Exact moments of a large or stiff network by an A-stable second-order scheme.

The moment equations (:mod:`.moments`) are stiff when c·ρ(L_B) is large: classical RK4
needs c·h·ρ <= κ, so a 300-agent network whose Lemma 1 coupling δ is in the hundreds
takes about 10⁴ steps of O((Nd)³) each. Here the drift is taken by the Crank–Nicolson
(Cayley) step of ε' = −c L_B ε lifted to S = E[εεᵀ],

    R S_{k+1} Rᵀ = P S_k Pᵀ + h/2 (c_k² N(S_k) + c_{k+1}² N(S*)),
    R = I + (h c_{k+½}/2) L_B,  P = I − (h c_{k+½}/2) L_B,

with N(S) = G Gᵀ + Σ_e G_e S G_eᵀ (the noise) and S* the same step with N(S_k) alone
(Heun's predictor). The product R S Rᵀ differs from the trapezoidal rule's
(I + h𝓛/2) S by h²/4·L S Lᵀ, which P S Pᵀ matches to O(h³), so the scheme is second order
and A-stable for the drift (|(1 − z/2)/(1 + z/2)| < 1 for Re z > 0) [1]_; each step is one
LU of R and four solves with Nd right-hand sides, O((Nd)³) like RK4's products, but the
step does not shrink with c·ρ(L_B). Steady states under constant forcing are exact
((1 + z/2)² − (1 − z/2)² = 2z); transients of modes with h·c·λ ≫ 1 are damped slowly
but are negligible by then. Accuracy about 3e-4 relative at ``ds`` = 0.005 on the
paper's G1 with a gain that varies fast at t = 0, against 1e-6 for RK4. The step is
bounded by the gain's variation (c·h <= ``DS``: steps uniform in s = ∫c dt) and by the
explicit noise term (c²·h·ρ_G <= ``KAPPA_NOISE``, ρ_G = 2 max_i Σ_{e ∋ i} ‖K_e‖², the
Gershgorin bound of the noise map's Laplacian structure).

References
----------
.. [1] E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
   Springer, 1996, Sec. IV.3 (A-stability of the trapezoidal rule).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import scipy.sparse as sps
from scipy.linalg import lu_factor, lu_solve

from .moments import MomentRecorder, MomentRhs, Moments, PreparedModes, check_moments_size, march
from .system import ModeSystem

DS = 0.01  # c·h per step (steps uniform in s = ∫c dt)
KAPPA_NOISE = 0.5  # c²·h·ρ_G per step (the noise is explicit)


def noise_radius(s: ModeSystem) -> float:
    """ρ_G = 2·max_i Σ_{e ∋ i} ‖K_e‖²: the noise map S ↦ Σ_e G_e S G_eᵀ lands on agent
    i's block from the edges into i and reads agents i and j; a Gershgorin bound of its
    scale per agent (compare ρ_Q of :func:`.moments.generator_radius`, a sum over every
    edge).

    Parameters
    ----------
    s : ModeSystem
        One mode's system.

    Returns
    -------
    float
    """
    if not s.h_blocks:
        return 0.0
    w = np.linalg.norm(s.k_blocks, ord=2, axis=(1, 2)) ** 2
    ii = np.array([i for i, _, _ in s.h_blocks])
    jj = np.array([j for _, j, _ in s.h_blocks])
    per = np.zeros(int(max(ii.max(), jj.max())) + 1)
    np.add.at(per, ii, w)
    np.add.at(per, jj, w)
    return 4.0 * float(per.max())


def _sandwich(lu, x: np.ndarray) -> np.ndarray:
    """R⁻¹ X R⁻ᵀ from the LU factors of R (LAPACK: SuperLU's solve is column by column,
    far slower with Nd right-hand sides)."""
    y = lu_solve(lu, x, check_finite=False)
    return lu_solve(lu, y.T, check_finite=False)


def cayley_moments(
    modes: PreparedModes,
    gain: Callable[[np.ndarray], np.ndarray],
    save_times: np.ndarray,
    ds: float = DS,
    abort_above: float | None = None,
) -> Moments:
    """The moment equations integrated by the Crank–Nicolson (Cayley) step (see the module).

    Parameters
    ----------
    modes : PreparedModes
        The systems per mode, the segments (start, stop, mode index) covering the
        horizon and ε(0).
    gain : callable
        Vectorised c(t).
    save_times : numpy.ndarray
        Where to record the moments.
    ds : float, optional
        c·h per step.
    abort_above : float, optional
        Stop once tr S exceeds it; the remaining saves are +∞.

    Returns
    -------
    Moments

    Raises
    ------
    InputError
        Nd is above ``MOMENTS_MAX_ND``.
    """
    n, d, eps0, systems = modes.n, modes.d, modes.eps0, modes.systems
    check_moments_size(n * d)
    nd_ = n * d
    eye = sps.identity(nd_, format="csc")
    laps = [sps.csc_matrix(s.lap_b) for s in systems]
    rhs = [MomentRhs(s, n, d) for s in systems]
    rho_g = [noise_radius(s) for s in systems]
    m = eps0.astype(float).copy()
    s = np.outer(eps0, eps0)
    rec = MomentRecorder(save_times, n, d)
    rec.at(0.0, m, s)
    steps = 0

    def cap(t: float, mode: int) -> float:
        c0 = float(gain(np.array([t]))[0])
        if c0 <= 0:
            return math.inf
        return min(ds / c0, KAPPA_NOISE / (c0 * c0 * rho_g[mode]) if rho_g[mode] > 0 else math.inf)

    for t, h, mode in march(modes.segments, rec.saves, cap):
        f = rhs[mode]
        c0, cm, c1 = (float(v) for v in gain(np.array([t, t + h / 2, t + h])))
        half = 0.5 * h * cm * laps[mode]
        lu = lu_factor((eye + half).toarray(), check_finite=False)
        p = (eye - half).tocsr()
        ps = p @ (p @ s).T
        n0 = c0 * c0 * f.noise(s)
        pred = _sandwich(lu, ps + h * n0)
        s = _sandwich(lu, ps + 0.5 * h * (n0 + c1 * c1 * f.noise(pred)))
        s = 0.5 * (s + s.T)
        m = lu_solve(lu, p @ m, check_finite=False)
        steps += 1
        if rec.stop(t + h, m, s, steps, abort_above):
            break
    return rec.result(s, steps)
