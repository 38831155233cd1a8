"""Conditions on the control gain c(t) of Theorems 1-4 (Niu & Wu, eqs. (13), (16), (17)
and (20)), decided safely.

The conditions (labels in :data:`CONDITION_LABELS`, the one table every layer uses):

* ``c`` continuous and ``c >= 0`` on [0, ∞) (a gain found negative or non-finite is bad input);
* ``∫₀^∞ c dt = ∞`` (cumulative effect; Theorems 1-4);
* ``c(t) → 0`` (asymptotic decay; Theorems 1-4);
* ``∫₀^∞ c² dt < ∞`` (finite noise energy; Theorems 2 and 4).

Each is true, false or undetermined (None) with its reason; never a guess.

How an improper integral ``∫^∞ h`` is decided (``h`` continuous, so only the tail matters):

1. *Limit comparison with a logarithmic scale.* With ``ψ₁ = t``, ``ψ₂ = t·log t``,
   ``ψ₃ = t·log t·log log t`` and ``L₁ = log t``, ``L₂ = log log t``, ...: if
   ``liminf h·ψ_k > 0`` the integral diverges (``∫ 1/ψ_k = ∞``); if
   ``limsup h·ψ_k·L_k² < ∞`` it converges (``∫ 1/(ψ_k L_k²) < ∞``). sympy's ``limit``
   (Gruntz) gives the limits; an oscillating limit comes back as an interval
   (``AccumBounds``), whose ends bound liminf and limsup.
2. *Oscillation split.* Products and powers of ``sin``/``cos`` with arguments ``a·t + b`` are
   linearised (``sin² t = (1 − cos 2t)/2``), so ``h = s + Σ g_k·trig(a_k t + b_k)``. When
   every ``g_k`` is free of oscillating functions and tends to 0, it is eventually monotone
   (it belongs to a Hardy field: Hardy, *Orders of infinity*), so ``∫ g_k·trig`` converges
   (Dirichlet's test) and ``∫ h`` behaves as ``∫ s``, decided by step 1.
3. Otherwise sympy's ``integrate`` when it returns ∞ or a finite number; else undetermined,
   with a stated numerical observation.

Symbolic work runs in a forked child process killed at a hard deadline
(:data:`GAIN_SECONDS` in all), so no input can hang the caller even inside C-level
arithmetic; inside the child each sympy call also has its own smaller budget
(:data:`STEP_SECONDS`, a SIGALRM) so that one slow step leaves time for the others.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import signal
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from ..errors import InputError
from ..expr.symbolic import compile_expression, parse_expression, show, symbol, user_text
from ..present.rows import Table, verdict

T = symbol("t")
GAIN_SECONDS = 6.0  # hard limit of one gain analysis (the child process is killed)
STEP_SECONDS = 2.0  # budget of one sympy call inside it (a third of a larger total)
_step = [STEP_SECONDS]  # the budget in force, set per analysis

#: The gain conditions, by key, with the label every report and verdict prints.
CONDITION_LABELS: dict[str, str] = {
    "continuous_nonnegative": "c continuous and >= 0 on [0, ∞)",
    "integral_diverges": "∫₀^∞ c dt = ∞",
    "tends_to_zero": "c(t) → 0",
    "square_integrable": "∫₀^∞ c² dt < ∞",
}


class _Timeout(BaseException):  # BaseException: sympy's own `except Exception` can't eat it
    pass


@dataclass(frozen=True)
class Condition:
    """One decided condition: ``value`` True, False or None (undetermined), and why."""

    value: bool | None
    reason: str

    def __post_init__(self) -> None:
        # reasons interpolate SymPy values: users read ∞ and ^, not oo and **
        object.__setattr__(self, "reason", user_text(self.reason))

    def to_dict(self) -> dict:
        """The condition as a JSON-ready mapping.

        Returns
        -------
        dict
            ``value`` (True, False or None) and ``reason``.
        """
        return {"value": self.value, "reason": self.reason}


@dataclass(frozen=True)
class GainAnalysis:
    """The four gain conditions of Theorems 1-4 for one gain c(t): ∫c = ∞ and c → 0
    (eqs. (13) and (17)), plus ∫c² < ∞ (eqs. (16) and (20)), with c continuous and
    nonnegative (Niu & Wu)."""

    expression: str
    expr: sp.Expr
    continuous_nonnegative: Condition
    integral_diverges: Condition  # ∫ c = ∞
    tends_to_zero: Condition  # c → 0
    square_integrable: Condition  # ∫ c² < ∞
    label: str | None = None  # what the table names instead of expr (a schedule)

    @property
    def mean_square(self) -> bool | None:
        """Premises on c of Theorems 1 and 3 (eqs. (13), (17)); None if undetermined."""
        return _and(
            self.continuous_nonnegative.value,
            self.integral_diverges.value,
            self.tends_to_zero.value,
        )

    @property
    def almost_sure(self) -> bool | None:
        """Premises on c of Theorems 2 and 4 (eqs. (16), (20)); None if undetermined."""
        return _and(self.mean_square, self.square_integrable.value)

    def condition(self, key: str) -> Condition:
        """The condition stored under a key of :data:`CONDITION_LABELS`.

        Parameters
        ----------
        key : str
            ``continuous_nonnegative``, ``integral_diverges``, ``tends_to_zero`` or
            ``square_integrable``.

        Returns
        -------
        Condition
            Its value and reason.
        """
        return getattr(self, key)

    def table(self) -> Table:
        """The conditions and the two verdicts as the table every face shows.

        Returns
        -------
        ntc_design.present.rows.Table
            One row per condition (holds, reason), then the mean-square and almost-sure
            verdicts.
        """
        rows: list[tuple] = [
            (label, verdict(self.condition(k).value), self.condition(k).reason)
            for k, label in CONDITION_LABELS.items()
        ]
        rows += [
            ("mean square (Theorems 1, 3)", verdict(self.mean_square), "eqs. (13), (17)"),
            ("almost sure (Theorems 2, 4)", verdict(self.almost_sure), "eqs. (16), (20)"),
        ]
        name = self.label or show(self.expr)
        return Table.build(f"gain c(t) = {name}", ("condition", "holds", "reason"), rows)

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        word = {True: "yes", False: "no", None: "undetermined"}
        return (
            f"GainAnalysis(c(t) = {self.label or show(self.expr)}, mean square {word[self.mean_square]}, "
            f"almost sure {word[self.almost_sure]})"
        )

    def to_dict(self) -> dict:
        """The analysis as a JSON-ready mapping (what ``ntc gain`` prints as JSON).

        Returns
        -------
        dict
            The expression as given and parsed, each condition, ``mean_square`` and
            ``almost_sure``.
        """
        out: dict[str, Any] = {"expression": self.expression, "parsed": show(self.expr)}
        for key in CONDITION_LABELS:
            out[key] = self.condition(key).to_dict()
        out["mean_square"] = self.mean_square
        out["almost_sure"] = self.almost_sure
        return out


def _and(*vals: bool | None) -> bool | None:
    if any(v is False for v in vals):
        return False
    if any(v is None for v in vals):
        return None
    return True


def parse_gain(text: str, field: str = "gain") -> sp.Expr:
    """Parse a gain ``c(t)`` safely (see :func:`ntc_design.expr.symbolic.parse_expression`).

    Parameters
    ----------
    text : str
        The gain, e.g. ``"1/(1+t)"``; ``^`` is a power; a leading minus sign is allowed
        (such a gain is then refused by :func:`analyse_gain` as negative).
    field : str, optional
        Field name that starts error messages.

    Returns
    -------
    sympy.Expr
        The gain as an expression in the symbol :data:`T` (``t >= 0``).

    Raises
    ------
    InputError
        One line when the text is not a whitelisted expression in t.
    """
    return parse_expression(text, field, variables={"t": T})


def gain_function(text: str, field: str = "gain") -> Callable[[np.ndarray], np.ndarray]:
    """A vectorised ``c(t)`` (array in, float array of the same shape out) from text.

    Parameters
    ----------
    text : str
        The gain expression.
    field : str, optional
        Field name that starts error messages.

    Returns
    -------
    callable
        ``c(t_array) -> numpy.ndarray``; non-finite values come back as inf/nan.

    Raises
    ------
    InputError
        As :func:`parse_gain`.
    """
    return compile_expression(parse_gain(text, field), (T,))


# ----------------------------------------------------------------- bounded sympy calls


def _bounded(fn: Callable[[], Any], seconds: float | None = None) -> Any:
    """Run a sympy call with a SIGALRM budget where possible; raise _Timeout past it."""
    seconds = _step[0] if seconds is None else seconds * _step[0] / STEP_SECONDS
    import threading

    if not hasattr(signal, "setitimer"):
        return fn()

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


def limit_at_infinity(expr: sp.Expr, seconds: float | None = None) -> sp.Expr | None:
    """lim_(t→∞) expr: a number, ±∞, an AccumBounds, or None if sympy fails or times out.

    Parameters
    ----------
    expr : sympy.Expr
        An expression of t.
    seconds : float, optional
        The time limit (default: the module's).

    Returns
    -------
    sympy.Expr or None
    """
    try:
        val = _bounded(lambda: sp.limit(expr, T, sp.oo), seconds)
    except _Timeout:
        return None
    except Exception:  # noqa: BLE001 - sympy's limit raises many types
        return None
    if isinstance(val, sp.AccumBounds) or val in (sp.oo, -sp.oo):
        return val
    if val.is_number and val.is_extended_real and val.is_finite:
        return val
    return None


def _bounds(val: sp.Expr) -> tuple[Any, Any]:
    """(lower, upper) ends of a limit value (an interval for an oscillating limit)."""
    if isinstance(val, sp.AccumBounds):
        return val.min, val.max
    return val, val


def _pos(x) -> bool:
    return x == sp.oo or bool(x.is_number and x.is_extended_positive)


def _finite(x) -> bool:
    return bool(x.is_number and x.is_finite)


# ----------------------------------------------------------------- improper integrals


def _scale():
    """(ψ_k, ψ_k·L_k², name of 1/ψ_k, name of 1/(ψ_k L_k²)) for k = 1, 2, 3."""
    lt, llt = sp.log(T), sp.log(sp.log(T))
    return [
        (T, T * lt**2, "1/t", "1/(t·log²t)"),
        (T * lt, T * lt * llt**2, "1/(t·log t)", "1/(t·log t·(log log t)²)"),
        (
            T * lt * llt,
            T * lt * llt * sp.log(llt) ** 2,
            "1/(t·log t·log log t)",
            "1/(t·log t·log log t·(log log log t)²)",
        ),
    ]


def _nonnegative_derivative(h: sp.Expr, y: sp.Symbol) -> bool | None:
    """∂h/∂y >= 0 (sympy's assumptions; None when undecided)."""
    return sp.diff(h, y).is_nonnegative


def _integral_piece(f: Callable[[float], Any], a: float, b: float) -> float:
    """∫_a^b f by adaptive quadrature."""
    from scipy.integrate import quad

    return float(quad(lambda x: float(f(x)), a, b, limit=100)[0])


def _compare(h: sp.Expr, name: str) -> tuple[bool | None, str]:
    """Limit comparison of ∫^∞ h with the logarithmic scale: (converges?, reason)."""
    for psi, psi_l2, div_ref, conv_ref in _scale():
        lo, _ = _bounds(d) if (d := limit_at_infinity(h * psi)) is not None else (None, None)
        if lo is not None and _pos(lo):
            what = "liminf" if isinstance(d, sp.AccumBounds) else "lim"
            return False, (
                f"{what} {name}·{_mul_name(div_ref)} = {lo} > 0: ∫ {name} dt diverges like "
                f"∫ {div_ref} dt (limit comparison)"
            )
        c = limit_at_infinity(h * psi_l2)
        if c is not None:
            clo, chi = _bounds(c)
            if _finite(chi) and _finite(clo):
                return True, (
                    f"{name}·{_mul_name(conv_ref)} stays bounded (limit {c}): ∫ {name} dt "
                    f"converges like ∫ {conv_ref} dt (limit comparison)"
                )
    return None, ""


def _mul_name(ref: str) -> str:
    return ref[2:].strip("()")


def _oscillating(a: sp.Expr) -> bool:
    """sin/cos/tan of an argument that tends to ±∞ (others are eventually monotone)."""
    lim = limit_at_infinity(a.args[0], STEP_SECONDS / 2)
    return lim in (sp.oo, -sp.oo) or lim is None or isinstance(lim, sp.AccumBounds)


def _linear_in_t(arg: sp.Expr) -> bool:
    poly = sp.Poly(arg, T) if arg.is_polynomial(T) else None
    return poly is not None and poly.degree() == 1 and all(c.is_real for c in poly.all_coeffs())


def _split(h: sp.Expr) -> tuple[sp.Expr, list[tuple[sp.Expr, sp.Expr]]] | None:
    """h = smooth + Σ g·trig with trig = sin/cos(a t + b), g free of oscillation; or None."""
    from sympy.simplify.fu import TR8

    trig = (sp.sin, sp.cos, sp.tan)
    osc = [a for a in h.atoms(*trig) if _oscillating(a)]
    if not osc:
        return h, []
    if any(a.func is sp.tan or not _linear_in_t(a.args[0]) for a in osc):
        return None
    cur = h
    for _ in range(4):  # linearise products and powers of sin/cos
        nxt = sp.expand(TR8(sp.expand(cur)))
        if nxt == cur:
            break
        cur = nxt
    smooth, parts = sp.Integer(0), dict[sp.Expr, sp.Expr]()
    for term in sp.Add.make_args(cur):
        atoms = [a for a in term.atoms(*trig) if a.func is not sp.tan and _linear_in_t(a.args[0])]
        atoms = [a for a in atoms if a.args[0].has(T)]
        if not atoms:
            smooth += term
            continue
        if len(atoms) != 1:
            return None
        g, rest = term.as_independent(atoms[0], as_Add=False)
        if rest != atoms[0] or g.has(sp.Abs, sp.Min, sp.Max):
            return None
        parts[atoms[0]] = parts.get(atoms[0], 0) + g
    return smooth, [(g, a) for a, g in parts.items()]


def _eventual_sign(f: sp.Expr) -> int | None:
    """Sign of f(t) for all large t (Gruntz's algorithm), or None if sympy cannot tell."""
    from sympy.series.gruntz import sign

    try:
        s = _bounded(lambda: sign(f, T), STEP_SECONDS / 2)
    except (_Timeout, Exception):  # noqa: BLE001
        return None
    return int(s) if s in (-1, 0, 1) else None


def _tail_form(expr: sp.Expr) -> sp.Expr:
    """An expression equal to ``expr`` for all large t with Min, Max and Abs resolved
    where the eventual order or sign of their arguments is decided (the conditions on c
    other than continuity and sign depend on the tail only)."""
    if not expr.has(sp.Min, sp.Max, sp.Abs):
        return expr

    def pick(args, bigger: bool):
        best = args[0]
        for a in args[1:]:
            s = _eventual_sign(a - best)
            if s is None:
                raise ValueError
            if (s > 0) == bigger and s != 0:
                best = a
        return best

    def rebuild(e: sp.Expr) -> sp.Expr:
        if not e.args:
            return e
        args = [rebuild(a) for a in e.args]
        if e.func in (sp.Min, sp.Max):
            return pick(args, e.func is sp.Max)
        if e.func is sp.Abs:
            s = _eventual_sign(args[0])
            if s is None:
                raise ValueError
            return args[0] if s >= 0 else -args[0]
        return e.func(*args)

    try:
        return rebuild(expr)
    except ValueError:
        return expr


def _monotone_bounds(h: sp.Expr, name: str) -> tuple[bool | None, str]:
    """Bounds for ``|sin u|``, ``|cos u|`` factors (u → ∞): where h is nondecreasing in
    the factor y ∈ [0, 1], ``y² <= y <= 1`` give ``h(y²) <= h <= h(1)``; a divergent lower
    bound or a convergent upper bound decides ∫ h."""
    atoms = [
        a for a in h.atoms(sp.Abs) if a.args[0].func in (sp.sin, sp.cos) and _oscillating(a.args[0])
    ]
    if not atoms:
        return None, ""
    ys = [sp.Dummy("y", nonnegative=True) for _ in atoms]
    hy = h.xreplace(dict(zip(atoms, ys, strict=True)))
    try:
        increasing = all(
            _bounded(functools.partial(_nonnegative_derivative, hy, y), _step[0] / 2) for y in ys
        )
    except (_Timeout, Exception):  # noqa: BLE001
        increasing = False
    if not increasing:
        return None, ""
    lower = hy.xreplace({y: a.args[0] ** 2 for y, a in zip(ys, atoms, strict=True)})
    conv, why = _integral(lower, f"({lower})")
    if conv is False:
        return False, f"{name} >= {lower} (|sin| >= sin², {name} increasing in it); {why}"
    upper = hy.xreplace({y: sp.Integer(1) for y in ys})
    conv, why = _compare(upper, f"({upper})")
    if conv is True:
        return True, f"{name} <= {upper} (|sin| <= 1, {name} increasing in it); {why}"
    return None, ""


def _integral(h: sp.Expr, name: str) -> tuple[bool | None, str]:
    """Does ∫₀^∞ h dt converge? (h continuous and >= 0 on [0, ∞))."""
    h = sp.factor_terms(h)
    if h == 0:
        return True, f"{name} = 0: the integral is 0"
    if any(a.args[0].func in (sp.sin, sp.cos) for a in h.atoms(sp.Abs)):
        conv, why = _monotone_bounds(h, name)
        if conv is not None:
            return conv, why
    split = _split(h)
    if split is None or not split[1]:  # no oscillation to take apart
        conv, why = _compare(h, name)
        if conv is not None:
            return conv, why
    if split is not None and split[1]:
        smooth, parts = split
        # g with a finite limit G is eventually monotone: ∫^T g·sin(a t + b) stays bounded
        # (Dirichlet's test for g − G, and G·∫ sin is bounded); as c >= 0, ∫^T c is
        # increasing, so ∫ c and ∫ smooth converge or diverge together.
        if all((g_lim := limit_at_infinity(g)) is not None and _finite(g_lim) for g, _ in parts):
            osc = ", ".join(str(a) for _, a in parts)
            if smooth == 0:
                return True, (
                    f"{name} is a sum of g·({osc}) with g of finite limit: ∫^T {name} stays "
                    "bounded (Dirichlet's test) and increases, so it converges"
                )
            conv, why = _compare(smooth, f"({smooth})")
            if conv is not None:
                return conv, (
                    f"{name} = {smooth} + terms g·({osc}) with g of finite limit, whose "
                    f"integrals stay bounded (Dirichlet's test); {why}"
                )
        conv, why = _compare(h, name)  # liminf/limsup bounds on the whole
        if conv is not None:
            return conv, why
    try:
        val = _bounded(lambda: sp.integrate(h, (T, 0, sp.oo)))
    except (_Timeout, Exception):  # noqa: BLE001 - sympy integrate raises many types
        val = None
    if val is not None and not val.has(sp.Integral):
        if val == sp.oo:
            return False, f"∫₀^∞ {name} dt = ∞ (sympy integrate)"
        if val.is_number and val.is_finite and val.is_real:
            approx = "" if val.is_Rational else f" ≈ {float(val):.6g}"
            return True, f"∫₀^∞ {name} dt = {val}{approx} (sympy integrate)"
    return None, f"cannot decide ∫₀^∞ {name} dt; {_numeric_integrals(h)}"


def _numeric_integrals(expr: sp.Expr) -> str:
    """A stated numerical observation (not a decision): ∫₀^T for growing T."""

    f = compile_expression(expr, (T,))
    edges = np.concatenate([[0.0], np.logspace(-2, 6, 81)])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            parts = [
                _bounded(functools.partial(_integral_piece, f, a, b), 1.0)
                for a, b in zip(edges[:-1], edges[1:], strict=True)
            ]
    except _Timeout:
        return "no numerical estimate within the time budget"
    cum = np.cumsum(parts)
    at = {int(k): cum[np.searchsorted(edges[1:], 10.0**k)] for k in (2, 4, 6)}
    return "numerically ∫₀^T ≈ " + ", ".join(f"{v:.4g} at T=1e{k}" for k, v in at.items())


# ----------------------------------------------------------------- the four conditions


def _continuity(expr: sp.Expr) -> Condition:
    if not expr.has(T):
        return Condition(True, "a constant")
    try:
        dom = _bounded(lambda: sp.calculus.util.continuous_domain(expr, T, sp.Interval(0, sp.oo)))
    except (_Timeout, Exception):  # noqa: BLE001
        return Condition(None, "cannot determine where c is continuous (sympy)")
    if dom == sp.Interval(0, sp.oo):
        return Condition(True, "continuous on [0, ∞) (sympy continuous_domain)")
    return Condition(False, f"continuous only on {dom}")


def _sign(expr: sp.Expr, text: str, continuous: bool | None) -> str:
    """Why c >= 0 on [0, ∞); raise InputError where c < 0 or c is not finite.

    A sample that overflows double precision is no error when c is proven continuous."""
    short = text if len(text) <= 60 else text[:59] + "…"
    try:  # sympy's assumptions (t >= 0) settle most gains at once; else solveset
        known = _bounded(lambda: expr.is_nonnegative, STEP_SECONDS / 2)
    except (_Timeout, Exception):  # noqa: BLE001
        known = None
    neg: Any = sp.S.EmptySet if known else None
    try:
        if neg is None:
            neg = _bounded(lambda: sp.solveset(expr < 0, T, sp.Interval(0, sp.oo)))
    except (_Timeout, Exception):  # noqa: BLE001
        neg = None
    if isinstance(neg, sp.Set) and neg is not sp.S.EmptySet:
        if not isinstance(neg, sp.ConditionSet):
            inf = neg.inf
            pt = inf if inf.is_finite else 0
            raise InputError(
                f"{short!r} is negative on {neg} (e.g. near t = {sp.N(pt, 4)}); c(t) must be >= 0",
                field="gain",
            )
    f = compile_expression(expr, (T,))
    ts = np.concatenate([[0.0], np.logspace(-6, 8, 4000)])
    vals = f(ts)
    bad = ts[~np.isfinite(vals)]
    if bad.size and continuous is not True:
        raise InputError(f"{short!r} is not finite at t = {bad[0]:.4g}", field="gain")
    bad = ts[np.isfinite(vals) & (vals < 0)]
    if bad.size:
        raise InputError(
            f"{short!r} is negative at t = {bad[0]:.4g}; c(t) must be >= 0", field="gain"
        )
    if neg is sp.S.EmptySet:
        return "c(t) >= 0 on [0, ∞) (sympy " + ("assumptions)" if known else "solveset)")
    return "c(t) >= 0 at 4001 sample points of [0, 1e8] (numerical; sympy could not decide)"


def _tends_to_zero(expr: sp.Expr) -> Condition:
    lim = limit_at_infinity(expr)
    if lim is not None and not isinstance(lim, sp.AccumBounds):
        return Condition(bool(lim == 0), f"lim_(t→∞) c(t) = {lim} (sympy)")
    if isinstance(lim, sp.AccumBounds) and _pos(lim.min):
        return Condition(False, f"liminf c(t) >= {lim.min} > 0")
    split = _split(expr)
    if split is not None and split[1]:
        smooth, parts = split
        s_lim = limit_at_infinity(smooth)
        g_lims = [limit_at_infinity(g) for g, _ in parts]
        if s_lim is not None and all(g is not None and _finite(g) for g in g_lims):
            if s_lim == 0 and all(g == 0 for g in g_lims):
                return Condition(True, "c = s + Σ g·sin/cos with s → 0 and every g → 0")
            if _finite(s_lim) and _pos(s_lim):
                return Condition(
                    False,
                    f"c = s + Σ g·sin/cos(a t + b) with s → {s_lim} > 0 and bounded g: the "
                    "mean of c over long windows stays near s, so c does not tend to 0",
                )
    return Condition(None, f"sympy gives lim c(t) = {lim}: undecided")


def _decide(expr: sp.Expr, text: str, send: Callable[[str, Any], None]) -> None:
    """Compute every condition, sending each as soon as it is known."""
    cont = _continuity(expr)
    try:
        sign = _sign(expr, text, cont.value)
    except InputError as exc:
        send("error", exc)  # pickled with its field across the worker's pipe
        return
    send("continuous_nonnegative", Condition(cont.value, f"{cont.reason}; {sign}"))
    tail = _tail_form(expr)
    conv, why = _integral(tail, "c")
    send("integral_diverges", Condition(None if conv is None else not conv, why))
    send("tends_to_zero", _tends_to_zero(tail))
    send("square_integrable", Condition(*_integral(tail**2, "c²")))


def _child(conn, expr: sp.Expr, text: str, step: float) -> None:  # pragma: no cover - fork
    warnings.simplefilter("ignore")
    _step[0] = step  # this process only
    try:
        _decide(expr, text, lambda k, v: conn.send((k, v)))
    except BaseException as exc:  # noqa: BLE001 - report, never a traceback
        conn.send(("failed", f"{type(exc).__name__}"))
    finally:
        conn.send(("done", None))
        conn.close()
        os._exit(0)


def _run(expr: sp.Expr, text: str, seconds: float) -> tuple[dict[str, Any], str]:
    """Run :func:`_decide` in a forked child killed at the deadline; (results, why missing)."""
    results: dict[str, Any] = {}
    step = max(STEP_SECONDS, seconds / 3)
    if (
        "fork" not in multiprocessing.get_all_start_methods()
        or sys.platform != "linux"
        or multiprocessing.current_process().daemon  # e.g. a Dask worker: no children
    ):
        old, _step[0] = _step[0], step
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                _decide(expr, text, results.__setitem__)
        finally:
            _step[0] = old
        return results, ""
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, expr, text, step), daemon=True)
    proc.start()
    send.close()
    deadline = time.monotonic() + seconds
    why = ""
    try:
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not recv.poll(left):
                why = f"not decided within the {seconds:g} s time limit"
                break
            try:
                key, val = recv.recv()
            except EOFError:
                why = "the symbolic analysis stopped unexpectedly"
                break
            if key == "done":
                proc.join(timeout=1.0)  # it is exiting: let it finish (and flush) first
                break
            if key == "failed":
                why = f"the symbolic analysis failed ({val})"
                continue
            results[key] = val
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()
        recv.close()
    return results, why


def analyse_gain(text: str, seconds: float = GAIN_SECONDS) -> GainAnalysis:
    """Decide the Theorem 1-4 conditions on a gain c(t) given as an expression string.

    Parameters
    ----------
    text : str
        The gain, e.g. ``"1/(1+t)"``.
    seconds : float, optional
        Hard time limit of the symbolic analysis; a condition not decided by then is
        undetermined (None) and says so.

    Returns
    -------
    GainAnalysis
        The four conditions, each True, False or None with its reason.

    Raises
    ------
    InputError
        One line when the text is not a whitelisted expression in t, or c(t) is found
        negative or non-finite on [0, ∞).
    """
    expr = parse_gain(text)
    if text in _DECIDED:
        return _DECIDED[text]
    results, why = _run(expr, text, seconds)
    if "error" in results:
        raise results["error"]
    missing = Condition(None, why or "not decided")
    got = {k: results.get(k, missing) for k in CONDITION_LABELS}
    analysis = GainAnalysis(text, expr, **got)
    if not why and all(k in results for k in CONDITION_LABELS):
        # every condition decided: the same answer on any machine, so kept for this process
        # (a notebook, a sweep or a tuning analyses one gain many times; a fork each)
        if len(_DECIDED) >= _DECIDED_MAX:
            del _DECIDED[next(iter(_DECIDED))]
        _DECIDED[text] = analysis
    return analysis


_DECIDED: dict[str, GainAnalysis] = {}  # text -> complete analysis, oldest first
_DECIDED_MAX = 256


__all__ = [
    "CONDITION_LABELS",
    "Condition",
    "GainAnalysis",
    "T",
    "analyse_gain",
    "gain_function",
    "parse_gain",
]
