"""Tests of :mod:`ntc_design.simulate.moments`."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    NoiseModel,
    moments,
    simulate,
    system,
)
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.moments import PreparedModes, em_moments, exact_moments
from ntc_design.simulate.prepare import prepare_modes
from ntc_design.simulate.spec import SimulationSpec
from ntc_design.simulate.system import mode_system
from tests.conftest import X0
from tests.support.moments_math import SIGMA, F, _moment_rhs


def test_implicit_recursion_moments_match_a_dense_reference(g1_system):
    """em_moments(implicit) against R (S + h(GGᵀ + Σ G_e S G_eᵀ)) Rᵀ written densely."""
    des, s = g1_system
    grid = build_grid(0.5, 0.05, [0, 0.25, 0.5])
    eps0 = X0 - np.tile(THETA, 7)
    got = em_moments(PreparedModes.of([s], eps0), grid, lambda t: 1 / (1 + t), scheme="implicit")
    lap, g = s.lap_b.toarray(), s.g.toarray()
    m, sm = eps0.copy(), np.outer(eps0, eps0)
    for k in range(grid.n_steps):
        c, h = 1 / (1 + grid.t[k]), grid.h[k]
        r = np.linalg.inv(np.eye(21) + c * h * lap)
        noise = g @ g.T
        for i, j, kk in s.h_blocks:
            gm = np.zeros((21, 21))
            gm[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += kk
            gm[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] -= kk
            noise += gm @ sm @ gm.T
        sm = r @ (sm + c * c * h * noise) @ r.T
        m = r @ m
    np.testing.assert_allclose(got.second, sm, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got.mean[-1], m, rtol=1e-10, atol=1e-12)


def test_sparse_moments_equal_dense_moments(g1, monkeypatch):
    """Moments on the edge-assembled sparse L_B equal those on the design's dense L_B."""
    des = nd.design(g1, THETA, thresholds=False)
    segs = [(0.0, 2.0, 0)]
    eps0 = X0 - np.tile(THETA, 7)
    gain = lambda t: 1 / (1 + t)  # noqa: E731
    a = exact_moments(
        PreparedModes.of([mode_system(des, NoiseModel())], eps0, segs), gain, [0, 1, 2]
    )
    monkeypatch.setattr(system, "DENSE_LB_MAX_ND", 0)
    b = exact_moments(
        PreparedModes.of([mode_system(des, NoiseModel())], eps0, segs), gain, [0, 1, 2]
    )
    np.testing.assert_allclose(a.ms_error, b.ms_error, rtol=1e-12)
    np.testing.assert_allclose(a.second, b.second, rtol=1e-10, atol=1e-14)


def test_moments_above_the_limit_are_refused_before_running(g1, monkeypatch):
    monkeypatch.setattr(moments, "MOMENTS_MAX_ND", 20)
    with pytest.raises(nd.InputError, match=r"exact moments at Nd = 21 need about .* GB"):
        simulate(g1, THETA, T=0.1, paths=4, method="both")


@pytest.mark.parametrize(
    "gain_text, gain",
    [("1/(1+t)", lambda t: 1 / (1 + t)), ("(1+t)^(-1/3)", lambda t: (1 + t) ** (-1 / 3))],
)
def test_exact_moments_match_an_independent_integration(g1, theta, gain_text, gain):
    rng = np.random.default_rng(np.random.SeedSequence(7))
    x_init = rng.uniform(-3, 3, size=g1.n * g1.dim)
    saves = np.linspace(0.0, 3.0, 13)
    res = simulate(
        g1,
        theta,
        method="exact",
        gain=gain_text,
        noise=NoiseModel(SIGMA, F),
        initial=x_init,
        T=3.0,
        save_times=saves.tolist(),
    )
    des = next(iter(res.designs.values()))
    eps0 = x_init - np.tile(theta, g1.n)
    y0 = np.concatenate([eps0, np.outer(eps0, eps0).ravel()])
    sol = solve_ivp(
        _moment_rhs(g1, des.grounded_laplacian(), gain),
        (0.0, 3.0),
        y0,
        t_eval=saves,
        rtol=1e-10,
        atol=1e-12,
        method="DOP853",
    )
    assert sol.success
    nd_ = g1.n * g1.dim
    for k in range(saves.size):
        s = sol.y[nd_:, k].reshape(nd_, nd_)
        per_agent = np.einsum("iaia->i", s.reshape(g1.n, g1.dim, g1.n, g1.dim))
        np.testing.assert_allclose(res.exact.ms_error[k], per_agent, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(
            res.exact.mean[k], sol.y[:nd_, k], rtol=1e-6, atol=1e-9 * np.abs(eps0).max()
        )


@pytest.mark.filterwarnings("ignore::ntc_design.AssumptionWarning")
def test_scalar_pair_has_the_closed_form():
    """Two agents, d = 1: 2 listens to 1 through an antagonistic edge (so 2 is informed),
    1 listens to 2 cooperatively. Without noise the moments are m(t) = exp(−L_B t)ε(0) and
    S = m mᵀ in closed form (c = 1); the RK4 error is measured against the scale of S(0)."""
    from scipy.linalg import expm

    top = nd.Topology.from_edges(2, 1, [(1, 2, -np.eye(1) * 2.0), (2, 1, np.eye(1) * 1.0)])
    times = [0.0, 0.5, 1.0, 2.0]
    res = simulate(
        top, [1.0], method="exact", gain="1", noise=NoiseModel(0.0, 0.0), initial=[0.0, 0.0],
        T=2.0, save_times=times,
    )  # fmt: skip
    lap_b = next(iter(res.designs.values())).grounded_laplacian()
    eps0 = -np.ones(2)  # x(0) = 0, θ = 1
    for k, t in enumerate(times):
        m = expm(-lap_b * t) @ eps0
        np.testing.assert_allclose(res.exact.mean[k], m, rtol=0, atol=1e-5)
        np.testing.assert_allclose(res.exact.ms_error[k], m**2, rtol=0, atol=1e-4)


def test_exact_curves_decrease_toward_zero(g1):
    res = simulate(
        g1, THETA, T=1000.0, initial=X0, method="exact", save_times=[1, 10, 100, 500, 1000]
    )
    tot = res.exact.ms_error.sum(axis=1)
    assert np.all(np.diff(tot[1:]) < 0)
    assert tot[-1] < 0.02 * tot[2] and tot[-1] < 0.05
    # E‖ε‖² ~ const·c(t) for c = 1/(1+t): the product settles
    ratio = tot[-2:] * (1 + np.array([500.0, 1000.0]))
    assert ratio[1] == pytest.approx(ratio[0], rel=0.1)


def test_exact_moments_match_dop853(g1):
    """Independent integration of the vectorised moment ODE with SciPy's DOP853."""
    des = nd.design(g1, THETA, thresholds=False)
    sysm = mode_system(des, NoiseModel(0.4, 0.3))
    nd_ = 21
    eye = np.eye(nd_)
    lop = -(np.kron(des.grounded_laplacian(), eye) + np.kron(eye, des.grounded_laplacian()))
    nop = np.zeros((nd_ * nd_, nd_ * nd_))
    for i, j, k in sysm.h_blocks:
        h = np.zeros((nd_, nd_))
        h[i * 3 : (i + 1) * 3, j * 3 : (j + 1) * 3] += k
        h[i * 3 : (i + 1) * 3, i * 3 : (i + 1) * 3] -= k
        nop += np.kron(h, h)
    q = (sysm.g @ sysm.g.T).toarray().ravel()
    eps0 = X0 - np.tile(THETA, 7)

    def rhs(t, v):
        c = 1 / (1 + t)
        return c * (lop @ v) + c * c * (nop @ v + q)

    sol = solve_ivp(
        rhs,
        (0, 20),
        np.outer(eps0, eps0).ravel(),
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        t_eval=[1, 5, 20],
    )
    ref = np.array(
        [
            [np.trace(s.reshape(21, 21)[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]) for i in range(7)]
            for s in sol.y.T
        ]
    )
    res = simulate(g1, THETA, T=20.0, initial=X0, method="exact", save_times=[1, 5, 20])
    np.testing.assert_allclose(res.exact.ms_error[1:], ref, rtol=1e-6)


def test_vanishing_gain_stays_away(g1):
    """c = (1+t)^-2: ∫c = 1, so the exact error freezes at a positive level."""
    res = simulate(
        g1, THETA, gain="(1+t)^-2", T=100.0, initial=X0, method="exact", save_times=[10, 50, 100]
    )
    tot = res.exact.ms_error.sum(axis=1)
    assert tot[-1] > 1.0
    assert tot[-1] == pytest.approx(tot[-2], rel=0.05)


@pytest.mark.parametrize("seed, d, f", [(1, 1, 0.3), (2, 2, 0.3), (3, 3, 0.5), (4, 2, 0.0)])
def test_the_noise_operator_is_the_sum_over_edges(seed, d, f):
    """𝓐₂ vec(S) against Σ_e K_e (S_jj − S_ji − S_ij + S_ii) K_eᵀ in block (i, i), summed
    edge by edge in plain loops; and the operator path of ``noise`` against the gathers."""
    from ntc_design.simulate.moments import MomentRhs
    from tests.conftest import random_topology

    top = random_topology(seed, n=6, d=d)
    des = nd.design(top, np.linspace(1.0, -1.0, d), thresholds=False)
    s = mode_system(des, nd.simulate.NoiseModel(0.4, f))
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    m = rng.normal(size=(s.nd, s.nd))
    big_s = m @ m.T
    want = np.zeros_like(big_s)
    for i, j, k in s.h_blocks:
        b = {
            (p, q): big_s[p * d : (p + 1) * d, q * d : (q + 1) * d] for p in (i, j) for q in (i, j)
        }
        delta = b[j, j] - b[j, i] - b[i, j] + b[i, i]
        want[i * d : (i + 1) * d, i * d : (i + 1) * d] += k @ delta @ k.T
    rhs = MomentRhs(s, top.n, d)
    got = (rhs.noise_operator() @ big_s.ravel()).reshape(big_s.shape)
    scale = np.abs(want).max() or 1.0
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * scale)
    assert (rhs.a2.nnz == 0) == (f == 0.0)  # no multiplicative noise: an empty operator
    via_operator = rhs.noise(big_s)
    rhs.a2 = None  # the gathers the operator replaces at small Nd
    np.testing.assert_allclose(via_operator, rhs.noise(big_s), rtol=0, atol=1e-13 * scale)


def test_prepared_modes_of_systems_give_the_moments_of_the_prepared_run(g1, theta):
    """ε's moments do not depend on θ: modes built from the systems and ε(0) alone (θ
    taken as 0) give the prepared run's moments to the last bit, and carry N, d, ε(0)."""
    spec = SimulationSpec.build(theta, noise=NoiseModel(SIGMA, F), method="exact", T=2.0)
    gain = lambda t: 1 / (1 + t)  # noqa: E731
    pm = prepare_modes(g1, spec, gain)
    assert np.any(pm.theta != 0)
    by_hand = PreparedModes.of(pm.systems, pm.eps0, pm.segments)
    assert (by_hand.n, by_hand.d, by_hand.names) == (g1.n, g1.dim, pm.names)
    np.testing.assert_array_equal(by_hand.eps0, pm.eps0)
    saves = np.linspace(0.0, 2.0, 5)
    want = pm.moments(gain, saves)
    got = exact_moments(by_hand, gain, saves)
    np.testing.assert_array_equal(got.ms_error, want.ms_error)
    np.testing.assert_array_equal(got.second, want.second)
