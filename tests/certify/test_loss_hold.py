"""Tests of :mod:`ntc_design.certify.loss_hold`: the (e, η) model against the exact lossy
moments of :mod:`ntc_design.simulate.loss` (hold), the structural zero of G(0) in exact
arithmetic, and the step inequality the module derives, E V(e', u') <= (1 − α'hc)V(z) −
zᵀG(c)z + hc²γ, against the expectation over every arrival pattern written out here."""

import itertools
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design import Topology
from ntc_design.certify.digital import edge_noises
from ntc_design.certify.loss import loss_edges
from ntc_design.certify.loss_hold import (
    HoldOps,
    HoldPlan,
    coupling,
    functional,
    hold_matrices,
    hold_model,
    hold_rate,
    holds_in_floats,
    step_matrix,
)
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.rigorous.exact import Dyadic
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss import loss_moments
from ntc_design.simulate.system import mode_system

H = 0.1


def _f(a):
    return np.array(a, dtype=float)


@pytest.fixture(scope="module")
def tiny():
    """Three agents, d = 2, one antagonistic edge, losses 0.3, 0.1, 0.25."""
    top = Topology.from_edges(
        3,
        2,
        [
            (2, 1, np.array([[1.0, 0.2], [0.2, 0.5]])),
            (3, 2, -np.array([[0.8, 0.0], [0.0, 0.6]])),
            (1, 3, np.array([[0.7, 0.1], [0.1, 0.9]])),
        ],
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        des = nd.design(top, np.array([1.0, -0.5]), thresholds=False)
    losses = dict(zip(top.edges, (0.3, 0.1, 0.25), strict=True))
    edges = loss_edges(top, losses)
    noises = edge_noises(top, 0.2 * np.eye(2), 0.3)
    lap = np.asarray(des.grounded_laplacian())
    loud = hold_model(lap, edges, edge_noises(top, 4.0 * np.eye(2), 0.3), 2)
    return top, loud, lap, hold_model(lap, edges, noises, 2), losses


def _recursion(mo, eps0, gain, steps):
    """E[z zᵀ] of z = (e, η) written out from the model (η₀ = 0: y at the noiseless a(e₀))."""
    pi, gam, lap = _f(mo.pi), _f(mo.gam), _f(mo.lap)
    q, p = _f(mo.q), _f(mo.p)
    n, m, d = mo.n, mo.m, mo.d
    z = np.concatenate([eps0, np.zeros(m)])
    zz = np.outer(z, z)
    out = []
    for k in range(steps):
        out.append(zz)
        tau = H * gain(k * H)
        a = np.block(
            [
                [np.eye(n) - tau * lap, tau * pi * p],
                [tau * gam @ lap, (np.eye(m) - tau * gam @ pi) * p],
            ]
        )
        bn = np.vstack([tau * pi, np.eye(m) - tau * gam @ pi])
        new = a @ zz @ a.T
        for e in range(m // d):
            cols = slice(e * d, (e + 1) * d)
            hm = np.zeros((n + m, n + m))
            hm[:, n:][:, cols] = -bn[:, cols]
            new += p[e * d] * q[e * d] * hm @ zz @ hm.T
            kd, g = _f(mo.kd[e]), _f(mo.g[e])
            noise = (np.outer(g, g) + kd @ zz[:n, :n] @ kd.T) / H
            new += q[e * d] * bn[:, cols] @ noise @ bn[:, cols].T
        zz = new
    out.append(zz)
    return out


@pytest.mark.parametrize("p", [0.1, 0.3])
def test_the_model_is_the_exact_lossy_moments_of_hold_on_g1(g1, p):
    des = nd.design(g1, THETA, thresholds=False)
    s = mode_system(des, NoiseModel(sigma=0.4, f=0.3))
    eps0 = np.linspace(-3, 3, 21) - np.tile(THETA, 7)
    steps = 30
    grid, _ = digital_grid(Digital(H), H * steps, np.array([H * steps]))

    def gain(t):
        return 1 / (1 + np.asarray(t, dtype=float))

    got = loss_moments(s, grid, gain, eps0, THETA, 0, np.full(s.n_edges, p), "hold")
    edges = loss_edges(g1, {k: p for k in g1.edges})
    mo = hold_model(
        np.asarray(des.grounded_laplacian()), edges, edge_noises(g1, 0.3 * np.eye(3), 0.4), 3
    )
    zz = _recursion(mo, eps0, gain, steps)[-1]
    assert np.trace(zz[: mo.n, : mo.n]) == pytest.approx(np.trace(got.moments.second), rel=1e-12)


def _random_sr(mo, seed):
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((mo.n, mo.n))
    s = a @ a.T / mo.n + np.eye(mo.n)
    b = rng.standard_normal((mo.m, mo.m))
    r = b @ b.T / mo.m + 20 * np.eye(mo.m)
    return s, r


def test_g0_has_zero_error_rows_exactly_and_the_stated_form(tiny):
    *_, mo, _ = tiny
    s, r = _random_sr(mo, 1)
    ops = HoldOps("dyadic")
    g0 = step_matrix(ops, mo, Dyadic.of(s), Dyadic.of(r), 0.3, 1 / 16, 0.2, H, 0.0)
    assert np.all(g0.num[: mo.n, :] == 0) and np.all(g0.num[:, : mo.n] == 0)
    # G₀ = R − 𝔈(ΠᵀSΠ − P_dΠᵀSΠP_d + R), 𝔈(Y) = P_d Y P_d + diag_e(p_e q_e Y_ee)
    pi, p, q = _f(mo.pi), np.diag(_f(mo.p)), _f(mo.q)
    y = pi.T @ s @ pi - p @ pi.T @ s @ pi @ p + r
    mask = np.kron(np.eye(mo.m // mo.d), np.ones((mo.d, mo.d)))
    want = r - (p @ y @ p + np.diag(_f(mo.p) * q) @ (mask * y))
    assert np.allclose(g0.to_float()[mo.n :, mo.n :], want, rtol=1e-12, atol=1e-12)
    # the coupling is [[βS, SΠP_d], [·, R]]
    cp = coupling(HoldOps("float"), mo, s, r, 0.25)
    assert np.allclose(cp, np.block([[0.25 * s, s @ pi @ p], [(s @ pi @ p).T, r]]))
    q_all = functional(HoldOps("float"), mo, s, r)
    assert np.allclose(q_all - cp, np.block([[0.75 * s, 0 * pi], [0 * pi.T, 0 * r]]))


def _expected_next(mo, qm, e, u, tau):
    """E V(e', u') at a step with τ' = τ: the sum over every arrival pattern, the noise's
    expectation exactly (its covariance at the current e)."""
    pi, gam, lap = _f(mo.pi), _f(mo.gam), _f(mo.lap)
    q, p = _f(mo.q), _f(mo.p)
    n, m, d = mo.n, mo.m, mo.d
    eta = u * q / tau
    total = 0.0
    for chi in itertools.product((0, 1), repeat=m // d):
        x = np.repeat(np.array(chi, dtype=float), d)
        prob = float(np.prod([q[k * d] if c else p[k * d] for k, c in enumerate(chi)]))
        zeta = (1 - x) * eta
        e1 = (np.eye(n) - tau * lap) @ e + tau * pi @ zeta
        eta1 = (np.eye(m) - tau * gam @ pi) @ zeta + tau * gam @ lap @ e
        z1 = np.concatenate([e1, tau * eta1 / q])
        bn = np.vstack([tau * pi, tau * ((np.eye(m) - tau * gam @ pi) / q[:, None])]) * x
        cov = np.zeros((m, m))
        for k in range(m // d):
            kd, g = _f(mo.kd[k]), _f(mo.g[k])
            kde = kd @ e
            cov[k * d : (k + 1) * d, k * d : (k + 1) * d] = (
                np.outer(g, g) + np.outer(kde, kde)
            ) / H
        total += prob * (z1 @ qm @ z1 + np.trace(qm @ bn @ cov @ bn.T))
    return total


def _gamma(mo, qm, kappa):
    """γ = Σ_e q_e g_eᵀ M_ee g_e, M = (1 + hκ)(B₀ᵀQB₀ + hκB₁ᵀQB₁), written out."""
    pi, gam, q = _f(mo.pi), _f(mo.gam), _f(mo.q)
    b0 = np.vstack([pi, np.diag(1 / q)])
    b1 = np.vstack([0 * pi, -(gam @ pi) / q[:, None]])
    mm = (1 + H * kappa) * (b0.T @ qm @ b0 + H * kappa * b1.T @ qm @ b1)
    d = mo.d
    return sum(
        q[k * d] * _f(mo.g[k]) @ mm[k * d : (k + 1) * d, k * d : (k + 1) * d] @ _f(mo.g[k])
        for k in range(mo.m // d)
    )


@pytest.mark.parametrize("seed, loud", [(2, False), (3, False), (4, True), (5, True)])
def test_the_step_inequality_holds_for_every_state_against_the_enumeration(tiny, seed, loud):
    _, noisy, _, quiet, _ = tiny
    mo = noisy if loud else quiet  # loud: a multiplicative noise f = 4 that the bound must carry
    s, r = _random_sr(mo, seed)
    ops = HoldOps("float")
    qm = functional(ops, mo, s, r)
    assert np.linalg.eigvalsh(qm)[0] > 0
    alpha1, rho, kappa = 0.3, 1 / 16, 0.4
    rng = np.random.default_rng(10 + seed)
    for c in (kappa / 3, kappa):
        gm = step_matrix(ops, mo, s, r, alpha1, rho, kappa, H, c)
        gamma = _gamma(mo, qm, kappa)
        for _ in range(4):
            z = rng.standard_normal(mo.n + mo.m) * 3
            v = z @ qm @ z
            got = _expected_next(mo, qm, z[: mo.n], z[mo.n :], H * c)
            bound = (1 - alpha1 * H * c) * v - z @ gm @ z + H * c * c * gamma
            assert got <= bound + 1e-9 * (abs(v) + gamma), (c, got, bound)
        # and the bound is not loose by orders of magnitude along the state alone
        z = np.concatenate([rng.standard_normal(mo.n), np.zeros(mo.m)])
        got = _expected_next(mo, qm, z[: mo.n], z[mo.n :], H * c)
        assert got > 0.5 * ((1 - alpha1 * H * c) * (z @ qm @ z) - z @ gm @ z)


def test_the_rate_and_the_stated_matrices(tiny):
    *_, mo, _ = tiny
    from fractions import Fraction

    assert hold_rate(0.5, 0.25, 1.0) == Fraction(1, 2) - Fraction(1, 3)
    s, r = _random_sr(mo, 4)
    pl = HoldPlan(s, r, 0.3, 1 / 16, 0.25, 1.0, 1e-3, 0.1)
    names = [n for n, _ in hold_matrices(mo, s, r, pl, H, True)]
    assert names == ["S", "[[βS, SΠP_d], [·, R]]", "G₀", "G(κ)"]
    # an R far too small fails the coupling (CᵀS⁻¹C ⪯ βR is false)
    assert not holds_in_floats(mo, HoldPlan(s, 1e-6 * r, 0.3, 1 / 16, 0.25, 1.0, 1e-3, 0.1), H)
