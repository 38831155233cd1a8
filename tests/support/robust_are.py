"""A 14-agent network past the LMI's size (Nd = 42), certified robustly once."""

import warnings

import pytest

import ntc_design as nd
from ntc_design.certify.robust import robust
from ntc_design.certify.robust.scale import robust_scale
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA


@pytest.fixture(scope="session")
def mid_robust():
    top = random_network(14, 3, seed=4)  # Nd = 42: past the LMI, where dominance is loose
    des = nd.design(top, THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return des, robust(des, 0.05, starts=2), robust_scale(des, 0.05)
