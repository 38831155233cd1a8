"""A network above the dense sizes simulates: the budget counts the sparse design, and the
step-size guard's ARPACK estimates agree with the dense eigenvalues."""

import numpy as np
import scipy.sparse as sp

from ntc_design.design import design
from ntc_design.generate import random_network
from ntc_design.simulate import simulate
from ntc_design.simulate.system import DENSE_EIG_MAX_ND, _eig_bounds


def test_guard_arpack_matches_dense_eigenvalues():
    top = random_network(300, 3, seed=4)  # Nd = 900 > DENSE_EIG_MAX_ND: ARPACK
    lap = design(top, [1, 2, -1], thresholds=False).grounded_laplacian_sparse()
    assert lap.shape[0] > DENSE_EIG_MAX_ND
    spec = _eig_bounds(sp.csr_matrix(lap))
    rho, bound, min_re, method = spec.rho, spec.bound, spec.min_real, spec.method
    lam = np.linalg.eigvals(lap.toarray())
    assert "ARPACK" in method
    assert rho == np.float64(rho) and abs(rho - np.max(np.abs(lam))) <= 1e-6 * rho
    assert abs(min_re - np.min(lam.real)) <= 1e-2 * abs(np.min(lam.real))
    exact = np.min(2 * lam.real / np.abs(lam) ** 2)
    assert abs(bound - exact) <= 1e-2 * exact


def test_sparse_network_above_the_dense_sizes_simulates():
    top = random_network(3000, 3, seed=2)  # Nd = 9000: sparse design and sparse L_B
    res = simulate(top, [1, 2, -1], T=2e-4, dt=1e-5, paths=4, method="mc", save_every=1e-4)
    ms = res.mc.mean
    assert ms.shape == (3, 3000) and np.all(np.isfinite(ms))
    # zero initial state: the error starts at ‖θ‖² = 6 for every agent; the informed agents
    # (δ in the hundreds) already move towards θ
    assert np.allclose(ms[0], 6.0)
    assert ms[-1].sum() < 0.99 * ms[0].sum()
