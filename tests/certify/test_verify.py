"""Tests of :mod:`ntc_design.certify.verify`."""

import json
import re
import shutil
from pathlib import Path

import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.format import digest
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.model.paper import THETA
from tests.cli_helpers import assert_input_error, run_cli
from tests.support.certificates import CERTS, _load

# what each shipped certificate is about (verified against the example file and θ too)
_SUBJECTS = {
    "g1.json": "g1.yaml",
    "switching.json": "switching.yaml",
    "g1_tv.json": "g1_tv.yaml",
    "g1_digital.json": "g1.yaml",
}
PREVIOUS_RELEASE = Path(__file__).resolve().parents[1] / "data" / "previous_release"


def _verifies(path, capsys, monkeypatch, examples) -> str:
    code, out, err = run_cli(["verify", path], capsys, monkeypatch)
    assert code == 0, (path.name, err)
    assert re.search(r"^VALID \((exact-rational|interval)\): \d+ checks$", out, re.M), out[-300:]
    subject = examples / _SUBJECTS[path.name]
    args = ["verify", path, "--topology", subject, "--theta", "1,2,-1", "--json"]
    code, out, err = run_cli(args, capsys, monkeypatch)
    assert code == 0 and json.loads(out)["valid"] is True, (path.name, err)
    return out


def test_every_shipped_certificate_verifies(capsys, monkeypatch, examples):
    # CI's check that `ntc verify` exits 0 on every file in certificates/
    shipped = sorted(CERTS.glob("*.json"))
    assert [p.name for p in shipped] == sorted(_SUBJECTS)
    for path in shipped:
        _verifies(path, capsys, monkeypatch, examples)


def test_the_previous_release_certificates_still_verify(capsys, monkeypatch, examples):
    # a certificate whose claims are true keeps verifying: g1_tv.json's Λ₁, an upper bound
    # 4e-9 above today's re-enclosure, is still a true upper bound
    previous = sorted(PREVIOUS_RELEASE.glob("*.json"))
    assert [p.name for p in previous] == sorted(set(_SUBJECTS) - {"g1_digital.json"})
    for path in previous:
        _verifies(path, capsys, monkeypatch, examples)
    tv = json.loads((PREVIOUS_RELEASE / "g1_tv.json").read_text())["results"]["time_varying"]
    assert tv["Lambda1"] == 238.86572880182226


@pytest.mark.hostile
@pytest.mark.parametrize(
    "mutate, needles",
    [
        (lambda d: "not json at all", ["not valid JSON"]),
        (lambda d: {k: v for k, v in d.items() if k != "claims"}, ["missing field 'claims'"]),
        (
            lambda d: d["matrices"]["P"].update(lyapunov=[[1.0, 0.0], [0.0, 1.0]]),
            ["matrices.P.lyapunov", "21x21"],
        ),
        (lambda d: d["matrices"]["P"]["lyapunov"][2].__setitem__(2, "x"), ["non-numeric"]),
        (lambda d: d.update(format="something"), ["format"]),
    ],
)
def test_malformed_certificates(tmp_path, capsys, monkeypatch, mutate, needles):
    doc = _load("g1.json")
    res = mutate(doc)
    p = tmp_path / "c.json"
    p.write_text(res if isinstance(res, str) else json.dumps(res if isinstance(res, dict) else doc))
    assert_input_error(["verify", p], capsys, monkeypatch, str(p), *needles)


def test_certificate_roundtrip_copy_still_valid(tmp_path, capsys, monkeypatch):
    shutil.copy(CERTS / "switching.json", tmp_path / "s.json")
    code, out, _ = run_cli(["verify", tmp_path / "s.json"], capsys, monkeypatch)
    assert code == 0 and out.count("ok ") >= 15


# -- certificates -------------------------------------------------------------------------


def test_certificate_with_a_schedule_verifies_and_forgeries_fail(g1):
    g = ScheduleGain([0, 2.5, 10], [1.5, 1.6, 0.05], tail="0.55/(1 + t)")
    res = certify(g1, THETA, gain=g)
    assert res.verification.valid and res.proven
    doc = json.loads(json.dumps(res.certificate))
    assert doc["gain"]["c"] == [1.5, 1.6, 0.05]
    assert verify(doc).valid
    for field, value in [
        ("c", [1.5, -1.6, 0.05]),
        ("t", [0, 10, 2.5]),
        ("tail", "0.7*(1+t)^(-0.4)"),
    ]:
        forged = json.loads(json.dumps(doc))
        forged["gain"][field] = value
        if field == "tail":
            forged["gain"]["c"][-1] = 0.7 * 11**-0.4
        forged["digest"] = digest(forged)  # even re-sealed, the conditions are re-derived
        ver = verify(forged)
        assert not ver.valid, field
        assert any(not c.ok and c.name.startswith("gain schedule") for c in ver.checks)


def _every_kind(g1_robust, big_cert):
    """A certificate of every registered kind (shipped, or issued here small)."""
    import ntc_design as nd
    from ntc_design.certify import scale_certificate
    from ntc_design.certify.kinds.registry import KINDS
    from ntc_design.certify.kinds.robust import robust_certificate
    from ntc_design.model.generate import random_network
    from ntc_design.protocol.digital import Digital

    docs = {
        name: json.loads((CERTS / f"{name}.json").read_text())
        for name in ("g1", "switching", "g1_tv", "g1_digital")
    }
    sw_digital = certify(
        nd.load(CERTS.parent / "examples" / "switching.yaml"),
        THETA,
        gain="1/(1+t)",
        digital=Digital(0.013, 0),
    )
    docs["digital_switching"] = sw_digital.certificate
    lossy = certify(
        nd.load(CERTS.parent / "examples" / "g1.yaml"),
        THETA,
        gain="1/(1+t)",
        digital=Digital(0.1, 0, 0.1, "skip"),
    )
    docs["digital_loss"] = lossy.certificate
    top = random_network(30, 2, seed=2, family="scale-free")
    docs["hurwitz_scale"] = scale_certificate(nd.design(top, [1.0, -1.0], thresholds=False))
    docs["switching_scale"] = big_cert
    docs["robust"] = robust_certificate(g1_robust[1])
    docs = {k: json.loads(json.dumps(v)) for k, v in docs.items()}
    assert {d["kind"] for d in docs.values()} == set(KINDS)
    return docs


def _resealed(doc):
    from ntc_design.certify.format import finish

    doc = json.loads(json.dumps(doc))
    for key in ("digest", "subject_digest", "versions"):
        doc.pop(key, None)
    method = doc.pop("verification_method", None)
    return finish(doc, method)


@pytest.mark.hostile
@pytest.mark.slow
def test_every_kind_refuses_a_field_it_does_not_read(g1_robust, big_cert):
    from ntc_design.errors import InputError

    for name, doc in _every_kind(g1_robust, big_cert).items():
        assert verify(json.loads(json.dumps(doc)), name).valid, name
        places = [("top", "note"), ("subject", "gain2")]
        if "modes" in doc["subject"]:
            places.append(("mode", "noise"))
        if "digital" in doc["subject"]:  # digital_loss reads its loss there: another name
            places.append(("digital", "loss" if "loss" not in doc["subject"]["digital"] else "p"))
        for where, field in places:
            forged = json.loads(json.dumps(doc))
            target = {
                "top": forged,
                "subject": forged["subject"],
                "mode": next(iter(forged["subject"].get("modes", {}).values()), None),
                "digital": forged["subject"].get("digital"),
            }[where]
            target[field] = 1
            with pytest.raises(InputError) as err:
                verify(_resealed(forged), name)
            msg = str(err.value)
            assert f"{field}: unknown field" in msg and "\n" not in msg, (name, msg)


@pytest.mark.hostile
def test_a_digital_certificate_with_another_top_level_gain_is_refused():
    # a re-sealed g1_digital.json with a schedule table at the top level verified VALID
    # (its own conditions checked) though the sampled proofs read subject.digital.gain only
    from ntc_design.errors import InputError

    doc = json.loads((CERTS / "g1_digital.json").read_text())
    table = {"t": [0, 1, 2], "c": [50, 40, 10], "interpolation": "linear", "tail": "30/(1+t)"}
    with pytest.raises(InputError) as err:
        verify(_resealed({**doc, "gain": table}), "forged.json")
    msg = str(err.value)
    assert msg.startswith("forged.json: gain: differs from subject.digital.gain"), msg
    # the same schedule at both places (as ntc certify writes a tabulated gain) is fine
    import ntc_design as nd
    from ntc_design.protocol.digital import Digital

    g = ScheduleGain([0.0, 1.0, 2.0], [1.0, 0.5, 1.0], "linear", "3/(1+t)", "gain")
    top = nd.load(CERTS.parent / "examples" / "g1.yaml")
    res = certify(top, THETA, gain=g, digital=Digital(0.1, 0))
    assert res.certificate["gain"] == res.certificate["subject"]["digital"]["gain"]
    assert verify(res.certificate).valid
