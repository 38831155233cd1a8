"""Tests of :mod:`ntc_design.rigorous.floatmat`: every bound contains the exact value
(computed with :class:`~ntc_design.rigorous.exact.Dyadic`), and the PD test agrees with it."""

import numpy as np
import pytest

from ntc_design.rigorous.exact import Dyadic, exact_pd
from ntc_design.rigorous.floatmat import FloatMat


def _exact(d: Dyadic) -> np.ndarray:
    return d.to_float()


@pytest.mark.parametrize("seed", range(6))
def test_bounds_contain_the_exact_value_of_an_expression(seed):
    rng = np.random.default_rng(seed)
    n = 7
    a, b = rng.normal(size=(n, n)) * 10.0 ** rng.integers(-3, 3), rng.normal(size=(n, n))
    s = float(rng.normal())
    fa, fb = FloatMat.of(a), FloatMat.of(b)
    da, db = Dyadic.of(a), Dyadic.of(b)
    got = ((fa @ fb).T - fa.scale(s) + fb @ fb).scale(0.5)
    want = ((da @ db).T - da.scale(Dyadic.of(s)) + db @ db).scale(Dyadic.of(0.5))
    # |exact − val| <= rad, the exact difference taken in rationals
    diff = Dyadic.of(got.val) - want
    assert np.all(np.abs(_exact(diff)) <= got.rad)
    assert np.all(got.rad <= 1e-12 * (1 + np.abs(got.val)))  # and the bound is tight


def test_a_given_radius_propagates():
    a = FloatMat.of(np.eye(2), 1e-3)
    b = a @ a
    assert np.all(b.rad >= 2e-3 * np.eye(2) - 1e-18)


def test_the_pd_test_agrees_with_the_exact_one():
    m = np.array([[2.0, 1.0], [1.0, 2.0]])
    assert FloatMat.of(m).positive_definite().holds and exact_pd(Dyadic.of(m)).holds
    singular = np.array([[1.0, 1.0], [1.0, 1.0]])
    assert not FloatMat.of(singular).positive_definite().holds
    assert not FloatMat.of(m, 2.0).positive_definite().holds  # the radius covers a non-PD one


@pytest.mark.hostile
def test_out_of_range_inputs_are_refused():
    with pytest.raises(ValueError, match="outside the verified-float range"):
        FloatMat.of(np.array([[1e300]]))
    with pytest.raises(ValueError):
        FloatMat.of(np.array([[np.nan]]))
