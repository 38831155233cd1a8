"""Tests of :mod:`ntc_design.certify.kinds.digital_loss_hold`: the hold certificate on G1
(h = 0.1, c = 1/(1+t), σ = 0.4, f = 0.3, p = 0.3) issued and re-proven by verify, its
contraction checked against the exact lossy moments (the (e, η) recursion written out in
tests/certify/test_loss_hold.py) after the certified k₀, forged numbers and matrices
rejected after re-sealing, and its export allowed."""

import copy
import json
import math

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.certify.digital import edge_noises
from ntc_design.certify.format import digest, document_hash
from ntc_design.certify.kinds.digital_loss_hold import (
    HoldStated,
    prove_nonincreasing,
    rate_conditions,
)
from ntc_design.certify.loss import loss_edges
from ntc_design.certify.loss_hold import HoldOps, functional, hold_model
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from tests.certify.test_loss_hold import _gamma, _recursion
from tests.support.shared import once_per_run

H = 0.1
P = 0.3


def _reseal(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="module")
def hold30(g1, tmp_path_factory):
    """G1's hold certificate (~30 s), issued once per run: the module's slow tests may land
    on both xdist workers (tests/support/shared.py)."""

    def build():
        digital = Digital(H, 0, P, "hold")
        return certify(g1, THETA, gain="1/(1+t)", digital=digital).certificate

    return once_per_run(tmp_path_factory, "hold30_certificate", build)


@pytest.mark.slow
def test_hold_is_certified_and_verify_proves_it(hold30):
    doc = hold30
    assert doc["kind"] == "digital_loss" and "digital_mean_square" in doc["certifies"]
    res = doc["results"]["digital"]
    assert res["policy"] == "hold" and res["p_max"] == P
    assert 0 < res["kappa"] < res["c_true"]
    assert 0.15 < res["kappa"] / res["c_true"] < 1  # measured: 0.29
    assert res["alpha"] > 0 and res["alpha"] <= res["alpha_step"]
    assert 1 / (1 + res["t0"]) < res["kappa"] and res["t0"] == pytest.approx(
        1 / res["kappa"] - 1, rel=1e-3
    )
    assert res["k0"] == math.ceil(res["t0"] / H)
    kinds = {c["kind"] for c in doc["claims"] if c["property"] == "digital_mean_square"}
    assert kinds == {"pd", "loss_hold_form", "loss_hold_step", "digital_t0", "loss_hold_gain"}
    ver = verify(copy.deepcopy(doc))
    assert ver.valid, [c.detail for c in ver.failed]


@pytest.mark.slow
def test_the_certified_functional_contracts_on_the_exact_moments_after_k0(g1, hold30):
    res = hold30["results"]["digital"]
    s = np.array(hold30["matrices"]["P"]["hold"])
    r = np.array(hold30["matrices"]["P"]["hold_R"])
    des = nd.design(g1, THETA, thresholds=False)
    edges = loss_edges(g1, {k: P for k in g1.edges})
    mo = hold_model(
        np.asarray(des.grounded_laplacian()), edges, edge_noises(g1, 0.3 * np.eye(3), 0.4), 3
    )
    qm = functional(HoldOps("float"), mo, s, r)
    gamma = _gamma(mo, qm, res["kappa"])
    eps0 = np.linspace(-3, 3, 21) - np.tile(THETA, 7)

    def gain(t):
        return 1 / (1 + t)

    steps, k0 = 1500, res["k0"]
    zz = _recursion(mo, eps0, gain, steps)
    q = np.array([float(x) for x in mo.q])
    ev, ms = [], []
    for k, z in enumerate(zz):  # E V_k with u = τ_k Q_d⁻¹ η
        tau = H * gain(k * H)
        dm = np.diag(np.concatenate([np.ones(mo.n), tau / q]))
        ev.append(float(np.trace(qm @ dm @ z @ dm)))
        ms.append(float(np.trace(z[: mo.n, : mo.n])))
    for k in range(k0, steps):
        c = gain(k * H)
        bound = (1 - res["alpha"] * H * c) * ev[k] + 2 * H * c * c * gamma
        assert ev[k + 1] <= bound * (1 + 1e-9), k
    # E‖x_k − 1⊗θ‖² goes to 0: below (1 − β) E V_k, and falling
    assert all(m <= e / (1 - res["beta"]) for m, e in zip(ms[k0:], ev[k0:], strict=True))
    assert ms[steps] < 0.2 * ms[300] < 0.2 * ms[k0]


@pytest.mark.slow
@pytest.mark.hostile
@pytest.mark.parametrize(
    ("where", "change"),
    [
        (("results", "digital", "kappa"), lambda v: v * 3),
        (("results", "digital", "alpha"), lambda v: v * 1.5),
        (("results", "digital", "beta"), lambda v: v / 4),
        (("results", "digital", "g"), lambda v: v / 2),
        (("results", "digital", "t0"), lambda v: v * 0.5),
        (("results", "digital", "k0"), lambda v: v - 1),
        (("matrices", "P", "hold_R"), lambda v: (np.array(v) * 0.01).tolist()),
        (("subject", "digital", "noise", "f"), lambda v: v * 30),
        (("subject", "digital", "gain"), lambda v: "(1+t)/(1+t)**2 + sin(t)**2"),
    ],
)
def test_forged_values_are_rejected_after_resealing(hold30, where, change):
    doc = copy.deepcopy(hold30)
    parent = doc
    for key in where[:-1]:
        parent = parent[key]
    parent[where[-1]] = change(parent[where[-1]])
    try:
        ver = verify(_reseal(doc))
    except InputError:
        return
    assert not ver.valid


@pytest.mark.slow
def test_the_export_of_a_proven_hold_certificate_is_allowed(hold30, tmp_path):
    from ntc_design.export.source import ExportOptions, from_certificate

    path = tmp_path / "hold.json"
    path.write_text(json.dumps(hold30))
    law = from_certificate(path).law
    assert law.policy == "hold" and np.all(law.modes[0].keep == 1.0 - P)
    with pytest.raises(InputError, match="policy: 'skip' differs"):
        from_certificate(path, ExportOptions(policy="skip"))
    # the same certificate with its section stopped is refused, as not proven
    stopped = copy.deepcopy(hold30)
    stopped["results"]["digital"] = {"stopped": "hold: not attempted"}
    stopped["certifies"].remove("digital_mean_square")
    stopped["claims"] = [c for c in stopped["claims"] if c["property"] != "digital_mean_square"]
    for key in ("hold", "hold_R"):
        stopped["matrices"]["P"].pop(key)
    path.write_text(json.dumps(_reseal(stopped)))
    with pytest.raises(InputError, match="lossy links with the hold policy are not proven"):
        from_certificate(path)


def test_the_rate_conditions_are_exact():
    st = HoldStated(0.1, 0.33, 0.14, 0.06, 1.01, 0.12, 7.3)
    assert rate_conditions(st, H)[0]
    # α' − gβ/(1 − β) = 0.33 − 1.01·0.14/0.86 = 0.16558…: α just above it fails
    assert not rate_conditions(HoldStated(0.1656, 0.33, 0.14, 0.06, 1.01, 0.12, 7.3), H)[0]
    assert rate_conditions(HoldStated(0.1655, 0.33, 0.14, 0.06, 1.01, 0.12, 7.3), H)[0]
    assert not rate_conditions(HoldStated(0.1, 0.33, 1.0, 0.06, 1.01, 0.12, 7.3), H)[0]
    assert not rate_conditions(HoldStated(0.1, 0.33, 0.14, 0.0, 1.01, 0.12, 7.3), H)[0]
    # ghκβ <= 1 − β: with κ = 100, 1.01·0.1·100·0.14 = 1.41 > 0.86
    assert not rate_conditions(HoldStated(0.1, 0.33, 0.14, 0.06, 1.01, 100.0, 7.3), H)[0]


@pytest.mark.parametrize(
    "gain, t0, want",
    [
        ("1/(1+t)", 0.0, True),
        ("0.5", 3.0, True),
        ("1/(1+t)**0.7", 1.0, True),
        ("2 + sin(t)", 0.0, False),
    ],
)
def test_the_gain_is_non_increasing_from_t0(gain, t0, want):
    assert prove_nonincreasing(gain, t0)[0] is want
    assert prove_nonincreasing({"t": [0, 1], "c": [1, 1]}, 0.0)[0] is False


@pytest.mark.slow
@pytest.mark.hostile
def test_the_forgery_oracle_accepts_the_honest_hold_certificate_and_catches_lies(hold30):
    from tests.system.test_forgery_property import truth

    assert truth("digital_loss", hold30, hold30) == []
    for key, change, what in (
        ("kappa", 3.0, "G(κ)"),
        ("alpha", 1.5, "α"),
        ("beta", 0.01, "coupling or S"),
    ):
        forged = copy.deepcopy(hold30)
        forged["results"]["digital"][key] *= change
        assert what in truth("digital_loss", forged, hold30), key


@pytest.fixture(scope="module")
def tiny_hold():
    """Hold on a 3-agent, d = 2 signed cycle (p = 0.2, h = 0.1): issued in about 2 s."""
    import warnings

    top = nd.Topology.from_edges(
        3,
        2,
        [
            (2, 1, np.array([[1.0, 0.2], [0.2, 0.5]])),
            (3, 2, -np.array([[0.8, 0.0], [0.0, 0.6]])),
            (1, 3, np.array([[0.7, 0.1], [0.1, 0.9]])),
        ],
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = certify(
            top, np.array([1.0, -0.5]), gain="3/(1+t)", digital=Digital(H, 0, 0.2, "hold")
        )
    return json.loads(json.dumps(res.certificate))


def test_a_small_hold_certificate_is_issued_and_re_proven(tiny_hold):
    doc = tiny_hold
    res = doc["results"]["digital"]
    assert "digital_mean_square" in doc["certifies"] and res["policy"] == "hold"
    assert 0 < res["kappa"] < res["c_true"]
    assert res["t0"] == pytest.approx(3 / res["kappa"] - 1, rel=1e-3)  # c(t0) = κ
    assert res["k0"] == math.ceil(res["t0"] / H)
    kinds = {c["kind"] for c in doc["claims"] if c["property"] == "digital_mean_square"}
    assert kinds == {"pd", "loss_hold_form", "loss_hold_step", "digital_t0", "loss_hold_gain"}
    ver = verify(copy.deepcopy(doc))
    assert ver.valid, [c.detail for c in ver.failed]


@pytest.mark.hostile
@pytest.mark.parametrize("key, factor", [("kappa", 4.0), ("alpha", 50.0), ("t0", 0.5)])
def test_a_small_hold_certificate_with_a_forged_number_fails(tiny_hold, key, factor):
    doc = copy.deepcopy(tiny_hold)
    doc["results"]["digital"][key] *= factor
    assert not verify(_reseal(doc)).valid
