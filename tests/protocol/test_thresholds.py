"""Tests of :mod:`ntc_design.protocol.thresholds`."""

import math
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model import paper
from ntc_design.model.generate import random_network
from ntc_design.numerics.linalg import DEF_CODES
from ntc_design.protocol import design
from ntc_design.protocol.thresholds import critical_couplings, rate_limit
from tests.conftest import random_topology
from tests.support.switching_scale import THETA_SW


def test_sparse_critical_couplings_agree_with_dense():
    """δ_S (sparse bisection) and δ_H (per component) against the dense method."""
    from ntc_design.protocol.thresholds import critical_couplings, critical_couplings_sparse

    for seed in range(4):
        top = random_network(25, 2, seed, "ring" if seed % 2 else "random")
        des = nd.design(top, [1.0, 1.0], thresholds=False)
        dense = critical_couplings(des.topology.laplacian(), des.coupling_matrix())
        sp_ = critical_couplings_sparse(
            top.laplacian_sparse(), des.coupling_matrix_sparse(), top.dim
        )
        assert sp_.symmetric == pytest.approx(dense.symmetric, rel=2e-4, abs=1e-9)
        if sp_.hurwitz is not None:
            assert sp_.hurwitz == pytest.approx(dense.hurwitz, rel=1e-6, abs=1e-9)
        assert DEF_CODES  # the batched codes table is exported


def test_component_decomposition_is_block_triangular():
    from ntc_design.protocol.thresholds import strong_components

    top = random_network(400, 2, seed=5)
    des = nd.design(top, [1.0, 1.0], thresholds=False)
    lb = des.grounded_laplacian_sparse()
    ncomp, comp = strong_components(lb, 2)
    ea = top.edge_arrays
    assert np.all(comp[ea.cols] <= comp[ea.rows])  # every edge goes forward
    # the eigenvalues of L_B are those of its component blocks
    dense = lb.toarray()
    ev = np.sort_complex(np.linalg.eigvals(dense))
    parts = []
    for c in range(ncomp):
        ix = (np.flatnonzero(comp == c)[:, None] * 2 + np.arange(2)).ravel()
        parts.append(np.linalg.eigvals(dense[np.ix_(ix, ix)]))
    np.testing.assert_allclose(
        np.sort_complex(np.concatenate(parts)), ev, atol=1e-8 * abs(ev).max()
    )
    assert ncomp > 1 and np.bincount(comp).max() > 1


def test_delta_s_is_skipped_with_a_reason_when_the_bisection_would_not_fit(monkeypatch):
    import ntc_design.numerics.linalg as la

    top = random_network(80, 3, seed=2)
    full = design(top, THETA_SW, thresholds=True).thresholds
    assert full.symmetric is not None and full.symmetric > 0
    monkeypatch.setattr(
        la,
        "SPARSE_FACTOR_MAX_FLOPS",
        10 * la.cholesky_fill((top.laplacian_sparse() + top.laplacian_sparse().T).tocsr()).flops,
    )
    th = design(top, THETA_SW, thresholds=True).thresholds
    assert th.symmetric is None
    assert any(n.startswith("δ_S not computed: the bisection needs about 50") for n in th.notes)
    assert th.hurwitz == full.hurwitz  # the per-component δ_H does not factorise


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


def _design(top):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", nd.AssumptionWarning)  # thresholds exist regardless
        return nd.design(top, np.ones(top.dim), 0.1, thresholds=True)


def _alpha(des, delta: float) -> float:
    """Spectral abscissa of −L_B(δ), by dense eigenvalues."""
    return float(np.linalg.eigvals(-des.grounded_laplacian(delta)).real.max())


def _lam_sym(des, delta: float) -> float:
    lb = des.grounded_laplacian(delta)
    return float(np.linalg.eigvalsh(lb + lb.T)[0])


# networks whose −L alone is not Hurwitz (δ_H > 0): found among random_topology's seeds
HURWITZ_CASES = [8, 11, 166, 201]


@pytest.mark.parametrize("seed", HURWITZ_CASES)
def test_delta_h_is_where_hurwitz_starts(seed):
    des = _design(random_topology(seed, n=5, d=2))
    dh = des.thresholds.hurwitz
    assert dh is not None and dh > 0
    assert _alpha(des, dh * (1 - 1e-3)) > 0  # just below: an eigenvalue in Re λ >= 0
    for f in (1 + 1e-3, 2.0, 10.0, 1e3):  # above: Hurwitz for every δ tried
        assert _alpha(des, dh * f) < 0, f
    # the reported Hurwitz set agrees with a scan of α(δ) computed here
    grid = np.geomspace(dh * 1e-2, dh * 1e2, 200)
    inside = [any(lo < x < hi for lo, hi in des.thresholds.hurwitz_intervals) for x in grid]
    alphas = np.array([_alpha(des, x) for x in grid])
    scale = np.abs(des.grounded_laplacian(dh)).max()
    clear = np.abs(alphas) > 1e-9 * scale  # away from the boundary itself
    assert np.array_equal(np.array(inside)[clear], (alphas < 0)[clear])


@pytest.mark.parametrize("seed", range(6))
def test_delta_s_is_where_the_symmetric_part_turns_positive(seed):
    # 10 agents: the Kronecker pencil is 400×400, not 900×900 (11× fewer flops, CI time)
    des = _design(random_network(10, 2, seed, "random"))
    ds = des.thresholds.symmetric
    assert ds is not None
    if ds > 0:
        assert _lam_sym(des, ds * (1 - 1e-4)) < 0
    assert _lam_sym(des, ds * (1 + 1e-4)) > 0
    assert _lam_sym(des, ds * 10 + 1) > 0  # monotone in δ: D ⪰ 0
    # L_B + L_Bᵀ ≻ 0 implies −L_B Hurwitz: δ_H never exceeds δ_S
    assert des.thresholds.hurwitz is not None and des.thresholds.hurwitz <= ds * (1 + 1e-9)


def test_best_rate_is_the_largest_abscissa_over_delta():
    des = _design(paper.g1())
    th = des.thresholds
    grid = np.geomspace(1e-2, 1e3, 400)
    rates = np.array([-_alpha(des, x) for x in grid])
    assert rates.max() <= th.best_rate * (1 + 1e-6)
    assert rates.max() >= th.best_rate * (1 - 1e-3)  # the grid comes close to it


@pytest.mark.parametrize("e", [0.01, 0.03, 0.1])
def test_an_asymptote_is_not_reported_as_an_attained_maximum(e):
    """L = [[1, e], [e, 5]], D = diag(1, 0): the bounded eigenvalue of L + δD is
    5 − e²/δ + O(δ⁻²), so the rate approaches 5 from below and never reaches it. A small e
    brings it within 1e-9 of 5 on the grid (it was 'reaches its maximum 5 at δ ≈ 14289')."""
    cc = critical_couplings(np.array([[1.0, e], [e, 5.0]]), np.diag([1.0, 0.0]))
    assert cc.best_rate == pytest.approx(5.0, rel=1e-12)  # the supremum, ZᵀLZ = 5
    assert cc.best_rate_delta is None
    assert any("approaches 5 as δ → ∞ (not attained" in n for n in cc.notes), cc.notes
    assert not any("reaches its maximum" in n for n in cc.notes)
    # the rate at any δ stays below it
    for delta in (1e2, 1e4, 1e6):
        lam = np.linalg.eigvalsh(np.array([[1.0 + delta, e], [e, 5.0]]))[0]
        assert lam < 5.0


def test_a_true_plateau_is_still_reported_as_reached():
    """L = [[1, 0], [-1, 5]] (agent 2 listens to agent 1 only), D = diag(1, 0): the
    eigenvalue 5 does not move with δ, the other is 1 + δ: the rate min(1 + δ, 5) reaches
    5 at δ = 4 and stays there."""
    cc = critical_couplings(np.array([[1.0, 0.0], [-1.0, 5.0]]), np.diag([1.0, 0.0]))
    assert cc.best_rate == pytest.approx(5.0, rel=1e-9)
    assert cc.best_rate_delta == pytest.approx(4.0, rel=1e-6)
    assert any("reaches its maximum 5 at δ ≈ 4" in n for n in cc.notes), cc.notes


def test_rate_limit_is_the_compression_to_ker_d():
    lap = np.array([[1.0, 0.3, 0.0], [0.2, 4.0, -1.0], [0.0, -1.0, 6.0]])
    d = np.diag([1.0, 0.0, 0.0])
    z = np.eye(3)[:, 1:]
    want = float(np.min(np.linalg.eigvals(z.T @ lap @ z).real))
    assert rate_limit(lap, d) == pytest.approx(want, rel=1e-12)
    assert rate_limit(lap, np.eye(3)) == math.inf  # every direction coupled: no bound
    # the bounded eigenvalue of L + δD tends to it
    lam = np.sort(np.linalg.eigvals(lap + 1e8 * d).real)[0]
    assert lam == pytest.approx(want, rel=1e-6)
