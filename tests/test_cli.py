"""The command line's ergonomics: exit codes, overrides, --json, help, spelling hints,
and warnings attributed to the user's own call."""

import json
import warnings

import pytest

import ntc_design as nd

from .cli_helpers import assert_input_error, run_cli
from .conftest import EXAMPLES


@pytest.mark.parametrize(
    "expr, code", [("1/(1+t)", 0), ("(1+t)^(-1/3)", 0), ("(1+t)^(-2)", 1), ("exp(-t)", 1)]
)
def test_gain_exit_code_says_whether_a_theorem_applies(expr, code, capsys, monkeypatch):
    got, out, _ = run_cli(["gain", expr], capsys, monkeypatch)
    assert got == code, out
    got, out, _ = run_cli(["gain", expr, "--json"], capsys, monkeypatch)
    assert got == code and (json.loads(out)["mean_square"] is True) == (code == 0)


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


def test_a_misspelt_key_is_named_with_its_close_match(tmp_path, capsys, monkeypatch):
    f = tmp_path / "t.yaml"
    f.write_text("dim: 1\nagents: 2\nedges:\n  - {from: 1, to: 2, wieght: 1}\n")
    line = assert_input_error(["check", f], capsys, monkeypatch, "edges[0]", "'wieght'")
    assert "did you mean 'weight'" in line and "missing" not in line
    f.write_text("dim: 1\nagent: 2\nedges: []\n")
    assert_input_error(["check", f], capsys, monkeypatch, "did you mean 'agents'")


@pytest.mark.parametrize("command", ["certify", "simulate", "sweep", "gain", "report", "design"])
def test_help_ends_with_an_example(command, capsys, monkeypatch):
    code, out, _ = run_cli([command, "--help"], capsys, monkeypatch)
    assert code == 0
    assert f"Example: ntc {command}" in " ".join(out.split())
    # flags take no value: no <bool> metavar on ours (typer's own --help keeps it)
    assert [ln for ln in out.splitlines() if "<bool>" in ln and "--help" not in ln] == []


def test_assumption_warning_points_at_the_users_call():
    top = nd.load(EXAMPLES / "g3.yaml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        nd.design(top, [1, 2, -1], 0.1)
    (w,) = [w for w in caught if issubclass(w.category, nd.AssumptionWarning)]
    assert w.filename == __file__


@pytest.mark.parametrize(
    "command",
    [
        "check",
        "design",
        "generate",
        "gain",
        "certify",
        "verify",
        "simulate",
        "sweep",
        "report",
        "reproduce",
    ],
)
def test_every_command_with_a_result_has_json(command, capsys, monkeypatch):
    code, out, _ = run_cli([command, "--help"], capsys, monkeypatch)
    assert code == 0 and "--json" in out


def test_generate_json(tmp_path, capsys, monkeypatch):
    code, out, err = run_cli(
        ["generate", "--n", "12", "--d", "2", "--out", tmp_path / "g.npz", "--json"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    doc = json.loads(out)
    top = nd.load(tmp_path / "g.npz")
    assert (
        (doc["N"], doc["d"], doc["edges"])
        == (top.n, top.dim, len(top.weights))
        == (12, 2, doc["edges"])
    )
