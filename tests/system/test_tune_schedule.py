"""Whole-program checks: tune schedule."""

import json

import pytest

from ntc_design.gain.schedule import read_schedule
from tests.cli_helpers import run_cli


def test_cli_schedule_end_to_end_writes_a_runnable_folder(tmp_path, capsys, monkeypatch):
    # a 3-agent signed cycle (d = 1): the folder, the certificate and the run are what is
    # checked here; the optimal schedule on G1 against independent evaluations is
    # tests/tune/test_optimal.py's (and its issue numbers tests/tune/test_schedule.py's)
    (tmp_path / "cycle.yaml").write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: cycle.yaml\ntheta: [1]\nnoise: {sigma: 0.4, f: 0.3}\n"
        "initial: [-3, 0.5, 3]\npaths: 40\nseed: 3\n",
        encoding="utf-8",
    )
    out = tmp_path / "out"
    code, text, err = run_cli(
        [
            "tune",
            sc,
            "--horizon",
            "1.5",
            "--schedule",
            "optimal",
            "--check-paths",
            "0",
            "--out",
            out,
            "--json",
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    doc = json.loads(text)
    assert (
        doc["ms_error_T"]["optimal"] < doc["ms_error_T"]["power"] <= doc["ms_error_T"]["baseline"]
    )
    assert {"tuned.yaml", "schedule.csv", "tune.json", "certificate.json", "tune.html"} <= {
        p.name for p in out.iterdir()
    }
    g = read_schedule(out / "schedule.csv")
    assert g.c.tolist() == doc["schedule"]["c"]
    code, _, err = run_cli(["verify", out / "certificate.json"], capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run_cli(
        ["certify", tmp_path / "cycle.yaml", "--theta", "1", "--gain", out / "schedule.csv"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    # the written scenario runs, with the schedule as its gain
    code, _, err = run_cli(
        ["simulate", out / "tuned.yaml", "--out", tmp_path / "mc", "--method", "exact"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    summary = json.loads((tmp_path / "mc" / "summary.json").read_text(encoding="utf-8"))
    assert summary["parameters"]["gain"]["c"] == doc["schedule"]["c"]  # recorded whole
    final = sum(summary["final_ms_error_exact"].values())
    assert final == pytest.approx(doc["ms_error_T"]["optimal"], rel=1e-3)
    # and its report shows the schedule (its label, its gain figure, its certificate)
    code, _, err = run_cli(["report", tmp_path / "mc"], capsys, monkeypatch)
    assert code == 0, err
    page = (tmp_path / "mc" / "report.html").read_text(encoding="utf-8")
    assert f"schedule ({len(doc['schedule']['t'])} points on [0, 1.5], linear)" in page
