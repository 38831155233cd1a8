"""Matrices in floating point with an entrywise bound on their distance from the exact
value: the verified-float counterpart of :class:`~ntc_design.rigorous.exact.Dyadic`, with the
same operations (``+``, ``-``, ``@``, ``.T``, ``scale``), so that one matrix expression is
written once and evaluated exactly or in verified floating point.

Each operation adds the standard model's rounding bound (Higham, *Accuracy and Stability
of Numerical Algorithms*, §3.5: a k-term inner product is within γ_k·|a|ᵀ|b| of its
exact value, γ_k = k·u/(1 − k·u)) to the propagated radii. The radii themselves are
computed in floating point; every bound is inflated by a factor (1 + γ_{k+2}) that covers
their own rounding. Inputs must lie within :data:`~ntc_design.rigorous.exact.SPAN` (no
underflow or overflow on the way): :meth:`FloatMat.of` refuses others.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .exact import PDProof, U, gamma, verified_float_pd, within_span


@dataclass(frozen=True)
class FloatMat:
    """A matrix ``val`` and an entrywise bound ``rad`` on |exact − val|.

    Examples
    --------
    >>> a = FloatMat.of(np.array([[0.1, 0.2], [0.2, 0.3]]))
    >>> b = (a @ a).scale(3.0) - a
    >>> bool(np.all(b.rad > 0)) and bool(np.all(b.rad < 1e-15))
    True
    """

    val: np.ndarray
    rad: np.ndarray

    @classmethod
    def of(cls, a: np.ndarray | float, rad: np.ndarray | float = 0.0) -> FloatMat:
        """A matrix taken as exact (``rad`` 0) or with a given bound.

        Parameters
        ----------
        a : numpy.ndarray or float
            The matrix (a scalar is taken as 1×1).
        rad : numpy.ndarray or float, optional
            An entrywise bound on its distance from the exact value.

        Returns
        -------
        FloatMat

        Raises
        ------
        ValueError
            An entry outside the range where the rounding bounds hold.
        """
        v = np.atleast_2d(np.asarray(a, dtype=float))
        r = np.broadcast_to(np.asarray(rad, dtype=float), v.shape).copy()
        if not within_span(v, r):
            raise ValueError("an entry is outside the verified-float range")
        return cls(v, r)

    @property
    def T(self) -> FloatMat:  # noqa: N802 - matrix transpose, as numpy
        """The transpose."""
        return FloatMat(self.val.T, self.rad.T)

    def __add__(self, other: FloatMat) -> FloatMat:
        v = self.val + other.val
        return FloatMat(v, (self.rad + other.rad) * (1 + 2 * U) + U * np.abs(v))

    def __sub__(self, other: FloatMat) -> FloatMat:
        v = self.val - other.val
        return FloatMat(v, (self.rad + other.rad) * (1 + 2 * U) + U * np.abs(v))

    def __matmul__(self, other: FloatMat) -> FloatMat:
        k = self.val.shape[1]
        av, bv = np.abs(self.val), np.abs(other.val)
        v = self.val @ other.val
        prop = av @ other.rad + self.rad @ bv + self.rad @ other.rad
        r = (prop + gamma(k + 1) * (av @ bv)) * (1 + gamma(k + 2))
        return FloatMat(v, r)

    def scale(self, s: float) -> FloatMat:
        """``s`` times the matrix (``s`` an exact double).

        Parameters
        ----------
        s : float
            The factor.

        Returns
        -------
        FloatMat
        """
        v = s * self.val
        return FloatMat(v, abs(s) * self.rad * (1 + 2 * U) + U * np.abs(v))

    def positive_definite(self) -> PDProof:
        """Rump's verified test that every matrix within the bounds is ≻ 0.

        Returns
        -------
        PDProof
        """
        return verified_float_pd(self.val, 2 * self.rad * (1 + 8 * gamma(self.val.shape[0])))


__all__ = ["FloatMat"]
