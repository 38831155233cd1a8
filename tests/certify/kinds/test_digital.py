"""Tests of :mod:`ntc_design.certify.kinds.digital`: issuing, verifying, forged numbers
rejected after re-sealing, where the certificate stops, and the CLI."""

import copy
import json
import math
from dataclasses import FrozenInstanceError

import numpy as np
import pytest

from ntc_design.certify import KINDS, certify, verify
from ntc_design.certify.dense import DenseContext
from ntc_design.certify.format import digest, document_hash
from ntc_design.certify.kinds.digital import DigitalContext, DigitalState
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from tests.cli_helpers import assert_input_error, run_cli


def _reseal(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="module")
def g1_d1(g1_digital_d1):
    return g1_digital_d1  # certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 1))


@pytest.fixture(scope="module")
def g1_d0(g1):
    return certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 0))


def test_issue_and_verify_with_and_without_delay(g1_d0, g1_d1):
    for r, delay in ((g1_d0, 0), (g1_d1, 1)):
        doc = r.certificate
        assert doc["kind"] == "digital" and r.verification.valid, r.verification.failed
        assert "digital_mean_square" in doc["certifies"]
        res = doc["results"]["digital"]
        assert res["k0"] == math.ceil(res["t0"] / 0.1 - 1e-12) + delay
        # D > 0: the delay line's functional (κ = 66 % of c_true) beat the Razumikhin bound
        assert res.get("bound") == ("delay_line" if delay else None)
        assert ("g" in res) == (delay > 0) and "beta" not in res
        assert 0 < res["kappa"] < res["c_true"]
        assert (
            doc["subject"]["digital"]["period"] == 0.1
            and doc["subject"]["digital"]["delay"] == delay
        )
        assert verify(json.loads(json.dumps(doc))).valid
        sampled = [t for t in r.theorems if t.sampled]
        assert [t.theorem for t in sampled] == [1, 2] and all(t.guaranteed for t in sampled)
    # without a delay a free P (an SDP) proves κ = 0.99 c_true: the contraction starts at
    # k₀ = 4 (t = 0.4, where the exact error of the sampled recursion peaks)
    r0 = g1_d0.certificate["results"]["digital"]
    assert r0["k0"] == 4 and r0["kappa"] >= 0.95 * r0["c_true"]


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("where", "change"),
    [
        (("results", "digital", "kappa"), lambda v: v * 1.01),
        (("results", "digital", "alpha"), lambda v: v * 2.2),
        (("results", "digital", "t0"), lambda v: v * 0.9),
        (("results", "digital", "k0"), lambda v: v - 1),
        (("results", "digital", "gamma"), lambda v: v * 0.99),
        (("results", "digital", "g"), lambda v: v * 0.5),
        (("results", "digital", "c_true"), lambda v: v * 0.5),
        (("subject", "digital", "period"), lambda v: v * 2),
        (("subject", "digital", "delay"), lambda v: v + 1),
        (("subject", "digital", "noise", "sigma"), lambda v: v * 3),
        (("subject", "digital", "noise", "f"), lambda v: v * 10),
        (("subject", "digital", "gain"), lambda v: "10/(1+t)"),
    ],
)
def test_forged_values_are_rejected_after_resealing(g1_d1, where, change):
    doc = copy.deepcopy(g1_d1.certificate)
    parent = doc
    for k in where[:-1]:
        parent = parent[k]
    parent[where[-1]] = change(parent[where[-1]])
    ver = verify(_reseal(doc))
    assert not ver.valid, where


@pytest.mark.hostile
def test_a_forged_matrix_and_a_dropped_claim_are_rejected(g1_d1):
    doc = copy.deepcopy(g1_d1.certificate)
    p = np.array(doc["matrices"]["P"]["digital"])
    doc["matrices"]["P"]["digital"] = (p * 2).tolist()
    assert not verify(_reseal(doc)).valid
    doc = copy.deepcopy(g1_d1.certificate)
    doc["claims"] = [c for c in doc["claims"] if c["kind"] != "digital_t0"]
    assert not verify(_reseal(doc)).valid
    doc = copy.deepcopy(g1_d1.certificate)
    doc["results"]["digital"]["forged"] = 1.0
    assert not verify(_reseal(doc)).valid


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["subject"]["digital"].update(period=-1), "subject.digital.period"),
        (lambda d: d["subject"]["digital"].update(delay=1.5), "subject.digital.delay"),
        (lambda d: d["subject"]["digital"].update(gain=[1]), "subject.digital.gain"),
        (lambda d: d["subject"]["digital"]["noise"].update(sigma=-1), "noise.sigma: must be >= 0"),
        (lambda d: d["subject"]["digital"].pop("noise"), "subject.digital: missing field 'noise'"),
        (lambda d: d["results"]["digital"].pop("kappa"), "results.digital: missing field 'kappa'"),
        (lambda d: d["results"]["digital"].update(bound="razumikhin"), "missing field 'beta'"),
        (lambda d: d["results"]["digital"].update(bound="other"), "results.digital.bound"),
    ],
)
def test_malformed_digital_fields_name_the_field(g1_d1, edit, message):
    doc = copy.deepcopy(g1_d1.certificate)
    edit(doc)
    with pytest.raises(InputError, match=message):
        verify(_reseal(doc))


def test_the_certificate_says_where_it_stops(g1):
    """A gain that never goes below the level: the continuous properties are certified,
    the sampled contraction is not, and the sampled theorems are not guaranteed."""
    r = certify(g1, THETA, gain="1", digital=Digital(0.1, 0))
    doc = r.certificate
    assert r.verification.valid and "digital_mean_square" not in doc["certifies"]
    assert "does not stay below" in doc["results"]["digital"]["stopped"]
    sampled = [t for t in r.theorems if t.sampled]
    assert sampled and not any(t.guaranteed for t in sampled) and not r.proven
    # a stopped section may not report numbers
    forged = copy.deepcopy(doc)
    forged["results"]["digital"]["kappa"] = 0.5
    assert not verify(_reseal(forged)).valid


def test_switching_schedule_is_certified_with_one_p(switching_set):
    with pytest.warns(Warning):
        r = certify(switching_set, THETA, gain="1/(1+t)", digital=Digital(0.013, 0))
    assert r.certificate["kind"] == "digital_switching" and r.verification.valid
    ms = [c for c in r.certificate["claims"] if c["kind"] == "digital_ms"]
    assert sorted(c["mode"] for c in ms) == ["G1", "G2", "G3"]
    assert [t.theorem for t in r.theorems if t.sampled] == [3, 4]


@pytest.mark.hostile
def test_digital_needs_a_gain_and_a_dense_network(g1):
    with pytest.raises(InputError, match="^gain: the digital certificate needs the gain"):
        certify(g1, THETA, digital=Digital(0.1))
    from ntc_design.model.generate import random_network

    big = random_network(25, 3, seed=1)
    with pytest.raises(InputError, match=r"^digital: .* N·d <= 60, this network has N·d = 75"):
        certify(big, [1.0, 2.0, -1.0], gain="1/(1+t)", digital=Digital(0.1))


def test_cli_certify_period_writes_a_certificate_ntc_verify_accepts(
    tmp_path, capsys, monkeypatch, examples
):
    out = tmp_path / "d.json"
    args = ["certify", examples / "g1.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, text, err = run_cli([*args, "--period", "0.1", "--out", out], capsys, monkeypatch)
    assert code == 0, err
    assert "Theorem 1 (mean square, sampled: h = 0.1, D = 0): guaranteed" in text
    assert "from step k₀ = 4" in text
    assert "of the mean-square limit c_true = 0.7735" in text
    code, text, err = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0 and "VALID" in text
    code, text, _ = run_cli([*args, "--period", "0.1", "--json"], capsys, monkeypatch)
    got = json.loads(text)
    assert got["certificate"]["kind"] == "digital" and got["proven"] is True
    assert any(t["sampled"] for t in got["theorems"])


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--period", "0"], "--period: must be a positive number"),
        (["--period", "nan"], "--period: must be finite"),
        (["--period", "0.1", "--delay", "-2"], "--delay: must be an integer >= 0"),
        (["--delay", "1"], "--delay: needs --period"),
    ],
)
def test_cli_bad_period_or_delay(extra, needle, capsys, monkeypatch, examples, tmp_path):
    out = tmp_path / "never.json"
    args = ["certify", examples / "g1.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)", "--out", out]
    assert_input_error([*args, *extra], capsys, monkeypatch, needle)
    assert not out.exists()


def test_the_razumikhin_bound_is_kept_and_an_older_certificate_verifies(g1, monkeypatch):
    """Where the delay line's SDP is not tried (here: forced off) the Razumikhin bound is
    issued, and the same certificate as an earlier release wrote it (no ``bound``, no
    ``c_true``) still verifies; a forged level is still rejected."""
    from ntc_design.certify.kinds import digital as kd

    monkeypatch.setattr(kd, "DELAY_LINE_MAX_ORDER", 0)
    doc = certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 1)).certificate
    res = doc["results"]["digital"]
    assert res["bound"] == "razumikhin" and "beta" in res and res["k0"] == 3032
    old = json.loads(json.dumps(doc))
    for key in ("bound", "c_true", "c_true_how"):
        old["results"]["digital"].pop(key)
    assert verify(_reseal(old)).valid
    old["results"]["digital"]["kappa"] *= 1.01
    assert not verify(_reseal(old)).valid


def test_the_reading_carries_the_digital_state_typed_and_frozen(g1_d1):
    doc = copy.deepcopy(g1_d1.certificate)
    ctx = KINDS["digital"].read(doc, "g1").state
    assert isinstance(ctx, DigitalContext) and isinstance(ctx, DenseContext)  # the base's too
    state = ctx.digital
    assert isinstance(state, DigitalState)
    res, sub = doc["results"]["digital"], doc["subject"]["digital"]
    assert (state.subject.period, state.subject.delay) == (sub["period"], sub["delay"])
    st = state.stated
    assert (st.alpha, st.kappa, st.gamma, st.t0) == tuple(
        res[k] for k in ("alpha", "kappa", "gamma", "t0")
    )
    assert (st.bound, st.growth, st.beta, st.ell2) == ("delay_line", res["g"], None, None)
    assert list(ctx.modes) == list(doc["subject"]["modes"])
    with pytest.raises(FrozenInstanceError):
        state.stated = None  # type: ignore[misc]
    # a certificate that does not certify the sampled property states no numbers
    doc["certifies"] = [p for p in doc["certifies"] if p != "digital_mean_square"]
    assert KINDS["digital"].read(doc, "g1").state.digital.stated is None
