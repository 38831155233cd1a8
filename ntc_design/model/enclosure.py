"""Interval proofs over t for time-varying weights: that a scalar or a matrix expression
keeps one strict sign on a domain (bisection with interval enclosures,
:mod:`ntc_design.rigorous.interval`), enclosures of a matrix on a t-interval, and a rigorous
lower bound on the smallest eigenvalue of a symmetric interval matrix."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import sympy as sp

from ..errors import InputError
from ..expr.symbolic import compile_expression, symbol
from ..rigorous.exact import gamma, verified_float_pd
from ..rigorous.interval import NotEnclosable, bounds, enclose, t_ball

SIGN_PIECES = 64  # first split of the domain for the sign-class proofs
SIGN_MIN_WIDTH = 1e-7  # relative to the domain: below this the proof gives up at that t


def _fmt(x: float) -> str:
    return f"{x:.6g}"


class SignProof:
    """Proofs that a scalar or a matrix keeps one strict sign on a domain, by bisection."""

    def __init__(self, where: Callable[[str], InputError], domain: tuple[float, float] | None):
        self.where = where
        self.domain = domain

    def scalar(self, e: sp.Expr, what: str) -> int:
        """The strict sign of a scalar expression on the whole domain, proved.

        Parameters
        ----------
        e : sympy.Expr
            An expression of t.
        what : str
            The entry's name, for the message.

        Returns
        -------
        int
            +1 or −1 (0 for an expression that is identically zero).

        Raises
        ------
        InputError
            The sign cannot be proven one and strict (naming the t where it fails).
        """
        if not e.has(symbol("t")):
            v = float(e)
            if v == 0:
                return 0
            return 1 if v > 0 else -1
        if self.domain is None:
            if e.is_positive:
                return 1
            if e.is_negative:
                return -1
            raise self.where(
                f"cannot prove that {what} = {e} keeps one sign for every t >= 0; "
                "declare period or constant_after"
            )
        fn = compile_expression(e)
        a0, b0 = self.domain
        probe = fn(np.linspace(a0, b0, 257))
        sgn = 1 if probe[0] > 0 else -1
        if not np.all(np.isfinite(probe)):
            k = int(np.argmax(~np.isfinite(probe)))
            t = a0 + (b0 - a0) * k / 256
            raise self.where(f"{what} = {e} is unbounded near t = {_fmt(t)}")
        bad = np.nonzero(sgn * probe <= 0)[0]
        if bad.size:
            t = a0 + (b0 - a0) * bad[0] / 256
            raise self.where(
                f"{what} = {e} changes sign ({probe[bad[0]]:.4g} at t = {_fmt(t)}); "
                "a weight must keep one sign class for every t"
            )
        stack = [
            (a0 + (b0 - a0) * k / SIGN_PIECES, a0 + (b0 - a0) * (k + 1) / SIGN_PIECES)
            for k in range(SIGN_PIECES)
        ]
        min_w = SIGN_MIN_WIDTH * max(b0 - a0, 1.0)
        cache_free = 0
        while stack:
            a, b = stack.pop()
            try:
                lo, hi = bounds(enclose(e, t_ball(a, b)))
            except NotEnclosable as exc:
                raise self.where(f"{what} = {e}: {exc}") from None
            if (sgn > 0 and lo > 0) or (sgn < 0 and hi < 0):
                continue
            if b - a < min_w:
                if not math.isfinite(lo) or not math.isfinite(hi):
                    raise self.where(f"{what} = {e} is unbounded near t = {_fmt(0.5 * (a + b))}")
                raise self.where(
                    f"cannot prove that {what} = {e} stays "
                    f"{'positive' if sgn > 0 else 'negative'} near t = {_fmt(0.5 * (a + b))} "
                    "(it may reach 0); a weight must keep one sign class for every t"
                )
            m = 0.5 * (a + b)
            stack += [(a, m), (m, b)]
            cache_free += 1
        return sgn

    def matrix(self, entries, what: str) -> int:
        """Definiteness on the whole domain of a symmetric matrix of expressions, proved.

        Parameters
        ----------
        entries : sequence of sequence of sympy.Expr
            The matrix.
        what : str
            Its name, for the message.

        Returns
        -------
        int
            +1 (positive definite) or −1 (negative definite) for every t.

        Raises
        ------
        InputError
            Neither can be proven (naming the t where the proof fails).
        """
        d = len(entries)
        if self.domain is None:
            raise self.where(
                f"{what}: a weight written by rows with expressions needs a declared "
                "period or constant_after (its definiteness is proven on that domain)"
            )
        a0, b0 = self.domain
        fns = [[compile_expression(entries[k][m]) for m in range(d)] for k in range(d)]
        ts = np.linspace(a0, b0, 257)
        vals = np.stack([np.stack([fns[k][m](ts) for m in range(d)], -1) for k in range(d)], -2)
        if not np.all(np.isfinite(vals)):
            k = int(np.argmax(~np.all(np.isfinite(vals), axis=(1, 2))))
            raise self.where(f"{what} is unbounded near t = {_fmt(ts[k])}")
        lam = np.linalg.eigvalsh(vals)
        sgn = 1 if lam[0, 0] > 0 else -1
        ext = lam[:, 0] if sgn > 0 else -lam[:, -1]
        if np.any(ext <= 0):
            k = int(np.argmax(ext <= 0))
            raise self.where(
                f"{what} is not {'positive' if sgn > 0 else 'negative'} definite at "
                f"t = {_fmt(ts[k])} (eigenvalues {lam[k, 0]:.4g} .. {lam[k, -1]:.4g}); a "
                "weight written by rows must stay definite (one sign class) for every t"
            )
        stack = [
            (a0 + (b0 - a0) * k / SIGN_PIECES, a0 + (b0 - a0) * (k + 1) / SIGN_PIECES)
            for k in range(SIGN_PIECES)
        ]
        min_w = SIGN_MIN_WIDTH * max(b0 - a0, 1.0)
        while stack:
            a, b = stack.pop()
            mid, rad = enclose_matrix(entries, a, b)
            if not np.all(np.isfinite(rad)):
                if b - a < min_w:
                    raise self.where(f"{what} is unbounded near t = {_fmt(a)}")
            else:
                lam_lo = sym_min_eig_lower(sgn * mid, rad)
                if lam_lo > 0:
                    continue
                if b - a < min_w:
                    raise self.where(
                        f"cannot prove {what} stays definite near t = {_fmt(0.5 * (a + b))}"
                    )
            m = 0.5 * (a + b)
            stack += [(a, m), (m, b)]
        return sgn


def enclose_matrix(entries, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """A rigorous entrywise enclosure of a matrix of expressions over a t-interval.

    Parameters
    ----------
    entries : sequence of sequences of sympy.Expr
        The d×d entries of A(t).
    a, b : float
        The interval [a, b] of t.

    Returns
    -------
    tuple of numpy.ndarray
        (mid, rad) with |A(t) − mid| <= rad entrywise for every t in [a, b] (rad infinite
        where an entry is unbounded).

    Raises
    ------
    NotEnclosable
        An entry uses a function without an interval rule.
    """
    tb = t_ball(a, b)
    cache: dict = {}
    d = len(entries)
    lo = np.empty((d, d))
    hi = np.empty((d, d))
    for k in range(d):
        for m in range(d):
            lo[k, m], hi[k, m] = bounds(enclose(entries[k][m], tb, cache))
    return interval_mid_rad(lo, hi)


def interval_mid_rad(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint and a radius (rounded up) of entrywise intervals [lo, hi].

    Parameters
    ----------
    lo, hi : numpy.ndarray
        The interval ends, entrywise.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        mid and rad with [lo, hi] ⊆ [mid − rad, mid + rad]; an entry that is not finite
        gets mid 0 and rad ∞.
    """
    with np.errstate(invalid="ignore", over="ignore"):
        mid = 0.5 * lo + 0.5 * hi
        rad = np.maximum(hi - mid, mid - lo)
        rad = np.nextafter(rad, np.inf)
    bad = ~np.isfinite(lo) | ~np.isfinite(hi)
    mid = np.where(bad, 0.0, mid)
    rad = np.where(bad, np.inf, rad)
    return mid, rad


U_ROUND = 2.0**-53


def sym_min_eig_lower(mid: np.ndarray, rad: np.ndarray) -> float:
    """A rigorous lower bound on λ_min(M) for every symmetric M with |M − mid| <= rad.

    Weyl: λ_min(M) >= λ_min(mid) − ‖M − mid‖₂ >= λ_min(mid) − ρ(rad) and ρ(rad) <= the
    largest row sum of rad (Perron). λ_min(mid) is computed in floating point and then
    proven: mid − s·I ≻ 0 for s = λ̃ − η by a Cholesky factorisation whose shift covers
    every rounding error (:func:`ntc_design.rigorous.exact.verified_float_pd`, Rump 2006).

    Parameters
    ----------
    mid : numpy.ndarray
        The midpoint matrix (symmetrised here).
    rad : numpy.ndarray
        The entrywise radius, >= 0.

    Returns
    -------
    float
        The bound (−inf when nothing could be proven or rad is not finite).
    """

    n = mid.shape[0]
    ms = 0.5 * (mid + mid.T)
    if not np.all(np.isfinite(rad)):
        return -math.inf
    asym = 0.5 * np.abs(mid - mid.T)
    rho = float(np.max(np.sum(rad + asym, axis=1))) * (1 + 2 * n * U_ROUND)
    if n == 1:
        return float(np.nextafter(ms[0, 0], -np.inf)) - rho
    lam = float(np.linalg.eigvalsh(ms)[0])
    scale = float(np.max(np.abs(np.diag(ms)))) + float(np.max(np.sum(np.abs(ms), axis=1)))
    eta = 8 * gamma(n + 2) * scale + 1e-300
    for _ in range(8):
        s = lam - eta
        shifted = ms - s * np.eye(n)
        err = gamma(2) * np.abs(shifted)
        if verified_float_pd(shifted, err).holds:
            return float(np.nextafter(s - rho, -np.inf))
        eta *= 8
    return -math.inf
