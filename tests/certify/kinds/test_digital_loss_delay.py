"""Tests of :mod:`ntc_design.certify.kinds.digital_loss_delay`: the lossy certificate with a
delay D = 1 on G1 (skip and rescale) issued and re-proven by verify, κ against c_true on
lossy links, the exact lossy moments contracting from the certified k₀ on, and forged
numbers, matrices and subjects rejected after re-sealing."""

import copy
import json
import math

import numpy as np
import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.format import digest, document_hash
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss import loss_moments, mean_offset
from ntc_design.simulate.prepare import make_gain, prepare_modes
from ntc_design.simulate.scenario import load_scenario
from tests.conftest import EXAMPLES

pytestmark = pytest.mark.slow  # each certificate is a few SDP solves (~10 s)


def _reseal(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="module")
def skip_d1(g1):
    dg = Digital(0.1, 1, 0.1)
    return json.loads(json.dumps(certify(g1, THETA, gain="1/(1+t)", digital=dg).certificate))


def test_issue_and_verify_skip_with_a_delay(skip_d1):
    doc = skip_d1
    assert doc["kind"] == "digital_loss" and "digital_mean_square" in doc["certifies"]
    res = doc["results"]["digital"]
    assert res["bound"] == "delay_line" and res["policy"] == "skip"
    assert res["k0"] == math.ceil(res["t0"] / 0.1) + 1
    assert 1 / (1 + res["t0"]) <= res["kappa"]
    # the functional reaches about two thirds of the lossy mean-square limit (the
    # lossless D = 1 one 66 %), and never past it
    assert 0.55 * res["c_true"] < res["kappa"] < res["c_true"]
    assert res["offset"] == pytest.approx(0.14332, abs=1e-5)  # the same x* as D = 0
    kinds = {c["kind"] for c in doc["claims"]}
    assert {"loss_delay_line_step", "digital_delay_line_form", "digital_growth"} <= kinds
    assert {"loss", "loss_R0", "loss_T0"} <= set(doc["matrices"]["P"])
    ver = verify(copy.deepcopy(doc))
    assert ver.valid, [c.detail for c in ver.failed]


def test_the_exact_lossy_moments_contract_from_k0_on(skip_d1):
    """E‖x_k − x*‖² from the exact lossy moments (simulate/loss.py) on G1's scenario
    decreases at every step from the certified k₀ to k = 300."""
    top, spec, _ = load_scenario(EXAMPLES / "scenarios" / "g1_deadline.yaml")
    t_end, h = 30.0, 0.1
    base = spec.replace(T=t_end, digital=None, method="exact")
    gain = make_gain(base.gain)[0]
    pm = prepare_modes(top, base, gain)
    saves = np.arange(301) * h
    grid, _ = digital_grid(Digital(h, 1), t_end, saves)
    s = pm.systems[0]
    loss = np.full(s.n_edges, 0.1)
    lm = loss_moments(s, grid, gain, pm.eps0, pm.theta, 1, loss, "skip")
    es = mean_offset(s, pm.theta, loss, "skip")
    err = lm.moments.ms_error.sum(axis=1) - 2 * lm.moments.mean @ es + es @ es
    k0 = skip_d1["results"]["digital"]["k0"]
    assert k0 == 23
    assert np.all(np.diff(err[k0:]) < 0)
    assert err[:k0].max() > 3 * err[k0]  # it did grow before k₀ (peak 2274 at k = 11)


def test_rescale_with_a_delay_is_certified(g1):
    dg = Digital(0.1, 1, 0.3, "rescale")
    doc = json.loads(json.dumps(certify(g1, THETA, gain="1/(1+t)", digital=dg).certificate))
    res = doc["results"]["digital"]
    assert res["bound"] == "delay_line" and "offset" not in res
    assert 0.55 * res["c_true"] < res["kappa"] < res["c_true"]
    assert verify(copy.deepcopy(doc)).valid


def _scale_matrix(name, factor):
    def edit(doc):
        m = np.array(doc["matrices"]["P"][name]) * factor
        doc["matrices"]["P"][name] = m.tolist()

    return edit


def _set(path, change):
    def edit(doc):
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        parent[path[-1]] = change(parent[path[-1]])

    return edit


@pytest.mark.hostile
@pytest.mark.parametrize(
    "edit",
    [
        _set(("results", "digital", "kappa"), lambda v: v * 1.6),
        _set(("results", "digital", "alpha"), lambda v: v * 3),
        _set(("results", "digital", "g"), lambda v: v * 0.5),
        _set(("results", "digital", "t0"), lambda v: v * 0.5),
        _set(("results", "digital", "k0"), lambda v: v - 1),
        _set(("results", "digital", "offset"), lambda v: v * 1.001),
        _set(("results", "digital", "c_true"), lambda v: v * 0.5),
        _set(("results", "digital", "p_max"), lambda v: v / 2),
        _scale_matrix("loss_R0", 40.0),
        _scale_matrix("loss_T0", 0.0),
        _scale_matrix("loss", 0.01),
        _set(("subject", "digital", "noise", "f"), lambda v: v * 10),
        _set(("subject", "digital", "gain"), lambda v: "10/(1+t)"),
        _set(("subject", "digital", "period"), lambda v: v * 8),
        _set(("subject", "digital", "loss", "policy"), lambda v: "rescale"),
    ],
)
def test_forged_values_are_rejected_after_resealing(skip_d1, edit):
    doc = copy.deepcopy(skip_d1)
    edit(doc)
    try:
        ver = verify(_reseal(doc))
    except Exception as exc:  # a field the reader refuses: rejected with exit 2
        assert type(exc).__name__ == "InputError"
        return
    assert not ver.valid


@pytest.mark.hostile
def test_a_higher_loss_or_a_longer_delay_in_the_subject_is_rejected(skip_d1):
    doc = copy.deepcopy(skip_d1)
    for e in doc["subject"]["digital"]["loss"]["edges"]:
        e["p"] = 0.6
    doc["results"]["digital"]["p_max"] = 0.6
    ver = verify(_reseal(doc))
    assert not ver.valid
    # the step over the arrivals itself fails, not only the offset
    assert any(c.claim is not None and c.claim.kind == "loss_delay_line_step" for c in ver.failed)
    doc = copy.deepcopy(skip_d1)
    doc["subject"]["digital"]["delay"] = 2
    doc["results"]["digital"]["k0"] += 1
    assert not verify(_reseal(doc)).valid  # the matrices of R_1, T_1 are missing
