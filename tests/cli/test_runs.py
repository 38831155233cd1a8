"""Tests of :mod:`ntc_design.cli.runs`: simulate, tune, sweep, report and reproduce."""

import json
from pathlib import Path

import pytest

from tests.cli_helpers import assert_input_error, run_cli
from tests.conftest import EXAMPLES, ROOT


def test_simulate_takes_overrides(tmp_path, capsys, monkeypatch):
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    args = ["simulate", sc, "--out", tmp_path / "o", "--paths", "30", "--T", "0.5"]
    code, _, err = run_cli(
        [*args, "--seed", "9", "--method", "mc", "--dt", "0.01"], capsys, monkeypatch
    )
    assert code == 0, err
    p = json.loads((tmp_path / "o" / "summary.json").read_text())["parameters"]
    assert (p["paths"], p["T"], p["seed"], p["method"], p["dt"]) == (30, 0.5, 9, "mc", 0.01)
    assert_input_error(
        ["simulate", sc, "--out", tmp_path / "p", "--paths", "0"], capsys, monkeypatch, "paths"
    )
    assert not (tmp_path / "p").exists()


def test_sweep_json(tmp_path, capsys, monkeypatch):
    sw = tmp_path / "sw.yaml"
    sw.write_text(
        f"base: {EXAMPLES / 'scenarios' / 'g1_fixed.yaml'}\ngrid: {{margin: [0.1, 1.0]}}\n"
    )
    code, out, err = run_cli(
        ["sweep", sw, "--out", tmp_path / "o", "--json", "--workers", "1"], capsys, monkeypatch
    )
    assert code == 0, err
    doc = json.loads(out)
    assert doc["points"] == 2 and doc["computed"] == 2 and doc["failed"] == 0
    assert doc["failures"] == [] and any(f.endswith("results.csv") for f in doc["files"])


def test_reproduce_unknown_target(tmp_path, capsys, monkeypatch):
    assert_input_error(
        ["reproduce", "thesis", "--out", tmp_path / "x"],
        capsys,
        monkeypatch,
        "unknown target 'thesis'",
    )
    assert not Path(tmp_path / "x").exists()


def test_simulate_json_and_plain_progress(tmp_path, capsys, monkeypatch):
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        f"topology: {ROOT / 'examples' / 'g1.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "T: 0.2\npaths: 20\nsave_every: 0.1\nworkers: 1\n"
    )
    code, text, err = run_cli(
        ["simulate", sc, "--out", tmp_path / "r", "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    doc = json.loads(text)
    assert doc["ok"] and set(doc["final_ms_error_exact"]) == {str(a) for a in range(1, 8)}
    assert str(tmp_path / "r" / "ms_error_long.csv") in doc["files"]


@pytest.mark.hostile
def test_cli_out_that_is_a_file_is_refused_before_the_run(examples, tmp_path, capsys, monkeypatch):
    f = tmp_path / "taken"
    f.write_text("mine", encoding="utf-8")
    assert_input_error(
        ["tune", examples / "scenarios" / "g1_fixed.yaml", "--horizon", "1", "--out", f],
        capsys,
        monkeypatch,
        "--out",
    )
    assert f.read_text(encoding="utf-8") == "mine"


def test_cli_prints_the_table_and_exits_zero(examples, capsys, monkeypatch, tmp_path):
    # a 3×3 landscape, not 13×9: its contour map is still drawn and named (CI time)
    monkeypatch.setattr("ntc_design.tune.power.LANDSCAPE_SHAPE", (3, 3))
    code, out, err = run_cli(
        [
            "tune",
            examples / "scenarios" / "g1_fixed.yaml",
            "--horizon",
            "2",
            "--evaluations",
            "30",
            "--out",
            tmp_path / "t",
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    for label in ("gain c(t)", "E Σ‖x_i(T) − θ‖², T = 2.0000", "certificate of the tuned design"):
        assert label in out
    said = " ".join(out.split("written to", 1)[1].split())  # the line, unwrapped
    files = sorted(p.name for p in (tmp_path / "t").iterdir() if p.is_file())
    assert files and all(f in said for f in files), (files, said)  # every file is named


@pytest.mark.hostile
def test_the_gpu_refusal_comes_before_any_progress_line(tmp_path, capsys, monkeypatch):
    # a loaded machine, made certain: the heartbeat prints as soon as a progress starts (as
    # if 5 s had gone by in the imports), and this machine has no GPU
    import ntc_design.reports.terminal as terminal
    import ntc_design.simulate.driver as driver
    from ntc_design.errors import InputError, Option

    class AtOnce(terminal.Progress):
        def __enter__(self):
            super().__enter__()
            self._line("simulating")
            return self

    def no_gpu():
        raise InputError(
            "gpu: no NVIDIA driver on this machine; use ",
            Option("device", "cpu", document=True),
            field="device",
        )

    monkeypatch.setattr(terminal, "Progress", AtOnce)
    monkeypatch.setattr(driver, "load_cuda", no_gpu)
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    args = ["simulate", sc, "--device", "gpu", "--paths", "8", "--T", "0.05"]
    code, out, err = run_cli([*args, "--out", tmp_path / "o"], capsys, monkeypatch)
    lines = [ln for ln in err.splitlines() if ln.strip()]  # every line, the heartbeat's too
    assert code == 2 and out == "" and len(lines) == 1, err
    assert lines[0].startswith("error: --device: gpu") and "no NVIDIA driver" in lines[0]
    assert not (tmp_path / "o").exists()
    code, _, err = run_cli(
        [*args[:2], "--paths", "8", "--T", "0.05", "--out", tmp_path / "c"], capsys, monkeypatch
    )
    assert code == 0 and "simulating" in err  # the progress itself is as before


@pytest.mark.hostile
def test_simulate_on_a_gpu_without_one_is_one_line_and_exit_2(tmp_path):
    # a fresh process without numba-cuda's simulator: the machine as it is
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if "CUDASIM" not in k and "NTC_CUDA" not in k}
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    in_file = tmp_path / "gpu.yaml"  # the same, with device: gpu in the file
    in_file.write_text(
        sc.read_text(encoding="utf-8").replace("../g1.yaml", str(EXAMPLES / "g1.yaml"))
        + "device: gpu\n",
        encoding="utf-8",
    )
    for scenario, flag, who in ((sc, ["--device", "gpu"], "--device"), (in_file, [], None)):
        args = ["simulate", scenario, *flag, "--paths", "8", "--T", "0.05"]
        r = subprocess.run(
            [sys.executable, "-m", "ntc_design", *map(str, args), "--out", str(tmp_path / "o")],
            env=env, cwd=ROOT, capture_output=True, text=True,
        )  # fmt: skip
        if r.returncode == 0:
            pytest.skip("this machine has a usable GPU")
        lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
        assert r.returncode == 2 and len(lines) == 1, r.stderr
        # the flag that asked for the GPU is named, or else the file that did
        head = f"error: {who}: gpu" if who else f"error: {in_file}: device: gpu"
        assert lines[0].startswith(head) and "Traceback" not in r.stderr, lines[0]
        assert not (tmp_path / "o").exists()


@pytest.mark.hostile
def test_simulate_device_gpu_with_numpy_normals_is_refused(tmp_path, capsys, monkeypatch):
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    args = ["simulate", sc, "--device", "gpu", "--rng", "numpy", "--out", tmp_path / "o"]
    assert_input_error(args, capsys, monkeypatch, "rng: numpy stays on the CPU")
    assert not (tmp_path / "o").exists()


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_simulate_device_gpu_runs_where_the_fixture_says(
    tmp_path, capsys, monkeypatch, cuda_device
):
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    args = ["simulate", sc, "--device", "gpu", "--paths", "4", "--T", "0.01", "--method", "mc"]
    code, out, err = run_cli([*args, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 0, err
    doc = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert doc["parameters"]["device"] == "gpu" and doc["run"]["engine"]["engine"] == "gpu"
    assert "path-steps/s on " in out


# -- a value given by a flag is checked and named as the flag, never as the file ---------

G1_FIXED = EXAMPLES / "scenarios" / "g1_fixed.yaml"


@pytest.mark.hostile
@pytest.mark.parametrize(
    "command, extra, line",
    [
        ("simulate", ["--paths", "-5"], "--paths: must be a positive integer, got -5"),
        ("simulate", ["--paths", "0"], "--paths: must be a positive integer, got 0"),
        ("simulate", ["--horizon", "-1"], "--horizon: must be a positive number"),
        ("simulate", ["--T", "nan"], "--horizon: must be finite"),
        ("simulate", ["--dt", "0"], "--dt: must be a positive number"),
        ("simulate", ["--seed", "-1"], "--seed: must be an integer >= 0"),
        ("simulate", ["--method", "fast"], "--method: must be mc, exact or both"),
        ("simulate", ["--rng", "pcg"], "--rng: expected xoshiro or numpy"),
        ("simulate", ["--device", "tpu"], "--device: expected cpu or gpu"),
        ("simulate", ["--paths", "100000000000"], "--paths: 1.01e+15 path-steps"),
        ("simulate", ["--period", "20"], "--period: h = 20 is longer than the horizon"),
        ("simulate", ["--period", "0.1", "--loss", "1.5"], "--loss: a loss probability must"),
        ("simulate", ["--period", "0.1", "--loss", "nan"], "--loss: a loss probability must"),
        ("simulate", ["--loss", "0.1"], "--loss: needs --period"),
        ("simulate", ["--period", "0.1", "--loss-policy", "drop"], "--loss-policy: unknown"),
        # the file's dt breaks a limit because of the flag: the file is named, with the flag
        ("simulate", ["--horizon", "1e12"], "g1_fixed.yaml: dt: the run would need"),
        ("tune", ["--horizon", "-1"], "--horizon: must be a positive number"),
        ("tune", ["--evaluations", "0"], "--evaluations: expected an integer in [10, 10000]"),
        ("tune", ["--eps", "-1"], "--eps: must be a positive number"),
        ("tune", ["--method", "both"], "--method: expected auto, exact or mc, got 'both'"),
        ("tune", ["--require", "sure"], "--require: expected one of both, mean-square"),
        ("tune", ["--schedule", "best"], "--schedule: expected power or optimal"),
        ("tune", ["--max-gain", "5"], "--max-gain: applies to --schedule optimal"),
        ("tune", ["--check-paths", "5"], "--check-paths: applies to --schedule optimal"),
        (
            "tune",
            ["--schedule", "optimal", "--max-gain", "-1"],
            "--max-gain: expected a number in (1e-06",
        ),
        ("tune", ["--schedule", "optimal", "--check-paths", "-1"], "--check-paths: expected"),
        # the library names its parameters; the command line writes them as its flags
        (
            "tune",
            ["--schedule", "optimal", "--method", "mc"],
            "--schedule optimal: uses exact moments (--method mc is for --schedule power)",
        ),
        ("tune", ["--period", "auto", "--loss", "auto"], "--period: give a number with --loss"),
        ("tune", ["--period", "0.1", "--delay", "-1"], "--delay: must be an integer >= 0"),
        ("tune", ["--period", "auto", "--horizon", "-2"], "--horizon: must be a positive"),
        ("tune", ["--period", "auto", "--tolerance", "-1"], "--tolerance: must be >= 0"),
        ("reproduce", ["--horizon", "-1"], "--horizon: must be a positive number"),
        ("reproduce", ["--paths", "0"], "--paths: must be a positive integer"),
        ("reproduce", ["--dt", "-1"], "--dt: must be a positive number"),
        ("reproduce", ["--stepping", "rk4"], "--stepping: must be uniform or intrinsic"),
        ("reproduce", ["--seed", "-1"], "--seed: must be an integer >= 0"),
        ("reproduce", ["--dt", "1e-12"], "--dt: the run would need"),
        ("report", ["--period", "-1"], "--period: must be a positive number"),
        ("sweep", ["--workers", "0"], "--workers: must be a positive integer"),
    ],
)
def test_an_override_flag_is_named_not_the_file(
    tmp_path, capsys, monkeypatch, command, extra, line
):
    out = tmp_path / "o"
    first = {
        "simulate": [G1_FIXED, "--out", out],
        "tune": [G1_FIXED, "--out", out],
        "reproduce": ["paper", "--out", out],
        "report": [tmp_path],
        "sweep": [EXAMPLES / "sweeps" / "g1_noise.yaml", "--out", out],
    }[command]
    got = assert_input_error([command, *first, *extra], capsys, monkeypatch)
    text = got.removeprefix("error: ")
    if line.startswith("--"):
        assert text.startswith(line), text
    else:
        assert line in text and text.endswith("(with --horizon 1e+12)"), text
    assert not out.exists()  # nothing written


def test_tune_defaults_its_deadline_to_the_scenario_t(tmp_path, capsys, monkeypatch):
    (tmp_path / "cycle.yaml").write_text(  # 3 agents, d = 1: the horizon is what is checked
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: cycle.yaml\ntheta: [1]\nT: 2\nnoise: {sigma: 0.4, f: 0.3}\n",
        encoding="utf-8",
    )
    args = ["tune", sc, "--evaluations", "10", "--json"]
    monkeypatch.setattr("ntc_design.tune.power.LANDSCAPE_SHAPE", (2, 2))  # not what is checked
    code, out, err = run_cli(args, capsys, monkeypatch)
    assert code in (0, 1), err
    assert json.loads(out)["horizon"] == 2.0  # no --horizon: the scenario's T
    code, out, err = run_cli([*args, "--horizon", "1"], capsys, monkeypatch)
    assert code in (0, 1), err
    assert json.loads(out)["horizon"] == 1.0  # --horizon still overrides it
    # a bad T in the file is the file's, named as its field
    sc.write_text(sc.read_text().replace("T: 2", "T: -2"), encoding="utf-8")
    assert_input_error(args, capsys, monkeypatch, "sc.yaml: T: must be a positive number")


# -- issue 41, item 7: what escaped as an internal error ------------------------------------


def _settled_scenario(tmp_path):
    """G1 with x(0) = 1⊗θ and no noise: the error is 0 at every t for every gain."""
    sc = tmp_path / "settled.yaml"
    sc.write_text(
        f"topology: {EXAMPLES / 'g1.yaml'}\ntheta: [1, 2, -1]\nnoise: {{sigma: 0, f: 0}}\n"
        f"initial: {[1, 2, -1] * 7}\nT: 2\ndt: 0.01\npaths: 10\n",
        encoding="utf-8",
    )
    return sc


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, line",
    [
        (["--family", "exp"], "--family: replaced by --schedule power|optimal"),
        (["--family", "power", "--schedule", "optimal"], "--family: power contradicts"),
    ],
)
def test_family_is_a_deprecated_alias_of_schedule_power(tmp_path, capsys, monkeypatch, extra, line):
    got = assert_input_error(["tune", G1_FIXED, *extra], capsys, monkeypatch)
    assert got.removeprefix("error: ").startswith(line)


@pytest.mark.parametrize(
    "command, usage",
    [
        ("design", "Usage: ntc design [OPTIONS] FILE"),
        ("tune", "Usage: ntc tune [OPTIONS] SCENARIO"),
        ("simulate", "Usage: ntc simulate [OPTIONS] SCENARIO"),
        ("report", "Usage: ntc report [OPTIONS] DIRECTORY"),
        ("verify", "Usage: ntc verify [OPTIONS] CERT"),
    ],
)
def test_usage_lines_name_arguments_as_click_does(capsys, monkeypatch, command, usage):
    code, out, _ = run_cli([command, "--help"], capsys, monkeypatch)
    assert code == 0 and usage in out and "{" not in out.split("\n\n")[0], out[:200]
    code, _, err = run_cli([command], capsys, monkeypatch)
    assert code == 2 and "Missing argument '" + usage.split()[-1] + "'" in err


@pytest.mark.hostile
@pytest.mark.parametrize(
    "command, needles",
    [
        (["tune", "fixed", "--horizon", "5e-324"], ["--horizon", "shortest horizon 1e-09"]),
        (["tune", "deadline", "--horizon", "1e-300", "--schedule", "optimal"], ["--horizon"]),
        (["tune", "tv", "--horizon", "1e-12"], ["--horizon", "shortest horizon"]),
        (["simulate", "tv", "--horizon", "5e-324"], ["--horizon", "shortest horizon"]),
        (
            ["tune", "deadline", "--horizon", "2", "--schedule", "optimal", "--max-gain", "1e-7"],
            ["--max-gain", "(1e-06, 1e+06]", "got 1e-07"],
        ),
        (
            ["tune", "settled", "--horizon", "2", "--schedule", "optimal", "--max-peak", "0.5"],
            ["initial: x(0) = 1⊗θ and noise.sigma = 0", "nothing to tune"],
        ),
        (
            ["tune", "settled", "--horizon", "2", "--schedule", "optimal"],
            ["nothing to tune"],
        ),
    ],
)
def test_what_was_an_internal_error_is_one_line_naming_the_flag(
    command, needles, tmp_path, capsys, monkeypatch
):
    files = {
        "fixed": EXAMPLES / "scenarios" / "g1_fixed.yaml",
        "deadline": EXAMPLES / "scenarios" / "g1_deadline.yaml",
        "tv": EXAMPLES / "scenarios" / "g1_tv.yaml",
    }
    name = command[1]
    sc = _settled_scenario(tmp_path) if name == "settled" else files[name]
    out = tmp_path / "o"
    args = [command[0], sc, *command[2:], "--out", out]
    line = assert_input_error(args, capsys, monkeypatch, *needles)
    assert "internal error" not in line
    assert not out.exists()


@pytest.mark.hostile
def test_reproduce_refuses_a_subnormal_horizon_before_any_run(tmp_path, capsys, monkeypatch):
    out = tmp_path / "p"
    args = ["reproduce", "paper", "--out", out, "--horizon", "5e-324"]
    assert_input_error(args, capsys, monkeypatch, "--horizon", "shortest horizon")
    assert not out.exists()


def test_simulate_says_when_it_replaces_an_earlier_run(tmp_path, capsys, monkeypatch):
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        f"topology: {ROOT / 'examples' / 'g1.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "T: 0.2\npaths: 4\nsave_every: 0.1\nworkers: 1\nmethod: exact\n"
    )
    out = tmp_path / "r"
    notes = []
    for seed in ("1", "2"):
        code, _, err = run_cli(["simulate", sc, "--out", out, "--seed", seed], capsys, monkeypatch)
        assert code == 0, err
        notes.append([ln for ln in err.splitlines() if ln.startswith("note: replacing")])
    assert notes == [[], [f"note: replacing the run in {out}"]]
    assert json.loads((out / "summary.json").read_text())["parameters"]["seed"] == 2


@pytest.mark.slow  # a first run compiles the kernel into an empty cache (~3 s of CPU)
def test_a_first_simulation_says_once_that_it_compiles(tmp_path):
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    said = []
    for run in ("first", "second"):
        args = ["simulate", sc, "--paths", "4", "--T", "0.01", "--method", "mc"]
        r = subprocess.run(
            [sys.executable, "-m", "ntc_design", *map(str, args), "--out", str(tmp_path / run)],
            env=env, cwd=ROOT, capture_output=True, text=True, timeout=600,
        )  # fmt: skip
        assert r.returncode == 0, r.stderr[-2000:]
        said.append([ln for ln in r.stderr.splitlines() if "compiling" in ln])
    # the first run: one line before it compiles; the second loads the kernel and is silent
    assert said == [["note: compiling the simulation kernels once, about 3 s of CPU"], []], said


def test_simulate_on_lossy_links_reports_the_offset(tmp_path, capsys, monkeypatch):
    out = tmp_path / "o"
    args = ["simulate", G1_FIXED, "--out", out, "--period", "0.1", "--loss", "0.1"]
    code, text, err = run_cli(
        [*args, "--method", "exact", "--horizon", "2", "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    doc = json.loads(text)
    block = doc["digital"]["loss"]
    assert block["policy"] == "skip" and block["p"] == 0.1
    assert block["offset"] == pytest.approx(0.1433, abs=1e-3)
    assert any("‖x* − 1⊗θ‖ = 0.1433" in n for n in doc["notes"])


@pytest.mark.hostile
def test_a_bad_loss_in_the_scenario_names_the_file_and_field(tmp_path, capsys, monkeypatch):
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        f"topology: {EXAMPLES / 'g1.yaml'}\ntheta: [1, 2, -1]\nT: 2\n"
        "digital: {period: 0.1, loss: 2}\n",
        encoding="utf-8",
    )
    out = tmp_path / "o"
    line = assert_input_error(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert "sc.yaml" in line and "digital.loss" in line
    assert not out.exists()


def test_tune_finds_the_largest_tolerable_loss(tmp_path, capsys, monkeypatch):
    sc = EXAMPLES / "scenarios" / "g1_deadline.yaml"
    out = tmp_path / "o"
    args = ["tune", sc, "--loss", "auto", "--period", "0.1", "--out", out, "--json"]
    code, text, err = run_cli(args, capsys, monkeypatch)
    assert code == 0, err
    doc = json.loads(text)
    assert doc["loss"] == pytest.approx(0.096, abs=1e-3) and doc["policy"] == "skip"
    assert doc["curve"][0]["loss"] == 0.0 and doc["curve"][0]["ok"]
    assert json.loads((out / "loss.json").read_text(encoding="utf-8"))["loss"] == doc["loss"]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, line",
    [
        (["--loss", "0.2", "--period", "0.1"], "--loss: expected auto"),
        (["--loss", "auto", "--period", "auto"], "--period: give a number with --loss auto"),
        (["--loss", "auto"], "--loss: needs --period"),
        (["--loss", "auto", "--period", "0.1", "--loss-policy", "x"], "--loss-policy: unknown"),
        (["--loss", "auto", "--period", "0.1", "--tolerance", "-1"], "--tolerance: must be >= 0"),
    ],
)
def test_tune_loss_refuses_bad_flags(tmp_path, capsys, monkeypatch, extra, line):
    out = tmp_path / "o"
    got = assert_input_error(["tune", G1_FIXED, "--out", out, *extra], capsys, monkeypatch)
    assert got.removeprefix("error: ").startswith(line), got
    assert not out.exists()


@pytest.mark.hostile
def test_report_loss_flags_are_checked(tmp_path, capsys, monkeypatch):
    line = assert_input_error(["report", tmp_path, "--loss", "2"], capsys, monkeypatch)
    assert line.startswith("error: --loss: a loss probability")
    line = assert_input_error(["report", tmp_path, "--loss", "0.1"], capsys, monkeypatch)
    assert line.startswith("error: --loss: needs --period")


def test_simulate_period_passes_one_digital_and_decides_its_steps_once(
    tmp_path, capsys, monkeypatch
):
    """``ntc simulate --period 0.1``: the flags make one Digital (beside the early check of
    the flags' values), passed as itself to the spec, whose K = ⌊T/h⌋ the size check, the
    grid and the summary read (issue 48: it was built three times and stepped five)."""
    from ntc_design.protocol.digital import Digital

    made, stepped = [], []
    init, steps = Digital.__post_init__, Digital.steps

    def counted_init(self):
        made.append(self)
        init(self)

    def counted_steps(self, t_end):
        stepped.append(t_end)
        return steps(self, t_end)

    monkeypatch.setattr(Digital, "__post_init__", counted_init)
    monkeypatch.setattr(Digital, "steps", counted_steps)
    args = ["simulate", G1_FIXED, "--out", tmp_path / "o", "--paths", "8", "--T", "1"]
    code, _, err = run_cli([*args, "--period", "0.1", "--method", "both"], capsys, monkeypatch)
    assert code == 0, err
    assert stepped == [1.0] and len(made) == 2
    doc = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert doc["overrides"]["digital"] == {"period": 0.1, "delay": 0}
    assert (doc["digital"]["steps"], doc["digital"]["partial_step"]) == (10, 0.0)
