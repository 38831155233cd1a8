"""Tests of :mod:`ntc_design.expr.code`: the straight-line code of an expression, its value
against the NumPy backend, the code it emits, and the helpers that give C's values where
Python's math raises."""

import math

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.expr.code import PYTHON_HELPERS, literal, scalar_program
from ntc_design.expr.tree import numeric_function
from tests.expr.test_tree import _HOSTILE, _VALID

T = [0.0, 0.1, 0.5, 1.0, 2.0, 7.3, 50.0]


def test_value_agrees_with_the_numpy_backend():
    for text in _VALID:  # one test: two dozen cheap expressions
        p = scalar_program(text, "gain")
        want = numeric_function(text, "gain")(np.array(T))
        got = np.array([p.evaluate(t) for t in T])
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=0, err_msg=text)


def _run_python(p, t):
    """The emitted Python lines, run (in the test) with the helpers they call."""
    space = {"math": math}
    exec(PYTHON_HELPERS, space)  # the module's own helper source
    body = "".join(f"    {line}\n" for line in p.python_lines())
    exec(f"def f(t):\n{body}    return {p.returned()}\n", space)
    return space["f"](t)


def test_the_python_code_computes_the_same_bits():
    for text in _VALID:
        p = scalar_program(text, "gain")
        for t in T:
            a, b = p.evaluate(t), _run_python(p, t)
            assert a == b or (math.isnan(a) and math.isnan(b)), (text, t)


@pytest.mark.parametrize(
    "text, lines, returned",
    [
        ("t^2", ["const double v0 = t * t;"], "v0"),
        ("t**-1", ["const double v0 = 1.0 / t;"], "v0"),
        ("t**-2", ["const double v0 = t * t;", "const double v1 = 1.0 / v0;"], "v1"),
        ("t^3", ["const double v0 = t * t;", "const double v1 = v0 * t;"], "v1"),
        ("t**0.5", ["const double v0 = sqrt(t);"], "v0"),
        ("(1+t)^(-1/3)", ["const double v0 = 1.0 + t;",
                          "const double v1 = pow(v0, (-0.33333333333333331));"], "v1"),
        ("t**17", ["const double v0 = pow(t, 17.0);"], "v0"),
        ("t^0", [], "1.0"),
        ("2*pi", [], "6.2831853071795862"),
        ("min(t, 1, 2)", ["const double v0 = ntc_fmin(t, 1.0);",
                          "const double v1 = ntc_fmin(v0, 2.0);"], "v1"),
        ("abs(-t)", ["const double v0 = -t;", "const double v1 = fabs(v0);"], "v1"),
        ("exp(1)*t", ["const double v0 = 2.7182818284590451 * t;"], "v0"),
    ],
)  # fmt: skip
def test_the_c_code(text, lines, returned):
    p = scalar_program(text, "gain")
    assert p.c_lines() == lines
    assert p.returned() == returned


def test_helpers_only_where_called():
    assert "ntc_fmin" in scalar_program("min(t, 1)", "gain").c_helpers()
    assert scalar_program("1/(1+t)", "gain").c_helpers() == ""
    assert scalar_program("0.5", "gain").constant
    assert not scalar_program("0.5*t", "gain").constant


@pytest.mark.parametrize(
    "text, t, want",
    [
        ("1/(t-t)", 1.0, math.inf),
        ("-1/(t-t)", 1.0, -math.inf),
        ("exp(t)", 1000.0, math.inf),
        ("1/exp(t)", 1000.0, 0.0),
        ("log(t-t)", 1.0, -math.inf),
        ("sinh(t)", -1000.0, -math.inf),
        ("cosh(t)", -1000.0, math.inf),
        ("(t-1)^(-3/2)", 1.0, math.inf),
        ("t^2.5", 1e200, math.inf),
        ("max(t, 2)", 1.0, 2.0),
    ],
)
def test_python_gives_c99_values_where_math_raises(text, t, want):
    assert scalar_program(text, "gain").evaluate(t) == want


@pytest.mark.parametrize("text", ["sqrt(t)", "log(t)", "(t)^(1/3)", "sin(1/(t-t))"])
def test_domain_errors_are_nan(text):
    assert math.isnan(scalar_program(text, "gain").evaluate(-1.0 if "1/(" not in text else 1.0))


@pytest.mark.hostile
def test_refuses_what_the_numpy_backend_refuses():
    for text in _HOSTILE:  # the same messages, word for word
        with pytest.raises(InputError) as a:
            numeric_function(text, "gain")
        with pytest.raises(InputError) as b:
            scalar_program(text, "gain")
        assert str(a.value) == str(b.value), text


@pytest.mark.parametrize(
    "x", [1.0, 0.1, -2.5, 1e-300, 5e-324, 1.7976931348623157e308, -0.0, 1 / 3, 2.0**53 + 2]
)
def test_literal_reads_back_to_the_same_double(x):
    s = literal(x)
    assert float(s.strip("()")) == x and math.copysign(1, float(s.strip("()"))) == math.copysign(
        1, x
    )
    assert any(c in s for c in ".e")  # never an integer literal in C


def test_literal_refuses_non_finite():
    with pytest.raises(ValueError):
        literal(math.inf)
