"""Tests of :mod:`ntc_design.sweep.run`."""

import pytest

from ntc_design.sweep import run_sweep
from tests.support.distributed import _stable


def test_interrupted_sweep_resumes_to_the_same_results(sweep_files, sweep_reference, tmp_path):
    out = tmp_path / "resumed"

    def stop_after_three(state) -> None:
        if state.points_done >= 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep_files / "sw.yaml", out, workers=1, progress=stop_after_three)
    assert len(list((out / "points").glob("*.json"))) == 3
    assert not (out / "results.csv").exists()
    assert not list(out.rglob("*.tmp*"))  # nothing half-written
    res = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (res.computed, res.reused) == (5, 3)
    assert _stable(out / "results.csv").equals(_stable(sweep_reference / "results.csv"))
    # a third run computes nothing
    again = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (again.computed, again.reused) == (0, 8)
