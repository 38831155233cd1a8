"""Tests of :mod:`ntc_design.tune.result`."""

import pytest

from ntc_design.tune import tune


def test_power_tune_reports_its_peak(g1, g1_spec):
    r = tune(g1, g1_spec, 2.0, max_evaluations=20, landscape=False, certificate=False)
    pk = r.ms_error_peak
    assert pk["tuned"]["value"] == pytest.approx(float(r.curves["tuned"].total.max()))
    assert 0 <= pk["tuned"]["t"] <= 2.0
    assert "ms_error_peak" in r.to_dict()
    assert any(
        "peak" in str(row[0].value if hasattr(row[0], "value") else row[0])
        for row in r.table().rows
    )
