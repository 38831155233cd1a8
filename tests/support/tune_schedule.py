"""The simulation settings of the deadline-schedule tests (G1, σ = 0.4, f = 0.3x)."""

import numpy as np
import pytest

from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, SimulationSpec

X0 = np.linspace(-3, 3, 21)


@pytest.fixture(scope="session")
def g1_spec():
    return SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3), initial=X0, margin=0.1)
