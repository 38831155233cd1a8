"""Safe parsing of user expressions such as a gain ``c(t) = 1/(1+t)``.

User text is never given to ``eval``, ``sympify`` or ``parse_expr``: it is parsed by
:func:`ast.parse` (which only builds a syntax tree and runs nothing), every node is checked
against a whitelist, and the sympy expression is built from sympy constructors.

Allowed: numbers (written in decimal; a float literal is taken exactly as written, ``0.1`` is
``1/10``), the permitted variable names (``t`` by default), the constants ``pi`` and ``E``,
unary ``+``/``-``, ``+ - * /``, powers written ``**`` or ``^``, and calls of the functions in
:data:`FUNCTIONS`. Everything else (attributes, subscripts, strings, comparisons, keyword
arguments, other names such as ``factorial`` or ``__import__``) is refused with one line
naming the field.

Bounds (each refused with one line): text length :data:`MAX_CHARS`, syntax-tree size
:data:`MAX_NODES` and depth :data:`MAX_DEPTH`, integer literals of at most :data:`MAX_DIGITS`
digits, decimal exponents of at most :data:`MAX_DECIMAL_EXPONENT`, numeric exponents of at
most :data:`MAX_EXPONENT` in absolute value, and every exact number met while building the
expression of at most :data:`MAX_BITS` bits (so ``2**2**2**2**2**2`` is refused before it is
computed).

The tree, the whitelist and the bounds are read in :mod:`ntc_design.expr.tree`, which SymPy
does not load; this module is its SymPy backend (:func:`ntc_design.expr.tree.numeric_function`
is the NumPy one, for simulation).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from .tree import (
    CALLS,
    MAX_BITS,
    MAX_CHARS,
    MAX_DECIMAL_EXPONENT,
    MAX_DEPTH,
    MAX_DIGITS,
    MAX_EXPONENT,
    MAX_NODES,
    MAX_VALUE,
    TreeBuilder,
    broadcasting,
    syntax_tree,
)

_SYMPY_FUNCTIONS: dict[str, Callable[..., sp.Expr]] = {
    "exp": sp.exp,
    "log": sp.log,
    "sqrt": sp.sqrt,
    "sin": sp.sin,
    "cos": sp.cos,
    "tan": sp.tan,
    "sinh": sp.sinh,
    "cosh": sp.cosh,
    "tanh": sp.tanh,
    "atan": sp.atan,
    "Abs": sp.Abs,
    "Min": sp.Min,
    "Max": sp.Max,
}
#: Functions a user may call, by the name written, with their number of arguments
#: (the whitelist of :data:`ntc_design.expr.tree.CALLS`, as SymPy functions).
FUNCTIONS: dict[str, tuple[Callable[..., sp.Expr], int | None]] = {
    name: (_SYMPY_FUNCTIONS[canonical], arity) for name, (canonical, arity, _, _) in CALLS.items()
}
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "E": sp.E}


_SYMPY_SPELLING = (("**", "^"), ("zoo", "complex ∞"), ("oo", "∞"))


def user_text(text: str) -> str:
    """Text for users in mathematical notation, not SymPy's: ``^`` for ``**`` and ``∞``
    for ``oo`` (``-oo`` becomes ``-∞``, ``zoo`` complex infinity).

    Parameters
    ----------
    text : str
        A message that may contain printed SymPy expressions.

    Returns
    -------
    str

    Examples
    --------
    >>> user_text("lim c·t = oo > 0, c = (t + 1)**(-1/3)")
    'lim c·t = ∞ > 0, c = (t + 1)^(-1/3)'
    """
    import re

    text = text.replace("**", "^")
    text = re.sub(r"\bzoo\b", "complex ∞", text)
    return re.sub(r"\boo\b", "∞", text)


def show(expr: sp.Basic) -> str:
    """An expression as users read it (:func:`user_text` of SymPy's string).

    Parameters
    ----------
    expr : sympy.Basic
        The expression.

    Returns
    -------
    str

    Examples
    --------
    >>> show(parse_expression("(1+t)^(-1/3)", "gain"))
    '(t + 1)^(-1/3)'
    """
    return user_text(sp.sstr(expr))


def symbol(name: str) -> sp.Symbol:
    """The sympy symbol used for a variable: ``t`` is time (real, ``t >= 0``), others real.

    Parameters
    ----------
    name : str
        Variable name.

    Returns
    -------
    sympy.Symbol
        The same symbol for the same name, so expressions parsed separately combine.
    """
    if name == "t":
        return sp.Symbol("t", real=True, nonnegative=True)
    return sp.Symbol(name, real=True)


class _Builder(TreeBuilder):
    """The SymPy backend of :class:`ntc_design.expr.tree.TreeBuilder`: the expression is
    built from SymPy's constructors, and a power whose exponent SymPy combines
    (``(t**1000)**1000``) is bounded again."""

    def exact(self, value: Any) -> Fraction | None:
        return Fraction(int(value.p), int(value.q)) if isinstance(value, sp.Rational) else None

    def variable(self, name: str) -> sp.Expr:
        return self.names[name]

    def constant(self, name: str) -> sp.Expr:
        return CONSTANTS[name]

    def rational(self, p: int, q: int) -> sp.Expr:
        return sp.Integer(p) if q == 1 else sp.Rational(p, q)

    def neg(self, x: sp.Expr) -> sp.Expr:
        return -x

    def binary(self, op: str, a: sp.Expr, b: sp.Expr) -> sp.Expr:
        if op == "+":
            return sp.Add(a, b)
        if op == "-":
            return sp.Add(a, -b)
        if op == "*":
            return sp.Mul(a, b)
        return sp.Mul(a, sp.Pow(b, -1))

    def power(self, base: sp.Expr, exp: sp.Expr) -> sp.Expr:
        value = sp.Pow(base, exp)
        if isinstance(value, sp.Pow) and isinstance(value.exp, sp.Rational):
            if abs(value.exp) > MAX_EXPONENT:  # (t**1000)**1000 is combined by sympy
                raise self.fail(f"an exponent larger than {MAX_EXPONENT} in absolute value")
        return value

    def apply(self, name: str, args: list[sp.Expr]) -> sp.Expr:
        return _SYMPY_FUNCTIONS[name](*args)


def parse_expression(
    text: str,
    field: str,
    variables: Sequence[str] | Mapping[str, sp.Symbol] = ("t",),
) -> sp.Expr:
    """Parse a user expression safely into a sympy expression (nothing is executed).

    Parameters
    ----------
    text : str
        The expression, e.g. ``"1/(1+t)"`` or ``"(1+t)^(-1/3)"``; ``^`` means a power.
    field : str
        Where the text came from (``"gain"``, ``"scenario.yaml: weights.a12"``); it starts
        every error message.
    variables : sequence of str or mapping of str to sympy.Symbol, optional
        Names that may appear as variables (default only ``t``). With names, the symbols
        come from :func:`symbol`; a mapping gives the symbols to use.

    Returns
    -------
    sympy.Expr
        A finite real-looking expression (no ``zoo``, ``nan``, ``oo`` or ``I``) in the
        allowed variables.

    Raises
    ------
    InputError
        One line naming ``field`` when the text is not a string, is empty or too long, does
        not parse, uses anything outside the whitelist, or exceeds a size bound.
    """
    names = (
        dict(variables)
        if isinstance(variables, Mapping)
        else {str(v): symbol(str(v)) for v in variables}
    )
    src, tree = syntax_tree(text, field)
    builder = _Builder(src, field, names)
    expr, _ = builder.build_tree(tree)
    if not isinstance(expr, sp.Expr):
        raise builder.fail("not an expression")
    if expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise builder.fail("an infinite or undefined value")
    if expr.has(sp.I):
        raise builder.fail("a non-real value")
    return expr


def _numpy_ready(expr: sp.Expr) -> sp.Expr:
    """Replace exact numbers NumPy cannot hold by floats, and Min/Max by elementwise ones."""
    big = {
        r: sp.Float(r, 17)
        for r in expr.atoms(sp.Rational)
        if abs(int(r.p)) >= 2**53 or int(r.q) >= 2**53
    }
    expr = expr.xreplace(big) if big else expr
    expr = expr.replace(sp.Min, lambda *a: functools.reduce(lambda x, y: _NP_MIN(x, y), a)).replace(
        sp.Max, lambda *a: functools.reduce(lambda x, y: _NP_MAX(x, y), a)
    )
    return expr


_NP_MIN = sp.Function("ntc_minimum")
_NP_MAX = sp.Function("ntc_maximum")


def compile_expression(
    expr: sp.Expr, variables: Sequence[str | sp.Symbol] = ("t",)
) -> Callable[..., np.ndarray]:
    """Turn a parsed expression into a vectorised NumPy function.

    Parameters
    ----------
    expr : sympy.Expr
        An expression built by :func:`parse_expression` (never user text).
    variables : sequence of str or sympy.Symbol, optional
        The positional arguments of the function, in order (names map through
        :func:`symbol`).

    Returns
    -------
    callable
        ``f(*arrays) -> numpy.ndarray`` of float64 with the broadcast shape of the
        arguments (a constant expression broadcasts too). Floating-point warnings are
        silenced: non-finite values come back as ``inf``/``nan`` for the caller to refuse.
    """
    syms = [v if isinstance(v, sp.Symbol) else symbol(str(v)) for v in variables]
    namespace = {"ntc_minimum": np.minimum, "ntc_maximum": np.maximum}
    fn = sp.lambdify(syms, _numpy_ready(expr), modules=[namespace, "numpy"])

    return broadcasting(lambda arrays: fn(*arrays), str(expr))


__all__ = [
    "FUNCTIONS",
    "MAX_BITS",
    "MAX_CHARS",
    "MAX_DECIMAL_EXPONENT",
    "MAX_DEPTH",
    "MAX_DIGITS",
    "MAX_EXPONENT",
    "MAX_NODES",
    "MAX_VALUE",
    "compile_expression",
    "parse_expression",
    "show",
    "symbol",
    "user_text",
]
