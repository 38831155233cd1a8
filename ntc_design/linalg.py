"""Small linear-algebra helpers shared by every layer, with the project's tolerances.

Tolerances (documented once, used everywhere):

* ``SYM_RTOL = 1e-12``: a weight ``A`` is symmetric when
  ``max|A - Aᵀ| <= SYM_RTOL * max|A|``. The matrix is used as given; it is never
  symmetrised for the user.
* ``DEF_RTOL = 1e-10``: an eigenvalue ``λ`` of a symmetric ``A`` counts as zero when
  ``|λ| <= DEF_RTOL * ‖A‖₂``. So ``diag(1, 1, 0)`` is PSD (not PD), and ``diag(1, 1, 1e-12)``
  is PSD too, while ``diag(1, 1, 1e-9)`` is PD.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np

SYM_RTOL = 1e-12
DEF_RTOL = 1e-10


class Definiteness(StrEnum):
    """Class of a symmetric weight (paper, Sec. 2.1: sgn and |·|)."""

    PD = "PD"
    PSD = "PSD"
    ND = "ND"
    NSD = "NSD"
    ZERO = "zero"
    INDEFINITE = "indefinite"

    @property
    def sign(self) -> int:
        """sgn(A): +1 for PD/PSD, -1 for ND/NSD, 0 for the zero matrix."""
        return {"PD": 1, "PSD": 1, "ND": -1, "NSD": -1, "zero": 0}.get(self.value, 0)

    @property
    def definite(self) -> bool:
        """True for PD or ND: the edges a positive-negative path may use."""
        return self in (Definiteness.PD, Definiteness.ND)


def sym_eigvalsh(a: np.ndarray) -> np.ndarray:
    """Eigenvalues of the symmetric part of ``a``, ascending."""
    return np.linalg.eigvalsh(0.5 * (a + a.T))


def is_symmetric(a: np.ndarray, rtol: float = SYM_RTOL) -> bool:
    scale = float(np.max(np.abs(a))) if a.size else 0.0
    return bool(np.max(np.abs(a - a.T), initial=0.0) <= rtol * scale)


def classify(a: np.ndarray, rtol: float = DEF_RTOL) -> Definiteness:
    """Classify a symmetric matrix as PD, PSD, ND, NSD, zero or indefinite.

    An eigenvalue counts as zero when ``|λ| <= rtol·‖A‖₂`` (see module docstring).
    """
    if not np.any(a):
        return Definiteness.ZERO
    lam = sym_eigvalsh(a)
    tol = rtol * float(np.max(np.abs(lam)))
    lo, hi = float(lam[0]), float(lam[-1])
    if lo > tol:
        return Definiteness.PD
    if hi < -tol:
        return Definiteness.ND
    if lo >= -tol:
        return Definiteness.PSD
    if hi <= tol:
        return Definiteness.NSD
    return Definiteness.INDEFINITE


def pd(a: np.ndarray, rtol: float = DEF_RTOL) -> bool:
    """``a ≻ 0`` for a symmetric ``a``: smallest eigenvalue above ``rtol·‖a‖₂``."""
    return classify(a, rtol) is Definiteness.PD
