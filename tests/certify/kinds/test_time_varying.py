"""Tests of :mod:`ntc_design.certify.kinds.time_varying`."""

import copy
import json

import pytest
import yaml

from ntc_design.certify import verify
from ntc_design.certify.format import digest
from tests.cli_helpers import run_cli
from tests.support.time_varying import small


def test_cli_certify_json_and_verify(tmp_path, capsys, monkeypatch):
    out = tmp_path / "c.json"
    doc = small({"1->2": {"diag": ["-1 - 0.5*sin(t)", -2]}}, {"period": "2*pi"})
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(doc))
    code, text, err = run_cli(
        [
            "certify",
            tmp_path / "t.yaml",
            "--theta",
            "1,2",
            "--gain",
            "1/(1+t)",
            "--json",
            "--out",
            out,
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    tv = json.loads(text)["certificate"]["results"]["time_varying"]
    assert {"lambda2", "D", "t0"} <= set(tv) and tv["lambda2"] > 0 and tv["D"] == pytest.approx(2.0)
    code, text, _ = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0 and "VALID" in text
    cert = json.loads(out.read_text())
    # a re-digested forgery: Λ₂ raised above what the enclosures give
    forged = copy.deepcopy(cert)
    forged["results"]["time_varying"]["lambda2"] *= 1.5
    forged["digest"] = digest(forged)
    ver = verify(forged)
    assert not ver.valid and [c.name for c in ver.failed] == [
        "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval",
        "reported results (each number recomputed, bounded or informational)",
    ]
    assert "lambda2: reported" in ver.failed[1].detail
    # an interval dropped: the cover fails
    gap = copy.deepcopy(cert)
    del gap["intervals"][len(gap["intervals"]) // 2]
    gap["digest"] = digest(gap)
    failed = verify(gap).failed
    assert [c.name for c in failed][:2] == [
        "the intervals cover the domain",
        "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval",
    ]
    assert "time_varying.intervals: reported" in failed[-1].detail
    # a weight edited: the digest breaks
    edited = copy.deepcopy(cert)
    edited["subject"]["topology"]["edges"][0]["weight"] = {"diag": ["-1 - 0.4*sin(t)", -2]}
    assert "digest" in [c.name for c in verify(edited).failed]
