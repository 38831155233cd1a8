"""The schedule problem on G1 that the optimiser's tests and the problem's share."""

import pytest

from ntc_design.simulate.prepare import prepare_modes
from ntc_design.tune.schedule_problem import ScheduleProblem


@pytest.fixture(scope="package")
def problem(g1, g1_spec):
    def build(horizon):
        pm = prepare_modes(g1, g1_spec.replace(T=horizon, method="exact"), lambda t: 1 + 0 * t)
        return ScheduleProblem(pm, horizon)

    return build
