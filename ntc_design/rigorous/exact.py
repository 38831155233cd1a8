"""Proving a symmetric matrix positive definite without trusting a solver.

Every IEEE double is a dyadic rational m·2^e, and sums and products of dyadic rationals
are dyadic. So a matrix expression in the numbers of a certificate (P, the topology's
weights, δ, α) is computed *exactly* as an integer matrix times a power of two
(:class:`Dyadic`), and positive definiteness is decided exactly by Sylvester's criterion:
all leading principal minors are positive. They are the pivots of a fraction-free LU
factorisation without row exchanges (FLINT's ``fmpz_mat.fflu`` through python-flint;
equivalent to an exact LDLᵀ with positive pivots).

The cost of exact arithmetic grows with the size n and with the bit length of the entries
(a matrix mixing 1e-300 and 1e300 has 2000-bit entries), so it is used only while
``n <= EXACT_MAX_N`` and ``n · bits <= EXACT_BIT_BUDGET`` (:func:`exact_affordable`);
otherwise a rigorous floating-point test is used instead: the expression is evaluated in floating point with an entrywise
bound E on its rounding error (standard model, γ_k = k·u/(1 − k·u), u = 2⁻⁵³), and a
floating-point Cholesky factorisation of ``M − c·I`` must succeed, with
``c = 2·γ_{n+1}/(1 − γ_{n+1})·tr(M) + ‖E‖_F·(1 + 4nu)`` (Rump, "Verification of positive
definiteness", BIT 46, 2006: success of the shifted Cholesky proves M ≻ 0; the factor 2 is
a safety margin; :func:`rump_shift_value` adds Rump's underflow term too).
"""

from __future__ import annotations

from dataclasses import dataclass

import flint
import numpy as np

EXACT_MAX_N = 80
#: n · (largest entry bit length) above which the exact test is not attempted: at n = 21
#: about 760-bit entries (G1's Lyapunov inequality needs ~150), at n = 80 about 200 bits.
EXACT_BIT_BUDGET = 16_000
U = 2.0**-53


def gamma(k: int) -> float:
    """γ_k = k·u/(1 − k·u), the rounding-error factor of a k-term sum of products.

    Parameters
    ----------
    k : int
        Number of terms.

    Returns
    -------
    float
    """
    return k * U / (1 - k * U)


#: Inputs of a verified-float bound are refused outside [2⁻²⁰⁰, 2²⁰⁰] in magnitude: then
#: a product of four stays normal and a sum of many finite, so γ_k bounds every rounding.
SPAN = 2.0**200


def within_span(*arrays: np.ndarray) -> bool:
    """Whether every nonzero entry is finite and within [1/SPAN, SPAN] in magnitude (the
    premise of the relative rounding bounds: no underflow or overflow on the way).

    Parameters
    ----------
    *arrays : numpy.ndarray
        The inputs.

    Returns
    -------
    bool
    """
    for a in arrays:
        v = np.abs(np.asarray(a, dtype=float))
        v = v[v != 0]
        if v.size and not (np.all(np.isfinite(v)) and v.min() >= 1 / SPAN and v.max() <= SPAN):
            return False
    return True


@dataclass(frozen=True)
class Dyadic:
    """An exact matrix ``num / 2**exp`` with ``num`` an object array of Python ints."""

    num: np.ndarray
    exp: int

    @classmethod
    def of(cls, a: np.ndarray | float) -> Dyadic:
        """The exact value of a float matrix (every finite double is dyadic).

        Parameters
        ----------
        a : numpy.ndarray or float
            A matrix or a scalar (taken as 1×1).

        Returns
        -------
        Dyadic
            ``a`` exactly, over the smallest common power of two.

        Raises
        ------
        ValueError
            An entry is NaN or infinite.
        """
        arr = np.atleast_2d(np.asarray(a, dtype=float))
        if not np.all(np.isfinite(arr)):
            raise ValueError("non-finite entry")
        ratios = [x.as_integer_ratio() for x in arr.ravel().tolist()]
        exp = max(d.bit_length() - 1 for _, d in ratios)
        num = np.array([n << (exp - (d.bit_length() - 1)) for n, d in ratios], dtype=object)
        return cls(num.reshape(arr.shape), exp)

    def _align(self, other: Dyadic) -> tuple[np.ndarray, np.ndarray, int]:
        e = max(self.exp, other.exp)
        return self.num * (1 << (e - self.exp)), other.num * (1 << (e - other.exp)), e

    def __add__(self, other: Dyadic) -> Dyadic:
        a, b, e = self._align(other)
        return Dyadic(a + b, e)

    def __sub__(self, other: Dyadic) -> Dyadic:
        a, b, e = self._align(other)
        return Dyadic(a - b, e)

    def __matmul__(self, other: Dyadic) -> Dyadic:
        prod = flint.fmpz_mat(self.num.tolist()) * flint.fmpz_mat(other.num.tolist())
        num = np.array([[int(x) for x in row] for row in prod.tolist()], dtype=object)
        return Dyadic(num.reshape(self.num.shape[0], other.num.shape[1]), self.exp + other.exp)

    @property
    def bits(self) -> int:
        """The largest bit length of a numerator: what exact arithmetic costs."""
        return max((abs(int(x)).bit_length() for x in self.num.ravel()), default=0)

    def scale(self, s: Dyadic) -> Dyadic:
        """Multiply by a dyadic scalar, exactly.

        Parameters
        ----------
        s : Dyadic
            A 1×1 Dyadic.

        Returns
        -------
        Dyadic
            ``s·self``.
        """
        return Dyadic(self.num * s.num[0, 0], self.exp + s.exp)

    @property
    def T(self) -> Dyadic:  # noqa: N802 - matrix transpose, as numpy
        """The transpose."""
        return Dyadic(self.num.T.copy(), self.exp)

    def to_float(self) -> np.ndarray:
        """The nearest floats.

        Returns
        -------
        numpy.ndarray
            The matrix rounded to float64.
        """
        return np.array([float(x) for x in (self.num.ravel() / (2**self.exp))]).reshape(
            self.num.shape
        )

    def equals(self, other: Dyadic) -> bool:
        """Exact equality of the values (not of the representations).

        Parameters
        ----------
        other : Dyadic
            A matrix of the same shape.

        Returns
        -------
        bool
            True when every entry is equal.
        """
        a, b, _ = self._align(other)
        return bool(np.all(a == b))


def first_nonpositive_minor(num: np.ndarray) -> int | None:
    """Sylvester's criterion on an integer symmetric matrix.

    The minors are the diagonal of U in FLINT's fraction-free LU; the factorisation
    exchanges rows only when a leading minor is zero, so a row exchange also marks a
    non-positive one.

    Parameters
    ----------
    num : ndarray
        A square object array of Python ints.

    Returns
    -------
    int or None
        None when every leading principal minor is positive (the matrix is positive
        definite), else the 1-based order of the first leading minor that is not.
    """
    n = num.shape[0]
    if n == 0:
        return None
    perm, _, _, upper = flint.fmpz_mat(np.asarray(num, dtype=object).tolist()).fflu()
    for k in range(n):
        if perm[k, k] != 1 or upper[k, k] <= 0:
            return k + 1
    return None


def exact_affordable(n: int, bits: int) -> bool:
    """Whether an exact test of an n×n integer matrix with entries of ``bits`` bits is
    within the budget (see the module docstring).

    Parameters
    ----------
    n : int
        The matrix size.
    bits : int
        The largest bit length of an entry.

    Returns
    -------
    bool
    """
    return n <= EXACT_MAX_N and n * max(bits, 1) <= EXACT_BIT_BUDGET


@dataclass(frozen=True)
class PDProof:
    """Whether ``m ≻ 0`` was proven, by which method and why."""

    holds: bool
    method: str  # "exact-rational" or "verified-float"
    detail: str


def exact_pd(m: Dyadic) -> PDProof:
    """Exact test of ``m ≻ 0`` for a symmetric dyadic matrix.

    Parameters
    ----------
    m : Dyadic
        The matrix, exactly.

    Returns
    -------
    PDProof
        ``holds`` True when every leading principal minor is positive (Sylvester).
    """
    if not np.all(m.num == m.num.T):
        return PDProof(False, "exact-rational", "the matrix is not symmetric")
    k = first_nonpositive_minor(m.num)
    if k is None:
        return PDProof(True, "exact-rational", f"all {m.num.shape[0]} leading minors > 0")
    return PDProof(False, "exact-rational", f"leading principal minor of order {k} is not positive")


#: The smallest positive double (subnormal): Rump's underflow term.
ETA = 2.0**-1074


def rump_shift_value(n: int, trace, e_frobenius, max_diag):
    """Rump's shift ``c = (2γ_{n+1}/(1−γ_{n+1})·tr|A| + ‖E‖_F(1+4nu)
    + 4(n+2)(2(n+2) + max|a_ii|)·η)(1+4u)``, η = 2⁻¹⁰⁷⁴ (Rump, "Verification of positive
    definiteness", BIT 46, 2006, Theorem 2.3 with the data error ‖E‖ added): if the
    floating-point Cholesky factorisation of A − cI runs to completion, the exact matrix
    within E of A is positive definite, for any order of the inner products. The factor 2
    is a safety margin. Works elementwise on arrays (a batch of matrices).

    Parameters
    ----------
    n : int
        The order of A.
    trace : float or numpy.ndarray
        tr|A| (Σ|a_ii|).
    e_frobenius : float or numpy.ndarray
        ‖E‖_F as computed (its own rounding is covered here).
    max_diag : float or numpy.ndarray
        max|a_ii|.

    Returns
    -------
    float or numpy.ndarray
        c.
    """
    g = gamma(n + 1)
    eta = 4 * (n + 2) * (2 * (n + 2) + max_diag) * ETA  # underflow
    return (2 * g / (1 - g) * trace + e_frobenius * (1 + 4 * n * U) + eta) * (1 + 4 * U)


def verified_float_pd(m: np.ndarray, err: np.ndarray) -> PDProof:
    """Rigorous test of ``M_exact ≻ 0`` from its floating-point value ``m`` and an
    entrywise bound ``err >= |M_exact − m|`` (see the module docstring).

    Parameters
    ----------
    m : ndarray
        The computed matrix.
    err : ndarray
        An entrywise bound on its rounding error.

    Returns
    -------
    PDProof
    """
    n = m.shape[0]
    ms = 0.5 * (m + m.T)
    err = err + 0.5 * np.abs(m - m.T)  # asymmetry of the float value is error too
    dg = np.abs(np.diag(ms))
    c = float(rump_shift_value(n, dg.sum(), float(np.linalg.norm(err, "fro")), dg.max()))
    shifted = ms - c * np.eye(n)
    try:
        r = np.linalg.cholesky(shifted)
    except np.linalg.LinAlgError:
        return PDProof(False, "verified-float", f"Cholesky of M − {c:.3g}·I fails")
    if not np.all(np.isfinite(r)) or np.any(np.diag(r) <= 0):
        return PDProof(False, "verified-float", f"Cholesky of M − {c:.3g}·I breaks down")
    return PDProof(
        True, "verified-float", f"Cholesky of M − {c:.3g}·I succeeds (shift covers rounding)"
    )


__all__ = [
    "SPAN",
    "Dyadic",
    "PDProof",
    "exact_affordable",
    "exact_pd",
    "first_nonpositive_minor",
    "gamma",
    "rump_shift_value",
    "verified_float_pd",
    "within_span",
]
