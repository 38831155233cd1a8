"""A 400-agent random network and its system: the drift-implicit solvers' test bed."""

import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.system import mode_system


@pytest.fixture(scope="session")
def implicit_net():
    top = nd.random_network(400, 3, seed=5)
    des = nd.design(top, THETA, thresholds=False)
    return des, mode_system(des, NoiseModel(sigma=0.4, f=0.3))
