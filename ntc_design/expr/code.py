"""A user expression as straight-line code: the backend of :mod:`ntc_design.expr.tree` that
the exported agents (:mod:`ntc_design.export`) and the toolkit's replay of them
(:mod:`ntc_design.simulate.replay`) share, so that C, a Python module and the toolkit
compute c(t) with the same operations in the same order, bit for bit.

The checked syntax tree (the same whitelist and bounds as
:func:`~ntc_design.expr.tree.numeric_function`, which validates the text first) becomes a
:class:`ScalarProgram`: a list of instructions, each one operation on earlier results, the
variables or constants (``v2 = v0 * v1``). Constants are folded at build time (exactly
for rationals, as the other backends do; in floating point through Python's ``math``,
i.e. the C library, for functions of constants), integer powers up to
:data:`MAX_UNROLL` become explicit products (``x**2`` is ``x*x``, ``x**-2`` is
``1.0/(x*x)``), ``x**0.5`` is ``sqrt(x)`` and every other power ``pow(x, y)``. The
functions are C99's ``math.h`` ones (``exp``, ``log``, ``sqrt``, ``sin``, ``cos``, ``tan``,
``sinh``, ``cosh``, ``tanh``, ``atan``, ``fabs``, ``pow``; ``fmin`` and ``fmax`` as two
small functions of their own, :data:`C_HELPERS`, whose ties are defined); Python calls the
same C library through :mod:`math`. Where Python's ``math`` raises and C returns a
value (overflow, a domain error, a division by zero) the Python forms return C's value
(:data:`PYTHON_HELPERS`), so the three agree there too. Nothing is ever evaluated from
the user's text: the code is generated from the checked tree.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from .tree import CONSTANT_VALUES, TreeBuilder, numeric_function, syntax_tree

#: Integer powers up to this |n| are written as products; above it, ``pow``.
MAX_UNROLL = 16


def literal(x: float) -> str:
    """A double as a literal that C99 and Python both read back to the same bits:
    ``%.17g``, with ``.0`` added when that reads as an integer, in parentheses when negative.

    Parameters
    ----------
    x : float
        A finite number.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        ``x`` is not finite.

    Examples
    --------
    >>> literal(1.0), literal(0.1), literal(-2.5)
    ('1.0', '0.10000000000000001', '(-2.5)')
    """
    v = float(x)
    if not math.isfinite(v):
        raise ValueError(f"not a finite number: {v!r}")
    s = f"{v:.17g}"
    if not any(ch in s for ch in ".e"):
        s += ".0"
    return f"({s})" if s.startswith("-") else s


@dataclass(frozen=True)
class Operand:
    """An instruction's argument: a variable (``kind == "var"``, ``index`` into the
    program's variables), an earlier result (``"slot"``) or a constant (``"const"``,
    ``value``)."""

    kind: str
    index: int = 0
    value: float = 0.0


@dataclass(frozen=True)
class Instruction:
    """One operation: ``op`` (``+ - * /``, ``neg``, or a C99 function name) on its
    operands; its result is the next slot."""

    op: str
    args: tuple[Operand, ...]


#: The binary operators and their C/Python spelling (the same in both).
OPERATORS = ("+", "-", "*", "/")
#: The functions an instruction may call: the canonical name of :data:`exprtree.CALLS`
#: and the C99 function it becomes.
FUNCTIONS = {
    "exp": "exp",
    "log": "log",
    "sqrt": "sqrt",
    "sin": "sin",
    "cos": "cos",
    "tan": "tan",
    "sinh": "sinh",
    "cosh": "cosh",
    "tanh": "tanh",
    "atan": "atan",
    "Abs": "fabs",
    "Min": "fmin",
    "Max": "fmax",
}


# The Python module's versions of the C functions that Python's ``math`` would raise on
# (their source is written into the exported module, and :meth:`ScalarProgram.evaluate`
# runs them): each returns C99's value instead (±inf on overflow, NaN on a domain error,
# the IEEE quotient for a division by zero).
def _div(a, b):
    if b == 0.0:
        if a != a or a == 0.0:
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def _odd(y):
    return math.isfinite(y) and y == math.floor(y) and math.fmod(y, 2.0) != 0.0


def _pow(x, y):
    try:
        return math.pow(x, y)
    except OverflowError:
        return -math.inf if (x < 0.0 and _odd(y)) else math.inf
    except ValueError:
        if x == 0.0:
            return math.copysign(math.inf, x) if _odd(y) else math.inf
        return math.nan


def _grow(f, x, sign):
    try:
        return f(x)
    except OverflowError:
        return math.copysign(math.inf, x) if sign else math.inf
    except ValueError:
        return math.nan


def _exp(x):
    return _grow(math.exp, x, False)


def _sinh(x):
    return _grow(math.sinh, x, True)


def _cosh(x):
    return _grow(math.cosh, x, False)


def _log(x):
    try:
        return math.log(x)
    except ValueError:
        return -math.inf if x == 0.0 else math.nan


def _domain(f, x):
    try:
        return f(x)
    except ValueError:
        return math.nan


def _sqrt(x):
    return _domain(math.sqrt, x)


def _sin(x):
    return _domain(math.sin, x)


def _cos(x):
    return _domain(math.cos, x)


def _tan(x):
    return _domain(math.tan, x)


def _fmin(a, b):
    if a != a:
        return b
    if b != b:
        return a
    return b if b < a else a


def _fmax(a, b):
    if a != a:
        return b
    if b != b:
        return a
    return b if b > a else a


_HELPERS = (
    _div,
    _odd,
    _pow,
    _grow,
    _exp,
    _sinh,
    _cosh,
    _log,
    _domain,
    _sqrt,
    _sin,
    _cos,
    _tan,
    _fmin,
    _fmax,
)
#: The source of those helpers, as the exported Python module holds it.
PYTHON_HELPERS = "\n\n".join(inspect.getsource(f) for f in _HELPERS)

#: Where C's own function could differ from Python's on a tie (``fmin(-0.0, 0.0)`` may give
#: either zero), the exported C calls these instead, which do what the Python helpers do.
C_HELPERS = {
    "fmin": """static double ntc_fmin(double a, double b)
{
    if (a != a) return b;
    if (b != b) return a;
    return b < a ? b : a;
}
""",
    "fmax": """static double ntc_fmax(double a, double b)
{
    if (a != a) return b;
    if (b != b) return a;
    return b > a ? b : a;
}
""",
}
#: The C spelling of each function (``math.h``, or :data:`C_HELPERS`).
C_FUNCTIONS = {
    **{f: f for f in FUNCTIONS.values()},
    "pow": "pow",
    "fmin": "ntc_fmin",
    "fmax": "ntc_fmax",
}

#: The Python spelling of each C function (helpers of :data:`PYTHON_HELPERS` or ``math``).
PYTHON_FUNCTIONS = {
    "exp": "_exp",
    "log": "_log",
    "sqrt": "_sqrt",
    "sin": "_sin",
    "cos": "_cos",
    "tan": "_tan",
    "sinh": "_sinh",
    "cosh": "_cosh",
    "tanh": "math.tanh",
    "atan": "math.atan",
    "fabs": "math.fabs",
    "fmin": "_fmin",
    "fmax": "_fmax",
    "pow": "_pow",
}


_EVAL: dict[str, Callable[..., float]] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": _div,
    "neg": lambda a: -a,
    "exp": _exp,
    "log": _log,
    "sqrt": _sqrt,
    "sin": _sin,
    "cos": _cos,
    "tan": _tan,
    "sinh": _sinh,
    "cosh": _cosh,
    "tanh": math.tanh,
    "atan": math.atan,
    "fabs": math.fabs,
    "fmin": _fmin,
    "fmax": _fmax,
    "pow": _pow,
}


@dataclass(frozen=True)
class ScalarProgram:
    """c(t) (or any expression of its variables) as straight-line code.

    Attributes
    ----------
    text : str
        The expression as the user wrote it.
    variables : tuple of str
        The variables, in the order :meth:`evaluate` takes them.
    code : tuple of Instruction
        The instructions; instruction k's result is slot k.
    result : Operand
        The value returned.

    Examples
    --------
    >>> p = scalar_program("1/(1+t)^2", "gain")
    >>> p.evaluate(1.0)
    0.25
    >>> print("\\n".join(p.c_lines()))
    const double v0 = 1.0 + t;
    const double v1 = v0 * v0;
    const double v2 = 1.0 / v1;
    """

    text: str
    variables: tuple[str, ...]
    code: tuple[Instruction, ...]
    result: Operand

    def evaluate(self, *xs: float) -> float:
        """The value at the variables' values, by the same operations as the C and
        Python code (Python's floats are IEEE doubles; its ``math`` is the C library).

        Parameters
        ----------
        *xs : float
            The variables' values, in :attr:`variables` order.

        Returns
        -------
        float
        """
        slots: list[float] = []
        vals = [float(x) for x in xs]

        def get(o: Operand) -> float:
            if o.kind == "const":
                return o.value
            return vals[o.index] if o.kind == "var" else slots[o.index]

        for ins in self.code:
            slots.append(_EVAL[ins.op](*(get(a) for a in ins.args)))
        return get(self.result)

    def _render(self, o: Operand, prefix: str) -> str:
        if o.kind == "const":
            return literal(o.value)
        return self.variables[o.index] if o.kind == "var" else f"{prefix}{o.index}"

    def _lines(self, prefix: str, python: bool) -> list[str]:
        out = []
        for k, ins in enumerate(self.code):
            a = [self._render(x, prefix) for x in ins.args]
            if ins.op == "neg":
                rhs = f"-{a[0]}"
            elif ins.op == "/" and python:
                rhs = f"_div({a[0]}, {a[1]})"
            elif ins.op in OPERATORS:
                rhs = f"{a[0]} {ins.op} {a[1]}"
            else:
                name = (PYTHON_FUNCTIONS if python else C_FUNCTIONS)[ins.op]
                rhs = f"{name}({', '.join(a)})"
            out.append(f"{prefix}{k} = {rhs}" if python else f"const double {prefix}{k} = {rhs};")
        return out

    @property
    def constant(self) -> bool:
        """Whether the value does not depend on the variables."""
        return self.result.kind == "const"

    def c_helpers(self) -> str:
        """The definitions of the :data:`C_HELPERS` the code calls (empty when none).

        Returns
        -------
        str
        """
        used = {ins.op for ins in self.code}
        return "\n".join(text for op, text in C_HELPERS.items() if op in used)

    def c_lines(self, prefix: str = "v") -> list[str]:
        """The instructions as C99 statements (``const double v0 = …;``).

        Parameters
        ----------
        prefix : str, optional
            The temporaries' name prefix.

        Returns
        -------
        list of str
        """
        return self._lines(prefix, python=False)

    def python_lines(self, prefix: str = "v") -> list[str]:
        """The instructions as Python statements (``v0 = …``; the helpers of
        :data:`PYTHON_HELPERS` must be defined).

        Parameters
        ----------
        prefix : str, optional
            The temporaries' name prefix.

        Returns
        -------
        list of str
        """
        return self._lines(prefix, python=True)

    def returned(self, prefix: str = "v") -> str:
        """The expression of the result (a temporary, a variable or a literal).

        Parameters
        ----------
        prefix : str, optional
            The temporaries' name prefix.

        Returns
        -------
        str
        """
        return self._render(self.result, prefix)


def _float_value(v: Fraction | float) -> float:
    return float(v)


class _CodeBuilder(TreeBuilder):
    """The backend: a value is an exact :class:`Fraction` (a constant folded exactly), a
    float (a constant folded in floating point) or an :class:`Operand` (computed)."""

    def __init__(self, text: str, field: str, names: Sequence[str]):
        super().__init__(text, field, {n: k for k, n in enumerate(names)})
        self.code: list[Instruction] = []

    def emit(self, op: str, *args: Any) -> Operand:
        self.code.append(Instruction(op, tuple(self.operand(a) for a in args)))
        return Operand("slot", len(self.code) - 1)

    @staticmethod
    def operand(v: Any) -> Operand:
        if isinstance(v, Operand):
            return v
        return Operand("const", value=_float_value(v))

    def exact(self, value: Any) -> Fraction | None:
        return value if isinstance(value, Fraction) else None

    def variable(self, name: str) -> Operand:
        return Operand("var", self.names[name])

    def constant(self, name: str) -> float:
        return CONSTANT_VALUES[name]

    def rational(self, p: int, q: int) -> Fraction:
        return Fraction(p, q)

    def neg(self, x: Any) -> Any:
        return self.emit("neg", x) if isinstance(x, Operand) else -x

    def binary(self, op: str, a: Any, b: Any) -> Any:
        if isinstance(a, Fraction) and isinstance(b, Fraction):
            return {"+": a + b, "-": a - b, "*": a * b, "/": a / b}[op]
        if not isinstance(a, Operand) and not isinstance(b, Operand):
            return _EVAL[op](float(a), float(b))
        return self.emit(op, a, b)

    def power(self, base: Any, exp: Any) -> Any:
        if isinstance(base, Fraction) and isinstance(exp, Fraction) and exp.denominator == 1:
            return base**exp.numerator  # bounded by raise_to before
        if not isinstance(base, Operand) and not isinstance(exp, Operand):
            return _EVAL["pow"](float(base), float(exp))
        if isinstance(exp, Fraction) and isinstance(base, Operand):
            if exp.denominator == 1 and abs(exp.numerator) <= MAX_UNROLL:
                n = exp.numerator
                if n == 0:
                    return 1.0  # as pow(x, 0): 1 for every x
                acc = base
                for _ in range(abs(n) - 1):
                    acc = self.emit("*", acc, base)
                return acc if n > 0 else self.emit("/", 1.0, acc)
            if exp == Fraction(1, 2):
                return self.emit("sqrt", base)
        return self.emit("pow", base, exp)

    def apply(self, name: str, args: list[Any]) -> Any:
        fn = FUNCTIONS[name]
        if not any(isinstance(a, Operand) for a in args):
            vals = [float(a) for a in args]
            out = vals[0]
            if len(vals) == 1:
                return _EVAL[fn](out)
            for v in vals[1:]:
                out = _EVAL[fn](out, v)
            return out
        if len(args) == 1:
            return self.emit(fn, args[0])
        acc = args[0]
        for a in args[1:]:
            acc = self.emit(fn, acc, a)
        return acc


def scalar_program(text: object, field: str, variables: Sequence[str] = ("t",)) -> ScalarProgram:
    """A user expression as a :class:`ScalarProgram`, checked by the same rules as
    :func:`~ntc_design.expr.tree.numeric_function` (which it runs first).

    Parameters
    ----------
    text : object
        The expression, e.g. ``"1/(1+t)"``; ``^`` means a power.
    field : str
        Where the text came from; it starts every error message.
    variables : sequence of str, optional
        The names allowed as variables.

    Returns
    -------
    ScalarProgram

    Raises
    ------
    InputError
        One line naming ``field`` when the text is not a whitelisted expression within the
        bounds, or a constant in it is out of range.

    Examples
    --------
    >>> scalar_program("2*t^-1 + sqrt(t)", "gain").evaluate(4.0)
    2.5
    """
    numeric_function(text, field, variables)  # the whitelist, the bounds, the messages
    src, tree = syntax_tree(text, field)
    builder = _CodeBuilder(src, field, list(variables))
    value, _ = builder.build_tree(tree)
    return ScalarProgram(str(text), tuple(variables), tuple(builder.code), builder.operand(value))


__all__ = [
    "C_FUNCTIONS",
    "C_HELPERS",
    "FUNCTIONS",
    "MAX_UNROLL",
    "OPERATORS",
    "PYTHON_FUNCTIONS",
    "PYTHON_HELPERS",
    "Instruction",
    "Operand",
    "ScalarProgram",
    "literal",
    "scalar_program",
]
