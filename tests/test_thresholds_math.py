"""The exact critical couplings against the definitions, checked by dense eigenvalues
computed here: −(L + δD) is Hurwitz for every δ > δ_H and not just below it, and
λ_min(L + Lᵀ + 2δD) changes sign at δ_S (Niu & Wu, Lemma 1 and Sec. 4's design family)."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.generate import random_network

from .conftest import random_topology


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
    des = _design(random_network(15, 2, seed, "random"))
    ds = des.thresholds.symmetric
    assert ds is not None
    if ds > 0:
        assert _lam_sym(des, ds * (1 - 1e-4)) < 0
    assert _lam_sym(des, ds * (1 + 1e-4)) > 0
    assert _lam_sym(des, ds * 10 + 1) > 0  # monotone in δ: D ⪰ 0
    # L_B + L_Bᵀ ≻ 0 implies −L_B Hurwitz: δ_H never exceeds δ_S
    assert des.thresholds.hurwitz is not None and des.thresholds.hurwitz <= ds * (1 + 1e-9)


def test_best_rate_is_the_largest_abscissa_over_delta():
    des = _design(nd.paper.g1())
    th = des.thresholds
    grid = np.geomspace(1e-2, 1e3, 400)
    rates = np.array([-_alpha(des, x) for x in grid])
    assert rates.max() <= th.best_rate * (1 + 1e-6)
    assert rates.max() >= th.best_rate * (1 - 1e-3)  # the grid comes close to it
