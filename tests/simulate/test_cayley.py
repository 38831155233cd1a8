"""Tests of :mod:`ntc_design.simulate.cayley`."""

from dataclasses import replace

import numpy as np
import pytest

from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.simulate.cayley import cayley_moments, noise_radius
from ntc_design.simulate.prepare import prepare_modes
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune import PowerGain


def _prepared(path):
    top, spec, _ = load_scenario(path)
    spec = spec.replace(method="exact")
    return prepare_modes(top, spec, lambda t: np.ones(np.shape(t)))


# each network with one gain in the fast lane (the stiffer gain on G1: the harder transient);
# the other two pairs in the slow lane
SLOW = pytest.mark.slow


@pytest.mark.parametrize(
    "scenario, gain",
    [
        ("g1_fixed.yaml", PowerGain(0.9374, 0.3738, 1.0)),
        ("switching.yaml", PowerGain(1, 1, 1)),
        pytest.param("g1_fixed.yaml", PowerGain(1, 1, 1), marks=SLOW),
        pytest.param("switching.yaml", PowerGain(0.9374, 0.3738, 1.0), marks=SLOW),
    ],
)
def test_cayley_moments_agree_with_rk4(examples, scenario, gain):
    pm = _prepared(examples / "scenarios" / scenario)
    t = np.linspace(0, 5, 11)
    ref = pm.moments(gain, t).ms_error.sum(axis=1)
    got = cayley_moments(pm, gain, t, ds=0.002)
    # about 2e-3 in the fast transient of the stiffer gain (E‖ε‖² peaks near t = 0.5)
    np.testing.assert_allclose(got.ms_error.sum(axis=1), ref, rtol=3e-3)
    assert abs(got.ms_error[-1].sum() / ref[-1] - 1) < 3e-4


def test_cayley_moments_are_second_order(examples):
    pm = _prepared(examples / "scenarios" / "g1_fixed.yaml")
    gain, t = PowerGain(1.0, 1.0, 1.0), np.array([0.0, 3.0])
    ref = pm.moments(gain, t).ms_error[-1].sum()
    err = [abs(cayley_moments(pm, gain, t, ds).ms_error[-1].sum() - ref) for ds in (0.004, 0.002)]
    assert 3.3 < err[0] / err[1] < 4.7  # halving the step quarters the error


def test_cayley_steady_state_is_exact_for_a_constant_gain(g1, theta):
    # c = 1, additive noise only: S → the solution of L_B S + S L_Bᵀ = G Gᵀ, whatever the step
    from scipy.linalg import solve_continuous_lyapunov

    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.0), method="exact")
    pm = prepare_modes(g1, spec, lambda t: np.ones(np.shape(t)))
    s = pm.systems[0]
    lap = s.lap_b.toarray()
    q = (s.g @ s.g.T).toarray()
    steady = solve_continuous_lyapunov(-lap, -q)
    long = replace(pm, segments=[(0.0, 60.0, 0)])
    m = cayley_moments(long, lambda t: np.ones(np.shape(t)), np.array([0.0, 60.0]), ds=0.5)
    np.testing.assert_allclose(m.second, steady, rtol=1e-6, atol=1e-9)


def test_cayley_stops_early_when_the_moments_blow_up(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.3), method="exact")
    pm = prepare_modes(g1, spec, lambda t: np.ones(np.shape(t)))
    big = PowerGain(20.0, 1.0, 0.6)  # c ≈ 20: multiplicative noise dominates
    m = cayley_moments(pm, big, np.linspace(0, 5, 6), abort_above=1e6)
    assert np.isinf(m.ms_error[-1]).all() and m.steps < 5000


def test_noise_radius_is_a_per_agent_bound(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.3), method="exact")
    s = prepare_modes(g1, spec, lambda t: np.ones(np.shape(t))).systems[0]
    w = np.linalg.norm(s.k_blocks, ord=2, axis=(1, 2)) ** 2
    per = np.zeros(g1.n)
    for (i, j, _), x in zip(s.h_blocks, w, strict=True):
        per[i] += x
        per[j] += x
    assert noise_radius(s) == pytest.approx(4 * per.max())
    assert noise_radius(s) <= 4 * 2 * w.sum()
