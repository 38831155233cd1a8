"""The decay rate without an SDP solver (issue 30): the shifted Lyapunov equation gives α
within 10⁻⁶ of the eigenvalue bound, proven by the same exact verifier as the LMI's."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.certify.kinds.hurwitz import hurwitz_certificate
from ntc_design.certify.lyapunov import RATE_BACKOFFS, decay_rate_lyapunov


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


def test_g1_rate_beats_the_lmi_bisection_and_both_verify(g1, theta):
    des = nd.design(g1, theta)
    lya = hurwitz_certificate(des)
    lmi = hurwitz_certificate(des, rate_method="lmi")
    a_lya, a_lmi = lya["results"]["lmi"]["alpha"], lmi["results"]["lmi"]["alpha"]
    bound = lya["results"]["eig_bound"]
    assert a_lmi < a_lya < bound and (bound - a_lya) <= 1e-5 * bound
    assert verify(lya).valid and verify(lmi).valid
    assert lya["solver"]["name"].startswith("Bartels") and "cvxpy" in lmi["solver"]["name"]


def test_certify_default_needs_no_sdp_solver(g1, theta, monkeypatch):
    from ntc_design.certify import lyapunov

    def no_sdp(*a, **k):
        raise AssertionError("an SDP was solved")

    monkeypatch.setattr(lyapunov, "_cvx", no_sdp)
    res = certify(g1, theta, gain="1/(1+t)")
    assert res.proven and "decay_rate" in res.certificate["certifies"]


@pytest.mark.hostile
def test_an_unknown_rate_method_is_bad_input(g1, theta):
    with pytest.raises(nd.InputError, match="rate_method"):
        certify(g1, theta, rate_method="sdp")
