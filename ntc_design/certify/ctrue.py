"""c_true, the mean-square limit a digital certificate's κ is measured against: the
largest constant gain below which the spectral radius of the augmented second-moment map
Z ↦ A_c Z A_cᵀ + h c² Σ_e Ĝ_e Z Ĝ_eᵀ (z = (e_k, …, e_{k−D})) is < 1, by bisection on c with
ARPACK on the operator (dense for tiny orders); per mode (frozen), the least over a
schedule's modes. Informational: it is not a claim (notation of :mod:`.delayline`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse.linalg as spla

from .digital import EdgeNoise

#: The most numbers the c_true iteration may hold ((D+1)·Nd)² × its Krylov vectors.
CTRUE_MAX_ORDER = 600


def _ms_map(lap: np.ndarray, gs: Sequence[np.ndarray], h: float, delay: int, c: float):
    n = lap.shape[0]
    m = n * (delay + 1)
    tau = h * c

    def apply(v: np.ndarray) -> np.ndarray:
        z = v.reshape(m, m)
        out = np.empty_like(z)
        # A z: the first block row e_k − τ L e_{k−D}, then the shift
        az = np.empty_like(z)
        az[:n] = z[:n] - tau * (lap @ z[m - n :])
        az[n:] = z[: m - n]
        out[:, :n] = az[:, :n] - tau * (az[:, m - n :] @ lap.T)
        out[:, n:] = az[:, : m - n]
        zd = z[m - n :, m - n :]
        out[:n, :n] += h * c * c * sum((ge @ zd @ ge.T for ge in gs), np.zeros((n, n)))
        return out.ravel()

    return apply, m


def _dense_g(e: EdgeNoise, n: int, d: int) -> np.ndarray:
    gm = np.zeros((n, n))
    k = e.k
    gm[e.i * d : e.i * d + d, e.j * d : e.j * d + d] += k
    gm[e.i * d : e.i * d + d, e.i * d : e.i * d + d] -= k
    return gm


def spectral_radius(
    lap: np.ndarray,
    edges: Sequence[EdgeNoise],
    d: int,
    h: float,
    delay: int,
    c: float,
    gs: Sequence[np.ndarray] | None = None,
) -> float:
    """The spectral radius of the augmented second-moment map at the constant gain c.

    Parameters
    ----------
    lap : numpy.ndarray
        L_B.
    edges : sequence of EdgeNoise
        The mode's edges.
    d : int
        The state dimension.
    h : float
        The period.
    delay : int
        D.
    c : float
        The gain.
    gs : sequence of numpy.ndarray, optional
        The Ĝ_e instead of the edges' (the lossy links' map, :mod:`.loss_delay`).

    Returns
    -------
    float
    """
    n = lap.shape[0]
    if gs is None:
        gs = [_dense_g(e, n, d) for e in edges]
    apply, m = _ms_map(lap, gs, h, delay, c)
    if m * m <= 400:
        dense = np.column_stack([apply(col) for col in np.eye(m * m)])
        return float(np.max(np.abs(np.linalg.eigvals(dense))))
    op = spla.LinearOperator((m * m, m * m), matvec=apply, dtype=float)
    vals = spla.eigs(op, k=3, which="LM", tol=1e-10, ncv=30, return_eigenvectors=False)
    return float(np.max(np.abs(vals)))


def ms_limit(
    laps: Sequence[np.ndarray],
    noises: Sequence[Sequence[EdgeNoise]],
    d: int,
    h: float,
    delay: int,
    gss: Sequence[Sequence[np.ndarray]] | None = None,
) -> tuple[float | None, str]:
    """c_true: per mode the largest constant gain with spectral radius < 1 of the augmented
    second-moment map (bisection to a relative 1e-4), the least over the modes.

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
    gss : sequence of sequence of numpy.ndarray, optional
        Every mode's Ĝ_e instead of its edges' (:func:`spectral_radius`).

    Returns
    -------
    (float or None, str)
        None (and why) past :data:`CTRUE_MAX_ORDER` or when the iteration fails.
    """
    m = laps[0].shape[0] * (delay + 1)
    if m > CTRUE_MAX_ORDER:
        return None, f"not computed: (D+1)·Nd = {m} > {CTRUE_MAX_ORDER}"
    out = math.inf
    try:
        for k, (lap, edges) in enumerate(zip(laps, noises, strict=True)):
            gs = None if gss is None else gss[k]

            def stable(c: float, lap: np.ndarray = lap, edges: Any = edges, gs: Any = gs) -> bool:
                return spectral_radius(lap, edges, d, h, delay, c, gs) < 1.0

            hi = 1.0 / h
            while stable(hi) and hi < 1e6:
                hi *= 2.0
            lo = 0.0
            while hi - lo > 1e-4 * hi:
                mid = 0.5 * (lo + hi)
                if stable(mid):
                    lo = mid
                else:
                    hi = mid
            out = min(out, lo)
    except (spla.ArpackNoConvergence, spla.ArpackError, np.linalg.LinAlgError):
        return None, "not computed: the eigenvalue iteration did not converge"
    how = "spectral radius of the augmented second-moment map < 1 (ARPACK), per mode, least"
    return out, how


__all__ = ["CTRUE_MAX_ORDER", "ms_limit", "spectral_radius"]
