"""Tests of :mod:`ntc_design.certify.kinds.hurwitz`."""

import control
import numpy as np
import pytest
import scipy.linalg as sla

import ntc_design as nd
from ntc_design.certify import certify, hurwitz_certificate, verify
from ntc_design.model.paper import THETA
from tests.support.certificates import _load


@pytest.mark.parametrize("g", ["g1", "g2", "g3"])
def test_hurwitz_both_ways_and_rate_below_eigen_bound(paper_designs, g):
    d = paper_designs[g]
    lap_b = d.grounded_laplacian()
    cert = hurwitz_certificate(d)
    ver = verify(cert)
    assert ver.valid and ver.method == "exact-rational", ver.failed
    eig = float(np.min(np.linalg.eigvals(lap_b).real))
    lmi = cert["results"]["lmi"]
    assert lmi["eig_bound"] == pytest.approx(eig, rel=1e-12)
    assert lmi["alpha"] <= eig + 1e-12  # never above the eigenvalue bound
    assert lmi["alpha"] >= eig - 1e-3
    # the Lyapunov P agrees with python-control (A X + X Aᵀ + Q = 0) and SciPy
    p = np.array(cert["matrices"]["P"]["lyapunov"])
    np.testing.assert_allclose(p, control.lyap(lap_b.T, -np.eye(21)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        p, sla.solve_continuous_lyapunov(lap_b.T, np.eye(21)), rtol=1e-9, atol=1e-12
    )
    assert np.linalg.eigvalsh(p)[0] > 0


def test_regenerated_certificates_match_the_shipped_subjects(examples):
    """certificates/ was produced by `ntc certify ... --out`: same subject, same claims."""
    d = nd.design(nd.load(examples / "g1.yaml"), THETA)
    fresh = hurwitz_certificate(d)
    shipped = _load("g1.json")
    assert fresh["subject_digest"] == shipped["subject_digest"]
    assert [c["id"] for c in fresh["claims"]] == [c["id"] for c in shipped["claims"]]


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
