"""Tests of :mod:`ntc_design.simulate.noise`."""

import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, simulate


def test_noise_callable_shape_is_checked(g1):
    with pytest.raises(nd.InputError, match=r"noise.f: returned shape"):
        simulate(g1, THETA, T=0.1, paths=4, noise=NoiseModel(0.4, lambda x: x[..., :1]))
