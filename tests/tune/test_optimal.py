"""Tests of :mod:`ntc_design.tune.optimal`."""

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import minimize

from ntc_design.errors import InputError
from ntc_design.gain.schedule import ScheduleGain, join_tail
from ntc_design.simulate.driver import prepare_modes
from ntc_design.tune import BASELINE, ExactObjective, PowerGain
from ntc_design.tune.optimal import ScheduleProblem, optimise_schedule


@pytest.fixture(scope="module")
def problem(g1, g1_spec):
    def build(horizon):
        pm = prepare_modes(g1, g1_spec.replace(T=horizon, method="exact"), lambda t: 1 + 0 * t)
        return ScheduleProblem(pm, horizon)

    return build


# -- the transcription and its gradient -----------------------------------------------------


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


def _independent_problem(pm, horizon, pieces):
    """tr S(T) for piecewise-constant c on ``pieces`` equal pieces, each propagated by the
    matrix exponential of the moment equation on S's upper triangle (built here from
    MomentRhs, not from the optimiser's operators)."""
    from ntc_design.simulate.moments import MomentRhs

    rhs = MomentRhs(pm.systems[0], pm.n, pm.d)
    nd_ = pm.n * pm.d
    iu = np.triu_indices(nd_)
    ns = iu[0].size
    a1 = np.empty((ns, ns))
    a2 = np.empty((ns, ns))
    for k, (i, j) in enumerate(zip(*iu, strict=True)):
        e = np.zeros((nd_, nd_))
        e[i, j] = e[j, i] = 1.0
        le = rhs.l @ e
        a1[:, k] = -(le + le.T)[iu]
        a2[:, k] = (rhs.noise(e) - rhs.q)[iu]
    s0 = np.append(np.outer(pm.eps0, pm.eps0)[iu], 1.0)
    diag = iu[0] == iu[1]
    h = horizon / pieces

    def value(x):
        s = s0
        for c in np.exp(x):
            m = np.zeros((ns + 1, ns + 1))
            m[:ns, :ns] = c * a1 + c * c * a2
            m[:ns, ns] = c * c * rhs.q[iu]
            s = expm(h * m) @ s
        v = float(s[:ns][diag].sum())
        return v if np.isfinite(v) else 1e30

    return value


@pytest.mark.slow
def test_optimum_is_within_3_percent_of_an_independent_optimum(problem, g1, g1_spec):
    """The independent optimum: 6 constant pieces propagated by matrix exponentials,
    L-BFGS-B with finite differences from c = 1. The continuous schedule on finer pieces
    is at least as good, and within 3 %."""
    horizon = 2.0
    sol = optimise_schedule(problem(horizon), BASELINE, levels=(10, 20, 40))
    pm = prepare_modes(g1, g1_spec.replace(T=horizon, method="exact"), lambda t: 1 + 0 * t)
    value = _independent_problem(pm, horizon, 6)
    r = minimize(
        value, np.zeros(6), method="L-BFGS-B", bounds=[(-6, 1.5)] * 6, options={"eps": 1e-6}
    )
    assert sol.value <= r.fun * (1 + 1e-4)
    assert sol.value >= 0.97 * r.fun


def test_optimum_is_below_an_independent_piecewise_constant_evaluation(problem, g1, g1_spec):
    horizon = 2.0
    prob = problem(horizon)
    sol = optimise_schedule(prob, BASELINE, levels=(10, 20, 40))
    pm = prepare_modes(g1, g1_spec.replace(T=horizon, method="exact"), lambda t: 1 + 0 * t)
    value = _independent_problem(pm, horizon, 8)
    mid = np.linspace(0, horizon, 17)[1::2]
    near = value(np.log(np.interp(mid, sol.t, sol.c)))
    # 8 constant pieces near the optimum, by matrix exponentials: no better, within 3 %
    assert sol.value <= near * (1 + 1e-6)
    assert sol.value >= near * 0.97
    # 1/(1 + t) sampled the same way is far worse
    assert value(np.log(1 / (1 + mid))) > 1.5 * sol.value
    # and re-evaluated independently, the returned schedule gives the reported value
    sched = ScheduleGain(sol.t, sol.c, tail=join_tail(horizon, float(sol.c[-1])))
    again = ExactObjective(g1, g1_spec, horizon).curve(sched, None).final
    assert again == pytest.approx(sol.value, rel=1e-3)
    assert sol.optimality < 1e-3
    assert [lv.pieces for lv in sol.levels][:2] == [10, 20]


def test_peak_bound_is_kept(problem):
    prob = problem(1.5)
    free = optimise_schedule(prob, BASELINE, levels=(10,))
    bound = 0.5 * (free.peak[0] + prob.initial)
    assert free.peak[0] > bound  # the bound binds
    held = optimise_schedule(prob, BASELINE, max_peak=bound, levels=(10,))
    assert held.peak[0] <= bound * (1 + 1e-6)
    assert held.value >= free.value * (1 - 1e-6)  # a constraint cannot help


@pytest.mark.hostile
def test_a_plan_too_large_is_refused_before_it_is_made(problem):
    prob = problem(10.0)
    with pytest.raises(InputError, match="RK4 steps would store"):
        prob.plan(np.full(11, 1e6))  # about 1e14 steps: refused from the count alone


def test_max_gain_binds_and_says_so(problem):
    prob = problem(2.0)
    sol = optimise_schedule(prob, BASELINE, max_gain=0.5, levels=(10, 20))
    assert sol.binds and sol.c.max() <= 0.5 * (1 + 1e-9)


def test_power_law_polish_improves_the_coarse_search(problem):
    from ntc_design.tune.optimal import fit_power

    prob = problem(2.0)
    start = PowerGain(1.0, 1.0, 1.0)
    better = fit_power(prob, start, (0.51, 1.0), (0.05, 20.0), (0.1, 10.0))
    c = lambda g: g(np.linspace(0, 2, 401))  # noqa: E731
    v0 = prob.forward(c(start), prob.plan(c(start)), False).value
    v1 = prob.forward(c(better), prob.plan(c(better)), False).value
    assert v1 < v0 and 0.51 <= better.gamma <= 1.0
