"""Whole-program checks: robust study."""

import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT
from tests.support.robust import _scenario


@pytest.mark.slow  # the full suite runs it; the fast lane stays under 3 min
def test_simulate_writes_robust_csv_and_the_report_shows_it(tmp_path):
    sc = _scenario(tmp_path, "robust: {realizations: 2, radius: 0.05, seed: 1}")
    out = tmp_path / "run"
    r = subprocess.run(
        [sys.executable, "-m", "ntc_design", "simulate", str(sc), "--out", str(out)],
        cwd=ROOT, capture_output=True, text=True,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "both proven bounds hold" in r.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["robust"]["realizations"] == 2 and (out / "robust.csv").is_file()
    r = subprocess.run(
        [sys.executable, "-m", "ntc_design", "report", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    html = (out / "report.html").read_text()
    assert "Weights within ρ" in html and "both proven bounds hold" in html
    assert 'id="run-fig-robust"' in html and (out / "figures" / "run_robust.png").is_file()
