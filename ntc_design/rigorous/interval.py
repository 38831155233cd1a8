"""Rigorous enclosures of expressions of t over a t-interval (ball arithmetic, python-flint).

:func:`enclose` evaluates a sympy expression (built by :mod:`ntc_design.expr.symbolic`, never user
text) in Arb ball arithmetic with t ranging over a closed interval [a, b]: the result is a
ball guaranteed to contain the expression's value at every t in [a, b] (Arb's outward
rounding; functions are evaluated on balls by their enclosure rules). A value that is not
finite on the interval (a pole of tan, log near 0, an overflow) gives a non-finite ball,
which callers treat as "unbounded here".

:func:`bounds` turns a ball into a pair of doubles (lo, hi) with lo <= every value <= hi
(one extra ulp outwards after Arb's own rounding).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import sympy as sp
from flint import arb

from ..expr.symbolic import symbol

_T = symbol("t")


class NotEnclosable(ValueError):
    """The expression uses an operation without an interval rule here."""


def t_ball(a: float, b: float) -> arb:
    """A ball containing the interval [a, b] of doubles.

    Parameters
    ----------
    a, b : float
        The ends, a <= b.

    Returns
    -------
    flint.arb
        A ball containing [a, b].
    """
    return arb(a).union(arb(b))


def _abs(x: arb) -> arb:
    """A ball containing ``{|v| : v in x}`` (not finite if ``x`` is not)."""
    if not x.is_finite():
        return arb("nan")
    lo, hi = x.lower(), x.upper()
    if lo >= 0:
        return x
    if hi <= 0:
        return -x
    return arb(0).union(-lo if -lo > hi else hi)


def _ipow(x: arb, n: int) -> arb:
    """``x**n`` for an integer n >= 0, from the ends: x**n is monotone on x for odd n and on
    |x| for even n. (python-flint's ``**`` returns NaN for a ball centred at 0 and ±1.01
    for ``[0.25, 1]**2``; products of the ball itself lose the sign of an even power.)"""
    if not x.is_finite():
        return arb("nan")
    y = _abs(x) if n % 2 == 0 else x

    def point_pow(v: arb) -> arb:  # a ball containing v**n, v exact: binary products
        r, b, k = arb(1), v, n
        while k:
            if k & 1:
                r = r * b
            k >>= 1
            if k:
                b = b * b
        return r

    return arb(point_pow(y.lower()).lower()).union(arb(point_pow(y.upper()).upper()))


def _pow(base: arb, e: sp.Expr, ev: Callable[[sp.Expr], arb]) -> arb:
    if isinstance(e, sp.Integer):
        n = int(e)
        return _ipow(base, n) if n >= 0 else 1 / _ipow(base, -n)
    if isinstance(e, sp.Rational) and int(e.q) == 2:
        r = base.sqrt()
        return _ipow(r, int(e.p)) if e.p > 0 else 1 / _ipow(r, int(-e.p))
    return (ev(e) * base.log()).exp()


def enclose(expr: sp.Expr, t: arb, cache: dict | None = None) -> arb:
    """A ball containing ``expr(τ)`` for every τ in the ball ``t``.

    Parameters
    ----------
    expr : sympy.Expr
        An expression of t built by :mod:`ntc_design.expr.symbolic`.
    t : flint.arb
        The ball t ranges over (see :func:`t_ball`).
    cache : dict, optional
        Enclosures of subexpressions over this same ``t``, shared between calls.

    Returns
    -------
    flint.arb
        The enclosure; not finite where the expression is unbounded on ``t``.

    Raises
    ------
    NotEnclosable
        A function without an interval rule here.
    """
    ts = _T
    memo: dict = cache if cache is not None else {}

    def ev(e: sp.Expr) -> arb:
        if e in memo:
            return memo[e]
        if e == ts:
            r = t
        elif isinstance(e, sp.Integer):
            r = arb(int(e))
        elif isinstance(e, sp.Rational):
            r = arb(int(e.p)) / int(e.q)
        elif isinstance(e, sp.Float):
            r = arb(float(e))
        elif e is sp.pi:
            r = arb.pi()
        elif e is sp.E:
            r = arb(1).exp()
        elif isinstance(e, sp.Add):
            r = arb(0)
            for a in e.args:
                r = r + ev(a)
        elif isinstance(e, sp.Mul):
            r = arb(1)
            for a in e.args:
                r = r * ev(a)
        elif isinstance(e, sp.Pow):
            r = _pow(ev(e.args[0]), e.args[1], ev)
        elif isinstance(e, sp.Abs):
            r = _abs(ev(e.args[0]))
        elif isinstance(e, (sp.Min, sp.Max)):
            xs = [ev(a) for a in e.args]
            if not all(x.is_finite() for x in xs):
                r = arb("nan")  # Python's min/max skip a NaN bound: never a finite answer
            else:
                pick = min if isinstance(e, sp.Min) else max
                r = arb(pick(x.lower() for x in xs)).union(arb(pick(x.upper() for x in xs)))
        else:
            fn = {
                sp.exp: arb.exp,
                sp.log: arb.log,
                sp.sin: arb.sin,
                sp.cos: arb.cos,
                sp.tan: arb.tan,
                sp.sinh: arb.sinh,
                sp.cosh: arb.cosh,
                sp.tanh: arb.tanh,
                sp.atan: arb.atan,
            }.get(type(e))
            if fn is None:
                raise NotEnclosable(f"no interval rule for {type(e).__name__}")
            r = fn(ev(e.args[0]))
        memo[e] = r
        return r

    return ev(expr)


def bounds(x: arb) -> tuple[float, float]:
    """Double bounds of a ball.

    Parameters
    ----------
    x : flint.arb
        A ball.

    Returns
    -------
    tuple of float
        (lo, hi) with lo <= x <= hi for every point of the ball, one ulp outwards
        (−inf, inf when the ball is not finite).
    """
    if not x.is_finite():
        return -math.inf, math.inf
    lo = float(x.lower())
    hi = float(x.upper())
    return float(np.nextafter(lo, -np.inf)), float(np.nextafter(hi, np.inf))


def upper(x: arb) -> float:
    """An upper bound of a ball as a double.

    Parameters
    ----------
    x : flint.arb
        A ball.

    Returns
    -------
    float
        ``bounds(x)[1]``.
    """
    return bounds(x)[1]


def lower(x: arb) -> float:
    """A lower bound of a ball as a double.

    Parameters
    ----------
    x : flint.arb
        A ball.

    Returns
    -------
    float
        ``bounds(x)[0]``.
    """
    return bounds(x)[0]


__all__ = ["NotEnclosable", "bounds", "enclose", "lower", "t_ball", "upper"]
