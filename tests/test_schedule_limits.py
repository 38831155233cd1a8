"""A schedule whose period overflows, or whose durations vanish in rounding, is refused by
the model itself, so every command (check, design, certify, simulate) sees the same error."""

import pytest

from tests.cli_helpers import assert_input_error

CASES = {
    "overflow": ([1.0e308, 1.0e308], "overflows to infinity"),
    "lost": ([1.0e300, 0.02], "lost in rounding"),
    "inf": ([float("inf"), 0.02], "finite"),
}


@pytest.mark.hostile
@pytest.mark.parametrize("command", ["check", "design", "certify"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_degenerate_schedule_is_one_line(tmp_path, examples, capsys, monkeypatch, command, case):
    durations, needle = CASES[case]
    sched = ", ".join(
        f"{{mode: {m}, duration: {'.inf' if d == float('inf') else f'{d:.1e}'}}}"
        for m, d in zip(["G1", "G2"], durations, strict=True)
    )
    f = tmp_path / "sw.yaml"
    f.write_text(
        f"modes: {{G1: {examples / 'g1.yaml'}, G2: {examples / 'g2.yaml'}}}\nschedule: [{sched}]\n"
    )
    args = [command, f] + (["--theta", "1,2,-1"] if command != "check" else [])
    assert_input_error(args, capsys, monkeypatch, "schedule", needle)
