"""Tests of :mod:`ntc_design.certify.loss_hold_plan`: c_true(hold) against the spectral
radius of the second-moment map built densely here (its columns by the map itself are not
used), and the SDP on a small network: κ > 0 and below c_true, every stated inequality in
floats and in verified floats."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design import Topology
from ntc_design.certify.digital import edge_noises
from ntc_design.certify.loss import loss_edges
from ntc_design.certify.loss_hold import hold_model, holds_in_floats
from ntc_design.certify.loss_hold_plan import (
    hold_ctrue,
    hold_spectral_radius,
    lowest,
    plan_hold,
)

H = 0.1


@pytest.fixture(scope="module")
def tiny():
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
    edges = loss_edges(top, dict(zip(top.edges, (0.3, 0.1, 0.25), strict=True)))
    lap = np.asarray(des.grounded_laplacian())
    return lap, hold_model(lap, edges, edge_noises(top, 0.2 * np.eye(2), 0.3), 2)


def _dense_radius(mo, c):
    """The second-moment map of (e, η) as a dense (W², W²) matrix: Kronecker products of
    the mean matrix, each edge's arrival term and its multiplicative noise."""
    f = lambda a: np.array(a, dtype=float)  # noqa: E731
    pi, gam, lap, q, p = f(mo.pi), f(mo.gam), f(mo.lap), f(mo.q), f(mo.p)
    n, m, d = mo.n, mo.m, mo.d
    w, tau = n + m, H * c
    a = np.block(
        [[np.eye(n) - tau * lap, tau * pi * p], [tau * gam @ lap, (np.eye(m) - tau * gam @ pi) * p]]
    )
    bn = np.vstack([tau * pi, np.eye(m) - tau * gam @ pi])
    op = np.kron(a, a)
    for e in range(m // d):
        b = np.zeros((w, w))
        b[:, n + e * d : n + (e + 1) * d] = bn[:, e * d : (e + 1) * d]
        op += p[e * d] * q[e * d] * np.kron(b, b)
        sel = np.zeros((w, w))
        sel[:, :n] = bn[:, e * d : (e + 1) * d] @ f(mo.kd[e])
        op += q[e * d] * np.kron(sel, sel) / H
    return float(np.max(np.abs(np.linalg.eigvals(op))))


@pytest.mark.parametrize("c", [0.2, 1.0, 3.0])
def test_the_spectral_radius_is_the_dense_operator_s(tiny, c):
    _, mo = tiny
    assert hold_spectral_radius(mo, H, c) == pytest.approx(_dense_radius(mo, c), rel=1e-7)


def test_c_true_is_where_the_radius_crosses_one(tiny):
    _, mo = tiny
    ct = hold_ctrue(mo, H)
    assert ct is not None and ct > 0
    assert _dense_radius(mo, 0.99 * ct) < 1 < _dense_radius(mo, 1.01 * ct)


@pytest.mark.slow
def test_the_plan_holds_below_c_true(tiny):
    lap, mo = tiny
    ct = hold_ctrue(mo, H)
    decay = float(np.min(np.linalg.eigvals(lap).real))
    pl = plan_hold(mo, H, 1.01, ct, decay)
    assert pl is not None and 0 < pl.kappa <= ct
    assert pl.alpha > 0 and pl.alpha <= pl.alpha1
    assert lowest(mo, pl, H, pl.kappa) >= 0
    assert holds_in_floats(mo, pl, H)
    # far above c_true the same matrices do not hold
    assert lowest(mo, pl, H, 3 * ct) < 0


def test_no_plan_without_a_decay_or_a_level(tiny):
    _, mo = tiny
    assert plan_hold(mo, H, 1.0, 0.0, 1.0) is None
    assert plan_hold(mo, H, 1.0, 1.0, -1.0) is None
