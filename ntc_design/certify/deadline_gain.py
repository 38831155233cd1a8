"""c(t) in ball arithmetic for the deadline figures (:mod:`ntc_design.certify.deadline`):
its value and its Taylor coefficients at a time or over an interval of times, from an
expression (a sympy tree evaluated on python-flint's arb_series) or a schedule (a table
interpolated linearly or by the previous value, and an expression after its end)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp
from flint import arb, arb_series

from ..errors import InputError, Option
from ..expr.symbolic import parse_expression


def _series_of(expr: sp.Expr, t: arb_series) -> arb_series:
    """A sympy expression in t evaluated on a truncated Taylor series (arb_series)."""
    if expr.is_Symbol:
        return t
    if expr.is_Integer or expr.is_Rational:
        p, q = expr.as_numer_denom()
        return arb_series([arb(int(p)) / int(q)], prec=t.prec)
    if expr.is_Float:
        return arb_series([arb(str(expr))], prec=t.prec)  # as sympy prints it: a ball
    if expr == sp.pi:
        return arb_series([arb.pi()], prec=t.prec)
    if expr == sp.E:
        return arb_series([arb(1).exp()], prec=t.prec)
    args = [_series_of(a, t) for a in expr.args]
    if isinstance(expr, sp.Add):
        out = args[0]
        for a in args[1:]:
            out = out + a
        return out
    if isinstance(expr, sp.Mul):
        out = args[0]
        for a in args[1:]:
            out = out * a
        return out
    if isinstance(expr, sp.Pow):
        e = expr.args[1]
        if e.is_Integer:
            k = int(e)
            r = args[0] ** abs(k)
            return 1 / r if k < 0 else r
        return (args[1] * args[0].log()).exp()
    fns: dict[Any, Callable[[arb_series], arb_series]] = {
        sp.exp: arb_series.exp,
        sp.log: arb_series.log,
        sp.sin: arb_series.sin,
        sp.cos: arb_series.cos,
        sp.tan: arb_series.tan,
        sp.atan: arb_series.atan,
    }
    fn = fns.get(expr.func)
    if fn is None or len(args) != 1:
        raise InputError(
            f"{Option('deadline')} needs an analytic c(t) (+, −, ·, /, powers, exp, log, sin, "
            f"cos, tan, atan), not {expr.func.__name__}",
            field="gain",
        )
    return fn(args[0])


class GainBalls:
    """c(t) as balls: its value and its Taylor coefficients at a time or over an interval
    (a ball), from an expression's text or a schedule document (a table interpolated
    linearly or by the previous value, and an expression after its end).

    Parameters
    ----------
    gain : str or dict
        c(t) as text, or a schedule document (``t``, ``c``, ``interpolation``, ``tail``).

    Raises
    ------
    InputError
        The expression is not allowed, or the schedule is malformed.
    """

    def __init__(self, gain: Any) -> None:
        self.doc = gain
        if isinstance(gain, dict):
            try:
                self.t = [float(x) for x in gain["t"]]
                self.c = [float(x) for x in gain["c"]]
                self.interp = str(gain.get("interpolation", "linear"))
                tail = gain["tail"]
            except (KeyError, TypeError, ValueError):
                raise InputError(
                    "expected a schedule {t, c, interpolation, tail}", field="gain"
                ) from None
            if self.interp not in ("linear", "previous") or len(self.t) != len(self.c):
                raise InputError(
                    "a schedule interpolated linearly or by the previous value", field="gain"
                )
            self.expr = parse_expression(tail, "gain.tail")
        elif isinstance(gain, str):
            self.t, self.c, self.interp = [], [], "linear"
            self.expr = parse_expression(gain, "gain")
        else:
            raise InputError("expected an expression in t or a schedule", field="gain")
        self.symbol = next(iter(self.expr.free_symbols), sp.Symbol("t"))

    def knots(self, t_end: float) -> list[float]:
        """The schedule's knots in (0, t_end) (a step never straddles one).

        Parameters
        ----------
        t_end : float
            The horizon.

        Returns
        -------
        list of float
        """
        return [x for x in self.t if 0.0 < x < t_end]

    def series(self, t: arb, n: int) -> list[arb]:
        """c's Taylor coefficients c^{(j)}(τ)/j!, j < n, enclosed for every τ in the ball
        ``t`` (which lies within one piece of a schedule).

        Parameters
        ----------
        t : flint.arb
            A time or an interval of times.
        n : int
            How many coefficients.

        Returns
        -------
        list of flint.arb
        """
        if self.t and t.upper() <= self.t[-1] and self.t[-1] > self.t[0]:
            k = 0
            lo = float(t.lower())
            while k + 2 < len(self.t) and self.t[k + 1] <= lo:
                k += 1
            c0, c1 = arb(self.c[k]), arb(self.c[k + 1])
            if self.interp == "previous":
                return [arb(self.c[k])] + [arb(0)] * (n - 1)
            slope = (c1 - c0) / (arb(self.t[k + 1]) - arb(self.t[k]))
            return [c0 + slope * (t - arb(self.t[k])), slope] + [arb(0)] * (n - 2)
        x = arb_series([t, arb(1)], prec=n)
        out = _series_of(self.expr, x).coeffs()
        return [out[j] if j < len(out) else arb(0) for j in range(n)]

    def value(self, t: arb) -> arb:
        """c at a time (or enclosed over a ball of times).

        Parameters
        ----------
        t : flint.arb
            The time.

        Returns
        -------
        flint.arb
        """
        if self.t and self.interp == "previous" and t.upper() <= self.t[-1]:
            k = max(i for i, x in enumerate(self.t) if x <= float(t.lower()) or i == 0)
            return arb(self.c[k])
        return self.series(t, 1)[0]


__all__ = ["GainBalls"]
