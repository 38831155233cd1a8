"""Tests of :mod:`ntc_design.sweep.point`."""

import numpy as np
import pandas as pd

from tests.cli_helpers import run_cli


def test_a_failing_point_is_a_row_and_the_others_go_on(sweep_files, tmp_path, capsys, monkeypatch):
    sw = tmp_path / "bad.yaml"
    sw.write_text(
        f"base: {sweep_files / 'sc.yaml'}\n"
        "points:\n"
        "  - {noise.sigma: 0.2}\n"
        "  - {noise.sigma: -1}\n"  # a bad parameter
        "  - {margin: 50, dt: 0.1}\n"  # Euler–Maruyama unstable at this step
        "  - {noise.sigma: 0.3, seed: 5}\n"
    )
    code, out, err = run_cli(["sweep", sw, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 1, err
    assert "2 failed" in out
    table = pd.read_csv(tmp_path / "o" / "results.csv")
    assert list(table.columns[:4]) == ["noise.sigma", "margin", "dt", "seed"]
    assert table["margin"].tolist() == [0.5, 0.5, 50, 0.5]  # the base's value where unset
    assert table["error"].notna().tolist() == [False, True, True, False]
    assert "noise.sigma: must be >= 0" in table["error"][1]
    assert "unstable" in table["error"][2]
    assert np.isfinite(table["ms_final_mc"][[0, 3]]).all()
    # plain progress lines on a non-terminal stderr (a batch job)
    assert "sweep: 4/4 points (2 failed" in err
