"""Tests of :mod:`ntc_design.expr.symbolic`."""

import math

import numpy as np
import pytest
import sympy as sp

from ntc_design.errors import InputError
from ntc_design.expr.symbolic import compile_expression, parse_expression, symbol

T = symbol("t")


@pytest.mark.parametrize(
    "text, expected",
    [
        ("1/(1+t)", 1 / (1 + T)),
        ("(1+t)^(-1/3)", (1 + T) ** sp.Rational(-1, 3)),
        ("(1+t)^-2", (1 + T) ** -2),
        ("(1+t)**-2", (1 + T) ** -2),
        ("0.1 - t", sp.Rational(1, 10) - T),
        ("1e-3*t", T / 1000),
        ("2.5E2", sp.Integer(250)),
        ("1_000*t", 1000 * T),
        ("-1/(1+t)", -1 / (1 + T)),
        ("+t", T),
        ("exp(-t)*sin(t)^2", sp.exp(-T) * sp.sin(T) ** 2),
        ("ln(2+t)", sp.log(2 + T)),
        ("abs(cos(t))", sp.Abs(sp.cos(T))),
        ("min(1, 1/t)", sp.Min(1, 1 / T)),
        ("max(t, 2, 1)", sp.Max(T, 2)),
        ("pi*E", sp.pi * sp.E),
        ("t**0.5", sp.sqrt(T)),
        ("2**2**2**2", sp.Integer(65536)),
    ],
)
def test_parses_exactly(text, expected):
    assert sp.simplify(parse_expression(text, "gain") - expected) == 0


def test_decimal_literals_are_exact():
    # 0.1 is one tenth, not the binary float 0.1000000000000000055...
    assert parse_expression("0.1", "g") == sp.Rational(1, 10)
    assert parse_expression("1.25e-2", "g") == sp.Rational(1, 80)


def test_other_variables():
    a = parse_expression("a*t + b", "w", variables=("t", "a", "b")).free_symbols - {T}
    assert {s.name for s in a} == {"a", "b"}
    x = sp.Symbol("x")
    assert parse_expression("2*x", "w", variables={"x": x}) == 2 * x
    with pytest.raises(InputError, match="uses t; only the variable s is allowed"):
        parse_expression("t", "w", variables=("s",))


@pytest.mark.hostile
@pytest.mark.parametrize(
    "text, needle",
    [
        ("__import__('os').system('touch x')", "only calls of named functions"),
        ("t*0+len(open('/etc/passwd').read())", "'len' not allowed"),
        ("factorial(10**9)", "'factorial' not allowed"),
        ("t**(10**10)", "exponent larger than 1000"),
        ("2**2**2**2**2**2", "exponent larger than 1000"),
        ("(t**1000)**1000", "exponent larger than 1000"),
        ("10**1000", "out of range"),
        ("exp(exp(exp(100)))", "out of range"),
        ("sin((pi**1000)**1000)", "out of range"),
        ("9" * 80, "more than 60 digits"),
        ("1e999", "too large"),
        ("1/0", "division by zero"),
        ("1/(t-t)", "division by zero"),
        ("log(0)", "out of range"),
        ("sqrt(-1)*t", "out of range"),
        ("(-8)**(1/3)", "non-real"),
        ("x + t", "uses x; only the variable t is allowed"),
        ("t.real", "Attribute"),
        ("t[0]", "Subscript"),
        ("lambda: t", "Lambda"),
        ("'t'", "constant"),
        ("True", "constant"),
        ("1j*t", "constant"),
        ("t if t else 1", "IfExp"),
        ("t < 1", "Compare"),
        ("t % 2", "Mod"),
        ("exp", "without arguments"),
        ("exp(t, t)", "takes 1 argument"),
        ("max(t)", "two or more"),
        ("exp(x=t)", "keyword"),
        ("t;1", "cannot parse"),
        ("t\nt", "control characters"),
        ("", "empty"),
        ("t+" * 600 + "t", "longer than 1000"),
        ("(" * 250 + "t" + ")" * 250, "cannot parse"),
        ("-" * 500 + "t", "too complex"),
        ("+".join(["t"] * 300), "too complex"),
        ("Piecewise((1, t < 1))", "'Piecewise' not allowed"),
        ("oo", "uses oo"),
    ],
)
def test_refused_with_one_line(text, needle, monkeypatch):
    import ntc_design.expr.symbolic as expr_mod

    built = []
    real = expr_mod._Builder.build

    def build(self, node, *a, **kw):
        built.append(node)
        return real(self, node, *a, **kw)

    monkeypatch.setattr(expr_mod._Builder, "build", build)
    with pytest.raises(InputError) as info:
        parse_expression(text, "gain")
    msg = str(info.value)
    # the work is bounded before SymPy: size and shape refusals build nothing, the others
    # at most one SymPy node per syntax node
    if needle in ("longer than 1000", "cannot parse", "too complex"):
        assert built == []
    assert len(built) <= expr_mod.MAX_NODES
    assert msg.startswith("gain: ") and "\n" not in msg
    assert needle in msg, msg


def test_not_a_string():
    with pytest.raises(InputError, match="as a string, got int"):
        parse_expression(3, "scenario.yaml: gain")


def test_compile_matches_sympy_and_broadcasts():
    expr = parse_expression("exp(-t)*(2+sin(t))/(1+t)^(1/3) + min(t, 1)", "g")
    f = compile_expression(expr)
    ts = np.linspace(0, 5, 11).reshape(1, 11)
    want = [float(expr.subs(T, v)) for v in ts.ravel()]
    got = f(ts)
    assert got.shape == ts.shape and got.dtype == float
    np.testing.assert_allclose(got.ravel(), want, rtol=1e-12)
    c = compile_expression(parse_expression("0.5", "g"))(np.zeros((3, 2)))
    assert c.shape == (3, 2) and np.all(c == 0.5)
    assert compile_expression(parse_expression("max(1, t)", "g"))(
        np.array([0.5, 2.0])
    ).tolist() == [
        1.0,
        2.0,
    ]


def test_compile_two_variables_and_huge_rationals():
    expr = parse_expression("a*t + 2**(1/10**30)", "w", variables=("t", "a"))
    f = compile_expression(expr, ("t", "a"))
    out = f(np.array([1.0, 2.0]), 3.0)
    np.testing.assert_allclose(out, [3.0 + 2**1e-30, 6.0 + 2**1e-30])
    # overflow gives inf for the caller to refuse, and no warning
    g = compile_expression(parse_expression("exp(t)", "g"))
    with np.errstate(all="raise"):
        assert math.isinf(g(np.array([1e6]))[0])
