"""Tests of :mod:`ntc_design.model.switching`."""

import numpy as np
import pytest

import ntc_design as nd
from tests.cli_helpers import assert_input_error


def test_switching_file_with_different_modes_is_bad_input(tmp_path, examples, capsys, monkeypatch):
    (tmp_path / "small.yaml").write_text("dim: 3\nagents: 2\nedges: []\n")
    p = tmp_path / "sw.yaml"
    p.write_text(
        f"modes: {{G1: {examples.resolve() / 'g1.yaml'}, S: small.yaml}}\nschedule: [{{mode: G1, duration: 1}}]\n"
    )
    assert_input_error(["certify", p, "--theta", "1,2,-1"], capsys, monkeypatch, "modes.S", "N=2")


def test_time_varying_topology_designed_at_any_t():
    rot = lambda t: np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])  # noqa: E731
    w = lambda t: rot(t) @ np.diag([2.0 + np.sin(t), 1.0]) @ rot(t).T  # noqa: E731
    tv = nd.TimeVaryingTopology(
        (1, 2, 3),
        2,
        {(1, 2): lambda t: -w(t), (2, 3): w, (3, 1): lambda t: (1 + t) * np.eye(2)},
    )
    for t in (0.0, 0.7, 3.0):
        des = nd.design(tv.at(t), [1.0, 1.0])
        assert des.identity_residual < 1e-12
        assert [des.topology.labels[i] for i in des.informed] == [2]
        np.testing.assert_allclose(des.B[1], w(t), atol=1e-12)
    bad = nd.TimeVaryingTopology((1, 2), 2, {(1, 2): lambda t: np.diag([1.0, -t])})
    nd.design(bad.at(0.0), [1.0, 0.0])
    with pytest.raises(nd.InputError, match=r"edge 1->2 at t=1: weight is indefinite"):
        bad.at(1.0)


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
