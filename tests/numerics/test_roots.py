"""Tests of :mod:`ntc_design.numerics.roots`."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from ntc_design.numerics.roots import brent_root

CASES = [
    (lambda x: x * x - 2.0, 0.0, 2.0),
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: x**3 - 2 * x - 5, 2.0, 3.0),  # Wallis' example
    (lambda x: math.exp(x) - 1e6, 0.0, 30.0),
    (lambda x: math.tanh(50 * (x - 0.3)), -1.0, 2.0),  # steep
    (lambda x: (x - 1e-9) * 1e12, -1.0, 1.0),
    (lambda x: np.sign(x - 0.25) * abs(x - 0.25) ** 0.1, 0.0, 1.0),  # non-smooth
    (lambda x: x**9, -1.0, 3.0),  # a root of multiplicity nine
]


@pytest.mark.parametrize("k", range(len(CASES)))
@pytest.mark.parametrize(
    "xtol, rtol", [(2e-12, 4 * np.finfo(float).eps), (1e-15, 4 * np.finfo(float).eps)]
)
def test_brent_root_agrees_with_scipy(k, xtol, rtol):
    f, a, b = CASES[k]
    calls = []

    def g(x):
        calls.append(x)
        return f(x)

    ours = brent_root(g, a, b, xtol=xtol, rtol=rtol, maxiter=500)
    ref, info = brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=500, full_output=True)
    assert ours == ref  # the same steps give the same bits
    assert len(calls) == info.function_calls
    assert abs(ours - ref) <= xtol + rtol * abs(ref)


def test_brent_root_refuses_a_non_bracket_and_reports_non_convergence():
    with pytest.raises(ValueError, match="same sign"):
        brent_root(lambda x: x * x + 1, -1.0, 1.0)
    with pytest.raises(ValueError, match="not finite"):
        brent_root(lambda x: x, -math.inf, 1.0)
    with pytest.raises(RuntimeError, match="no convergence in 3 steps"):
        brent_root(lambda x: math.tanh(50 * (x - 0.3)), -1.0, 2.0, xtol=0.0, rtol=0.0, maxiter=3)
    assert brent_root(lambda x: x, 0.0, 1.0) == 0.0  # an end that is a root
