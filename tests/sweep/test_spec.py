"""Tests of :mod:`ntc_design.sweep.spec`."""

import pytest

from ntc_design.sweep import MAX_POINTS, load_sweep
from tests.cli_helpers import assert_input_error
from tests.support.distributed import SCENARIO, TOPOLOGY


@pytest.mark.hostile
@pytest.mark.parametrize(
    "body, needles",
    [
        ("base: sc.yaml\ngrid: {seed: [0]}\nextra: 1\n", ["extra", "unknown field"]),
        ("base: sc.yaml\ngrid: {noise.sgima: [0.1]}\n", ["grid.noise.sgima", "no such field"]),
        ("base: sc.yaml\ngrid: {sigma: [0.1]}\n", ["grid.sigma", "not a scenario field"]),
        ("base: sc.yaml\ngrid: {workers: [1, 2]}\n", ["grid.workers", "not a scenario field"]),
        ("base: sc.yaml\ngrid: {seed: []}\n", ["grid.seed", "non-empty list"]),
        ("base: sc.yaml\ngrid: {seed: 3}\n", ["grid.seed", "non-empty list"]),
        ("base: sc.yaml\ngrid: {}\n", ["grid", "non-empty mapping"]),
        ("base: sc.yaml\n", ["grid", "exactly one"]),
        ("base: sc.yaml\ngrid: {seed: [0]}\npoints: [{seed: 1}]\n", ["exactly one"]),
        ("base: nope.yaml\ngrid: {seed: [0]}\n", ["base", "no such file"]),
        ("grid: {seed: [0]}\n", ["base", "expected the path"]),
        ("base: sc.yaml\npoints: []\n", ["points", "non-empty list"]),
        ("base: sc.yaml\npoints: [{seed: 1}, 3]\n", ["points[1]", "mapping"]),
        ("base: sc.yaml\npoints: [{seed: 1}, {seed: 1}]\n", ["points", "repeats point 0"]),
        (
            "base: sc.yaml\ngrid: {noise: [{sigma: 1}], noise.sigma: [0.1]}\n",
            ["noise.sigma", "conflicts"],
        ),
        ("base: sc.yaml\ngrid: {seed: [1, 2]\n", ["not valid YAML"]),
        # a trailing dot used to set all of noise to each value: every point failed
        ('base: sc.yaml\ngrid: {"noise.": [0.1, 0.2]}\n', ["grid.noise.", "no such field"]),
        ('base: sc.yaml\npoints: [{"noise.": 0.1}]\n', ["points[0].noise.", "no such field"]),
        ('base: sc.yaml\ngrid: {"initial.": [1]}\n', ["grid.initial.", "no such field"]),
        # a name that is not text used to be used as its repr
        ("name: [1]\nbase: sc.yaml\ngrid: {seed: [0]}\n", ["name", "expected text, got list"]),
        ("description: {a: 1}\nbase: sc.yaml\ngrid: {seed: [0]}\n", ["description", "text"]),
        # issue 41, item 7: integers the results table cannot hold (ArrowInvalid and
        # OverflowError escaped as internal errors)
        (
            "base: sc.yaml\ngrid: {margin: [0.1, " + "9" * 400 + "]}\n",
            ["grid.margin[1]", "400 digits"],
        ),
        ("base: sc.yaml\ngrid: {paths: [" + "9" * 400 + "]}\n", ["grid.paths[0]", "64-bit"]),
        (
            "base: sc.yaml\npoints: [{noise: {sigma: " + str(2**64) + "}}]\n",
            ["points[0].noise.sigma"],
        ),
    ],
)
def test_bad_sweep_files(sweep_files, tmp_path, capsys, monkeypatch, body, needles):
    (tmp_path / "sc.yaml").write_text((sweep_files / "sc.yaml").read_text())
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    sw = tmp_path / "sw.yaml"
    sw.write_text(body)
    assert_input_error(["sweep", sw, "--out", tmp_path / "o"], capsys, monkeypatch, *needles)
    assert not (tmp_path / "o").exists()


@pytest.mark.hostile
def test_too_many_points_is_refused_before_anything_runs(sweep_files, tmp_path):
    sw = tmp_path / "big.yaml"
    n = int(MAX_POINTS**0.5) + 1
    sw.write_text(
        f"base: {sweep_files / 'sc.yaml'}\ngrid:\n  seed: {list(range(n))}\n  margin: {[0.1 * (k + 1) for k in range(n)]}\n"
    )
    with pytest.raises(Exception, match=f"{n * n} points; at most {MAX_POINTS}"):
        load_sweep(sw)


@pytest.mark.hostile
def test_initial_seed_needs_a_mapping_initial(sweep_files, tmp_path):
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO.replace("{uniform: [-1, 1], seed: 1}", "[0, 1, 2]"))
    (tmp_path / "sw.yaml").write_text("base: sc.yaml\ngrid: {initial.seed: [1, 2]}\n")
    with pytest.raises(Exception, match="initial.seed: the base scenario's initial"):
        load_sweep(tmp_path / "sw.yaml")


def test_point_hash_depends_on_resolved_parameters_only(tmp_path):
    """The same resolved parameters are the same point whichever sweep lists them (so a
    point computed by one sweep is reused by another); an edited topology file is not."""
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO)
    (tmp_path / "a.yaml").write_text("base: sc.yaml\npoints: [{margin: 0.5}, {margin: 0.7}]\n")
    (tmp_path / "b.yaml").write_text("base: sc.yaml\ngrid: {margin: [0.7], T: [1]}\n")
    a = [t.point for t in load_sweep(tmp_path / "a.yaml").tasks()]
    b = [t.point for t in load_sweep(tmp_path / "b.yaml").tasks()]
    assert len(set(a)) == 2 and b == a[1:]  # T: 1 is the base's own value
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY.replace("[[2]]", "[[3]]"))
    assert [t.point for t in load_sweep(tmp_path / "b.yaml").tasks()] != b


def test_device_is_a_sweep_key(tmp_path):
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO)
    (tmp_path / "sw.yaml").write_text("base: sc.yaml\ngrid: {device: [cpu, gpu]}\n")
    tasks = load_sweep(tmp_path / "sw.yaml").tasks()
    assert [t.params for t in tasks] == [{"device": "cpu"}, {"device": "gpu"}]
    assert [t.scenario["device"] for t in tasks] == ["cpu", "gpu"]
    assert tasks[0].point != tasks[1].point  # the same paths to rounding, not bit for bit
