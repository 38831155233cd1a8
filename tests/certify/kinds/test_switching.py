"""Tests of :mod:`ntc_design.certify.kinds.switching`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import switching_certificate, verify
from ntc_design.model.paper import THETA


def test_switching_set_symmetric_parts_and_common_p(examples):
    sd = nd.design(nd.load(examples / "switching.yaml"), THETA)
    cert = switching_certificate(sd)
    assert verify(cert).valid
    lam = cert["results"]["symmetric_part_min_eig"]
    for k, d in sd.modes.items():
        lap_b = d.grounded_laplacian()
        assert lam[k] == pytest.approx(np.linalg.eigvalsh(lap_b + lap_b.T)[0], rel=1e-12)
        assert lam[k] > 0
    assert lam == pytest.approx(
        {"G1": 0.8080097556, "G2": 2.6952230315, "G3": 1.6166592570}, rel=1e-8
    )
    assert cert["results"]["common_lyapunov"]["structure"] == "identity"
    ids = [c["id"] for c in cert["claims"]]
    assert "P_common ≻ 0" in ids and sum("P_common·L_B" in i for i in ids) == 3


def test_weight_bound_is_the_largest_entry_of_any_mode(examples):
    from ntc_design.certify.kinds.switching import weight_bound

    sd = nd.design(nd.load(examples / "switching.yaml"), THETA)
    loop = max(
        float(np.max(np.abs(a))) for m in sd.switching.modes.values() for a in m.weights.values()
    )
    assert weight_bound(sd) == loop > 0  # from the (E, d, d) arrays, no loop over edges
