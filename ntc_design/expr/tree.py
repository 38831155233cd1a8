"""The safe reading of a user expression's syntax tree, without SymPy: the text checks, the
whitelist, the size bounds and the walk that builds a value bottom-up, shared by two
backends: :mod:`ntc_design.expr.symbolic` (SymPy expressions, for analysis and proofs) and the
numeric one here, :func:`numeric_function` (NumPy, for simulation, where importing SymPy
would cost a third of a second of start-up and an analysis is not needed).

The text is parsed by :func:`ast.parse` (which builds a tree and runs nothing); every node is
checked against the whitelist; each backend builds its value from its own constructors.
Constants are folded exactly (integers and fractions, as SymPy does) with a float estimate
beside them, so that a huge number is refused before it is computed. What the two backends
accept differs only where SymPy simplifies symbolically (``(t**1000)**1000`` is refused by
SymPy's bound on a combined exponent, ``1/(t - t)`` by its ``zoo``); the numeric function
returns non-finite values there, which the simulation refuses at its first sample.
"""

from __future__ import annotations

import ast
import decimal
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from ..errors import InputError

MAX_CHARS = 1000  # length of the text
MAX_NODES = 400  # nodes of the syntax tree
MAX_DEPTH = 60  # nesting of the syntax tree
MAX_DIGITS = 60  # digits of an integer literal
MAX_DECIMAL_EXPONENT = 400  # |e| in a literal such as 1e-300
MAX_EXPONENT = 1000  # |p| of a numeric exponent in a ** p
MAX_BITS = 20_000  # size of any exact number built (numerator and denominator)
MAX_VALUE = 1e300  # size of any constant subexpression (estimated in floats)

#: The functions a user may call: the name written, its canonical name, its number of
#: arguments (None: two or more), and its float and NumPy versions.
CALLS: dict[str, tuple[str, int | None, Callable[..., float], Callable[..., Any]]] = {
    "exp": ("exp", 1, math.exp, np.exp),
    "log": ("log", 1, math.log, np.log),
    "ln": ("log", 1, math.log, np.log),
    "sqrt": ("sqrt", 1, math.sqrt, np.sqrt),
    "sin": ("sin", 1, math.sin, np.sin),
    "cos": ("cos", 1, math.cos, np.cos),
    "tan": ("tan", 1, math.tan, np.tan),
    "sinh": ("sinh", 1, math.sinh, np.sinh),
    "cosh": ("cosh", 1, math.cosh, np.cosh),
    "tanh": ("tanh", 1, math.tanh, np.tanh),
    "atan": ("atan", 1, math.atan, np.arctan),
    "abs": ("Abs", 1, abs, np.abs),
    "Abs": ("Abs", 1, abs, np.abs),
    "min": ("Min", None, min, np.minimum),
    "Min": ("Min", None, min, np.minimum),
    "max": ("Max", None, max, np.maximum),
    "Max": ("Max", None, max, np.maximum),
}
#: The named constants and their values.
CONSTANT_VALUES = {"pi": math.pi, "E": math.e}

_BINARY = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}


def short(text: str, n: int = 60) -> str:
    """The text quoted for a message: one line, at most ``n`` characters.

    Parameters
    ----------
    text : str
        The text.
    n : int, optional
        Most characters shown.

    Returns
    -------
    str
    """
    s = text if len(text) <= n else text[: n - 1] + "…"
    return repr(s)


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


def syntax_tree(text: object, field: str) -> tuple[str, ast.Expression]:
    """The checked syntax tree of a user expression (nothing is evaluated).

    Parameters
    ----------
    text : object
        The expression; ``^`` means a power.
    field : str
        Where the text came from; it starts every error message.

    Returns
    -------
    (str, ast.Expression)
        The source as parsed (``^`` written ``**``) and its tree, within the size bounds.

    Raises
    ------
    InputError
        One line naming ``field``: not a string, empty, too long, control characters,
        does not parse, or too many nodes or too deep.
    """
    if not isinstance(text, str):
        raise InputError(
            f"expected an expression as a string, got {type(text).__name__}", field=field
        )
    if not text.strip():
        raise InputError("empty expression", field=field)
    if len(text) > MAX_CHARS:
        raise InputError(f"expression longer than {MAX_CHARS} characters", field=field)
    if not text.isprintable():
        raise InputError("expression contains control characters or newlines", field=field)
    src = text.strip().replace("^", "**")
    try:
        tree = ast.parse(src, mode="eval")
    except (SyntaxError, ValueError, MemoryError, RecursionError):
        raise InputError(f"cannot parse expression {short(text)}", field=field) from None
    count, depth = _shape_of_tree(tree)
    if count > MAX_NODES or depth > MAX_DEPTH:
        raise InputError(
            f"expression too complex (at most {MAX_NODES} syntax nodes and nesting {MAX_DEPTH})",
            field=field,
        )
    return src, tree


class TreeBuilder:
    """The walk over a checked tree: every whitelist and size rule, with the values built
    by a backend's methods (:meth:`variable`, :meth:`constant`, :meth:`rational`,
    :meth:`neg`, :meth:`binary`, :meth:`power`, :meth:`apply`, :meth:`exact`). Each
    value travels with a float estimate when it is a constant (else None)."""

    def __init__(self, text: str, field: str, names: Mapping[str, Any]):
        self.text = text
        self.field = field
        self.names = names

    # -- the backend ------------------------------------------------------------------
    def variable(self, name: str) -> Any:
        raise NotImplementedError

    def constant(self, name: str) -> Any:
        raise NotImplementedError

    def rational(self, p: int, q: int) -> Any:
        raise NotImplementedError

    def neg(self, x: Any) -> Any:
        raise NotImplementedError

    def binary(self, op: str, a: Any, b: Any) -> Any:
        raise NotImplementedError

    def power(self, base: Any, exp: Any) -> Any:
        raise NotImplementedError

    def apply(self, name: str, args: list[Any]) -> Any:
        raise NotImplementedError

    def exact(self, value: Any) -> Fraction | None:
        """The value as an exact fraction when the backend holds it as one."""
        raise NotImplementedError

    # -- the rules ----------------------------------------------------------------------
    def fail(self, what: str) -> InputError:
        return InputError(f"{what} in expression {short(self.text)}", field=self.field)

    def checked(self, value: Any, approx: float | None) -> tuple[Any, float | None]:
        ex = self.exact(value)
        if ex is not None:
            bits = max(ex.numerator.bit_length(), ex.denominator.bit_length())
            if bits > MAX_BITS:
                raise self.fail(f"a number with more than {MAX_BITS} bits")
        if approx is not None and not (
            isinstance(approx, float) and math.isfinite(approx) and abs(approx) <= MAX_VALUE
        ):
            raise self.fail(f"a constant that is not a real number of size at most {MAX_VALUE:g}")
        return value, approx

    def approx(self, fn: Callable[..., Any], *xs: float | None) -> float | None:
        if any(x is None for x in xs):
            return None
        try:
            v = fn(*xs)
        except (ArithmeticError, ValueError):  # overflow, log(0), sqrt(-1), 1/0
            raise self.fail(
                "a constant out of range (overflow, division by zero or a non-real value)"
            ) from None
        return float(v) if isinstance(v, (int, float)) else v  # complex is refused later

    def build_tree(self, tree: ast.Expression) -> tuple[Any, float | None]:
        """The value of a checked tree (:func:`syntax_tree`), any failure as one line."""
        try:
            return self.build(tree)
        except InputError:
            raise
        except (ArithmeticError, ValueError, TypeError, RecursionError, MemoryError):
            raise self.fail("cannot build") from None

    def build(self, node: ast.AST) -> tuple[Any, float | None]:
        if isinstance(node, ast.Expression):
            return self.build(node.body)
        if isinstance(node, ast.Constant):
            return self.number(node)
        if isinstance(node, ast.Name):
            if node.id in self.names:
                return self.variable(node.id), None
            if node.id in CONSTANT_VALUES:
                return self.constant(node.id), CONSTANT_VALUES[node.id]
            if node.id in CALLS:
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
                return self.checked(self.neg(x), None if ax is None else -ax)
            raise self.fail(f"operator {type(node.op).__name__!r} not allowed")
        if isinstance(node, ast.BinOp):
            op = _BINARY.get(type(node.op))
            if op is None:
                raise self.fail(f"operator {type(node.op).__name__!r} not allowed")
            (a, aa), (b, ab) = self.build(node.left), self.build(node.right)
            if op == "**":
                return self.raise_to(a, aa, b, ab)
            if op == "/" and (self.exact(b) == 0 or ab == 0):
                raise self.fail("division by zero")
            fn = _FLOAT_OPS[op]
            return self.checked(self.binary(op, a, b), self.approx(fn, aa, ab))
        if isinstance(node, ast.Call):
            return self.call(node)
        raise self.fail(f"{type(node).__name__} not allowed")

    def number(self, node: ast.Constant) -> tuple[Any, float | None]:
        v = node.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.fail(f"constant {short(repr(v), 30)} not allowed")
        seg = (ast.get_source_segment(self.text, node) or repr(v)).replace("_", "")
        if isinstance(v, int):
            if v.bit_length() > MAX_DIGITS * 4:
                raise self.fail(f"an integer literal with more than {MAX_DIGITS} digits")
            if len(str(v)) > MAX_DIGITS:
                raise self.fail(f"an integer literal with more than {MAX_DIGITS} digits")
            return self.checked(self.rational(v, 1), self.approx(float, v))
        try:  # the literal exactly as written: 0.1 is 1/10, not the nearest binary float
            d = decimal.Decimal(seg)
        except decimal.InvalidOperation:
            raise self.fail(f"number {short(seg, 30)} not understood") from None
        if not d.is_finite():
            raise self.fail(f"number {short(seg, 30)} is not finite")
        if abs(d.adjusted()) > MAX_DECIMAL_EXPONENT or len(d.as_tuple().digits) > MAX_DIGITS:
            raise self.fail(f"number {short(seg, 30)} is too large, too small or too long")
        p, q = d.as_integer_ratio()
        return self.checked(self.rational(p, q), float(v))

    def raise_to(self, base, ab, exp, ae) -> tuple[Any, float | None]:
        if ae is not None:
            if abs(ae) > MAX_EXPONENT:
                raise self.fail(f"an exponent larger than {MAX_EXPONENT} in absolute value")
            eb, ee = self.exact(base), self.exact(exp)
            if eb is not None and ee is not None:
                # an exact power is computed: bound its size first
                bits = max(eb.numerator.bit_length(), eb.denominator.bit_length())
                if bits * abs(ee.numerator) > MAX_BITS * max(1, ee.denominator):
                    raise self.fail(f"a power whose value has more than {MAX_BITS} bits")
        approx = self.approx(lambda x, y: x**y, ab, ae)
        if isinstance(approx, complex):
            raise self.fail("a non-real power")
        return self.checked(self.power(base, exp), approx)

    def call(self, node: ast.Call) -> tuple[Any, float | None]:
        if not isinstance(node.func, ast.Name):
            raise self.fail("only calls of named functions are allowed")
        name = node.func.id
        if name not in CALLS:
            known = ", ".join(sorted({k for k in CALLS if k.islower()}))
            raise self.fail(f"function {name!r} not allowed (allowed: {known})")
        if node.keywords:
            raise self.fail(f"keyword arguments to {name!r}")
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.fail(f"starred arguments to {name!r}")
        canonical, arity, as_float, _ = CALLS[name]
        n = len(node.args)
        if (arity is None and n < 2) or (arity is not None and n != arity):
            want = "two or more arguments" if arity is None else f"{arity} argument"
            raise self.fail(f"{name!r} takes {want}, got {n}")
        built = [self.build(a) for a in node.args]
        approx = self.approx(as_float, *(b[1] for b in built))
        return self.checked(self.apply(canonical, [b[0] for b in built]), approx)


_FLOAT_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "+": lambda x, y: x + y,
    "-": lambda x, y: x - y,
    "*": lambda x, y: x * y,
    "/": lambda x, y: x / y,
}

_NUMPY_CALLS = {canonical: fn for canonical, _, _, fn in CALLS.values()}
_NUMPY_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "+": np.add,
    "-": np.subtract,
    "*": np.multiply,
    "/": np.true_divide,
}

# A numeric value: an exact fraction (a constant folded as SymPy folds it) or a function
# of the variables' arrays.
_Fn = Callable[[Sequence[np.ndarray]], Any]


class _Power:
    """base(xs) ** exponent, keeping an exact exponent for the nested-power bound."""

    def __init__(self, base: _Fn, exponent: Any):
        self.base = base
        self.exponent = exponent if isinstance(exponent, Fraction) else None
        self._exp = _NumericBuilder._fn(exponent)

    def __call__(self, xs: Sequence[np.ndarray]) -> Any:
        return np.power(self.base(xs), self._exp(xs))


class _NumericBuilder(TreeBuilder):
    """The NumPy backend: constants folded exactly (Fraction), the rest composed into one
    function of the variables' arrays."""

    def __init__(self, text: str, field: str, names: Sequence[str]):
        super().__init__(text, field, {n: k for k, n in enumerate(names)})

    @staticmethod
    def _fn(v: Fraction | float | _Fn) -> _Fn:
        if callable(v):
            return v
        c = float(v)
        return lambda xs: c

    def exact(self, value: Any) -> Fraction | None:
        return value if isinstance(value, Fraction) else None

    def variable(self, name: str) -> _Fn:
        k = self.names[name]
        return lambda xs: xs[k]

    def constant(self, name: str) -> float:
        return CONSTANT_VALUES[name]

    def rational(self, p: int, q: int) -> Fraction:
        return Fraction(p, q)

    def neg(self, x: Any) -> Any:
        if isinstance(x, (Fraction, float)):
            return -x
        return lambda xs: np.negative(x(xs))

    def binary(self, op: str, a: Any, b: Any) -> Any:
        if isinstance(a, Fraction) and isinstance(b, Fraction):
            return _FLOAT_OPS[op](a, b)
        fa, fb, f = self._fn(a), self._fn(b), _NUMPY_OPS[op]
        return lambda xs: f(fa(xs), fb(xs))

    def power(self, base: Any, exp: Any) -> Any:
        if isinstance(base, Fraction) and isinstance(exp, Fraction) and exp.denominator == 1:
            return base**exp.numerator  # bounded by raise_to before
        if isinstance(base, _Power) and base.exponent is not None and isinstance(exp, Fraction):
            # SymPy writes (t**a)**b as t**(a·b): the same bound on the combined exponent
            if abs(base.exponent * exp) > MAX_EXPONENT:
                raise self.fail(f"an exponent larger than {MAX_EXPONENT} in absolute value")
        return _Power(self._fn(base), exp)

    def apply(self, name: str, args: list[Any]) -> Any:
        f = _NUMPY_CALLS[name]
        fs = [self._fn(a) for a in args]
        if len(fs) == 1:
            (f0,) = fs
            return lambda xs: f(f0(xs))

        def reduce(xs):
            out = fs[0](xs)
            for g in fs[1:]:
                out = f(out, g(xs))
            return out

        return reduce


def numeric_function(
    text: object, field: str, variables: Sequence[str] = ("t",)
) -> Callable[..., np.ndarray]:
    """A user expression as a vectorised NumPy function, read without SymPy (the same
    whitelist and bounds as :func:`ntc_design.expr.symbolic.parse_expression`).

    Parameters
    ----------
    text : object
        The expression, e.g. ``"1/(1+t)"``; ``^`` means a power.
    field : str
        Where the text came from; it starts every error message.
    variables : sequence of str, optional
        The names allowed as variables, in the order the function takes them.

    Returns
    -------
    callable
        ``f(*arrays) -> numpy.ndarray`` of float64 with the arguments' broadcast shape;
        floating-point warnings are silenced and non-finite values come back as
        ``inf``/``nan`` for the caller to refuse.

    Raises
    ------
    InputError
        One line naming ``field`` when the text is not a whitelisted expression within the
        bounds, or a constant in it is out of range.

    Examples
    --------
    >>> f = numeric_function("1/(1+t)^2", "gain")
    >>> f([0.0, 1.0]).tolist()
    [1.0, 0.25]
    """
    if not isinstance(text, str):  # refused in one line by the parser, never cached
        return _numeric_function(text, field, tuple(variables))
    return _cached_function(text, field, tuple(variables))


@functools.lru_cache(maxsize=256)
def _cached_function(
    text: str, field: str, variables: tuple[str, ...]
) -> Callable[..., np.ndarray]:
    # a run reads its gain once: the scenario's check, the simulator and the reports share
    # the function (pure: the same text gives the same values)
    return _numeric_function(text, field, variables)


def _numeric_function(
    text: object, field: str, variables: tuple[str, ...]
) -> Callable[..., np.ndarray]:
    src, tree = syntax_tree(text, field)
    builder = _NumericBuilder(src, field, list(variables))
    value, approx = builder.build_tree(tree)
    if isinstance(approx, complex):
        raise builder.fail("a non-real value")
    return broadcasting(builder._fn(value), src)


def broadcasting(fn: Callable[[list], Any], what: str) -> Callable[..., np.ndarray]:
    """``fn`` (list of arrays in) as ``f(*arrays)``: float64 out with the arguments'
    broadcast shape (a constant broadcasts too), floating-point warnings silenced.

    Parameters
    ----------
    fn : callable
        Takes the list of float arrays.
    what : str
        The expression, for the docstring.

    Returns
    -------
    callable
    """

    def evaluate(*args):
        arrays = [np.asarray(a, dtype=float) for a in args]
        shape = np.broadcast_shapes(*(a.shape for a in arrays)) if arrays else ()
        with np.errstate(all="ignore"):
            out = np.asarray(fn(arrays), dtype=float)
        return np.broadcast_to(out, shape).copy() if out.shape != shape else out

    evaluate.__doc__ = f"NumPy evaluation of {what}"
    return evaluate


__all__ = [
    "CALLS",
    "CONSTANT_VALUES",
    "MAX_BITS",
    "MAX_CHARS",
    "MAX_DECIMAL_EXPONENT",
    "MAX_DEPTH",
    "MAX_DIGITS",
    "MAX_EXPONENT",
    "MAX_NODES",
    "MAX_VALUE",
    "broadcasting",
    "numeric_function",
    "short",
    "syntax_tree",
]
