"""Hostile input to ``ntc simulate``, ``ntc report`` and the CLI's argument parsing: every
case exits 2 with one line naming the field, no traceback, nothing on stdout, nothing
written; Ctrl-C with 2 workers stops promptly with exit 130 and leaves no output."""

import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.simulate import NoiseModel, SimulationSpec
from tests.cli_helpers import assert_input_error, run_cli, said_lines, without_progress
from tests.conftest import ROOT

G1 = str(ROOT / "examples" / "g1.yaml")
G1_TV = str(ROOT / "examples" / "g1_tv.yaml")
NAN, INF = float("nan"), float("inf")
BASE = {
    "topology": G1,
    "theta": [1, 2, -1],
    "gain": "1/(1+t)",
    "noise": {"sigma": 0.4, "f": 0.3},
    "initial": {"uniform": [-3, 3], "seed": 1},
    "T": 0.1,
    "dt": 0.001,
    "paths": 8,
    "seed": 0,
    "save_every": 0.05,
    "method": "both",
    "workers": 1,
}
DROP = object()


def scenario(tmp_path, name="sc.json", **over):
    doc = {**BASE, **over}
    if "save_times" in over and "save_every" not in over:
        doc.pop("save_every")
    doc = {k: v for k, v in doc.items() if v is not DROP}
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(doc))  # JSON: NaN and Infinity survive (Python's json reads them)
    return p


def fails(tmp_path, capsys, monkeypatch, sc, *needles):
    out = tmp_path / "out"
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    line = assert_input_error(["simulate", sc, "--out", out], capsys, monkeypatch, *needles)
    assert not out.exists()
    # nothing written anywhere below tmp_path (no output, no temporary file or folder)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before
    return line


# (field, bad value, words the one line must hold)
BAD_FIELDS = [
    ("theta", [[1, 2], [3]], ["theta[0]", "nested"]),
    ("theta", [1, NAN, 2], ["theta[1]", "finite"]),
    ("theta", [1, INF, 2], ["theta[1]", "finite"]),
    ("theta", [1, True, 2], ["theta[1]"]),
    ("theta", "1,2,-1", ["theta", "list of numbers"]),
    ("theta", [], ["theta"]),
    ("theta", [0, 0, 0], ["theta", "non-zero"]),
    ("theta", [1e300, 2, -1], ["theta[0]", "at most 1e+100"]),
    ("theta", [1, 2], ["theta", "expected 3 numbers"]),
    ("theta", {"a": 1}, ["theta"]),
    ("theta", DROP, ["theta", "missing"]),
    ("margin", 0, ["margin", "positive"]),
    ("margin", -1, ["margin"]),
    ("margin", NAN, ["margin", "finite"]),
    ("margin", INF, ["margin", "finite"]),
    ("margin", "big", ["margin", "number"]),
    ("margin", True, ["margin"]),
    ("gain", 5, ["gain", "expression"]),
    ("gain", ["t"], ["gain"]),
    ("gain", "-1", ["gain", "negative"]),
    ("gain", "0.05 - t", ["gain", "negative"]),
    ("gain", "1/(t-0.05)", ["gain"]),
    ("gain", "exp(t)^1000", ["gain"]),
    ("gain", "1/(1+", ["gain"]),
    ("gain", "__import__('os').system('true')", ["gain"]),
    ("gain", "t" * 20001, ["gain"]),
    ("noise", "loud", ["noise"]),
    ("noise", [0.4], ["noise"]),
    ("noise", {"sigma": -1}, ["noise.sigma", ">= 0"]),
    ("noise", {"sigma": NAN}, ["noise.sigma", "finite"]),
    ("noise", {"sigma": INF}, ["noise.sigma", "finite"]),
    ("noise", {"sigma": True}, ["noise.sigma"]),
    ("noise", {"sigma": "x"}, ["noise.sigma"]),
    ("noise", {"f": True}, ["noise.f"]),
    ("noise", {"f": "x"}, ["noise.f"]),
    ("noise", {"f": NAN}, ["noise.f", "finite"]),
    ("noise", {"f": [1, 2, 3]}, ["noise.f[0]"]),
    ("noise", {"f": [[1, 2], [3]]}, ["noise.f"]),
    ("noise", {"f": [[NAN, 0], [0, 1]]}, ["noise.f[0][0]", "finite"]),
    ("noise", {"f": [[1, 0], [0, 1]]}, ["noise.f", "3x3"]),
    ("noise", {"f": [[1, 0, 0], [0, 1, 0]]}, ["noise.f", "square"]),
    ("noise", {"colour": 1}, ["noise.colour", "unknown field"]),
    # magnitudes bounded (MAX_MAGNITUDE = 1e100): 1e300 used to overflow inside the run
    ("noise", {"f": 1e300}, ["noise.f", "at most 1e+100 in magnitude"]),
    ("noise", {"f": -1e101}, ["noise.f", "at most 1e+100"]),
    ("noise", {"f": [[1e300, 0, 0], [0, 1, 0], [0, 0, 1]]}, ["noise.f[0][0]", "at most"]),
    ("noise", {"sigma": 1e300}, ["noise.sigma", "at most 1e+100"]),
    ("noise", {"sigma_edges": "all"}, ["noise.sigma_edges"]),
    ("noise", {"sigma_edges": [{"from": 2, "to": 1}]}, ["noise.sigma_edges[0]"]),
    ("noise", {"sigma_edges": [{"from": 2, "to": 1, "sigma": -1}]}, ["sigma_edges[0].sigma"]),
    ("noise", {"sigma_edges": [{"from": 2, "to": 1, "sigma": NAN}]}, ["sigma_edges[0].sigma"]),
    ("noise", {"sigma_edges": [{"from": 2, "to": 1, "sigma": "x"}]}, ["sigma_edges[0].sigma"]),
    ("noise", {"sigma_edges": [{"from": [2], "to": 1, "sigma": 1}]}, ["sigma_edges[0].from"]),
    ("noise", {"sigma_edges": [{"from": 1, "to": 5, "sigma": 0.1}]}, ["sigma_edges"]),
    (
        "noise",
        {"sigma_edges": [{"from": 2, "to": 1, "sigma": 1e300}]},
        ["sigma_edges[0].sigma", "at most 1e+100"],
    ),
    (
        "noise",
        {"sigma_edges": [{"from": 2, "to": 1, "sigma": 1}, {"from": 2, "to": 1, "sigma": 2}]},
        ["sigma_edges[1]", "twice"],
    ),
    ("initial", "zero", ["initial"]),
    ("initial", {"uniform": [3, -3], "seed": 1}, ["initial.uniform", "lo < hi"]),
    ("initial", {"uniform": [0, NAN], "seed": 1}, ["initial.uniform[1]"]),
    ("initial", {"uniform": [0, 1], "seed": 1.5}, ["initial.seed"]),
    ("initial", {"uniform": [0, 1], "seed": -1}, ["initial.seed"]),
    ("initial", {"uniform": [0, 1]}, ["initial"]),
    ("initial", {"uniform": 1, "seed": 0}, ["initial.uniform"]),
    # rng.uniform raised OverflowError (high - low range exceeds valid bounds)
    ("initial", {"uniform": [-1e308, 1e308], "seed": 1}, ["initial.uniform[0]", "at most 1e+100"]),
    ("initial", {"uniform": [0, 1e101], "seed": 1}, ["initial.uniform[1]", "at most 1e+100"]),
    ("initial", [[1e300, 0, 0]] + [[0, 0, 0]] * 6, ["initial[0][0]", "at most 1e+100"]),
    ("initial", [0] * 20 + [1e300], ["initial[20]", "at most 1e+100"]),
    # ragged or mixed states used to be flattened and run (21 numbers in all)
    (
        "initial",
        [[1, 2, 3], [1, 2], [1, 2, 3, 4]] + [[1, 2, 3]] * 4,
        ["initial[1]", "2 numbers", "initial[0] has 3"],
    ),
    ("initial", [[1] * 7, [2] * 7, [3] * 7], ["expected 7 states of 3", "3 states of 7"]),
    ("initial", [1, 2, 3] + [[1, 2, 3]] * 6, ["initial[0]", "expected a state", "initial[3]"]),
    ("initial", [[1, 2, 3]] * 6, ["initial", "expected 7 states"]),
    ("initial", [[[1, 2, 3]]] * 7, ["initial[0]", "nested"]),
    ("initial", [NAN] * 21, ["initial[0]", "finite"]),
    ("initial", [True] * 21, ["initial[0]"]),
    ("initial", ["a"] * 21, ["initial[0]"]),
    ("T", 0, ["T", "positive"]),
    ("T", -1, ["T", "positive"]),
    ("T", NAN, ["T", "finite"]),
    ("T", INF, ["T", "finite"]),
    ("T", "10", ["T", "number"]),
    ("T", True, ["T"]),
    ("T", 1e308, ["dt", "memory"]),
    ("dt", 0, ["dt", "positive"]),
    ("dt", -0.1, ["dt", "positive"]),
    ("dt", NAN, ["dt"]),
    ("dt", "small", ["dt"]),
    ("dt", 1e-300, ["dt", "memory"]),
    ("paths", 0, ["paths", "positive integer"]),
    ("paths", -5, ["paths"]),
    ("paths", 1.5, ["paths"]),
    ("paths", 2.0, ["paths"]),
    ("paths", "10", ["paths"]),
    ("paths", True, ["paths"]),
    ("paths", 10**30, ["paths", "at most"]),
    ("seed", -1, ["seed"]),
    ("seed", 1.5, ["seed"]),
    ("seed", 1.0, ["seed"]),
    ("seed", "x", ["seed"]),
    ("seed", True, ["seed"]),
    ("seed", 2**200, ["seed", "at most"]),
    ("save_every", 0, ["save_every", "positive"]),
    ("save_every", -1, ["save_every"]),
    ("save_every", NAN, ["save_every"]),
    ("save_every", "x", ["save_every"]),
    ("save_every", 1e-300, ["save_every", "memory"]),
    ("save_times", [], ["save_times"]),
    ("save_times", [-1], ["save_times", ">= 0"]),
    ("save_times", [NAN], ["save_times[0]", "finite"]),
    ("save_times", [100], ["save_times", "[0, T"]),
    ("save_times", "0.1", ["save_times"]),
    ("save_times", [[0.1]], ["save_times[0]"]),
    ("method", "magic", ["method"]),
    ("method", 3, ["method"]),
    ("method", ["mc"], ["method"]),
    ("stepping", "rk4", ["stepping"]),
    ("stepping", 1, ["stepping"]),
    ("workers", 0, ["workers", "positive integer"]),
    ("workers", -1, ["workers"]),
    ("workers", 1.5, ["workers"]),
    ("workers", "all", ["workers"]),
    ("workers", 10**6, ["workers", "at most"]),
    ("block_size", 0, ["block_size"]),
    ("block_size", -1, ["block_size"]),
    ("block_size", 2.5, ["block_size"]),
    ("store_paths", -1, ["store_paths", ">= 0"]),
    ("store_paths", 1.5, ["store_paths"]),
    ("store_paths", "x", ["store_paths"]),
    ("resample", 0.1, ["resample", "functions of t"]),
    ("resample", -1, ["resample"]),
    ("resample", NAN, ["resample"]),
    ("colour", "red", ["'colour'", "unknown field"]),
    ("description", {"a": 1}, ["description", "expected text"]),
    ("__class__", 1, ["'__class__'", "unknown field"]),
    ("topology", DROP, ["topology", "missing"]),
    ("topology", 5, ["topology", "file path"]),
    ("topology", "nope.yaml", ["topology", "no such file"]),
    ("topology", "", ["topology"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "field, value, needles", BAD_FIELDS, ids=[f"{f}-{k}" for k, (f, _, _) in enumerate(BAD_FIELDS)]
)
def test_bad_scenario_field(tmp_path, capsys, monkeypatch, field, value, needles):
    sc = scenario(tmp_path, **{field: value})
    line = fails(tmp_path, capsys, monkeypatch, sc, *needles)
    assert str(sc) in line  # the file is named


@pytest.mark.hostile
@pytest.mark.parametrize(
    "over, needles",
    [
        ({"stepping": "intrinsic", "ds": 0}, ["ds", "positive"]),
        ({"stepping": "intrinsic", "ds": -1e-3}, ["ds", "positive"]),
        ({"stepping": "intrinsic", "ds": NAN}, ["ds"]),
        ({"stepping": "intrinsic", "ds": "x"}, ["ds"]),
        ({"stepping": "intrinsic", "ds": 1e-300}, ["memory"]),
        ({"save_times": [0.05], "save_every": 0.05}, ["save_times", "not both"]),
        ({"dt": 0.3, "T": 1.0, "save_every": 1.0}, ["dt", "unstable"]),
        ({"method": "exact", "gain": "1e4"}, ["method", "RK4 steps"]),
    ],
)
def test_bad_scenario_combinations(tmp_path, capsys, monkeypatch, over, needles):
    fails(tmp_path, capsys, monkeypatch, scenario(tmp_path, **over), *needles)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "topology, over",
    [
        # 5·10⁶ save times: refused only after ~50 s of building the time grid
        (G1, {"T": 1e7, "dt": 1.0, "save_every": 2.0}),
        (G1, {"T": 1e7, "gain": "1", "dt": 10.0, "save_every": 1e5}),
        (G1, {"T": 1e7, "gain": "1", "dt": 10.0, "save_every": 1e5, "method": "both"}),
        # A(t): the RK4 steps were not bounded at all (ran until memory ran out)
        (G1_TV, {"T": 1e7, "gain": "1", "dt": 10.0, "save_every": 1e5}),
    ],
    ids=["saves", "constant-gain", "before-the-mc", "time-varying"],
)
def test_long_exact_run_is_refused_before_the_grid(tmp_path, capsys, monkeypatch, topology, over):
    def no_grid(*args, **kw):
        raise AssertionError("the time grid was built before the exact-moment estimate")

    monkeypatch.setattr("ntc_design.simulate.steps.build_grid", no_grid)
    monkeypatch.setattr("ntc_design.simulate.grid.build_grid", no_grid)
    # the memory guard refuses "saves" first below ~13 GiB: this test is about the work
    # guard, so it assumes a machine large enough for the memory (the same on every machine)
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", "1T")
    sc = scenario(tmp_path, topology=topology, **{"method": "exact", **over})
    fails(tmp_path, capsys, monkeypatch, sc, "method", "RK4 steps", "more than 300 s")


SWITCHING = [
    ([1e308, 1e308], ["schedule", "overflows to infinity"]),
    ([1.0, 1e-300], ["schedule[1].duration", "collide"]),
    ([1e308, 0.02], ["schedule[1].duration", "collide"]),
    ([1e-9, 1e-9], ["schedule", "switching segments"]),
    ([0.02, -0.02], ["schedule[1].duration", "positive"]),
    ([0.02, NAN], ["schedule[1].duration"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize("durations, needles", SWITCHING)
def test_bad_schedules(tmp_path, capsys, monkeypatch, durations, needles):
    sw = {
        "modes": {"G1": G1, "G2": str(ROOT / "examples" / "g2.yaml")},
        "schedule": [
            {"mode": m, "duration": t} for m, t in zip(("G1", "G2"), durations, strict=True)
        ],
    }
    top = tmp_path / "sw.json"
    top.write_text(json.dumps(sw))
    sc = scenario(tmp_path, topology=str(top), T=10.0, method="exact", save_every=5.0)
    fails(tmp_path, capsys, monkeypatch, sc, *needles)


@pytest.mark.hostile
def test_scenario_name_must_be_text(tmp_path, capsys, monkeypatch):
    p = tmp_path / "sc.json"
    p.write_text(json.dumps({**BASE, "name": [1]}))  # was accepted as the text "[1]"
    line = fails(tmp_path, capsys, monkeypatch, p, "name", "expected text, got list [1]")
    assert str(p) in line


@pytest.mark.hostile
@pytest.mark.parametrize(
    "text, needles",
    [
        ("", ["empty"]),
        ("[1, 2]", ["mapping"]),
        ("{", ["not valid"]),
        ('{"theta": [1, 2, -1]}', ["topology", "missing"]),
    ],
)
def test_bad_scenario_documents(tmp_path, capsys, monkeypatch, text, needles):
    p = tmp_path / "sc.json"
    p.write_text(text)
    fails(tmp_path, capsys, monkeypatch, p, *needles)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "noise, field",
    [
        (NoiseModel(f=1e300), "noise.f"),
        (NoiseModel(f=np.diag([1e300, 1.0, 1.0])), "noise.f"),
        (NoiseModel(sigma=1e300), "noise.sigma"),
        (NoiseModel(sigma_edges={(2, 1): 1e300}), "noise.sigma_edges 2->1"),
    ],
)
def test_noise_magnitude_is_bounded_in_the_api(noise, field):
    # the Python API reaches check_noise directly, without the scenario reader
    with pytest.raises(InputError) as exc:
        SimulationSpec.build([1, 2, -1], noise=noise)
    assert str(exc.value).startswith(field + ":"), exc.value
    assert "at most 1e+100 in magnitude" in str(exc.value)


@pytest.mark.hostile
def test_ragged_initial_array_in_the_api():
    spec = SimulationSpec.build([1, 2, -1], initial=np.zeros((3, 7)))
    with pytest.raises(InputError, match="expected 7 states of 3 numbers, got 3 states of 7"):
        spec.initial_state(7, 3)


def test_initial_rows_equal_the_flat_list(tmp_path, capsys, monkeypatch):
    x = (np.arange(21.0).reshape(7, 3) - 10) / 4
    got = {}
    for name, ini in (("rows", x.tolist()), ("flat", x.reshape(-1).tolist())):
        sc = scenario(tmp_path, name=f"{name}.json", initial=ini, method="exact")
        code, _, err = run_cli(["simulate", sc, "--out", tmp_path / name], capsys, monkeypatch)
        assert code == 0, err
        got[name] = json.loads((tmp_path / name / "summary.json").read_text())
    assert got["rows"]["parameters"]["initial"] == x.reshape(-1).tolist()
    assert got["rows"]["final_ms_error_exact"] == got["flat"]["final_ms_error_exact"]


@pytest.mark.hostile
def test_label_with_newline_cannot_forge_an_error_line(tmp_path, capsys, monkeypatch):
    top = tmp_path / "t.json"
    top.write_text(
        json.dumps({"dim": 1, "agents": ["a\nerror: forged", "a\nerror: forged"], "edges": []})
    )
    code, out, err = run_cli(["check", top], capsys, monkeypatch)
    lines = err.splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert "a\\nerror: forged" in lines[0]  # escaped: it cannot start a line of its own
    sw = {"from": "x\nerror: forged", "to": 1, "sigma": 0.1}
    sc = scenario(tmp_path, noise={"sigma_edges": [sw, sw]})
    line = fails(tmp_path, capsys, monkeypatch, sc, "twice")
    assert "'x\\nerror: forged'" in line


def test_runtime_warnings_do_not_leak(tmp_path, capsys, monkeypatch):
    sc = scenario(tmp_path, gain="exp(t)^400", T=2.0, method="exact", save_every=1.0)
    line = fails(tmp_path, capsys, monkeypatch, sc, "gain", "not finite")
    assert "Warning" not in line


def test_one_path_shows_no_band(tmp_path, capsys, monkeypatch):
    sc = scenario(tmp_path, paths=1)
    out = tmp_path / "o"
    code, stdout, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0 and without_progress(err) == "", err
    summ = json.loads((out / "summary.json").read_text())
    assert set(map(tuple, summ["final_ms_error_mc_band"].values())) == {(None, None)}
    assert "one sample path: no confidence band" in stdout
    row = (out / "ms_error.csv").read_text().splitlines()[-1].split(",")
    assert row[2] == "nan" and row[3] == "nan"  # mc_1_lo, mc_1_hi


# --------------------------------------------------------------------------- --out


@pytest.mark.hostile
def test_out_names_an_existing_file(tmp_path, capsys, monkeypatch):
    f = tmp_path / "taken"
    f.write_text("mine")
    assert_input_error(
        ["simulate", scenario(tmp_path), "--out", f],
        capsys,
        monkeypatch,
        "--out",
        "existing file",
    )
    assert f.read_text() == "mine"


@pytest.mark.hostile
def test_out_under_a_file(tmp_path, capsys, monkeypatch):
    f = tmp_path / "taken"
    f.write_text("mine")
    assert_input_error(
        ["simulate", scenario(tmp_path), "--out", f / "sub"], capsys, monkeypatch, "--out", "file"
    )


@pytest.mark.hostile
def test_out_folder_with_other_files_is_refused(tmp_path, capsys, monkeypatch):
    d = tmp_path / "mine"
    d.mkdir()
    (d / "thesis.tex").write_text("x")
    assert_input_error(
        ["simulate", scenario(tmp_path), "--out", d], capsys, monkeypatch, "--out", "other files"
    )
    assert os.listdir(d) == ["thesis.tex"]


@pytest.mark.hostile
@pytest.mark.parametrize("how", ["permissions", "creation fails"])
def test_read_only_out_folder(tmp_path, capsys, monkeypatch, how):
    # the same on every machine: root ignores permission bits, so the refusal is driven
    # through what the check asks (the permission bits, then creating a folder there)
    import errno

    from ntc_design.io import outputs

    ro = tmp_path / "ro"
    ro.mkdir()
    if how == "permissions":
        monkeypatch.setattr(outputs.os, "access", lambda p, mode: Path(p) != ro)
        needle = "not writable"
    else:

        def refuse(*a, **k):
            raise OSError(errno.EROFS, "Read-only file system")

        monkeypatch.setattr(outputs.tempfile, "mkdtemp", refuse)
        needle = "Read-only file system"
    assert_input_error(
        ["simulate", scenario(tmp_path), "--out", ro / "o"], capsys, monkeypatch, "--out", needle
    )
    assert list(ro.iterdir()) == []


def test_rerun_replaces_the_whole_folder(tmp_path, capsys, monkeypatch):
    out = tmp_path / "o"
    assert run_cli(["simulate", scenario(tmp_path), "--out", out], capsys, monkeypatch)[0] == 0
    (out / "report.html").write_text("old report")  # what ntc report adds to a run
    (out / "certificate.json").write_text("{}")
    (out / "figures").mkdir()
    sc2 = scenario(tmp_path, name="sc2.json", seed=5)
    assert run_cli(["simulate", sc2, "--out", out], capsys, monkeypatch)[0] == 0
    assert not (out / "report.html").exists()  # nothing from the old run is left beside it
    assert not (out / "figures").exists() and not (out / "certificate.json").exists()
    assert json.loads((out / "summary.json").read_text())["parameters"]["seed"] == 5
    assert sorted(os.listdir(tmp_path)) == ["o", "sc.json", "sc2.json"]


# ------------------------------------------------------------------------ ntc report


@pytest.fixture(scope="module")
def good_run(tmp_path_factory):
    import contextlib
    import io
    import warnings

    from ntc_design.cli import main

    d = tmp_path_factory.mktemp("run")
    sc = scenario(d)
    # the CLI in this process (a real process's start is test_startup.py's), its global
    # settings (warning filters, MPLBACKEND) undone after
    err = io.StringIO()
    with (
        pytest.MonkeyPatch.context() as m,
        warnings.catch_warnings(),
        contextlib.redirect_stdout(io.StringIO()),
        contextlib.redirect_stderr(err),
        pytest.raises(SystemExit) as done,
    ):
        m.setenv("MPLBACKEND", os.environ.get("MPLBACKEND", "Agg"))
        main(["simulate", str(sc), "--out", str(d / "o")])
    assert done.value.code in (0, None), err.getvalue()
    return {p.name: p.read_bytes() for p in (d / "o").iterdir()}


def _bad_npz_bomb(path):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        info = zipfile.ZipInfo("t.npy")
        zf.writestr(info, b"\0" * 1000)
    # claim an enormous unpacked size in the directory entry
    raw = bytearray(path.read_bytes())
    cd = raw.rfind(b"PK\x01\x02")
    raw[cd + 24 : cd + 28] = (2**32 - 1).to_bytes(4, "little")
    path.write_bytes(bytes(raw))


CORRUPT = [
    ("paths.npz", b"", ["paths.npz", "not a readable"]),
    ("paths.npz", b"PK\x03\x04garbage", ["paths.npz", "not a readable"]),
    ("paths.npz", "npz-missing-key", ["paths.npz", "missing array 'theta'"]),
    ("paths.npz", "npz-object", ["paths.npz"]),
    ("ms_error.csv", b"", ["ms_error.csv", "no data rows"]),
    ("ms_error.csv", b"t,mc_1\n0.0\n", ["ms_error.csv", "line 2"]),
    ("ms_error.csv", b"t,mc_1\n0.0,abc\n", ["ms_error.csv", "not a number"]),
    ("ms_error.csv", b"x,mc_1\n0.0,1\n", ["ms_error.csv", "header"]),
    ("ms_error.csv", b"t,mc_1\n0.0,1\n0.0,1\n", ["ms_error.csv", "increasing"]),
    ("ms_error.csv", b"t\n0.0\n", ["save times"]),
    ("ms_error.csv", b"\xff\xfe", ["ms_error.csv", "unreadable"]),
    ("summary.json", b"", ["summary.json", "not valid JSON"]),
    ("summary.json", b"[1, 2]", ["summary.json", "mapping"]),
    ("summary.json", b"{}", ["summary.json", "parameters"]),
    ("summary.json", b'{"parameters": {}, "topologies": {"a": 1}}', ["summary.json"]),
    ("summary.json", b"[" * 100000, ["summary.json", "not valid JSON"]),
    ("summary.json", None, ["missing summary.json"]),
    ("paths.npz", None, ["missing paths.npz"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize("name, content, needles", CORRUPT)
def test_report_on_a_corrupt_run(tmp_path, capsys, monkeypatch, good_run, name, content, needles):
    d = tmp_path / "o"
    d.mkdir()
    for k, v in good_run.items():
        (d / k).write_bytes(v)
    if content is None:
        (d / name).unlink()
    elif content == "npz-missing-key":
        np.savez(d / name, t=np.zeros(3), paths=np.zeros((0, 3, 0)), labels=np.array(["1"]))
    elif content == "npz-object":
        np.savez(
            d / name,
            t=np.zeros(3),
            paths=np.zeros((0, 3, 0)),
            labels=np.array([{"a": 1}], dtype=object),
            theta=np.ones(3),
        )
    else:
        (d / name).write_bytes(content)
    before = sorted(os.listdir(d))
    assert_input_error(["report", d], capsys, monkeypatch, *needles)
    assert sorted(os.listdir(d)) == before  # no report.html, no figures


def _set_param(key, value):
    def change(summary, npz):
        summary["parameters"][key] = value

    return change


def _set_npz(key, fn):
    def change(summary, npz):
        npz[key] = fn(npz[key])

    return change


# a run whose files parse but do not fit together: (what, change, file, words)
MISMATCHED = [
    ("schedule-text", _set_param("schedule", "x"), "summary.json", ["parameters.schedule"]),
    ("schedule-entry", _set_param("schedule", ["x"]), "summary.json", ["parameters.schedule"]),
    (
        "schedule-mode",
        _set_param("schedule", [{"mode": "nope", "duration": 1.0}]),
        "summary.json",
        ["schedule[0]", "unknown mode 'nope'"],
    ),
    ("theta-text", _set_param("theta", "x"), "summary.json", ["parameters.theta", "list"]),
    ("theta-short", _set_param("theta", [1.0]), "summary.json", ["parameters.theta", "d = 3"]),
    ("margin", _set_param("margin", [1]), "summary.json", ["parameters.margin", "number"]),
    ("gain-list", _set_param("gain", ["t"]), "summary.json", ["parameters.gain", "expression"]),
    ("gain-text", _set_param("gain", "x"), "summary.json", ["parameters.gain", "variable t"]),
    ("noise", _set_param("noise", "x"), "summary.json", ["parameters.noise", "mapping"]),
    (
        "sample-paths",
        lambda s, z: s.__setitem__("sample_paths", "x"),
        "summary.json",
        ["sample_paths", "mapping"],
    ),
    (
        "spread",
        lambda s, z: s["sample_paths"].__setitem__("final_error_norm_mean", "x"),
        "summary.json",
        ["sample_paths", "numbers"],
    ),
    ("run-info", lambda s, z: s.__setitem__("run", 5), "summary.json", ["run", "mapping"]),
    ("scenario", lambda s, z: s.__setitem__("scenario", 5), "summary.json", ["scenario"]),
    # "cannot reshape array of size 36 into shape (6,1,2)": labels of another run
    ("labels-fewer", _set_npz("labels", lambda a: a[:6]), "paths.npz", ["labels", "6 agents"]),
    (
        "labels-renamed",
        _set_npz("labels", lambda a: np.array([f"x{k}" for k in range(a.size)])),
        "paths.npz",
        ["labels", "different runs"],
    ),
    ("paths-shape", _set_npz("paths", lambda a: a[:, :, :-1]), "paths.npz", ["paths", "N·d = 21"]),
    ("paths-times", _set_npz("paths", lambda a: a[:, :1, :]), "paths.npz", ["paths", "save times"]),
    ("theta-npz", _set_npz("theta", lambda a: a[:2]), "paths.npz", ["theta", "(3,)"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "change, file, needles", [m[1:] for m in MISMATCHED], ids=[m[0] for m in MISMATCHED]
)
def test_report_on_a_mismatched_run(tmp_path, capsys, monkeypatch, good_run, change, file, needles):
    """Each used to end in a TypeError or ValueError (an internal error), some after the
    certificate and the figures were written."""
    d = tmp_path / "o"
    d.mkdir()
    for k, v in good_run.items():
        (d / k).write_bytes(v)
    summary = json.loads((d / "summary.json").read_text())
    with np.load(d / "paths.npz") as z:
        npz = {k: z[k] for k in z.files}
    change(summary, npz)
    (d / "summary.json").write_text(json.dumps(summary))
    np.savez_compressed(d / "paths.npz", **npz)
    before = sorted(os.listdir(d))
    line = assert_input_error(["report", d], capsys, monkeypatch, f"{d / file}", *needles)
    assert "re-run" in line or "schedule[0]" in line
    assert sorted(os.listdir(d)) == before  # no certificate.json, figures/, report.html


@pytest.mark.hostile
def test_report_html_that_is_a_folder(tmp_path, capsys, monkeypatch, good_run):
    """One line already, but report.html.tmp was left behind (and the certificate and
    figures written before the refusal)."""
    d = tmp_path / "o"
    d.mkdir()
    for k, v in good_run.items():
        (d / k).write_bytes(v)
    (d / "report.html").mkdir()
    before = sorted(os.listdir(d))
    assert_input_error(
        ["report", d], capsys, monkeypatch, "report:", f"{d / 'report.html'}", "is a folder"
    )
    assert sorted(os.listdir(d)) == before and os.listdir(d / "report.html") == []


@pytest.mark.hostile
def test_report_refuses_a_decompression_bomb(tmp_path, capsys, monkeypatch, good_run):
    d = tmp_path / "o"
    d.mkdir()
    for k, v in good_run.items():
        (d / k).write_bytes(v)
    _bad_npz_bomb(d / "paths.npz")
    monkeypatch.setattr("ntc_design.reports.rundata.available_memory", lambda: 2.0**30)
    assert_input_error(["report", d], capsys, monkeypatch, "paths.npz", "unpacks to")


# ------------------------------------------------------------------ CLI arguments

ARGS = [
    (["design", G1], ["Missing option '--theta'", "ntc design --help"]),
    (["certify", G1], ["--theta: missing"]),
    (["design", G1, "--theta", "1,2,-1", "--bogus"], ["No such option: --bogus"]),
    (["check", G1, "--bogus"], ["No such option"]),
    (["simulate", "x.yaml", "--out", "o", "--bogus"], ["No such option"]),
    (["report", "d", "--bogus"], ["No such option"]),
    (["verify", "c.json", "--bogus"], ["No such option"]),
    (["gain", "1/(1+t)", "--bogus"], ["No such option"]),
    (["design", G1, "--theta", "1,2,-1", "--margin", "abc"], ["'--margin'"]),
    (["certify", G1, "--theta", "1,2,-1", "--margin", "nan?"], ["'--margin'"]),
    (["design", G1, "--theta", "1,2,-1", "--margin"], ["--margin"]),
    (["simulate", "x.yaml", "--out", "o", "--workers", "many"], ["'--workers'"]),
    (["simulate", "SC", "--out", "o", "--workers", "0"], ["--workers: must be a positive"]),
    (["simulate", "SC", "--out", "o", "--workers", "-3"], ["--workers: must be a positive"]),
    (["simulate", "SC", "--out", "o", "--workers", "5000"], ["--workers: must be at most 4096"]),
    # an empty address ran locally as if no --scheduler had been given
    (["simulate", "SC", "--out", "o", "--scheduler", ""], ["--scheduler", "expected an address"]),
    (["reproduce", "paper", "--out", "o", "--workers", "0"], ["--workers: must be a positive"]),
    (["simulate", "x.yaml"], ["Missing option '--out'"]),
    (["simulate"], ["Missing argument"]),
    (["report"], ["Missing argument"]),
    (["check"], ["Missing argument"]),
    (["gain"], ["Missing argument"]),
    (["reproduce", "paper", "--out", "o", "--paths", "1e3"], ["'--paths'"]),
    (["reproduce", "paper", "--out", "o", "--T", "x"], ["'--T'"]),
    (["reproduce", "cake", "--out", "o"], ["reproduce", "unknown target"]),
    (["frobnicate"], ["No such command"]),
    (["check", "/"], ["is a folder"]),
    (["gain", "-1/(1+t)"], ["gain", "negative"]),
    (["gain", "-1"], ["gain", "negative"]),
    (["gain", "-1", "--json"], ["gain", "negative"]),
    (["gain", "--json", "-1/(1+t)"], ["gain", "negative"]),
    (["design", G1, "--theta", "1,2,-1", "--margin", "-0.5"], ["margin", "positive"]),
    (["gain", "-(1+t)^(-1)"], ["gain", "negative"]),
    (["gain", ".5 - t"], ["gain", "negative"]),
    (["certify", G1, "--theta", "1,2,-1", "--gain", "-1"], ["gain", "negative"]),
    (["certify", G1, "--theta", "1,2,-1", "--gain=-1/(1+t)"], ["gain", "negative"]),
    (["design", G1, "--theta", "0,0,0"], ["theta", "non-zero"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize("args, needles", ARGS, ids=[" ".join(a[:2]) for a, _ in ARGS])
def test_argument_errors_are_one_line(tmp_path, capsys, monkeypatch, args, needles):
    monkeypatch.chdir(tmp_path)
    if "SC" in args:
        sc = scenario(tmp_path.parent / "sc", name=f"{tmp_path.name}.json")
        args = [str(sc) if a == "SC" else a for a in args]
    assert_input_error(args, capsys, monkeypatch, *needles)
    assert os.listdir(tmp_path) == []


def test_negative_theta_and_version(capsys, monkeypatch):
    code, out, err = run_cli(["design", G1, "--theta", "-1,2,1", "--json"], capsys, monkeypatch)
    assert code == 0 and json.loads(out)["theta"] == [-1.0, 2.0, 1.0], err
    code, out, err = run_cli(["--version"], capsys, monkeypatch)
    from ntc_design import __version__

    assert code == 0 and out.strip() == f"ntc {__version__}"


# ------------------------------------------------------------------------- Ctrl-C


def test_ctrl_c_with_two_workers_stops_promptly(tmp_path):
    """A run of 4e8 path-steps (10-20 s) on 2 workers, SIGINT a second after the workers
    start: exit 130 within 3 s, one line, the old output folder untouched and no temporary
    folder left."""
    sc = scenario(
        tmp_path, T=100.0, paths=4000, block_size=100, method="mc", workers=2, save_every=1.0
    )
    out = tmp_path / "o"
    out.mkdir()
    (out / "summary.json").write_text("old")
    (out / "paths.npz").write_bytes(b"old")
    proc = subprocess.Popen(
        [sys.executable, "-m", "ntc_design", "simulate", str(sc), "--out", str(out)],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a suite started in the background by a non-interactive shell ignores SIGINT, and
        # its children inherit that: the run must get Ctrl-C as a user's terminal gives it
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    # interrupt once the Monte Carlo is running: its 2 worker processes exist (a loaded
    # machine may need several seconds for the imports alone)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        kids = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
        if kids.exists() and len(kids.read_text().split()) >= 2:
            break
        time.sleep(0.2)
    time.sleep(1.0)
    assert proc.poll() is None, "the run ended before the interrupt: make it longer"
    proc.send_signal(signal.SIGINT)
    try:  # a hang guard, not a speed test: the outcome below is what is checked
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    # a heartbeat line may come first; the note says the old run would be replaced
    assert said_lines(err) == [f"note: replacing the run in {out}", "error: interrupted"], err
    assert sorted(os.listdir(out)) == ["paths.npz", "summary.json"]
    assert (out / "summary.json").read_text() == "old"
    assert sorted(os.listdir(tmp_path)) == ["o", "sc.json"]


def test_a_ctrl_c_whose_exception_was_lost_still_stops_the_run(tmp_path):
    """Python drops a KeyboardInterrupt raised inside a finaliser ("Exception ignored"): the
    CLI's handler notes the signal too, the Monte Carlo loop checks the note. Simulated by a
    SIGINT handled inside a try/except that swallows it, while the workers run."""
    sc = scenario(
        tmp_path, T=100.0, paths=4000, block_size=100, method="mc", workers=2, save_every=1.0
    )
    probe = tmp_path / "probe.py"
    probe.write_text(
        "import os, signal, sys\n"
        "from ntc_design import cli\n"
        "import ntc_design.simulate.montecarlo as mc\n"
        "def swallow():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        for _ in range(10**6): pass  # the handler runs here and raises\n"
        "    except KeyboardInterrupt:\n"
        "        pass  # lost, as in a __del__\n"
        f"sys.argv = ['ntc', 'simulate', {str(sc)!r}, '--out', {str(tmp_path / 'o')!r}]\n"
        "orig = mc.merge\n"  # called in this process per finished chunk, one worker or two
        "calls = []\n"
        "def merge(*a, **k):\n"
        "    calls.append(1)\n"
        "    if len(calls) == 3: swallow()\n"
        "    return orig(*a, **k)\n"
        "mc.merge = merge\n"
        "cli.run()\n"
    )
    proc = subprocess.run(
        [sys.executable, str(probe)], cwd=ROOT, capture_output=True, text=True, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    assert proc.returncode == 130, proc.stderr[-500:]
    assert said_lines(proc.stderr) == ["error: interrupted"], proc.stderr[-500:]
    assert not (tmp_path / "o").exists()  # nothing half-written


@pytest.mark.hostile
def test_reproduce_out_checked_before_the_run(tmp_path, capsys, monkeypatch):
    import ntc_design.reports.reproduce as rp

    def no_run(*a, **kw):
        raise AssertionError("the paper's runs started before --out was checked")

    monkeypatch.setattr(rp, "simulate", no_run)
    f = tmp_path / "taken"
    f.write_text("mine")
    assert_input_error(
        ["reproduce", "paper", "--out", f], capsys, monkeypatch, "--out", "existing file"
    )
    assert f.read_text() == "mine"


@pytest.mark.hostile
def test_os_error_is_one_line(tmp_path, capsys, monkeypatch):
    import ntc_design.reports.report as rp

    def denied(directory, **kw):
        raise PermissionError(13, "Permission denied", str(directory))

    monkeypatch.setattr(rp, "write_report", denied)
    assert_input_error(["report", tmp_path], capsys, monkeypatch, "Permission denied")
