"""Tests of :mod:`ntc_design.tune.schedule_problem`: the moment equations, RK4 forward and its discrete adjoint."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.gain.schedule import ScheduleGain, join_tail
from ntc_design.tune import ExactObjective


def test_adjoint_gradient_matches_finite_differences(problem):
    prob = problem(2.0)
    c = 1.0 / (1.0 + np.linspace(0, 2, 11))
    plan = prob.plan(c)
    st = prob.forward(c, plan)
    g = prob.adjoint(plan, st)
    for k in (0, 3, 10):
        e = np.zeros_like(c)
        e[k] = 1e-6
        fd = (
            prob.forward(c + e, plan, False).value - prob.forward(c - e, plan, False).value
        ) / 2e-6
        assert g[k] == pytest.approx(fd, rel=1e-6, abs=1e-9)
    # the peak aggregate's gradient too (sources on every step end)
    w = np.linspace(0, 1, plan.steps)
    gw = prob.adjoint(plan, st, sources=w)
    e = np.zeros_like(c)
    e[2] = 1e-6
    up, down = prob.forward(c + e, plan, False), prob.forward(c - e, plan, False)
    fd = (w @ up.traces - w @ down.traces) / 2e-6
    assert gw[2] == pytest.approx(fd, rel=1e-6)


def test_forward_agrees_with_the_independent_moment_integrator(problem, g1, g1_spec):
    """tr S(T) of the half-vectorised RK4 against the tuner's matrix RK4 (κ = 0.2)."""
    prob = problem(3.0)
    nodes = np.linspace(0, 3, 31)
    c = 1.3 / (0.5 + nodes)
    sched = ScheduleGain(nodes, c, tail=join_tail(3.0, float(c[-1])))
    st = prob.forward(c, prob.plan(c), store=False)
    ind = ExactObjective(g1, g1_spec, 3.0).curve(sched, None, points=31).final
    assert st.value == pytest.approx(ind, rel=2e-5)


def test_a_stable_constant_gain_decays_to_the_steady_state(problem):
    """c = 1.5 on G1 is mean-square stable: tr S(T) converges as the steps shrink (RK4,
    fourth order) and settles at its stationary level; no rounding mode grows (the
    shortcut (L S)ᵀ for S Lᵀ made one grow)."""
    prob = problem(3.0)
    c = np.full(31, 1.5)
    runs = [prob.forward(c, prob.plan(c, k), False) for k in (1.5, 0.75, 0.3)]
    vals = [r.value for r in runs]
    assert abs(vals[0] - vals[2]) <= 1e-9 * vals[2]
    tr = runs[2].traces  # it settles at the noise's stationary level, nothing grows
    assert abs(tr[-1] - tr[-50]) < 1e-3 * tr[-1] and tr.max() < 1.01 * tr[-1]


@pytest.mark.hostile
def test_a_plan_too_large_is_refused_before_it_is_made(problem):
    prob = problem(10.0)
    with pytest.raises(InputError, match="RK4 steps would store"):
        prob.plan(np.full(11, 1e6))  # about 1e14 steps: refused from the count alone
