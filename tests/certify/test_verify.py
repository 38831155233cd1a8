"""Tests of :mod:`ntc_design.certify.verify`."""

import json
import shutil

import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.format import digest
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.schedule import ScheduleGain
from tests.cli_helpers import assert_input_error, run_cli
from tests.support.certificates import CERTS, _load


def test_certificate_files_verify(capsys, monkeypatch):
    for name in ("g1.json", "switching.json"):
        code, out, err = run_cli(["verify", CERTS / name], capsys, monkeypatch)
        assert code == 0, err
        assert "VALID (exact-rational)" in out


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
