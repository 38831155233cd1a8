"""Tests of :mod:`ntc_design.tune.result`."""

import pytest

from ntc_design.tune import PowerOptions, tune


def test_power_tune_reports_its_peak(g1, g1_spec):
    r = tune(g1, g1_spec, 2.0, PowerOptions(max_evaluations=20, landscape=False, certificate=False))
    pk = r.ms_error_peak
    assert pk["tuned"]["value"] == pytest.approx(float(r.curves["tuned"].total.max()))
    assert 0 <= pk["tuned"]["t"] <= 2.0
    assert "ms_error_peak" in r.to_dict()
    assert any(
        "peak" in str(row[0].value if hasattr(row[0], "value") else row[0])
        for row in r.table().rows
    )


def test_the_note_says_what_took_the_time(g1, g1_spec):
    r = tune(g1, g1_spec, 2.0, PowerOptions(max_evaluations=20, landscape=False, certificate=False))
    st = r.stage_seconds
    assert list(st) == ["search", "final curves", "step check", "theorems and certificate"]
    assert all(v >= 0 for v in st.values()) and sum(st.values()) <= r.seconds * (1 + 1e-9)
    note = r.table().notes[0]
    text = str(note.value if hasattr(note, "value") else note)
    assert f"{r.evaluations} evaluations in {st['search']:.1f} s; then " in text
    assert f"step check {st['step check']:.1f} s" in text
    assert r.to_dict()["stage_seconds"] == st
    # a result without stage timings (built by hand) keeps the total
    from dataclasses import replace

    assert (
        replace(r, stage_seconds={}).time_note()
        == f"{r.evaluations} evaluations in {r.seconds:.1f} s"
    )
