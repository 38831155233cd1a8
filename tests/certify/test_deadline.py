"""The proven figures at the deadline against independent computations: a written-out
NumPy recursion of the sampled protocol (with the partial step to T), simulate/digital.py's
exact moments, and SciPy's DOP853 on the continuous moment equations."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ntc_design.certify.deadline import deadline_bound, deadline_steps
from ntc_design.certify.deadline_subject import build_problem, initial_moment
from ntc_design.certify.digital import edge_noises
from ntc_design.protocol import design
from ntc_design.rigorous.exact import Dyadic

NOISE = {"sigma": 0.4, "f": 0.3, "sigma_edges": []}


@pytest.fixture(scope="module")
def g1_case(g1, theta):
    lap = design(g1, theta, 0.1).grounded_laplacian()
    x0 = np.linspace(-3.0, 3.0, g1.nd)
    return g1, theta, lap, x0


def _problem(case, t_end, period=None, delay=0, initial=None):
    top, theta, lap, x0 = case
    section = {
        "T": t_end,
        "period": period,
        "delay": delay,
        "gain": "1/(1+t)",
        "noise": NOISE,
        "initial": initial or {"x0": x0.tolist()},
    }
    modes = {"g1": (top, lap, np.zeros_like(lap), Dyadic.of(lap))}
    return build_problem(modes, None, section, theta)


def _g_matrices(top, lap):
    """Every edge's G_e (Nd×Nd) and g_e, written out: G_e e = e_i ⊗ K_e (e_j − e_i)."""
    d, nd = top.dim, lap.shape[0]
    out = []
    for e in edge_noises(top, 0.3 * np.eye(d), 0.4):
        g_mat = np.zeros((nd, nd))
        k = e.absw @ e.f
        g_mat[e.i * d : e.i * d + d, e.j * d : e.j * d + d] += k
        g_mat[e.i * d : e.i * d + d, e.i * d : e.i * d + d] -= k
        g_vec = np.zeros(nd)
        g_vec[e.i * d : e.i * d + d] = e.g
        out.append((g_mat, g_vec))
    return out


def _float_sampled(case, t_end, h, delay):
    """E‖e(t)‖² at every sample and at T by the sampled protocol's moments, in floats."""
    top, theta, lap, x0 = case
    gs = _g_matrices(top, lap)
    e0 = x0 - np.tile(theta, top.n)
    z = {(a, b): np.outer(e0, e0) for a in range(delay + 1) for b in range(delay + 1)}
    k_full, s = deadline_steps(t_end, h)
    values = [np.trace(z[0, 0])]
    for k in range(k_full + 1):
        c = 1.0 / (1.0 + k * h)
        zdd = z[delay, delay]
        noise = sum(np.outer(g, g) + gm @ zdd @ gm.T for gm, g in gs)

        def second(step, z=z, c=c, zdd=zdd, noise=noise):
            return (
                z[0, 0]
                - step * c * (lap @ z[delay, 0] + z[0, delay] @ lap.T)
                + step**2 * c**2 * lap @ zdd @ lap.T
                + step**2 / h * c**2 * noise  # (s/√h)·c·ξ: the same normals as step k
            )

        if k == k_full:
            if s > 0:
                values.append(np.trace(second(s)))
            break
        new = {(0, 0): second(h)}
        for b in range(1, delay + 1):
            new[0, b] = z[0, b - 1] - h * c * lap @ z[delay, b - 1]
            new[b, 0] = new[0, b].T
        for a in range(1, delay + 1):
            for b in range(1, delay + 1):
                new[a, b] = z[a - 1, b - 1]
        z = new
        values.append(np.trace(z[0, 0]))
    return values


@pytest.mark.parametrize(("t_end", "delay"), [(1.0, 0), (1.05, 1), (0.93, 2)])
def test_sampled_bound_encloses_the_float_recursion(g1_case, t_end, delay):
    ref = _float_sampled(g1_case, t_end, 0.1, delay)
    got = deadline_bound(_problem(g1_case, t_end, 0.1, delay))
    assert ref[-1] <= got.ms_error_bound * (1 + 1e-12)
    assert got.ms_error_bound == pytest.approx(ref[-1], rel=1e-9)
    assert max(ref) <= got.peak_bound * (1 + 1e-12)
    assert got.peak_bound == pytest.approx(max(ref), rel=1e-9)  # convex in s: at an end


def test_sampled_bound_matches_simulate_digital(g1_case):
    from ntc_design.protocol.digital import Digital
    from ntc_design.simulate.digital import digital_grid, digital_moments
    from ntc_design.simulate.moments import PreparedModes
    from ntc_design.simulate.noise import NoiseModel
    from ntc_design.simulate.system import mode_system

    top, theta, lap, x0 = g1_case
    sys_ = mode_system(design(top, theta, 0.1), NoiseModel(0.4, 0.3))
    grid, _ = digital_grid(Digital(0.1, 1), 2.0, np.array([2.0]))
    modes = PreparedModes.of([sys_], x0 - np.tile(theta, top.n))
    ref = digital_moments(modes, grid, lambda t: 1 / (1 + t), 1)
    got = deadline_bound(_problem(g1_case, 2.0, 0.1, 1))
    assert got.ms_error_bound == pytest.approx(float(ref.moments.ms_error[-1].sum()), rel=1e-9)
    assert got.peak_bound == pytest.approx(ref.peak, rel=1e-9)


def test_continuous_enclosure_against_dop853(g1_case):
    top, theta, lap, x0 = g1_case
    gs = _g_matrices(top, lap)
    q = sum(np.outer(g, g) for _, g in gs)
    nd = lap.shape[0]

    def rhs(t, y):
        s = y.reshape(nd, nd)
        c = 1 / (1 + t)
        noise = q + sum(gm @ s @ gm.T for gm, _ in gs)
        return (-c * (lap @ s + s @ lap.T) + c * c * noise).ravel()

    e0 = x0 - np.tile(theta, top.n)
    t_eval = np.linspace(0, 0.5, 501)
    sol = solve_ivp(
        rhs, (0, 0.5), np.outer(e0, e0).ravel(), "DOP853", t_eval, rtol=1e-12, atol=1e-12
    )
    traces = np.einsum("iit->t", sol.y.reshape(nd, nd, -1))
    got = deadline_bound(_problem(g1_case, 0.5))
    assert traces[-1] <= got.ms_error_bound
    assert got.ms_error_bound <= 1.001 * traces[-1]
    assert traces.max() <= got.peak_bound <= 1.05 * traces.max()


def test_steps_snap_to_whole_periods():
    assert deadline_steps(10.0, 0.1) == (100, 0.0)
    k, s = deadline_steps(1.05, 0.1)
    assert k == 10 and s == pytest.approx(0.05)


def test_initial_distribution_uses_its_second_moment(theta):
    m = initial_moment({"mean": [1.0] * 6, "variance": [3.0] * 6}, theta, 2)
    e = np.ones(6) - np.tile(theta, 2)
    np.testing.assert_allclose(m, np.outer(e, e) + 3.0 * np.eye(6))
