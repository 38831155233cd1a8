"""Tests of :mod:`ntc_design.tune.sampled`: the sampled recursion's value against the
simulator's exact digital moments, its discrete adjoint against finite differences, and
the optimal sampled schedule through ``tune``."""

import numpy as np
import pytest

from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.simulate.digital import digital_moments
from ntc_design.simulate.prepare import make_gain, prepare_modes, sampled_grid
from ntc_design.tune import ScheduleOptions, tune
from ntc_design.tune.sampled import SampledScheduleProblem

X0 = np.linspace(-3, 3, 21)


@pytest.fixture(scope="module")
def parts(g1):
    spec = SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3), initial=X0.tolist(), T=2.0)
    gain = make_gain(spec.gain)[0]
    return spec, prepare_modes(g1, spec.replace(method="exact"), gain)


@pytest.mark.parametrize(("h", "delay"), [(0.1, 0), (0.1, 2), (0.13, 1)])
def test_value_and_adjoint(g1, parts, h, delay):
    """h = 0.13: 15 samples and the held input's partial step of 0.05 to T = 2."""
    spec, pm = parts
    dg = Digital(h, delay)
    grid = sampled_grid(g1, pm, dg, 2.0, np.array([2.0]))
    assert grid.t[-1] == 2.0 and (grid.noise_last is not None) == (h == 0.13)
    prob = SampledScheduleProblem(pm, grid, dg)
    nodes = prob.node_times(5)
    c = 1 / (1 + nodes) + 0.1 * np.sin(np.arange(6))
    plan = prob.plan(c)
    fwd = prob.forward(c, plan)
    dm = digital_moments(pm, grid, lambda t: np.interp(t, nodes, c), delay)
    assert fwd.value == pytest.approx(float(dm.moments.ms_error[-1].sum()), rel=1e-12)
    src = np.random.default_rng(0).random(plan.steps)
    for sources in (None, src):
        got = prob.adjoint(plan, fwd, sources)
        w = np.zeros(plan.steps) if sources is None else sources
        if sources is None:
            w[-1] = 1.0
        fd = []
        for i in range(c.size):
            e = np.zeros_like(c)
            e[i] = 1e-6
            fp, fm = prob.forward(c + e, plan), prob.forward(c - e, plan)
            fd.append((w @ fp.traces - w @ fm.traces) / 2e-6)
        assert np.allclose(got, fd, rtol=1e-6, atol=1e-8 * np.max(np.abs(fd)))


def test_optimal_sampled_schedule_beats_the_power_law_and_is_certified(g1):
    spec = SimulationSpec.build(
        THETA, noise=NoiseModel(0.4, 0.3), initial=X0.tolist(), digital=Digital(0.2, 1)
    )
    r = tune(g1, spec, 4.0, ScheduleOptions(check_paths=0))
    assert r.ms_error_T["optimal"] <= r.ms_error_T["power"] <= r.ms_error_T["baseline"]
    assert r.solution.levels[-1].pieces == 20  # one node per sample at the finest level
    assert r.certificate is not None and r.certificate.certificate["kind"] == "digital"
    assert "sampled every h = 0.2" in r.method
