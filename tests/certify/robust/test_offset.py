"""Tests of :mod:`ntc_design.certify.robust.offset`."""

import warnings
from fractions import Fraction

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.robust.offset import (
    OFFSET_MAX_ROWS,
    gains,
    gains_proven,
    input_float,
    offset_search,
)
from ntc_design.certify.robust.problem import dense_problem
from ntc_design.certify.robust.realise import climb as _climb
from ntc_design.certify.robust.realise import offset_of as _offset
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.protocol.lemma1 import coupling_matrix
from tests.support.robust import features, sample


def _fr(a):
    return np.vectorize(Fraction, otypes=[object])(np.asarray(a, dtype=float))


def _exact_lap_b(des):
    """L_B in rational arithmetic, from the weights, B and δ (no floating point)."""
    top, d = des.topology, des.topology.dim
    lap = np.full((top.nd, top.nd), Fraction(0), dtype=object)
    for (i, j), a in top.weights.items():
        lam = np.linalg.eigvalsh(a)
        s = 1 if lam[-1] > 0 else -1
        fa = _fr(a)
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= fa
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += s * fa
    return lap + Fraction(des.delta) * _fr(coupling_matrix(top, des.B))


@pytest.fixture(scope="module")
def small():
    des = nd.design(random_network(4, 2, seed=3), [1.0, -2.0], thresholds=False)
    return des, offset_search(des)


def test_the_rounding_bounds_hold_against_exact_arithmetic(small):
    des, s = small
    top = des.topology
    n = top.nd
    # u and r0
    x0 = (1.0 + 2.0 / des.delta) * des.theta
    u_ex = np.full(n, Fraction(0), dtype=object)
    for i, b in des.B.items():
        u_ex[i * top.dim : (i + 1) * top.dim] = Fraction(des.delta) * (_fr(b) @ _fr(x0))
    u, u_err, c = input_float(top, des.B, des.delta, des.theta)
    assert np.all(np.abs((u_ex - _fr(u)).astype(float)) <= u_err)
    lap_ex = _exact_lap_b(des)
    r0_ex = u_ex - lap_ex @ _fr(c)
    assert np.all(np.abs((r0_ex - _fr(s.r0)).astype(float)) <= s.r0_err)
    # Γ for a few multipliers and a witness Y
    rng = np.random.default_rng(np.random.SeedSequence(7))
    rad = np.full(s.m, 0.1)
    for _ in range(3):
        lam = rng.uniform(0.1, 10.0, s.m)
        gam = float(rng.uniform(0.5, 2.0))
        y = s.witness(gam, lam, rad, 1e-2)
        g, err = s.gamma_matrix(gam, lam, y, rad)
        k, d = g.shape[0], top.dim
        phi = np.full((k, k), Fraction(0), dtype=object)
        q = np.full((n, n), Fraction(0), dtype=object)
        for e in range(s.m):
            dm = np.zeros((n, d), dtype=object)
            dm[s.i[e] : s.i[e] + d] += np.eye(d, dtype=int)
            dm[s.j[e] : s.j[e] + d] -= int(s.s[e]) * np.eye(d, dtype=int)
            coef = Fraction(lam[e]) * Fraction(rad[e]) ** 2
            q = q + coef * (dm @ _fr(s.w[e]) @ dm.T)
        cf = _fr(c)
        phi[:n, :n] = -np.eye(n, dtype=int) - q
        phi[:n, -1] = phi[-1, :n] = -(q @ cf)
        phi[-1, -1] = Fraction(gam) - cf @ q @ cf
        for e in range(s.m):
            for t in range(d):
                phi[n + e * d + t, n + e * d + t] = Fraction(lam[e])
        a = np.full((n, k), Fraction(0), dtype=object)
        a[:, :n] = lap_ex
        for e in range(s.m):
            a[s.i[e] : s.i[e] + d, n + e * d : n + (e + 1) * d] = _fr(s.g[e])
        a[:, -1] = -r0_ex
        ay = a.T @ _fr(y)
        exact = phi + ay + ay.T
        gap = np.abs((exact - _fr(g)).astype(float))
        assert np.all(gap <= err)
        assert float(np.max(gap / np.maximum(err, 1e-300))) < 0.5  # the bound is not vacuous-tight


def test_gains_dominate_their_weights_even_when_singular():
    v = np.array([1.0, 2.0, 3.0]) / 7.0
    u = np.array([0.3, -1.0, 0.5])
    singular = np.stack([np.outer(v, v), np.outer(v, v) + np.outer(u, u), np.diag([1.0, 0.0, 2.0])])
    g = gains(singular)
    assert gains_proven(g, singular)
    for gi, w in zip(g, singular, strict=True):
        lam = np.linalg.eigvalsh(gi @ gi.T - w)
        assert lam[0] > 0 and lam[-1] < 1e-10 * np.linalg.norm(w)  # tight: ε·λ_max
    assert not gains_proven(0.999 * g, singular)  # G Gᵀ ⪰ W fails in some direction


@pytest.fixture(scope="module")
def mid():
    top = random_network(20, 3, seed=7)  # Nd = 60
    des = nd.design(top, THETA, thresholds=False)
    s = offset_search(des)
    rad = np.full(s.m, 0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return des, s, rad, s(rad)


def test_the_bound_is_sound_and_within_the_target(mid):
    des, s, rad, got = mid
    assert s.rows <= OFFSET_MAX_ROWS and got is not None
    gam, lam = got
    assert s.proven(gam, lam, rad)
    bound = np.sqrt(gam)
    rng = np.random.default_rng(np.random.SeedSequence(11))
    seen = [features(des, sample(des, 0.05, rng, "vertex" if k % 2 else "random"))[1]
            for k in range(30)]  # fmt: skip
    p = dense_problem(des)
    climbed = _offset(p, p.lap(_climb(p, rad, "offset", 3, 5)))
    assert max(seen) <= climbed <= bound
    assert bound / climbed < 1.5  # the target; measured 1.007
    # the reduced value matches the proven γ (λ bumped, γ rounded up: within 1 %)
    assert s.reduced(lam, rad) <= gam <= 1.01 * s.reduced(lam, rad)


def test_a_proof_is_refused_when_any_premise_fails(mid):
    des, s, rad, (gam, lam) = mid
    p = dense_problem(des)
    climbed = _offset(p, p.lap(_climb(p, rad, "offset", 3, 5)))
    assert not s.proven(0.99 * climbed**2, lam, rad)  # below an attained offset
    assert not s.proven(gam, np.zeros_like(lam), rad)
    assert not s.proven(gam, np.where(np.arange(lam.size) == 0, -1.0, lam), rad)
    assert not s.proven(gam, lam, 4.0 * rad)  # the multipliers do not cover a wider set
    assert not s.proven(gam, lam[:-1], rad[:-1])
    assert not s.proven(float("nan"), lam, rad)
    assert not s.proven(gam, lam * 2.0**300, rad)  # outside the span of the rounding bounds


def test_a_network_past_the_sdp_size_is_declined(small, monkeypatch):
    from ntc_design.certify.robust import offset as robust_offset

    _, s = small
    rad = np.full(s.m, 0.05)
    assert s(rad) is not None
    monkeypatch.setattr(robust_offset, "OFFSET_MAX_ROWS", s.rows - 1)
    assert s(rad) is None
