"""Tests of :mod:`ntc_design.certify.kinds.digital_loss`: issuing and verifying the
certificate on lossy links, forged numbers and subjects rejected after re-sealing, where
it stops (hold with a delay, an unproven hold), the registry's choice and the CLI."""

import copy
import json
from dataclasses import FrozenInstanceError

import numpy as np
import pytest

from ntc_design.certify import KINDS, certify, verify
from ntc_design.certify.format import digest, document_hash
from ntc_design.certify.kinds.digital import DigitalContext
from ntc_design.certify.kinds.digital_loss import LossState
from ntc_design.certify.kinds.registry import kind_for
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital, DigitalDesign
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.loss import mean_offset
from ntc_design.simulate.system import mode_system
from tests.cli_helpers import assert_input_error, run_cli


def _reseal(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="module")
def skip10(g1):
    return json.loads(
        json.dumps(certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 0, 0.1)).certificate)
    )


@pytest.fixture(scope="module")
def rescale30(g1):
    digital = Digital(0.1, 0, 0.3, "rescale")
    return json.loads(json.dumps(certify(g1, THETA, gain="1/(1+t)", digital=digital).certificate))


def test_issue_and_verify_skip_and_rescale(g1, skip10, rescale30):
    import ntc_design as nd

    for doc, policy in ((skip10, "skip"), (rescale30, "rescale")):
        assert doc["kind"] == "digital_loss"
        assert "digital_mean_square" in doc["certifies"]
        res = doc["results"]["digital"]
        assert res["policy"] == policy and res["alpha"] > 0 and res["kappa"] > 0
        assert res["k0"] == int(np.ceil(res["t0"] / 0.1))
        assert 1 / (1 + res["t0"]) <= res["kappa"]
        ver = verify(copy.deepcopy(doc))
        assert ver.valid, [c.detail for c in ver.failed]
    # the offset under skip is the mean's limit the exact moments converge to
    s = mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))
    want = np.linalg.norm(mean_offset(s, THETA, np.full(s.n_edges, 0.1), "skip"))
    assert skip10["results"]["digital"]["offset"] == pytest.approx(want, rel=1e-10)
    assert want == pytest.approx(0.1433, abs=1e-4)
    assert "offset" not in rescale30["results"]["digital"]
    assert {e["p"] for e in skip10["subject"]["digital"]["loss"]["edges"]} == {0.1}


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("where", "change"),
    [
        (("results", "digital", "offset"), lambda v: v * 1.001),
        (("results", "digital", "kappa"), lambda v: v * 3),
        (("results", "digital", "alpha"), lambda v: v * 3),
        (("results", "digital", "t0"), lambda v: v * 0.5),
        (("results", "digital", "k0"), lambda v: v - 1),
        (("results", "digital", "p_max"), lambda v: v / 2),
        # σ enters only the additive term, which the certificate does not state: not here
        (("subject", "digital", "noise", "f"), lambda v: v * 10),
        (("subject", "digital", "gain"), lambda v: "10/(1+t)"),
    ],
)
def test_forged_values_are_rejected_after_resealing(skip10, where, change):
    doc = copy.deepcopy(skip10)
    parent = doc
    for k in where[:-1]:
        parent = parent[k]
    parent[where[-1]] = change(parent[where[-1]])
    assert not verify(_reseal(doc)).valid, where


@pytest.mark.hostile
def test_a_changed_loss_in_the_subject_breaks_the_offset(skip10):
    doc = copy.deepcopy(skip10)
    for e in doc["subject"]["digital"]["loss"]["edges"]:
        e["p"] = 0.05
    doc["results"]["digital"]["p_max"] = 0.05
    ver = verify(_reseal(doc))
    assert not ver.valid
    assert any("exact rational solve" in c.detail for c in ver.failed)


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["subject"]["digital"]["loss"].update(policy="drop"), "loss.policy: unknown"),
        (lambda d: d["subject"]["digital"]["loss"]["edges"][0].update(p=1.5), r"edges\[0\]\.p"),
        (lambda d: d["subject"]["digital"]["loss"]["edges"][0].update(to="7"), "no edge"),
        (lambda d: d["subject"]["digital"].pop("loss"), "missing field 'loss'"),
        (lambda d: d["results"]["digital"].pop("offset"), "missing field 'offset'"),
    ],
)
def test_malformed_loss_fields_name_the_field(skip10, edit, message):
    doc = copy.deepcopy(skip10)
    edit(doc)
    with pytest.raises(InputError, match=message):
        verify(_reseal(doc))


def test_an_unproven_hold_is_not_certified_and_says_so(g1):
    # a delay under skip or rescale is certified (tests/certify/kinds/test_digital_loss_delay.py),
    # hold at D = 0 where its functional proves it (test_digital_loss_hold.py); with a delay,
    # or a gain whose 1/c grows without bound, hold stops at once
    for dg, gain, why in (
        (Digital(0.1, 1, 0.1, "hold"), "1/(1+t)", "hold is certified for D = 0"),
        (Digital(0.1, 0, 0.1, "hold"), "exp(-t)", "hold: (1/c)' has no finite bound"),
    ):
        doc = certify(g1, THETA, gain=gain, digital=dg).certificate
        assert doc["kind"] == "digital_loss"
        assert "digital_mean_square" not in doc["certifies"]
        assert why in doc["results"]["digital"]["stopped"]
        assert verify(copy.deepcopy(doc)).valid
        forged = copy.deepcopy(doc)
        forged["certifies"].append("digital_mean_square")
        with pytest.raises(InputError, match="digital_mean_square on lossy links|'alpha'|'offset'"):
            verify(_reseal(forged))


def test_the_registry_picks_the_lossy_kind_only_with_loss(g1):
    import ntc_design as nd

    des = nd.design(g1, THETA, thresholds=False)
    assert kind_for(DigitalDesign(des, Digital(0.1), "1/(1+t)")).name == "digital"
    assert kind_for(DigitalDesign(des, Digital(0.1, 0, 0.2), "1/(1+t)")).name == "digital_loss"


def test_cli_certify_with_loss_writes_a_certificate_verify_accepts(
    capsys, monkeypatch, examples, tmp_path
):
    out = tmp_path / "c.json"
    args = ["certify", examples / "g1.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, _, err = run_cli(
        [*args, "--period", "0.1", "--loss", "0.3", "--loss-policy", "rescale", "--out", out],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    assert json.loads(out.read_text())["results"]["digital"]["policy"] == "rescale"
    code, text, _ = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0 and "VALID" in text
    assert_input_error([*args, "--period", "0.1", "--loss", "1.2"], capsys, monkeypatch, "--loss")


def test_the_reading_carries_the_loss_state_typed_and_frozen(skip10):
    doc = copy.deepcopy(skip10)
    ctx = KINDS["digital_loss"].read(doc, "g1").state
    assert isinstance(ctx, DigitalContext) and isinstance(ctx.digital, LossState)
    state, res = ctx.digital, doc["results"]["digital"]
    assert (state.subject.period, state.subject.delay, state.loss.policy) == (0.1, 0, "skip")
    assert max(state.loss.losses.values()) == res["p_max"] == 0.1
    st = state.stated
    assert (st.alpha, st.kappa, st.t0, st.offset) == tuple(
        res[k] for k in ("alpha", "kappa", "t0", "offset")
    )
    with pytest.raises(FrozenInstanceError):
        state.loss = None  # type: ignore[misc]


@pytest.fixture(scope="module")
def cycle(tmp_path_factory):
    from ntc_design.model.load import load

    p = tmp_path_factory.mktemp("cycle") / "cycle.yaml"
    p.write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    return load(p)


FORGED_WORDS = [
    (delay, field, forged)
    for delay in (0, 1)
    for field, forged in [("bound", None), ("bound", "razumikhin"), ("bound", "delay_line"),
                          ("bound", "absent"), ("policy", "rescale"), ("policy", "hold"),
                          ("policy", "absent")]
    if (field, forged) != ("bound", "absent" if delay == 0 else "delay_line")  # the honest
]  # fmt: skip


@pytest.mark.hostile
@pytest.mark.parametrize("delay, field, forged", FORGED_WORDS)
def test_the_words_the_rows_print_are_proven_not_read(cycle, delay, field, forged):
    # the bound named in the rows (the delay line's functional) and the policy are the
    # subject's: a resealed certificate that names another is invalid, on a 3-agent cycle
    # whose certificates take about 0.2 s (G1's: test_digital_loss_delay.py, slow)
    doc = certify(cycle, [1.0], gain="1/(1+t)", digital=Digital(0.1, delay, 0.1)).certificate
    doc = json.loads(json.dumps(doc))
    assert verify(doc).valid and doc["results"]["digital"]["policy"] == "skip"
    assert ("bound" in doc["results"]["digital"]) == (delay == 1)
    res = doc["results"]["digital"]
    if forged == "absent":
        del res[field]
    else:
        res[field] = forged
    ver = verify(_reseal(doc))
    assert not ver.valid and any(f"digital.{field}" in str(c) for c in ver.failed), ver.failed
