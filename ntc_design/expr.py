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
"""

from __future__ import annotations

import ast
import decimal
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from .errors import InputError

MAX_CHARS = 1000  # length of the text
MAX_NODES = 400  # nodes of the syntax tree
MAX_DEPTH = 60  # nesting of the syntax tree
MAX_DIGITS = 60  # digits of an integer literal
MAX_DECIMAL_EXPONENT = 400  # |e| in a literal such as 1e-300
MAX_EXPONENT = 1000  # |p| of a numeric exponent in a ** p
MAX_BITS = 20_000  # size of any exact number built (numerator and denominator)
MAX_VALUE = 1e300  # size of any constant subexpression (estimated in floats)

#: Functions a user may call, by the name written, with their number of arguments.
FUNCTIONS: dict[str, tuple[Callable[..., sp.Expr], int | None]] = {
    "exp": (sp.exp, 1),
    "log": (sp.log, 1),
    "ln": (sp.log, 1),
    "sqrt": (sp.sqrt, 1),
    "sin": (sp.sin, 1),
    "cos": (sp.cos, 1),
    "tan": (sp.tan, 1),
    "sinh": (sp.sinh, 1),
    "cosh": (sp.cosh, 1),
    "tanh": (sp.tanh, 1),
    "atan": (sp.atan, 1),
    "abs": (sp.Abs, 1),
    "Abs": (sp.Abs, 1),
    "min": (sp.Min, None),  # two or more arguments
    "Min": (sp.Min, None),
    "max": (sp.Max, None),
    "Max": (sp.Max, None),
}
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "E": sp.E}

_BINARY = {
    ast.Add: "+",
    ast.Sub: "-",
    ast.Mult: "*",
    ast.Div: "/",
    ast.Pow: "**",
}


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


def _short(text: str, n: int = 60) -> str:
    """The text quoted for a message: one line, at most ``n`` characters."""
    s = text if len(text) <= n else text[: n - 1] + "…"
    return repr(s)


_MATH: dict[Any, Callable[..., float]] = {
    sp.exp: math.exp,
    sp.log: math.log,
    sp.sqrt: math.sqrt,
    sp.sin: math.sin,
    sp.cos: math.cos,
    sp.tan: math.tan,
    sp.sinh: math.sinh,
    sp.cosh: math.cosh,
    sp.tanh: math.tanh,
    sp.atan: math.atan,
    sp.Abs: abs,
    sp.Min: min,
    sp.Max: max,
}
_CONSTANT_VALUES = {"pi": math.pi, "E": math.e}


class _Builder:
    """Builds the sympy expression bottom-up, keeping a float estimate of every constant
    subexpression so that sympy is never asked to evaluate a huge number (``sin`` of
    ``pi**(10**6)`` would need a million digits)."""

    def __init__(self, text: str, field: str, names: Mapping[str, sp.Symbol]):
        self.text = text
        self.field = field
        self.names = names

    def fail(self, what: str) -> InputError:
        return InputError(f"{self.field}: {what} in expression {_short(self.text)}")

    def checked(self, value: sp.Expr, approx: float | None) -> tuple[sp.Expr, float | None]:
        if isinstance(value, sp.Rational):
            bits = max(int(value.p).bit_length(), int(value.q).bit_length())
            if bits > MAX_BITS:
                raise self.fail(f"a number with more than {MAX_BITS} bits")
        if approx is not None and not (
            isinstance(approx, float) and math.isfinite(approx) and abs(approx) <= MAX_VALUE
        ):
            raise self.fail(f"a constant that is not a real number of size at most {MAX_VALUE:g}")
        return value, approx

    def approx(self, fn: Callable[..., float], *xs: float | None) -> float | None:
        if any(x is None for x in xs):
            return None
        try:
            v = fn(*xs)
        except (ArithmeticError, ValueError):  # overflow, log(0), sqrt(-1), 1/0
            raise self.fail(
                "a constant out of range (overflow, division by zero or a non-real value)"
            ) from None
        return float(v) if isinstance(v, (int, float)) else v  # complex is refused later

    def build(self, node: ast.AST) -> tuple[sp.Expr, float | None]:
        if isinstance(node, ast.Expression):
            return self.build(node.body)
        if isinstance(node, ast.Constant):
            return self.number(node)
        if isinstance(node, ast.Name):
            if node.id in self.names:
                return self.names[node.id], None
            if node.id in CONSTANTS:
                return CONSTANTS[node.id], _CONSTANT_VALUES[node.id]
            if node.id in FUNCTIONS:
                raise self.fail(f"function {node.id!r} used without arguments")
            names = sorted(self.names)
            allowed = (
                "no variables are allowed"
                if not names
                else f"only the variable {names[0]} is allowed"
                if len(names) == 1
                else f"only the variables {', '.join(names)} are allowed"
            )
            raise self.fail(f"uses {node.id}; {allowed}")
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, (ast.USub, ast.UAdd)):
                x, ax = self.build(node.operand)
                if isinstance(node.op, ast.UAdd):
                    return x, ax
                return self.checked(-x, None if ax is None else -ax)
            raise self.fail(f"operator {type(node.op).__name__!r} not allowed")
        if isinstance(node, ast.BinOp):
            op = _BINARY.get(type(node.op))
            if op is None:
                raise self.fail(f"operator {type(node.op).__name__!r} not allowed")
            (a, aa), (b, ab) = self.build(node.left), self.build(node.right)
            if op == "**":
                return self.power(a, aa, b, ab)
            if op == "/" and (b == 0 or ab == 0):
                raise self.fail("division by zero")
            if op == "+":
                return self.checked(sp.Add(a, b), self.approx(lambda x, y: x + y, aa, ab))
            if op == "-":
                return self.checked(sp.Add(a, -b), self.approx(lambda x, y: x - y, aa, ab))
            if op == "*":
                return self.checked(sp.Mul(a, b), self.approx(lambda x, y: x * y, aa, ab))
            return self.checked(sp.Mul(a, sp.Pow(b, -1)), self.approx(lambda x, y: x / y, aa, ab))
        if isinstance(node, ast.Call):
            return self.call(node)
        raise self.fail(f"{type(node).__name__} not allowed")

    def number(self, node: ast.Constant) -> tuple[sp.Expr, float | None]:
        v = node.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.fail(f"constant {_short(repr(v), 30)} not allowed")
        seg = (ast.get_source_segment(self.text, node) or repr(v)).replace("_", "")
        if isinstance(v, int):
            if v.bit_length() > MAX_DIGITS * 4:
                raise self.fail(f"an integer literal with more than {MAX_DIGITS} digits")
            if len(str(v)) > MAX_DIGITS:
                raise self.fail(f"an integer literal with more than {MAX_DIGITS} digits")
            return self.checked(sp.Integer(v), self.approx(float, v))
        try:  # the literal exactly as written: 0.1 is 1/10, not the nearest binary float
            d = decimal.Decimal(seg)
        except decimal.InvalidOperation:
            raise self.fail(f"number {_short(seg, 30)} not understood") from None
        if not d.is_finite():
            raise self.fail(f"number {_short(seg, 30)} is not finite")
        if abs(d.adjusted()) > MAX_DECIMAL_EXPONENT or len(d.as_tuple().digits) > MAX_DIGITS:
            raise self.fail(f"number {_short(seg, 30)} is too large, too small or too long")
        p, q = d.as_integer_ratio()
        return self.checked(sp.Rational(p, q), float(v))

    def power(self, base, ab, exp, ae) -> tuple[sp.Expr, float | None]:
        if ae is not None:
            if abs(ae) > MAX_EXPONENT:
                raise self.fail(f"an exponent larger than {MAX_EXPONENT} in absolute value")
            if isinstance(exp, sp.Rational) and isinstance(base, sp.Rational):
                # an exact power is computed by sympy: bound its size first
                bits = max(int(base.p).bit_length(), int(base.q).bit_length())
                if bits * abs(int(exp.p)) > MAX_BITS * max(1, int(exp.q)):
                    raise self.fail(f"a power whose value has more than {MAX_BITS} bits")
        approx = self.approx(lambda x, y: x**y, ab, ae)
        if isinstance(approx, complex):
            raise self.fail("a non-real power")
        value = sp.Pow(base, exp)
        if isinstance(value, sp.Pow) and isinstance(value.exp, sp.Rational):
            if abs(value.exp) > MAX_EXPONENT:  # (t**1000)**1000 is combined by sympy
                raise self.fail(f"an exponent larger than {MAX_EXPONENT} in absolute value")
        return self.checked(value, approx)

    def call(self, node: ast.Call) -> tuple[sp.Expr, float | None]:
        if not isinstance(node.func, ast.Name):
            raise self.fail("only calls of named functions are allowed")
        name = node.func.id
        if name not in FUNCTIONS:
            known = ", ".join(sorted({k for k in FUNCTIONS if k.islower()}))
            raise self.fail(f"function {name!r} not allowed (allowed: {known})")
        if node.keywords:
            raise self.fail(f"keyword arguments to {name!r}")
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.fail(f"starred arguments to {name!r}")
        fn, arity = FUNCTIONS[name]
        n = len(node.args)
        if (arity is None and n < 2) or (arity is not None and n != arity):
            want = "two or more arguments" if arity is None else f"{arity} argument"
            raise self.fail(f"{name!r} takes {want}, got {n}")
        built = [self.build(a) for a in node.args]
        args = [b[0] for b in built]
        approx = self.approx(_MATH[fn], *(b[1] for b in built))
        return self.checked(fn(*args), approx)


def _shape_of_tree(tree: ast.AST) -> tuple[int, int]:
    """(node count, depth) of a syntax tree, iteratively; stops early past the bounds."""
    count, depth = 0, 0
    stack = [(tree, 1)]
    while stack:
        node, d = stack.pop()
        count += 1
        depth = max(depth, d)
        if count > MAX_NODES or depth > MAX_DEPTH:
            break
        stack.extend((c, d + 1) for c in ast.iter_child_nodes(node))
    return count, depth


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
    if not isinstance(text, str):
        raise InputError(f"{field}: expected an expression as a string, got {type(text).__name__}")
    if not text.strip():
        raise InputError(f"{field}: empty expression")
    if len(text) > MAX_CHARS:
        raise InputError(f"{field}: expression longer than {MAX_CHARS} characters")
    if not text.isprintable():
        raise InputError(f"{field}: expression contains control characters or newlines")
    src = text.strip().replace("^", "**")
    try:
        tree = ast.parse(src, mode="eval")
    except (SyntaxError, ValueError, MemoryError, RecursionError):
        raise InputError(f"{field}: cannot parse expression {_short(text)}") from None
    count, depth = _shape_of_tree(tree)
    if count > MAX_NODES or depth > MAX_DEPTH:
        raise InputError(
            f"{field}: expression too complex (at most {MAX_NODES} syntax nodes and "
            f"nesting {MAX_DEPTH})"
        )
    builder = _Builder(src, field, names)
    try:
        expr, _ = builder.build(tree)
    except InputError:
        raise
    except (ArithmeticError, ValueError, TypeError, RecursionError, MemoryError):
        raise builder.fail("cannot build") from None
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

    def evaluate(*args):
        arrays = [np.asarray(a, dtype=float) for a in args]
        shape = np.broadcast_shapes(*(a.shape for a in arrays)) if arrays else ()
        with np.errstate(all="ignore"):
            out = np.asarray(fn(*arrays), dtype=float)
        return np.broadcast_to(out, shape).copy() if out.shape != shape else out

    evaluate.__doc__ = f"NumPy evaluation of {expr}"
    return evaluate


__all__ = ["FUNCTIONS", "compile_expression", "parse_expression", "show", "symbol", "user_text"]
