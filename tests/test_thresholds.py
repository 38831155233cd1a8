"""Critical couplings δ_H, δ_S and the best rate, cross-checked against an independent
eigenvalue scan over δ."""

import math

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.thresholds import critical_couplings

from .conftest import random_topology


def scan(lap, dmat, deltas):
    """Independent: spectral abscissa of -(L + δD) and λmin(L_B + L_Bᵀ) on a grid."""
    alpha = np.array([np.max(np.linalg.eigvals(-(lap + x * dmat)).real) for x in deltas])
    lam_s = np.array([np.linalg.eigvalsh(lap + lap.T + 2 * x * dmat)[0] for x in deltas])
    return alpha, lam_s


def check_against_scan(lap, dmat, cc):
    deltas = np.unique(np.concatenate([np.logspace(-4, 3, 400), [1.0]]))
    alpha, lam_s = scan(lap, dmat, deltas)
    scale = np.linalg.norm(lap, 2)
    if cc.hurwitz is not None:
        above = deltas > cc.hurwitz * (1 + 1e-6) + 1e-12
        assert np.all(alpha[above] < 0), "scan finds a non-Hurwitz δ above δ_H"
        if cc.hurwitz > 0:
            x = cc.hurwitz * (1 - 1e-4)
            assert np.max(np.linalg.eigvals(-(lap + x * dmat)).real) >= -1e-9 * scale
            # α(δ_H) = 0 at the boundary, to high precision
            a_h = np.max(np.linalg.eigvals(-(lap + cc.hurwitz * dmat)).real)
            assert abs(a_h) < 1e-8 * scale
    else:
        assert np.any(alpha[deltas > 1] >= 0) or np.max(alpha) >= -1e-9 * scale
    if cc.symmetric is not None:
        assert np.all(lam_s[deltas > cc.symmetric * (1 + 1e-6) + 1e-12] > 0)
        if cc.symmetric > 0:
            lam = np.linalg.eigvalsh(lap + lap.T + 2 * cc.symmetric * dmat)[0]
            assert abs(lam) < 1e-8 * scale
            below = cc.symmetric * (1 - 1e-6)
            assert np.linalg.eigvalsh(lap + lap.T + 2 * below * dmat)[0] < 0
    else:
        assert np.all(lam_s <= 1e-9 * scale)
    # the best rate is at least every rate the scan sees (within its resolution)
    assert cc.best_rate >= np.max(-alpha) - 1e-6 * max(1.0, abs(cc.best_rate))
    if cc.best_rate_delta is not None:
        r = -np.max(np.linalg.eigvals(-(lap + cc.best_rate_delta * dmat)).real)
        assert r == pytest.approx(cc.best_rate, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("name", ["g1", "g2", "g3"])
def test_paper_modes_against_scan(examples, name):
    d = nd.design(nd.load(examples / f"{name}.yaml"), [1, 2, -1])
    lap, dmat = d.topology.laplacian(), d.coupling_matrix()
    cc = d.thresholds
    check_against_scan(lap, dmat, cc)
    # every δ > 0 gives a Hurwitz -L_B on the paper's three modes: the lemma is conservative
    assert cc.hurwitz == 0.0
    assert cc.hurwitz_intervals == ((0.0, math.inf),)
    # the designed δ is above δ_S, as Theorems 3-4 need
    assert 0 < cc.symmetric < d.delta


def test_g1_symmetric_threshold_and_plateau(examples):
    d = nd.design(nd.load(examples / "g1.yaml"), [1, 2, -1])
    # agent 4 only listens to 3 through A43 = diag(1,1,2): the rate can never exceed 1
    assert d.thresholds.best_rate == pytest.approx(1.0, rel=1e-9)
    assert d.thresholds.best_rate_delta == pytest.approx(9.0, rel=1e-6)
    assert d.thresholds.symmetric == pytest.approx(3.117692596869806, rel=1e-6)


def test_positive_hurwitz_threshold():
    """-(L + δD) with L = [[-2, 1], [1, 1]], D = diag(1, 0): det = δ − 3, trace = δ − 1,
    so it is Hurwitz exactly for δ > 3; L_B + L_Bᵀ = [[2δ−4, 2], [2, 2]] ≻ 0 iff δ > 3."""
    lap = np.array([[-2.0, 1.0], [1.0, 1.0]])
    dmat = np.diag([1.0, 0.0])
    cc = critical_couplings(lap, dmat)
    assert cc.hurwitz == pytest.approx(3.0, rel=1e-9)
    assert cc.symmetric == pytest.approx(3.0, rel=1e-9)
    check_against_scan(lap, dmat, cc)


def test_bounded_hurwitz_set_has_no_threshold():
    """L = [[0, 1], [-5, -1]], D = diag(1, 0): trace = δ − 1, det = 5 − δ, so -L_B is
    Hurwitz only on (1, 5): no δ_H exists and the interval is reported."""
    lap = np.array([[0.0, 1.0], [-5.0, -1.0]])
    cc = critical_couplings(lap, np.diag([1.0, 0.0]))
    assert cc.hurwitz is None
    assert len(cc.hurwitz_intervals) == 1
    lo, hi = cc.hurwitz_intervals[0]
    assert lo == pytest.approx(1.0, rel=1e-9) and hi == pytest.approx(5.0, rel=1e-9)
    assert any("not Hurwitz for large" in n for n in cc.notes)


@pytest.mark.parametrize("seed", range(12))
def test_random_topologies_against_scan(seed):
    top = random_topology(seed, n=4, d=2)
    d = nd.design(top, [1.0, -0.5])
    check_against_scan(top.laplacian(), d.coupling_matrix(), d.thresholds)
