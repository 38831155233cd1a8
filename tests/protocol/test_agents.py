"""Tests of :mod:`ntc_design.protocol.agents`: the file edge order, the agents' tables, and
that the agent law summed over the edges is the model's recursion (drift, additive and
multiplicative noise) as the simulator's matrices state it."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.protocol.agents import agent_law, file_edges, make_law, mode_law
from ntc_design.protocol.digital import Digital, step_modes
from ntc_design.simulate.noise import NoiseModel
from ntc_design.simulate.system import mode_system


@pytest.fixture(scope="module")
def g1_design(g1, theta):
    return nd.design(g1, theta, thresholds=False)


def test_file_order_is_the_weights_order_without_zero_weights():
    eye = np.eye(2)
    top = nd.Topology.from_edges(
        3, 2, [(3, 1, eye), (1, 2, 0 * eye), (2, 3, -eye), (1, 3, 2 * eye), (3, 2, eye)]
    )
    assert file_edges(top) == [(0, 2), (2, 1), (2, 0), (1, 2)]
    assert list(top.edges) != file_edges(top)  # the simulator's order is sorted
    law = mode_law("m", top, [2], {2: eye}, 2.0, np.array([1.0, 1.0]), 0.4)
    assert [top.edges[k] for k in law.sorted_index] == file_edges(top)
    assert law.sign.tolist() == [1.0, -1.0, 1.0, 1.0]
    assert law.in_edges(2) == [1, 2] and law.in_edges(0) == [0]


def test_slots_hold_each_agent_once_in_file_order(g1_design):
    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3).modes[0]
    seen = []
    for agents, edges in law.slots:
        assert len(set(agents.tolist())) == agents.size
        assert (law.dst[edges] == agents).all()
        seen += edges.tolist()
    assert sorted(seen) == list(range(law.n_edges))
    for i in range(7):
        by_slot = [e[a == i][0] for a, e in law.slots if (a == i).any()]
        assert by_slot == law.in_edges(i)
    assert law.max_in_degree == 2  # agent 2 listens to 1 and 6


def test_the_law_summed_over_edges_is_the_model(g1_design):
    """h c Σ_e |A| m_e + h c (u_i − δ|B_i| xd_i), in exact arithmetic the recursion's
    increment: compared with the simulator's L_B, u, g_e and K_e to rounding."""
    f = np.array([[0.3, 0.1, 0.0], [0.1, 0.2, 0.0], [0.0, 0.0, 0.4]])
    sig = {(5, 6): 0.9}
    law = agent_law(g1_design, Digital(0.04), "1/(1+t)", 0.4, f, sig)
    ml = law.modes[0]
    s = mode_system(g1_design, NoiseModel(0.4, f, sig), "G1")
    rng = np.random.default_rng(5)
    xd = rng.normal(size=(7, 3))
    # drift: every normal zero
    acc = ml.u - np.einsum("iab,ib->ia", ml.bd, xd)
    for e in range(ml.n_edges):
        i, j = ml.dst[e], ml.src[e]
        acc[i] += ml.weight[e] @ (ml.sign[e] * xd[j] - xd[i])
    want = s.u - s.lap_b @ xd.ravel()
    np.testing.assert_allclose(acc.ravel(), want, rtol=1e-13, atol=1e-12)
    # noise: h c |A| (σ z1 + (F diff) z2)/√h = c √h (g_e z1 + K_e diff z2), edge by edge
    for e in range(ml.n_edges):
        k = ml.sorted_index[e]
        i, j = ml.dst[e], ml.src[e]
        assert s.dst[k] == i and s.src[k] == j
        np.testing.assert_allclose(ml.weight[e] @ (ml.sigma[e] * np.ones(3)), s.g_edge[k])
        diff = xd[j] - xd[i]
        np.testing.assert_allclose(ml.weight[e] @ (f @ diff), s.k_blocks[k] @ diff, rtol=1e-14)
    assert ml.sigma[list(zip(ml.src + 1, ml.dst + 1, strict=True)).index((5, 6))] == 0.9
    assert (ml.bd[[0, 3, 4, 5, 6]] == 0).all() and (ml.u[[0, 3, 4, 5, 6]] == 0).all()
    assert ml.informed == (1, 2) and ml.delta == g1_design.delta


def test_a_scalar_f_is_s_times_the_identity(g1_design):
    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3)
    assert (law.noise_f == NoiseModel(0.4, 0.3).f_matrix(3)).all()
    assert law.sqrt_period == 0.1**0.5 and law.n == 7 and law.dim == 3


def test_switching_steps_follow_the_shared_rule(switching_set, theta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        des = nd.design(switching_set, theta, thresholds=False)
    law = agent_law(des, Digital(0.013, 2), "1/(1+t)", 0.4, 0.3)
    k = 300
    t = np.arange(k) * 0.013
    names = list(switching_set.modes)
    assert (law.step_modes(k) == step_modes(switching_set.schedule, t, names, 0.013)).all()
    assert set(law.step_modes(k).tolist()) == {0, 1, 2}  # every mode is sampled
    edges = np.array([m.n_edges for m in law.modes])
    assert (law.normals_per_step(k) == 2 * edges[law.step_modes(k)]).all()
    assert law.schedule_period == float(sum(d for _, d in switching_set.schedule))
    assert law.schedule_ends == np.cumsum([d for _, d in switching_set.schedule]).tolist()
    assert law.schedule_ticks.ends == (20, 40, 60, 80, 100) and law.schedule_ticks.step == 13
    assert [law.mode_names[m] for m in law.schedule_modes] == [m for m, _ in law.schedule]


@pytest.mark.hostile
def test_refusals(g1_design):
    with pytest.raises(InputError, match=r"noise.sigma_edges: no edge 1->7 in G1"):
        agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3, {(1, 7): 0.2})
    with pytest.raises(InputError, match=r"noise.f: expected a scalar or a 3x3 matrix"):
        agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, np.eye(2))
    with pytest.raises(InputError, match=r"noise.f: a Python function cannot be exported"):
        agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, lambda x: x)
    ml = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3).modes
    top = g1_design.topology
    with pytest.raises(InputError, match=r"schedule\[0\]: unknown mode 'G9'"):
        make_law("x", top, g1_design.theta, ml, [("G9", 1.0)], Digital(0.1), "1", 0.3)


@pytest.mark.hostile
def test_a_topology_given_as_expressions_of_t_is_refused_by_one_check_everywhere(g1, g1tv, theta):
    """The digital protocol's refusal of A(t) is one function with one text: the
    simulator, the period search and the certificate say it alike (issue 48)."""
    from ntc_design.certify import certify
    from ntc_design.protocol.agents import NOT_SAMPLED, require_sampled
    from ntc_design.simulate import SimulationSpec, simulate
    from ntc_design.tune.period import longest_safe_period

    require_sampled(g1)  # one fixed topology: nothing to say
    with pytest.raises(InputError) as exc:
        require_sampled(g1tv, "digital")
    assert str(exc.value) == f"digital: {NOT_SAMPLED}"
    spec = SimulationSpec.build(theta, T=1.0, digital={"period": 0.1}, noise=NoiseModel(0.4, 0.3))
    refusals = []
    for call in (
        lambda: simulate(g1tv, spec=spec),
        lambda: longest_safe_period(g1tv, spec, 1.0),
        lambda: certify(g1tv, theta, gain="1/(1+t)", digital=Digital(0.1)),
    ):
        with pytest.raises(InputError) as exc:
            call()
        refusals.append(str(exc.value))
    # each in the caller's words: the spec's block, the search's period, certify's digital=
    assert refusals == [f"{name}: {NOT_SAMPLED}" for name in ("digital", "period", "digital")]
