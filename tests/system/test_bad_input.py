"""Bad input: one line naming the file and the edge or field, exit code 2, nothing on
stdout, no traceback."""

import subprocess
import sys
import textwrap

import pytest

from tests.cli_helpers import assert_input_error, run_cli

HEAD = "dim: 2\nagents: 3\nedges:\n"


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


@pytest.mark.parametrize(
    "edges, needles",
    [
        ("  - {from: 1, to: 2, weight: [[1, 2], [0, 1]]}\n", ["edge 1->2", "not symmetric"]),
        ("  - {from: 1, to: 2, weight: {diag: [1, -1]}}\n", ["edge 1->2", "indefinite"]),
        ("  - {from: 1, to: 2, weight: [[.nan, 0], [0, 1]]}\n", ["edge 1->2", "finite"]),
        ("  - {from: 1, to: 2, weight: [[.inf, 0], [0, 1]]}\n", ["edge 1->2", "finite"]),
        ("  - {from: 1, to: 2, weight: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}\n", ["edge 1->2", "2x2"]),
        ("  - {from: 1, to: 9, weight: 1}\n", ["edge 1->9", "unknown agent label '9'"]),
        ("  - {from: 2, to: 2, weight: 1}\n", ["edge 2->2", "self-loop"]),
        (
            "  - {from: 1, to: 2, weight: 1}\n  - {from: 1, to: 2, weight: 2}\n",
            ["edge 1->2", "duplicated"],
        ),
        (
            "  - {from: 1, to: 2, weight: [[1, x], [x, 1]]}\n",
            ["edge 1->2: weight[0][1]", "only the variable t"],
        ),
        (
            "  - {from: 1, to: 2, wieght: 1}\n",
            ["edges[0]", "unknown field 'wieght'", "did you mean 'weight'"],
        ),
    ],
)
def test_bad_weights(tmp_path, capsys, monkeypatch, edges, needles):
    p = write(tmp_path, "bad.yaml", HEAD + edges)
    assert_input_error(["check", p], capsys, monkeypatch, str(p), *needles)


@pytest.mark.parametrize(
    "text, needles",
    [
        ("", ["the file is empty"]),
        ("dim: 2\nagents: [1, 2\n", ["not valid YAML"]),
        ("- 1\n- 2\n", ["expected a mapping"]),
        ("agents: 3\nedges: []\n", ["dim: missing"]),
        ("dim: 0\nagents: 3\nedges: []\n", ["dim: expected a positive integer"]),
        ("dim: 2\nagents: 3\nedges: []\ncolour: red\n", ["colour: unknown field"]),
    ],
)
def test_malformed_files(tmp_path, capsys, monkeypatch, text, needles):
    p = write(tmp_path, "bad.yaml", text)
    assert_input_error(["check", p], capsys, monkeypatch, str(p), *needles)


def test_bad_json(tmp_path, capsys, monkeypatch):
    p = write(tmp_path, "bad.json", '{"dim": 2, "agents": 3,}')
    assert_input_error(
        ["design", p, "--theta", "1,1"], capsys, monkeypatch, str(p), "not valid JSON"
    )


def test_missing_file(tmp_path, capsys, monkeypatch):
    p = tmp_path / "nope.yaml"
    assert_input_error(["check", p], capsys, monkeypatch, str(p), "no such file")


@pytest.mark.parametrize(
    "theta, margin, needles",
    [
        ("0,0,0", "0.1", ["theta", "non-zero"]),
        ("1,2", "0.1", ["theta", "expected 3 numbers"]),
        ("1,a,2", "0.1", ["--theta", "comma-separated numbers"]),
        ("1,2,-1", "0", ["margin", "positive"]),
        ("1,2,-1", "-0.5", ["margin", "positive"]),
    ],
)
def test_bad_design_parameters(examples, capsys, monkeypatch, theta, margin, needles):
    args = ["design", examples / "g1.yaml", "--theta", theta, "--margin", margin]
    assert_input_error(args, capsys, monkeypatch, *needles)


def test_switching_unknown_mode_and_duration(tmp_path, examples, capsys, monkeypatch):
    g1 = (examples / "g1.yaml").resolve()
    p = write(
        tmp_path, "sw.yaml", f"modes: {{G1: {g1}}}\nschedule: [{{mode: G9, duration: 0.1}}]\n"
    )
    assert_input_error(
        ["check", p], capsys, monkeypatch, str(p), "schedule[0]", "unknown mode 'G9'"
    )
    p = write(tmp_path, "sw2.yaml", f"modes: {{G1: {g1}}}\nschedule: [{{mode: G1, duration: 0}}]\n")
    assert_input_error(
        ["check", p], capsys, monkeypatch, str(p), "schedule[0].duration", "positive"
    )
    p = write(
        tmp_path,
        "sw3.yaml",
        f"modes: {{G1: {g1}, H: small.yaml}}\nschedule: [{{mode: G1, duration: 1}}]\n",
    )
    write(tmp_path, "small.yaml", "dim: 3\nagents: 2\nedges: []\n")
    assert_input_error(["check", p], capsys, monkeypatch, str(p), "modes.H", "all modes must share")


def test_missing_mode_file_names_it(tmp_path, capsys, monkeypatch):
    p = write(tmp_path, "sw.yaml", "modes: {A: gone.yaml}\nschedule: [{mode: A, duration: 1}]\n")
    assert_input_error(["check", p], capsys, monkeypatch, "gone.yaml", "no such file")


def test_real_process_exit_code_and_no_traceback(tmp_path):
    p = write(tmp_path, "bad.yaml", HEAD + "  - {from: 1, to: 2, weight: {diag: [1, -1]}}\n")
    r = subprocess.run(
        [sys.executable, "-m", "ntc_design", "design", str(p), "--theta", "1,1"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert r.stderr.startswith(f"error: {p}: edge 1->2: weight is indefinite")


def test_design_json_keys(examples, capsys, monkeypatch):
    import json

    code, out, err = run_cli(
        ["design", examples / "g1.yaml", "--theta", "1,2,-1", "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    doc = json.loads(out)
    for k in (
        "C",
        "delta",
        "k1",
        "x0",
        "informed",
        "B",
        "V1",
        "V2",
        "assumption_holds",
        "violations",
        "identity_residual",
        "thresholds",
    ):
        assert k in doc
    for k in ("hurwitz", "symmetric", "best_rate", "best_rate_delta"):
        assert k in doc["thresholds"]
    assert doc["delta"] == pytest.approx(7.2440, abs=5e-5)
    assert set(doc["B"]) == {"2", "3"}
    code, out, _ = run_cli(
        ["design", examples / "switching.yaml", "--theta", "1,2,-1", "--json"], capsys, monkeypatch
    )
    sw = json.loads(out)
    assert sw["modes"]["G3"]["delta"] == pytest.approx(3.1, abs=5e-5)
    code, out, _ = run_cli(["check", examples / "g1.yaml", "--json"], capsys, monkeypatch)
    chk = json.loads(out)
    assert chk["V1"] == [2, 3] and chk["U"] == [2, 3]
    assert chk["per_agent"]["3"]["in_degree_dominated"] is False
