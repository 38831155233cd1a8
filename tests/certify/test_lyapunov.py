"""Tests of :mod:`ntc_design.certify.lyapunov`."""

import control
import numpy as np
import pytest
import scipy.linalg as sla

from ntc_design.certify import certify
from ntc_design.certify.dense import prove_hurwitz
from ntc_design.certify.lyapunov import (
    RATE_BACKOFFS,
    common_lyapunov,
    decay_rate_lmi,
    decay_rate_lyapunov,
    lyapunov_solve,
)
from ntc_design.model import paper


def test_g1_rate_is_the_eigenvalue_bound(paper_designs):
    """At δ = 7.244 the slowest G1 mode is 0.1 + 0.1·δ = 0.8244 (agent 3's loop)."""
    r = decay_rate_lmi(paper_designs["g1"].grounded_laplacian())
    assert r.eig_bound == pytest.approx(0.1 + 0.1 * paper_designs["g1"].delta, rel=1e-9)
    assert r.eig_bound - 1e-3 <= r.alpha <= r.eig_bound


def test_common_lyapunov_block_diagonal_when_identity_fails():
    """Modes similar to symmetric-PD ones through T = blockdiag(t_i I): P = TᵀT is
    block-diagonal and certifies all modes, while P = I does not."""
    rng = np.random.default_rng(3)
    n, d = 4, 2
    tvec = np.repeat([1.0, 6.0, 0.3, 2.0], d)
    mats = {}
    for k in range(3):
        m = rng.normal(size=(n * d, n * d))
        s = m @ m.T + np.eye(n * d)
        k_skew = rng.normal(size=(n * d, n * d))
        base = s + 0.5 * (k_skew - k_skew.T)
        mats[f"M{k}"] = (tvec[:, None] * base) / tvec[None, :]
    res = common_lyapunov(mats, d)
    assert res.structure == "block-diagonal"
    assert res.attempts[0][0] == "identity" and "fails" in res.attempts[0][1]
    for m in mats.values():
        s = res.p @ m + m.T @ res.p
        assert np.linalg.eigvalsh(s)[0] > 0
    off = res.p.copy()
    for i in range(n):
        off[i * d : (i + 1) * d, i * d : (i + 1) * d] = 0.0
    assert not np.any(off)  # exactly block-diagonal


def test_lyapunov_solver_matches_scipy_on_larger_matrices():
    rng = np.random.default_rng(0)
    m = np.eye(400) * 3 + rng.normal(size=(400, 400)) * 0.05
    p = lyapunov_solve(m)
    np.testing.assert_allclose(
        p, sla.solve_continuous_lyapunov(m.T, np.eye(400)), rtol=1e-9, atol=1e-12
    )
    assert prove_hurwitz(m).holds and prove_hurwitz(m).p_pd.method == "verified-float"


def test_control_lyap_cross_checks_the_certificate():
    res = certify(paper.g1(), paper.THETA, 0.1)
    mats = res.certificate["matrices"]
    lap_b = np.array(mats["L_B"]["G1"])
    p = np.array(mats["P"]["lyapunov"])
    # control.lyap solves A X + X Aᵀ + Q = 0: with A = −L_Bᵀ, Q = I it is P L_B + L_Bᵀ P = I
    x = control.lyap(-lap_b.T, np.eye(lap_b.shape[0]))
    assert np.allclose(x, p, rtol=1e-9, atol=1e-12)
    assert np.linalg.eigvalsh(0.5 * (x + x.T))[0] > 0


def _hurwitz(seed: int, n: int = 12) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))
    lam = np.linalg.eigvals(a).real.min()
    return a + (0.3 - lam) * np.eye(n)  # min Re λ = 0.3 exactly


@pytest.mark.parametrize("seed", range(6))
def test_rate_is_near_the_bound_and_p_proves_it(seed):
    lap = _hurwitz(seed)
    bound = float(np.linalg.eigvals(lap).real.min())
    r = decay_rate_lyapunov(lap)
    assert r.p is not None and 0 < r.alpha < bound
    assert r.alpha >= (1 - RATE_BACKOFFS[-1]) * bound
    # independent check: P ≻ 0 and P L + Lᵀ P − 2αP ≻ 0 by eigenvalues
    m = r.p @ lap + lap.T @ r.p - 2 * r.alpha * r.p
    assert np.linalg.eigvalsh(r.p)[0] > 0
    assert np.linalg.eigvalsh(0.5 * (m + m.T))[0] > 0


def test_not_hurwitz_gives_no_rate():
    lap = _hurwitz(1) - 0.5 * np.eye(12)  # min Re λ = −0.2
    r = decay_rate_lyapunov(lap)
    assert r.alpha == 0.0 and r.p is None and "not Hurwitz" in r.status
