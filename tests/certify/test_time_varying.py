"""Tests of :mod:`ntc_design.certify.time_varying`."""

import numpy as np
import pytest

from ntc_design.certify import certify
from ntc_design.certify.time_varying import CertificationRefused, certify_lambda2
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.model.timevarying import from_document
from ntc_design.protocol.timevarying import TimeVaryingDesign
from tests.support.time_varying import small


@pytest.fixture(scope="module")
def g1tv_cert(g1tv):
    return certify(g1tv, THETA, 0.1, "1/(1+t)")


def dense_lambda_min(des: TimeVaryingDesign, k: int = 6000) -> float:
    a, b = des.topology.domain
    lb = des.at(np.linspace(a, b, k))
    lap = lb.lap_b(des.structure)
    return float(np.min(np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0]))


def test_certified_lambda2_below_and_within_one_percent_of_sampled_infimum(g1tv, g1tv_cert):
    r = g1tv_cert.certificate["results"]["time_varying"]
    inf = dense_lambda_min(g1tv_cert.design)
    assert 0 < r["lambda2"] <= inf
    assert (inf - r["lambda2"]) / inf <= 0.01
    assert r["D"] >= 12.0 and r["D"] < 12.5  # sup |a_kl|: A52's (3,3) entry rotates to ≈ 12.24
    assert r["t0"] is not None and r["t0"] > 0
    kappa = r["lambda2"] / (2 * r["sigma_bar"] * r["Lambda1"] * 7)
    assert 1 / (1 + r["t0"]) < kappa <= 1 / (1 + 0.999 * r["t0"])
    assert g1tv_cert.verification.valid
    assert [t.guaranteed for t in g1tv_cert.theorems] == [True, True]


def test_refuses_fading_weight():
    doc = small(
        {
            k: {"identity": s + "exp(-t)"}
            for k, s in (("1->2", "-"), ("2->3", ""), ("3->1", ""), ("2->1", ""))
        }
    )
    tv = from_document(doc, "fade.yaml")  # positive definite at every t ...
    with pytest.raises(CertificationRefused, match=r"Λ₂ = 0: .*fade"):
        certify_lambda2(tv)  # ... but no uniform bound


def test_refuses_unbounded_weight():
    tv = from_document(small({"2->3": {"identity": "1 + t"}}), "grow.yaml")
    with pytest.raises(CertificationRefused, match=r"edge 2->3: .*unbounded.*Assumption 3"):
        certify_lambda2(tv)
    with pytest.raises(InputError, match=r"edge 2->3: scale = .* is unbounded near t = 0"):
        from_document(small({"2->3": {"identity": "1/abs(sin(t))"}}, {"period": "pi"}), "p.yaml")
