"""Tests of :mod:`ntc_design.simulate.steps`."""

import numpy as np

from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, simulate
from tests.conftest import X0


def test_nonlinear_f_runs_mc_only(g1):
    res = simulate(
        g1,
        THETA,
        T=0.2,
        paths=50,
        initial=X0,
        noise=NoiseModel(0.4, lambda x: 0.3 * np.tanh(x)),
        save_every=0.1,
        workers=1,
    )
    assert res.exact is None and any("not linear" in n for n in res.notes)
