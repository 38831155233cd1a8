"""Tests of :mod:`ntc_design.tune.objective`."""

import math
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.simulate import NoiseModel, SimulationSpec, simulate
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune import (
    ExactObjective,
    MonteCarloObjective,
    PowerGain,
    PowerOptions,
    objective_for,
    tune,
)
from tests.support.tune import T_PAIR


@pytest.mark.parametrize("a, b", [(1.0, 1.0), (0.3, 2.0), (2.0, 0.5), (6.0, 7.0)])
def test_exact_objective_equals_the_closed_form(pair_network, a, b):
    top, spec, closed = pair_network
    obj = ExactObjective(top, spec, T_PAIR)
    assert obj.curve(PowerGain(a, b, 1.0)).final == pytest.approx(closed(a, b), rel=1e-8)
    # the search's coarser RK4 is still accurate to 1e-5
    assert obj.value(PowerGain(a, b, 1.0)) == pytest.approx(closed(a, b), rel=1e-5)


def test_nonlinear_noise_is_tuned_by_monte_carlo_with_common_random_numbers(g1, theta):
    spec = SimulationSpec.build(
        theta,
        noise=NoiseModel(0.4, lambda x: 0.3 * np.sin(x)),
        initial=np.linspace(-3, 3, g1.n * g1.dim),
        paths=64,
        dt=0.01,
        seed=3,
        workers=1,
    )
    obj = objective_for(g1, spec, 1.0)
    assert isinstance(obj, MonteCarloObjective) and obj.statistical
    g = PowerGain(1.3, 0.8, 0.9)
    assert obj.value(g) == obj.value(g)  # the same draws for every evaluation
    res = tune(g1, spec, 1.0, PowerOptions(max_evaluations=12, landscape=False, certificate=False))
    assert res.statistical and "statistical" in res.method
    c = res.curves["tuned"]
    assert c.lo[-1] <= c.final <= c.hi[-1] and c.hi[-1] > c.lo[-1]
    assert res.ms_error_T["tuned"] <= res.ms_error_T["baseline"]


def test_exact_is_refused_for_a_nonlinear_f(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, np.sin))
    with pytest.raises(nd.InputError, match="exact moments are not available here"):
        objective_for(g1, spec, 1.0, method="exact")


def test_a_stiff_or_unstable_candidate_scores_infinity_without_being_integrated(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.3), initial=np.ones(21))
    obj = ExactObjective(g1, spec, 10.0)
    assert obj.value(PowerGain(20.0, 0.1, 1.0)) == math.inf  # c(0) = 200: about 4e5 RK4 steps
    assert "too stiff" in next(iter(obj.skipped.values()))
    # c(0) = 4.5: integrable, but the multiplicative noise makes E‖ε‖² grow without bound
    assert obj.value(PowerGain(4.472, 1.0, 0.51)) == math.inf


@pytest.mark.slow  # ~14 s: exact moments of a time-varying topology at every evaluation
def test_a_topology_given_as_expressions_of_t_is_tuned_by_its_exact_moments(examples):
    top, spec, _ = load_scenario(examples / "scenarios" / "g1_tv.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = tune(
            top, spec, 1.0, PowerOptions(max_evaluations=10, landscape=False, certificate=False)
        )
        again = simulate(top, spec=spec.replace(T=1.0, gain=res.tuned.text, method="exact"))
    assert res.method == "exact moments (A(t))" and not res.statistical
    assert res.ms_error_T["tuned"] <= res.ms_error_T["baseline"]
    assert res.ms_error_T["tuned"] == pytest.approx(again.exact.ms_error[-1].sum(), rel=1e-9)


def test_a_stiff_candidate_on_expressions_of_t_is_not_integrated_while_searching(
    examples, monkeypatch
):
    """The search's step cap is the exact objective's (MAX_STEPS): c(t) = 4.472(1 + t)^−0.51
    on the time-varying G1 at T = 10 needs about 25,000 steps (21 s, to find its moments
    grow without bound); it scores +∞ without a simulation. Its reported curve may take up
    to 5·MAX_STEPS."""
    from ntc_design.tune import objective
    from ntc_design.tune.objective import MAX_STEPS, objective_for

    top, spec, _ = load_scenario(examples / "scenarios" / "g1_tv.yaml")
    obj = objective_for(top, spec, 10.0)
    gain = PowerGain(4.472, 1.0, 0.51)
    assert MAX_STEPS < obj._steps(gain) < 5 * MAX_STEPS

    def no_run(*a, **k):
        raise AssertionError("simulated a candidate above the search's step cap")

    monkeypatch.setattr(objective, "simulate", no_run)
    assert obj.value(gain) == math.inf and "too stiff" in obj.skipped[gain.text]
    assert obj.seconds(gain) == 0.0 and obj.seconds(gain, accurate=True) > 0


def test_the_digital_objective_at_any_period_is_the_sampled_recursion(g1, theta):
    """DigitalObjective.moments at a period other than the scenario's (what ``--period
    auto`` evaluates) equals the recursion written out: e_{k+1} = e_k − h c_k L_B e_k
    with the second moment propagated by hand (D = 0, one mode)."""
    from ntc_design.protocol.digital import Digital
    from ntc_design.tune.objective import DigitalObjective
    from ntc_design.tune.period import period_curve

    x0 = np.linspace(-1.0, 1.0, g1.n * g1.dim)
    spec = SimulationSpec.build(
        theta, noise=NoiseModel(0.4, 0.3), initial=x0, T=1.0, digital={"period": 0.5}
    )
    obj = DigitalObjective(g1, spec, 1.0)
    gain = PowerGain(1.0, 1.0, 1.0)
    h = 0.25  # not the scenario's 0.5
    dm = obj.moments(gain, np.array([1.0]), Digital(h))
    pm = obj.prepared(None)[0]
    s = pm.systems[0]
    n, d = s.n_agents, s.dim
    lap = s.lap_b.toarray()
    # edge j -> i: g_e = e_i ⊗ σ|A_ij| 1_d, G_e e = e_i ⊗ |A_ij| F (e_j − e_i)
    gs, big_gs = [], []
    for e, (i, j) in enumerate(zip(s.dst.tolist(), s.src.tolist(), strict=True)):
        gv = np.zeros(n * d)
        gv[i * d : (i + 1) * d] = s.g_edge[e]
        sel = np.zeros((n, n))
        sel[i, j], sel[i, i] = 1.0, -1.0
        gs.append(gv)
        big_gs.append(np.kron(sel, s.abs_w[e] @ s.fmat))
    m = np.outer(pm.eps0, pm.eps0)
    for k in range(4):
        c = float(gain(np.array([k * h]))[0])
        a = np.eye(n * d) - h * c * lap
        noise = sum(np.outer(g, g) + big @ m @ big.T for g, big in zip(gs, big_gs, strict=True))
        m = a @ m @ a.T + c * c * h * noise
    assert dm.moments.ms_error[-1].sum() == pytest.approx(np.trace(m), rel=1e-10)
    # the period search evaluates the same objective: its curve at h is this number
    final, _ = period_curve(g1, spec.replace(gain=gain.text), 1.0, 0, np.array([h]))[0]
    assert final == pytest.approx(np.trace(m), rel=1e-10)
