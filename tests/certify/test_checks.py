"""Tests of :mod:`ntc_design.certify.checks`."""

import json

import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.format import topology_hash
from ntc_design.model import SwitchingTopology
from ntc_design.model.generate import random_network
from tests.cli_helpers import run_cli
from tests.support.certificates import CERTS, _load, _write
from tests.support.switching_scale import THETA_SW


@pytest.mark.hostile
@pytest.mark.parametrize(
    "path",
    [
        ("matrices", "P", "lyapunov", 0, 0),
        ("matrices", "P", "rate", 3, 4),
        ("matrices", "L_B", "G1", 1, 1),
        ("subject", "modes", "G1", "delta"),
        ("subject", "modes", "G1", "B", "2", 0, 0),
        ("claims", 4, "alpha"),
        ("results", "lmi", "alpha"),
    ],
)
def test_tampering_any_entry_fails(tmp_path, capsys, monkeypatch, path):
    doc = _load("g1.json")
    node = doc
    for key in path[:-1]:
        node = node[key]
    old = node[path[-1]]
    node[path[-1]] = (old * (1 + 1e-9) + 1e-12) if old else 1e-12
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1
    assert "INVALID" in err and "digest" in err


def test_verify_account_is_typed_rows_and_one_line_per_check():
    import copy as _copy

    from ntc_design.certify import verify as _verify
    from ntc_design.certify.checks import verification_tables

    doc = json.loads((CERTS / "g1.json").read_text())
    ver = _verify(doc).to_dict()
    about, checks = verification_tables(ver)
    assert about.labels[0] == "kind" and about.labels.count("certifies") == 2
    assert len(checks.rows) == len(ver["checks"]) and all(
        r[0].verdict_word == "ok   " for r in checks.rows
    )
    forged = _copy.deepcopy(doc)
    forged["subject"]["modes"]["G1\nerror: forged"] = forged["subject"]["modes"].pop("G1")
    lines = [ln for t in verification_tables(_verify(forged).to_dict()) for ln in t.list_lines()]
    assert not any(ln.startswith("error:") for ln in lines)
    assert any(ln.startswith("FAILS") for ln in lines)


def test_verify_checks_the_users_topology_and_theta(big_switching, big_cert):
    assert verify(big_cert, topology=big_switching, theta=THETA_SW).valid
    other = SwitchingTopology(dict(big_switching.modes), (("A", 0.1), ("B", 0.3)))
    ver = verify(big_cert, topology=other)
    assert [c.name for c in ver.failed] == ["about the given topology"]
    ver = verify(big_cert, theta=[1.0, 2.0, 0.5])
    assert [c.name for c in ver.failed] == ["θ is the one given"]
    ver = verify(big_cert, topology=big_switching.modes["A"])
    assert [c.name for c in ver.failed] == ["about the given topology"]


def test_hurwitz_scale_verify_checks_the_users_topology_and_theta():
    top = random_network(40, 3, seed=5)
    res = certify(top, THETA_SW)
    assert res.certificate["kind"] == "hurwitz-scale" and res.verification.valid
    assert verify(res.certificate, topology=top, theta=THETA_SW).valid
    other = random_network(40, 3, seed=6)
    assert [c.name for c in verify(res.certificate, topology=other).failed] == [
        "about the given topology"
    ]
    assert [c.name for c in verify(res.certificate, theta=[1, 1, 1]).failed] == [
        "θ is the one given"
    ]
    assert verify(res.certificate).about.modes[0].topology_hash == topology_hash(top)


def test_a_topology_mismatch_names_the_mode(big_switching, big_cert):
    other = SwitchingTopology(
        {"A": big_switching.modes["A"], "B": big_switching.modes["A"]}, (("A", 0.1), ("B", 0.2))
    )
    (bad,) = verify(big_cert, topology=other).failed
    assert "(mode B differs)" in bad.detail
    moved = SwitchingTopology(dict(big_switching.modes), (("A", 0.1), ("B", 0.25)))
    (bad,) = verify(big_cert, topology=moved).failed
    assert "(the schedule differs)" in bad.detail
