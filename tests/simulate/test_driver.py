"""Tests of :mod:`ntc_design.simulate.driver`."""

import os

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    SimulationSpec,
    simulate,
)
from ntc_design.simulate.grid import build_grid
from tests.conftest import ROOT, X0
from tests.support.simulate import assert_mc_matches_exact, em_exact


def test_sparse_network_above_the_dense_sizes_simulates():
    top = random_network(3000, 3, seed=2)  # Nd = 9000: sparse design and sparse L_B
    res = simulate(top, [1, 2, -1], T=2e-4, dt=1e-5, paths=4, method="mc", save_every=1e-4)
    ms = res.mc.mean
    assert ms.shape == (3, 3000) and np.all(np.isfinite(ms))
    # zero initial state: the error starts at ‖θ‖² = 6 for every agent; the informed agents
    # (δ in the hundreds) already move towards θ
    assert np.allclose(ms[0], 6.0)
    assert ms[-1].sum() < 0.99 * ms[0].sum()


@pytest.fixture(scope="module")
def sw():
    return nd.load(ROOT / "examples" / "switching.yaml")


def test_g1_monte_carlo_agrees_with_exact(g1):
    """MC against the exact moments of its own Euler–Maruyama recursion (no
    discretisation gap: a sharp test), and the recursion against the continuous moments
    (the O(dt) bias of Euler–Maruyama, visible for agent 3 at dt = 1e-3)."""
    res = simulate(g1, THETA, T=2.0, dt=1e-3, paths=2000, seed=3, initial=X0, save_every=0.1)
    assert res.mc.count == 2000
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em)
    np.testing.assert_allclose(res.mc.mean[0], res.exact.ms_error[0], rtol=1e-9)
    gap = np.abs(em[1:] - res.exact.ms_error[1:]) / res.exact.ms_error[1:]
    assert 1e-5 < np.max(gap) < 0.02  # O(dt) bias: present, and small
    fine = simulate(g1, THETA, T=2.0, dt=2.5e-4, paths=2000, seed=3, initial=X0, save_every=0.1)
    assert_mc_matches_exact(fine)


def test_switching_agreement_and_switch_times(sw):
    res = simulate(sw, THETA, T=1.0, dt=1e-3, paths=2000, seed=5, initial=X0, save_every=0.05)
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em)
    assert np.max(np.abs(em[1:] / res.exact.ms_error[1:] - 1)) < 0.02
    segs = sw.segments(1.0)
    names = list(sw.modes)
    grid = build_grid(1.0, 1e-3, [0, 1.0], [(a, b, names.index(m)) for a, b, m in segs])
    for a, _, m in segs:
        k = int(np.argmin(np.abs(grid.t - a)))
        assert grid.t[k] == a  # every switching instant is a grid point, exactly
        assert names[grid.mode[k]] == m
    starts = grid.t[:-1]
    assert [names[m] for m in grid.mode[::7]] == [sw.mode_at(t) for t in starts[::7]]


def test_time_varying_topology_simulates(g1):
    w = lambda t: np.diag([2.0 + np.sin(t), 1.0, 1.5])  # noqa: E731
    tv = nd.TimeVaryingTopology(
        (1, 2, 3), 3, {(1, 2): lambda t: -w(t), (2, 3): w, (3, 1): lambda t: np.eye(3)}
    )
    res = simulate(tv, THETA, T=1.0, paths=400, seed=1, save_every=0.25, resample=0.1, workers=1)
    assert len(res.designs) == 10 and res.exact is not None
    assert_mc_matches_exact(res, max_outside=0.25)


def test_spec_and_keywords_give_identical_runs(g1):
    kw = dict(T=0.2, dt=1e-3, paths=20, seed=2, save_every=0.1, workers=1)
    a = simulate(g1, THETA, **kw)
    b = simulate(g1, SimulationSpec.build(THETA, **kw))
    assert np.array_equal(a.mc.mean, b.mc.mean)
    assert np.array_equal(a.exact.ms_error, b.exact.ms_error)


@pytest.mark.hostile
def test_resample_on_a_fixed_topology_is_refused(g1):
    with pytest.raises(InputError, match=r"^resample: applies only"):
        simulate(g1, THETA, T=0.1, paths=2, resample=0.05)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "durations, needle",
    [
        ([1e308, 1e308], "overflows to infinity"),
        ([1.0, 1e-300], "schedule[1].duration"),
        ([1e-6, 1e-6], "switching segments"),
    ],
)
def test_switching_schedule_limits(durations, needle):
    g1 = nd.load(ROOT / "examples" / "g1.yaml")
    # a degenerate schedule is refused by the model itself, a too fine one by the budget
    with pytest.raises(InputError) as exc:
        sw = nd.SwitchingTopology({"a": g1, "b": g1}, tuple(zip("ab", durations, strict=True)))
        simulate(sw, THETA, T=100.0, paths=2, method="exact")
    assert needle in str(exc.value)


def test_workers_capped_at_the_machine(g1):
    res = simulate(g1, THETA, T=0.05, paths=4, block_size=2, save_every=0.05, workers=4096)
    assert res.parameters["workers"] == (os.cpu_count() or 1)
    assert any("workers: 4096 asked" in n for n in res.notes)
    one = simulate(g1, THETA, T=0.05, paths=4, block_size=2, save_every=0.05, workers=1)
    assert np.array_equal(res.mc.mean, one.mc.mean)


def test_check_stepping_says_what_simulate_says_before_any_path(g1):
    from ntc_design.errors import InputError
    from ntc_design.protocol.digital import Digital
    from ntc_design.simulate import SimulationSpec
    from ntc_design.simulate.driver import check_stepping, simulate

    ok = SimulationSpec.build([1, 2, -1], T=1.0, dt=1e-3, paths=2, workers=1, method="mc")
    got = check_stepping(g1, ok)
    # G1's mean-square limit of c·h at c = 1 is 0.0573 (check_step_size's documented value)
    assert got is not None and got.ratio == pytest.approx(1e-3 / 0.0573, rel=2e-3)
    assert got.warning is None
    bad = ok.replace(gain="200/(1+t)")  # c(0)·h = 0.2 past 2/ρ(L_B) = 0.137
    with pytest.raises(InputError) as guard:
        check_stepping(g1, bad)
    with pytest.raises(InputError) as run:
        simulate(g1, spec=bad)
    assert str(guard.value) == str(run.value) and "unstable" in str(guard.value)
    assert check_stepping(g1, ok.replace(digital=Digital(0.1))) is None  # no step to choose
