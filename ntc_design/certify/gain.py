"""Conditions on the control gain c(t) (Theorems 1-4), decided with sympy.

* continuity and ``c >= 0`` on [0, ∞) (a gain negative somewhere is bad input);
* ``∫₀^∞ c dt = ∞`` (cumulative effect; Theorems 1-4);
* ``c(t) → 0`` (asymptotic decay; Theorems 1-4);
* ``∫₀^∞ c² dt < ∞`` (finite noise energy; Theorems 2 and 4).

Each is true, false or undetermined (None) with its reason: symbolic (sympy's integrate /
limit) where sympy can; else the power-law exponent ``p = lim log c / log t`` decides an
improper integral by comparison with t^p (diverges for p > −1, converges for p < −1);
where neither applies the answer is undetermined with a numerical observation, never a
silent guess.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.parsing.sympy_parser import (
    convert_xor,
    implicit_multiplication_application,
    parse_expr,
    standard_transformations,
)

from ..errors import InputError

T = sp.Symbol("t", nonnegative=True, real=True)
_ALLOWED = {
    name: getattr(sp, name)
    for name in (
        "exp",
        "log",
        "sqrt",
        "sin",
        "cos",
        "tan",
        "atan",
        "sinh",
        "cosh",
        "tanh",
        "pi",
        "E",
        "Abs",
        "Min",
        "Max",
        "Piecewise",
    )
}
_TRANSFORMS = standard_transformations + (convert_xor, implicit_multiplication_application)
SYMPY_SECONDS = 4  # budget of one sympy call; past it the condition is undetermined


class _Timeout(Exception):
    pass


def _bounded(fn: Callable[[], Any], seconds: float = SYMPY_SECONDS) -> Any:
    """Run a sympy call with a time budget (SIGALRM, main thread only); raise _Timeout."""
    if threading.current_thread() is not threading.main_thread():
        return fn()

    def on_alarm(signum, frame):  # noqa: ARG001
        raise _Timeout

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return fn()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@dataclass(frozen=True)
class Condition:
    value: bool | None
    reason: str

    def to_dict(self) -> dict:
        return {"value": self.value, "reason": self.reason}


@dataclass(frozen=True)
class GainAnalysis:
    expression: str
    expr: sp.Expr
    continuous_nonnegative: Condition
    integral_diverges: Condition  # ∫ c = ∞
    tends_to_zero: Condition  # c → 0
    square_integrable: Condition  # ∫ c² < ∞

    @property
    def mean_square(self) -> bool | None:
        """Premises on c of Theorems 1 and 3."""
        return _and(
            self.continuous_nonnegative.value,
            self.integral_diverges.value,
            self.tends_to_zero.value,
        )

    @property
    def almost_sure(self) -> bool | None:
        """Premises on c of Theorems 2 and 4."""
        return _and(self.mean_square, self.square_integrable.value)

    def to_dict(self) -> dict:
        return {
            "expression": self.expression,
            "parsed": str(self.expr),
            "continuous_nonnegative": self.continuous_nonnegative.to_dict(),
            "integral_diverges": self.integral_diverges.to_dict(),
            "tends_to_zero": self.tends_to_zero.to_dict(),
            "square_integrable": self.square_integrable.to_dict(),
            "mean_square": self.mean_square,
            "almost_sure": self.almost_sure,
        }


def _and(*vals: bool | None) -> bool | None:
    if any(v is False for v in vals):
        return False
    if any(v is None for v in vals):
        return None
    return True


def parse_gain(text: str, field: str = "gain") -> sp.Expr:
    """Parse ``c(t)`` (``^`` is a power); only the variable t is allowed."""
    if not isinstance(text, str) or not text.strip():
        raise InputError(f"{field}: expected an expression in t, e.g. 1/(1+t)")
    try:
        expr = parse_expr(
            text, local_dict={"t": T, **_ALLOWED}, transformations=_TRANSFORMS, evaluate=True
        )
    except Exception as exc:  # sympy raises many types for bad syntax
        raise InputError(f"{field}: cannot parse {text!r} ({exc.__class__.__name__})") from None
    if not isinstance(expr, sp.Expr):
        raise InputError(f"{field}: {text!r} is not an expression in t")
    other = sorted(str(s) for s in expr.free_symbols if s != T)
    if other:
        raise InputError(
            f"{field}: {text!r} uses {', '.join(other)}; only the variable t is allowed"
        )
    if expr.has(sp.I) or expr.has(sp.zoo) or expr.has(sp.nan):
        raise InputError(f"{field}: {text!r} is not a real function of t")
    return expr


def _continuity(expr: sp.Expr) -> Condition:
    try:
        dom = _bounded(lambda: sp.calculus.util.continuous_domain(expr, T, sp.Interval(0, sp.oo)))
    except (NotImplementedError, ValueError, TypeError, _Timeout):
        return Condition(None, "sympy cannot determine the continuous domain")
    if dom == sp.Interval(0, sp.oo):
        return Condition(True, "continuous on [0, ∞) (sympy continuous_domain)")
    return Condition(False, f"continuous only on {dom}")


def _sign(expr: sp.Expr, text: str) -> str:
    """'symbolic' if c >= 0 is shown on [0, ∞); raise InputError where c < 0 is found."""
    try:
        neg = _bounded(lambda: sp.solveset(expr < 0, T, sp.Interval(0, sp.oo)))
    except (NotImplementedError, ValueError, TypeError, _Timeout):
        neg = None
    if neg is not None and neg is not sp.S.EmptySet and not isinstance(neg, sp.ConditionSet):
        pt = neg.inf if neg.inf.is_finite else 0
        raise InputError(
            f"gain: {text!r} is negative on {neg} (e.g. near t = {sp.N(pt, 4)}); c(t) must be >= 0"
        )
    if neg is sp.S.EmptySet:
        return "c(t) >= 0 on [0, ∞) (sympy solveset)"
    import numpy as np

    f = sp.lambdify(T, expr, modules="numpy")
    ts = np.concatenate([[0.0], np.logspace(-6, 8, 4000)])
    with np.errstate(all="ignore"):
        vals = np.asarray(f(ts), dtype=float) * np.ones_like(ts)
    bad = ts[vals < 0]
    if bad.size:
        raise InputError(f"gain: {text!r} is negative at t = {bad[0]:.4g}; c(t) must be >= 0")
    return "c(t) >= 0 at 4001 sample points of [0, 1e8] (numerical; sympy could not decide)"


def _power(expr: sp.Expr) -> sp.Expr | None:
    try:
        p = _bounded(lambda: sp.limit(sp.log(expr) / sp.log(T), T, sp.oo))
    except Exception:  # noqa: BLE001 - sympy limit can fail in many ways
        return None
    return p if p.is_real or p in (sp.oo, -sp.oo) else None


def _integral(expr: sp.Expr, name: str) -> tuple[bool | None, str]:
    """Does ∫₀^∞ expr dt converge? (expr continuous, >= 0)."""
    try:
        val = _bounded(lambda: sp.integrate(expr, (T, 0, sp.oo)))
    except Exception:  # noqa: BLE001
        val = None
    if val is not None and not val.has(sp.Integral):
        if val == sp.oo:
            return False, f"∫₀^∞ {name} dt = ∞ (sympy)"
        if val.is_finite:
            approx = "" if val.is_Rational else f" ≈ {float(val):.6g}"
            return True, f"∫₀^∞ {name} dt = {val}{approx} (sympy)"
    p = _power(expr)
    if p is not None:
        if p == -sp.oo or (p.is_number and p < -1):
            return (
                True,
                f"{name} ~ t^{p} with {p} < −1 as t → ∞: the integral converges (comparison)",
            )
        if p == sp.oo or (p.is_number and p > -1):
            return (
                False,
                f"{name} ~ t^{p} with {p} > −1 as t → ∞: the integral diverges (comparison)",
            )
        # p = −1: compare with 1/(t log t) (diverges) and 1/(t log² t) (converges)
        for w, diverges, ref in (
            (T * sp.log(T), True, "1/(t log t)"),
            (T * sp.log(T) ** 2, False, "1/(t log² t)"),
        ):
            try:
                lim = _bounded(lambda w=w: sp.limit(w * expr, T, sp.oo))
            except Exception:  # noqa: BLE001
                continue
            if diverges and (lim == sp.oo or (lim.is_number and lim > 0)):
                return False, f"{name}·t·log t → {lim} > 0: the integral diverges like ∫ {ref} dt"
            if not diverges and lim.is_number and lim.is_finite:
                return True, f"{name}·t·log² t → {lim}: the integral converges like ∫ {ref} dt"
    return None, f"sympy cannot decide ∫₀^∞ {name} dt; {_numeric_integrals(expr)}"


def _numeric_integrals(expr: sp.Expr) -> str:
    """A stated numerical observation (not a decision): ∫₀^T for growing T."""
    import numpy as np
    from scipy.integrate import quad

    f = sp.lambdify(T, expr, modules="numpy")
    edges = np.concatenate([[0.0], np.logspace(-2, 6, 161)])
    with np.errstate(all="ignore"):
        parts = [quad(f, a, b, limit=200)[0] for a, b in zip(edges[:-1], edges[1:], strict=True)]
    cum = np.cumsum(parts)
    at = {int(k): cum[np.searchsorted(edges[1:], 10.0**k)] for k in (2, 4, 6)}
    return "numerically ∫₀^T ≈ " + ", ".join(f"{v:.4g} at T=1e{k}" for k, v in at.items())


def analyse_gain(text: str) -> GainAnalysis:
    """Decide the Theorem 1-4 conditions on c(t) given as an expression string."""
    expr = parse_gain(text)
    cont = _continuity(expr)
    sign_reason = _sign(expr, text)
    cn = Condition(cont.value, f"{cont.reason}; {sign_reason}")
    conv, why = _integral(expr, "c")
    div = Condition(None if conv is None else not conv, why)
    try:
        lim = _bounded(lambda: sp.limit(expr, T, sp.oo))
        if lim.is_number and not lim.has(sp.AccumBounds):
            zero = Condition(bool(lim == 0), f"lim_(t→∞) c(t) = {lim} (sympy)")
        else:
            zero = Condition(None, f"sympy gives lim c(t) = {lim}: no single limit")
    except Exception:  # noqa: BLE001
        zero = Condition(None, "sympy cannot compute lim_(t→∞) c(t)")
    conv2, why2 = _integral(expr**2, "c²")
    sq = Condition(conv2, why2)
    return GainAnalysis(text, expr, cn, div, zero, sq)
