"""Tests of :mod:`ntc_design.tune.family`."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

import ntc_design as nd
from ntc_design.gain.conditions import gain_function
from ntc_design.tune import PowerGain

# -- the family ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "a, b, gamma", [(1.0, 1.0, 1.0), (2.345, 0.2, 0.7123), (0.05, 10.0, 0.51), (7.0, 0.3, 0.05)]
)
def test_power_gain_text_is_read_back_as_the_same_function(a, b, gamma):
    g = PowerGain(a, b, gamma).rounded()
    t = np.array([0.0, 0.5, 3.0, 100.0])
    np.testing.assert_allclose(gain_function(g.text)(t), g(t), rtol=1e-12)


@pytest.mark.parametrize("gamma", [0.3, 0.5, 0.8, 1.0])
def test_power_gain_integrals_against_quadrature(gamma):
    g = PowerGain(1.7, 0.4, gamma)
    i1, i2 = g.integrals(7.0)
    assert i1 == pytest.approx(quad(lambda t: g(t), 0, 7.0)[0], rel=1e-9)
    assert i2 == pytest.approx(quad(lambda t: g(t) ** 2, 0, 7.0)[0], rel=1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_power_gain_refuses_non_positive_parameters(bad):
    with pytest.raises(nd.InputError, match="a: expected a finite number > 0"):
        PowerGain(bad, 1.0, 1.0)
