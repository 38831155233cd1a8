"""Tests of :mod:`ntc_design.simulate.scenario`."""

import json
import os

import numpy as np
import pytest

from ntc_design.model.paper import THETA
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import write_outputs
from tests.cli_helpers import run_cli
from tests.support.simulate import write_scenario


def test_cli_simulate_writes_outputs(tmp_path, capsys, monkeypatch):
    sc = write_scenario(tmp_path)
    out = tmp_path / "out"
    code, _, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0, err
    header = (out / "ms_error.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "mc_1", "mc_1_lo", "mc_1_hi", "exact_1"] and header[-1] == "exact_7"
    rows = (out / "ms_error.csv").read_text().splitlines()[1:]
    assert len(rows) == 5 and float(rows[-1].split(",")[0]) == pytest.approx(0.2)
    summ = json.loads((out / "summary.json").read_text())
    assert summ["parameters"]["seed"] == 0 and summ["designs"]["G1"]["delta"] == pytest.approx(
        7.244, abs=1e-3
    )
    z = np.load(out / "paths.npz")
    assert z["paths"].shape == (10, 5, 21)


def test_interrupted_write_outputs_leaves_the_old_run(g1, tmp_path, monkeypatch):
    res = simulate(g1, THETA, T=0.1, paths=4, save_every=0.05, workers=1)
    out = tmp_path / "o"
    write_outputs(res, out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    import ntc_design.simulate.scenario as sc

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(sc.np, "savez_compressed", boom)
    with pytest.raises(KeyboardInterrupt):
        write_outputs(res, out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert os.listdir(tmp_path) == ["o"]
