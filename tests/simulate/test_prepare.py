"""Tests of :mod:`ntc_design.simulate.prepare`: the prepared modes, their sampling grid
and c(t)."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.prepare import make_gain, prepare_modes, sampled_grid
from ntc_design.simulate.spec import SimulationSpec
from tests.conftest import ROOT


def test_a_constant_gain_is_broadcast_and_a_callable_keeps_its_name():
    c, text = make_gain("2")
    assert text == "2" and c(np.array([0.0, 1.0, 5.0])).tolist() == [2.0, 2.0, 2.0]

    def decay(t):
        return 1 / (1 + t)

    c, text = make_gain(decay)
    assert text == "decay" and c(np.array([0.0, 1.0])).tolist() == [1.0, 0.5]
    with pytest.raises(InputError, match="^gain: expected an expression in t or a callable"):
        make_gain(3.0)  # type: ignore[arg-type]


@pytest.mark.filterwarnings("ignore:Assumption 2 fails")
def test_a_switching_set_is_prepared_mode_by_mode_on_its_schedule(switching_set):
    spec = SimulationSpec.build(THETA, T=3.0)
    pm = prepare_modes(switching_set, spec, lambda t: np.ones_like(t))
    assert pm.names == list(switching_set.modes) and len(pm.systems) == len(pm.names)
    # the segments are the schedule's, written out: durations repeated until T
    want, t, k = [], 0.0, 0
    sched = switching_set.schedule
    while t < 3.0 - 1e-12:
        m, dur = sched[k % len(sched)]
        want.append((t, min(t + dur, 3.0), pm.names.index(m)))
        t += dur
        k += 1
    np.testing.assert_allclose(np.array(pm.segments, dtype=float), np.array(want), rtol=1e-12)
    np.testing.assert_array_equal(pm.eps0, pm.x_init - np.tile(pm.theta, pm.n))


def test_the_sampling_grid_is_one_step_per_period_and_refuses_expressions(g1):
    spec = SimulationSpec.build(THETA, T=1.0)
    pm = prepare_modes(g1, spec, lambda t: np.ones_like(t))
    grid = sampled_grid(g1, pm, Digital(0.25), 1.0, np.array([0.0, 1.0]))
    np.testing.assert_allclose(grid.t, [0.0, 0.25, 0.5, 0.75, 1.0])
    tv = nd.load(ROOT / "examples" / "g1_tv.yaml")
    with pytest.raises(InputError, match="^digital: a topology given as expressions"):
        sampled_grid(tv, pm, Digital(0.25), 1.0, np.array([0.0, 1.0]))
