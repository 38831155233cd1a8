"""The deadline figures in a certificate: issued, re-derived by verify, and forgeries
(a bound lowered by 1 %, T raised, the initial state changed, each re-sealed) rejected;
the CLI's one-line errors for a scenario without T or an initial state."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.deadline_subject import add_deadline
from ntc_design.certify.format import finish
from ntc_design.protocol.digital import Digital


@pytest.fixture(scope="module")
def deadline_cert(g1, theta):
    res = certify(g1, theta, 0.1, "1/(1+t)", digital=Digital(0.1, 1))
    doc = res.certificate
    section = {
        "T": 1.0,
        "period": 0.1,
        "delay": 1,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
        "initial": {"x0": np.linspace(-3, 3, g1.nd).tolist()},
    }
    bound = add_deadline(doc, section)
    return doc, bound


def _resealed(doc):
    doc.pop("digest", None)
    return finish(doc, doc.get("verification_method"))


def test_issued_figures_verify(deadline_cert):
    doc, bound = deadline_cert
    ver = verify(copy.deepcopy(doc))
    assert ver.valid
    assert doc["results"]["deadline"]["ms_error_bound"] == bound.ms_error_bound
    assert any(c.name.startswith("deadline T = 1") and c.ok for c in ver.checks)


@pytest.mark.parametrize(
    "forge",
    [
        lambda d: d["results"]["deadline"].update(
            ms_error_bound=0.99 * d["results"]["deadline"]["ms_error_bound"]
        ),
        lambda d: d["results"]["deadline"].update(
            peak_bound=0.99 * d["results"]["deadline"]["peak_bound"]
        ),
        lambda d: d["subject"]["deadline"].update(T=2.0),
        lambda d: d["subject"]["deadline"]["initial"]["x0"].__setitem__(0, 3.0),
    ],
    ids=["bound", "peak", "T", "initial"],
)
def test_forged_deadline_fields_are_rejected(deadline_cert, forge):
    doc = copy.deepcopy(deadline_cert[0])
    forge(doc)
    assert not verify(_resealed(doc)).valid


def test_unproven_deadline_numbers_fail_the_audit(deadline_cert):
    doc = copy.deepcopy(deadline_cert[0])
    del doc["subject"]["deadline"]
    assert not verify(_resealed(doc)).valid  # results.deadline left unaccounted for


@pytest.mark.hostile
@pytest.mark.parametrize(("drop", "field"), [("initial", "initial: missing"), ("T", "T: missing")])
def test_cli_names_the_missing_field(tmp_path, capsys, drop, field):
    from pathlib import Path

    from ntc_design.cli.program import main

    src = Path("examples/scenarios/g1_deadline.yaml").read_text()
    text = "\n".join(line for line in src.splitlines() if not line.startswith(f"{drop}:")).replace(
        "../g1.yaml", str(Path("examples/g1.yaml").resolve())
    )
    scen = tmp_path / "s.yaml"
    scen.write_text(text)
    with pytest.raises(SystemExit) as exc:
        main(["certify", str(scen), "--deadline", "--out", str(tmp_path / "c.json")])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not (tmp_path / "c.json").exists()


@pytest.mark.hostile
def test_cli_refuses_work_past_the_limit(capsys):
    from ntc_design.cli.program import main

    with pytest.raises(SystemExit) as exc:
        main(["certify", "examples/scenarios/g1_deadline.yaml", "--period", "1e-5", "--deadline"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--deadline" in err[0]
