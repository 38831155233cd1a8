"""Tests of :mod:`ntc_design.tune.entry`."""

import json

import pytest

from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import load_scenario


@pytest.mark.slow
def test_g1_written_scenario_agrees_with_monte_carlo(g1_tuned):
    proc, out = g1_tuned
    doc = json.loads(proc.stdout)
    top, spec, _ = load_scenario(out / "tuned.yaml", {"paths": 400, "method": "mc"})
    assert spec.gain == doc["gain"] and spec.T == 10.0
    run = simulate(top, spec=spec)
    lo, hi = run.mc.lo[-1].sum(), run.mc.hi[-1].sum()  # the per-agent 95 % bands added
    assert lo <= doc["ms_error_T"]["tuned"] <= hi
    report = (out / "tune.html").read_text(encoding="utf-8")
    assert doc["gain"] in report and "figures/tune_landscape.png" in report
    assert (out / "figures" / "tune_curves.pdf").stat().st_size > 1000
