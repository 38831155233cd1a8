"""Tests of :mod:`ntc_design.certify.switching_scale`."""

import copy
import json

import numpy as np
import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.kinds.switching_scale import switching_scale_certificate
from ntc_design.errors import InputError
from ntc_design.model import SwitchingTopology, Topology
from ntc_design.protocol import design
from tests.support.switching_scale import (
    THETA_SW,
    _count_numeric,
    _dense_sym_min,
    _refresh,
)


@pytest.mark.parametrize(
    "field, value, needle",
    [
        ("lower", -1.0, "lower"),
        ("lower", float("nan"), "lower"),
        ("lower", 1e300, "lower"),
        ("lower", True, "lower"),
        ("k", 3, "expected {lower}"),
    ],
)
def test_malformed_proof_fields_are_bad_input(big_cert, field, value, needle):
    doc = copy.deepcopy(big_cert)
    doc["proofs"]["A"][field] = value
    with pytest.raises(InputError, match=needle):
        verify(_refresh(doc))


def test_a_bound_below_the_number_range_is_issued_as_zero():
    """Second review: ℓ < 2^-250 made an honest certificate unreadable; it is issued as 0."""
    s = 2.0**-240
    i2, t2 = np.eye(2) * s, np.diag([1.0, 2.0**-9]) * s
    a = Topology.from_edges(4, 2, [(1, 2, -i2), (2, 1, -i2), (3, 4, -t2), (4, 3, -t2)])
    b = Topology.from_edges(4, 2, [(1, 2, -i2), (2, 1, -i2), (3, 4, -i2), (4, 3, -i2)])
    big_switching = SwitchingTopology({"A": a, "B": b}, (("A", 1.0), ("B", 1.0)))
    c = switching_scale_certificate(design(big_switching, [1.0, -2.0], thresholds=False))
    assert c["proofs"]["A"]["lower"] == 0.0 and c["results"]["symmetric_part_min_eig"]["A"] > 0
    assert verify(json.loads(json.dumps(c))).valid


def test_factorisations_per_mode(big_switching, monkeypatch):
    """Issue 20: the issuer factorises twice per mode (the ℓ = 0 proof, which is also the
    eigensolver's inverse, then ℓ), ``certify`` re-verifies without factorising the same
    matrices again, and a fresh verify factorises once per mode."""
    import ntc_design.numerics.linalg as la

    la._PROVEN.clear()
    calls = _count_numeric(monkeypatch)
    res = certify(big_switching, THETA_SW)
    assert res.certificate["kind"] == "switching-scale" and res.verification.valid
    assert all(lo > 0 for lo in res.certificate["results"]["symmetric_part_lower_bound"].values())
    assert len(calls) == 4
    la._PROVEN.clear()
    assert verify(json.loads(json.dumps(res.certificate))).valid
    assert len(calls) == 6


def test_a_mode_above_the_rate_proof_size_keeps_one_factorisation(big_switching, monkeypatch):
    """Issue 20: above RATE_PROOF_MAX_FLOPS the second factorisation (ℓ > 0) is not made:
    ℓ = 0 is proven by the factor that serves the estimate, the estimate is still the
    dense eigenvalue, and the certificate verifies."""
    from ntc_design.certify import switching_scale as ss
    from ntc_design.numerics import linalg

    calls = []
    real = linalg.SPDFamily.factor

    def counting(self, *a, **k):
        calls.append(1)
        return real(self, *a, **k)

    monkeypatch.setattr(linalg.SPDFamily, "factor", counting)
    des = design(big_switching, THETA_SW, thresholds=False)
    full = switching_scale_certificate(des)
    n_full = len(calls)
    monkeypatch.setattr(ss, "RATE_PROOF_MAX_FLOPS", 0.0)
    calls.clear()
    one = switching_scale_certificate(des)
    assert n_full == 4 and len(calls) == 2  # two modes: two factorisations each, then one
    for k, d in des.modes.items():
        assert full["proofs"][k]["lower"] > 0 and one["proofs"][k]["lower"] == 0.0
        assert one["results"]["symmetric_part_min_eig"][k] == pytest.approx(
            _dense_sym_min(d), rel=1e-9
        )
        assert "ℓ > 0 not attempted" in one["results"]["details"][k]
    assert verify(one).valid


def test_big_modes_are_proven_in_parallel_with_the_same_certificate(big_switching, monkeypatch):
    """Modes above PARALLEL_MIN_ND are proven in forked processes (certify and verify):
    the same proofs and numbers as in one process, and certify's own re-verification
    still reuses the children's factorisations (none repeated in the parent)."""
    from ntc_design.certify import switching_scale as ss
    from ntc_design.numerics import linalg

    des = design(big_switching, THETA_SW, thresholds=False)
    serial = switching_scale_certificate(des)
    big_nd = ss.PARALLEL_MIN_ND
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", 0)
    monkeypatch.setattr(linalg, "proof_workers", lambda n: 2)
    monkeypatch.setattr(ss, "proof_workers", lambda n: 2)
    linalg._PROVEN.clear()
    par = switching_scale_certificate(des)
    assert par["proofs"] == serial["proofs"]
    assert par["results"]["symmetric_part_min_eig"] == serial["results"]["symmetric_part_min_eig"]
    assert len(linalg._PROVEN) == 4  # the children's successes, known to the parent
    calls = []
    real = linalg.SPDFamily.factor

    def counting(self, *a, **k):
        ok = real(self, *a, **k)
        calls.append(self._symbolic is not None)  # a numeric factorisation happened here
        return ok

    monkeypatch.setattr(linalg.SPDFamily, "factor", counting)
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", big_nd)  # verify in this process
    ver = verify(par)  # in the parent: every mode's matrix was proven by a child
    assert ver.valid and calls and not any(calls)
    # verify's own parallel path, from scratch: the same checks as in one process
    from ntc_design.certify.kinds import switching_scale as kind

    monkeypatch.setattr(linalg.SPDFamily, "factor", real)
    linalg._PROVEN.clear()
    one = verify(par)
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", 0)
    used = []
    monkeypatch.setattr(kind, "fork_map", lambda c, w: used.append(w) or linalg.fork_map(c, w))
    linalg._PROVEN.clear()
    two = verify(par)
    assert used == [2]
    assert one.valid and two.valid
    assert [(c.name, c.ok, c.detail) for c in one.checks] == [
        (c.name, c.ok, c.detail) for c in two.checks
    ]
    assert len(linalg._PROVEN) == 2  # the children's proofs reached the parent
