"""Tests of :mod:`ntc_design.certify.loss`: the mean matrix, the factors, the inequality's
matrix against a dense NumPy construction from the weights, the plan it proves, and the
exact offset against the floating-point solve."""

from fractions import Fraction

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.digital import edge_noises, prove_psd
from ntc_design.certify.loss import (
    EXACT_OFFSET_MAX_ND,
    edge_laplacian,
    exact_offset,
    factors,
    loss_edges,
    loss_ms_matrix,
    mean_laplacian,
    offset_value,
    plan_loss,
)
from ntc_design.model.paper import THETA
from ntc_design.rigorous.exact import Dyadic
from ntc_design.rigorous.floatmat import FloatMat
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.loss import mean_offset
from ntc_design.simulate.system import mode_system


@pytest.fixture(scope="module")
def g1_parts(g1):
    des = nd.design(g1, THETA, thresholds=False)
    loss = {k: 0.05 * (1 + m % 5) for m, k in enumerate(g1.edges)}
    return g1, des, des.grounded_laplacian(), loss_edges(g1, loss), loss


def _dense(g1, des, loss, p, alpha, kappa, h, policy):
    """The inequality's matrix written out from the weights, δ and B."""
    n, d = 21, 3
    ground = np.zeros((n, n))
    for i, b in des.B.items():
        ground[i * d : i * d + d, i * d : i * d + d] = des.delta * np.asarray(b)
    lbar, s, nbar = ground.copy(), np.zeros((n, n)), np.zeros((n, n))
    for i, j in g1.edges:
        a, ab = g1.weight(i, j), g1.abs_weight(i, j)
        le = np.zeros((n, n))
        le[i * d : i * d + d, i * d : i * d + d] = ab
        le[i * d : i * d + d, j * d : j * d + d] = -a
        q = 1 - loss[(i, j)]
        mean, var, sq = (q, q * (1 - q), q) if policy == "skip" else (1, (1 - q) / q, 1 / q)
        lbar += mean * le
        s += var * le.T @ p @ le
        g = np.zeros((n, n))
        g[i * d : i * d + d, j * d : j * d + d] = 0.3 * ab
        g[i * d : i * d + d, i * d : i * d + d] = -0.3 * ab
        nbar += sq * g.T @ p @ g
    mu = 2 if policy == "skip" else 1
    m = p @ lbar + lbar.T @ p
    return m - alpha * p - kappa * (h * (lbar.T @ p @ lbar + 2 * s) + mu * nbar)


@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_matrix_is_the_written_out_inequality(g1_parts, policy):
    g1, des, lap, edges, loss = g1_parts
    rng = np.random.default_rng(2)
    a = rng.normal(size=(21, 21))
    p = a @ a.T + 21 * np.eye(21)
    noises = edge_noises(g1, 0.3 * np.eye(3), 0.4)
    got = loss_ms_matrix(FloatMat.of(p), FloatMat.of(lap), edges, noises, 3, 0.3, 0.2, 0.1, policy)
    want = _dense(g1, des, loss, p, 0.3, 0.2, 0.1, policy)
    assert got.val == pytest.approx(want, rel=1e-9, abs=1e-9 * np.abs(want).max())


def test_the_mean_matrix_and_the_factors(g1_parts):
    g1, _, lap, edges, _ = g1_parts
    lbar = mean_laplacian(lap, edges, 21, 3, "skip")
    want = lap - sum(e.p * edge_laplacian(e, 21, 3) for e in edges)
    assert lbar == pytest.approx(want, abs=1e-15)
    assert mean_laplacian(lap, edges, 21, 3, "rescale") is lap
    exact = mean_laplacian(Dyadic.of(lap), edges, 21, 3, "skip")
    assert np.array(exact.num, dtype=float) / 2.0**exact.exp == pytest.approx(want, abs=1e-14)
    for p in (0.1, 0.3, 0.7):
        q = 1 - Fraction(p)
        var, sq = factors(p, "rescale")
        assert Fraction(var) >= (1 - q) / q and Fraction(sq) >= 1 / q
        assert float((1 - q) / q) == pytest.approx(var, rel=1e-15)
        var, sq = factors(p, "skip")
        assert Fraction(var) >= q * (1 - q) and Fraction(sq) >= q


@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_plan_is_proven_exactly(g1_parts, policy):
    g1, _, lap, edges, _ = g1_parts
    noises = edge_noises(g1, 0.3 * np.eye(3), 0.4)
    pl = plan_loss(lap, edges, noises, 3, 0.1, policy)
    assert pl is not None and pl.alpha > 0 and pl.kappa > 0
    m = loss_ms_matrix(
        Dyadic.of(pl.p), Dyadic.of(lap), edges, noises, 3, pl.alpha, pl.kappa, 0.1, policy
    )
    assert prove_psd(m).holds
    # a level 10 % above κ is not proven
    over = loss_ms_matrix(
        Dyadic.of(pl.p), Dyadic.of(lap), edges, noises, 3, pl.alpha, 1.1 * pl.kappa, 0.1, policy
    )
    assert not prove_psd(over).holds


def test_the_exact_offset_is_the_mean_limit(g1, g1_parts):
    _, des, lap, edges, loss = g1_parts
    norm2 = exact_offset(lap, edges, THETA, 3)
    s = mode_system(des, NoiseModel(0.4, 0.3))
    p = np.array([loss[(int(i), int(j))] for i, j in zip(s.dst, s.src, strict=True)])
    want = np.linalg.norm(mean_offset(s, THETA, p, "skip"))
    assert offset_value(norm2) == pytest.approx(want, rel=1e-12)
    uniform = loss_edges(g1, {k: 0.1 for k in g1.edges})
    assert offset_value(exact_offset(lap, uniform, THETA, 3)) == pytest.approx(0.14332, abs=1e-5)
    assert exact_offset(lap, loss_edges(g1, {}), THETA, 3) == 0
    big = np.eye(EXACT_OFFSET_MAX_ND + 3)
    assert exact_offset(big, [], np.ones(3), 3) is None
    assert exact_offset(np.zeros((3, 3)), [], np.ones(3), 3) is None
