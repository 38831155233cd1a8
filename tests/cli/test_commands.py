"""Tests of :mod:`ntc_design.cli.commands`."""

import copy
import json

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import verify
from tests.cli_helpers import assert_input_error, run_cli
from tests.conftest import EXAMPLES


def test_certify_out_is_written_only_on_success(tmp_path, examples, capsys, monkeypatch):
    out = tmp_path / "c.json"
    assert_input_error(
        ["certify", examples / "g1.yaml", "--theta", "0,0,0", "--out", out],
        capsys,
        monkeypatch,
        "theta",
    )
    assert not out.exists()
    code, _, err = run_cli(
        ["certify", examples / "g1.yaml", "--theta", "1,2,-1", "--out", out], capsys, monkeypatch
    )
    assert code == 0, err
    assert verify(json.loads(out.read_text())).valid
    doc = copy.deepcopy(json.loads(out.read_text()))
    assert verify(doc).method == "exact-rational"


@pytest.mark.parametrize(
    "expr, code", [("1/(1+t)", 0), ("(1+t)^(-1/3)", 0), ("(1+t)^(-2)", 1), ("exp(-t)", 1)]
)
def test_gain_exit_code_says_whether_a_theorem_applies(expr, code, capsys, monkeypatch):
    got, out, _ = run_cli(["gain", expr], capsys, monkeypatch)
    assert got == code, out
    got, out, _ = run_cli(["gain", expr, "--json"], capsys, monkeypatch)
    assert got == code and (json.loads(out)["mean_square"] is True) == (code == 0)


@pytest.mark.parametrize(
    "command", ["certify", "simulate", "sweep", "gain", "report", "design", "export"]
)
def test_help_ends_with_an_example(command, capsys, monkeypatch):
    code, out, _ = run_cli([command, "--help"], capsys, monkeypatch)
    assert code == 0
    assert f"Example: ntc {command}" in " ".join(out.split())
    # flags take no value: no <bool> metavar on ours (typer's own --help keeps it)
    assert [ln for ln in out.splitlines() if "<bool>" in ln and "--help" not in ln] == []


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
        "export",
    ],
)
def test_every_command_with_a_result_has_json(command, capsys, monkeypatch):
    code, out, _ = run_cli([command, "--help"], capsys, monkeypatch)
    assert code == 0 and "--json" in out


def test_generate_json(tmp_path, capsys, monkeypatch):
    code, out, err = run_cli(
        ["generate", "--agents", "12", "--dim", "2", "--out", tmp_path / "g.npz", "--json"],
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


@pytest.mark.parametrize(
    "flags",
    [["--agents", "7", "--dim", "2"], ["--n", "7", "--d", "2"]],
    ids=["names", "old names"],
)
def test_generate_names_agents_and_dimension(tmp_path, capsys, monkeypatch, flags):
    code, _, err = run_cli(["generate", *flags, "--out", tmp_path / "g.npz"], capsys, monkeypatch)
    top = nd.load(tmp_path / "g.npz")
    assert code == 0 and (top.n, top.dim) == (7, 2)
    notes = [ln for ln in err.splitlines() if ln.startswith("note:")]
    assert notes == (
        [] if flags[0] == "--agents" else
        ["note: --n is deprecated; it is --agents", "note: --d is deprecated; it is --dim"]
    )  # fmt: skip


@pytest.mark.hostile
@pytest.mark.parametrize(
    "flags, needle",
    [
        ([], "--agents: missing"),
        (["--agents", "1"], "--agents: a network needs at least 2 agents"),
        (["--agents", "5", "--seed", "-1"], "--seed: must be a non-negative integer"),
        (["--agents", "5", "--p-negative", "2"], "--p-negative: must be in [0, 1]"),
        (["--agents", "5", "--n", "5"], "--n: the old spelling of --agents"),
    ],
)
def test_generate_refusals_name_the_flag(tmp_path, capsys, monkeypatch, flags, needle):
    assert_input_error(
        ["generate", *flags, "--out", tmp_path / "g.npz"], capsys, monkeypatch, needle
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.hostile
def test_out_above_the_dense_size_is_refused_before_work(tmp_path, capsys, monkeypatch):
    from ntc_design.model.generate import random_network

    p = tmp_path / "big.yaml"
    import yaml

    p.write_text(yaml.safe_dump(random_network(70, 3, seed=1).to_dict()))  # Nd = 210
    from ntc_design.certify.robust.are import RICCATI_MAX_ND

    args = ["robust", p, "--theta", "1,2,-1", "--out", tmp_path / "c.json"]
    needle = f"--out: a robust certificate is issued up to Nd = {RICCATI_MAX_ND}"
    assert_input_error(args, capsys, monkeypatch, needle)
    assert not (tmp_path / "c.json").exists()


# -- ntc export ---------------------------------------------------------------------------


def _cycle_scenario(tmp_path) -> str:
    """A scenario on a 3-agent signed cycle (d = 1): its D = 1 certificate takes about 0.2 s
    (G1's delay line about 10 s; G1's export at D = 1 is tests/export/test_run.py's)."""
    (tmp_path / "cycle.yaml").write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    p = tmp_path / "cycle-scenario.yaml"
    p.write_text("topology: cycle.yaml\ntheta: [1]\ngain: 1/(1+t)\ninitial: [1, -1, 0.5]\nT: 5\n")
    return str(p)


def test_export_writes_the_folder(tmp_path, examples, capsys, monkeypatch):
    out = tmp_path / "cycle-c"
    args = ["export", _cycle_scenario(tmp_path), "--lang", "c"]
    code, text, err = run_cli(
        [*args, "--out", out, "--period", "0.1", "--delay", "1"], capsys, monkeypatch
    )
    assert code == 0, err
    assert (
        "exported cycle-scenario (3 agents, d = 1, 1 mode; h = 0.1, D = 1, c(t) = 1/(1+t)) as c"
        in text
    )
    assert (out / "ntc_protocol.c").is_file() and (out / "README.txt").is_file()
    code, text, err = run_cli(
        ["export", examples.parent / "certificates" / "g1.json", "--lang", "python",
         "--out", tmp_path / "py", "--period", "0.05", "--gain", "2/(2+t)", "--json"],
        capsys, monkeypatch,
    )  # fmt: skip
    doc = json.loads(text)
    assert code == 0 and doc["ok"] and doc["kind"] == "certificate (hurwitz)"
    assert doc["period"] == 0.05 and doc["delay"] == 0 and doc["gain"] == "2/(2+t)"
    assert doc["files"] == [
        "ntc_protocol.py",
        "README.txt",
        "example_input.txt",
        "example_output.txt",
    ]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, needles",
    [
        (["--period", "0"], ["--period: must be a positive number"]),
        (["--period", "-0.1"], ["--period: must be a positive number"]),
        (["--period", "nan"], ["--period: must be finite"]),
        (["--period", "inf"], ["--period: must be finite"]),
        (["--period", "11"], ["--period: h = 11 is longer than the horizon T = 10"]),
        (["--period", "0.1", "--delay", "-1"], ["--delay: must be an integer >= 0"]),
        (["--period", "0.1", "--delay", "1.5"], ["--delay", "integer"]),
        (["--period", "0.1", "--lang", "fortran"], ["--lang: expected one of c, python"]),
        ([], ["--period:", "g1_deadline.yaml has no digital block"]),
        (["--period", "0.1", "--gain", "1"], ["g1_deadline.yaml: no theorem is guaranteed"]),
        (["--period", "0.1", "--gain", "__import__('os')"], ["gain: "]),
    ],
)
def test_export_refusals_write_nothing(tmp_path, examples, capsys, monkeypatch, extra, needles):
    out = tmp_path / "o"
    args = ["export", examples / "scenarios" / "g1_deadline.yaml", "--out", out, *extra]
    assert_input_error(args, capsys, monkeypatch, *needles)
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, needles",
    [
        (["--loss", "1"], ["--loss: a loss probability must be finite and in [0, 1)"]),
        (["--loss", "nan"], ["--loss: a loss probability must be finite"]),
        (["--loss", "0.1", "--loss-policy", "drop"], ["--loss-policy: unknown policy 'drop'"]),
        (
            ["--loss", "0.1", "--loss-policy", "hold", "--gain", "exp(-t)"],
            ["lossy links with the hold policy are not proven", "nothing exported"],
        ),
        (
            ["--loss", "0.1", "--delay", "9"],
            ["no theorem is guaranteed", "D = 9", "nothing exported"],
        ),
    ],
)
def test_export_loss_refusals_write_nothing(
    tmp_path, examples, capsys, monkeypatch, extra, needles
):
    out = tmp_path / "o"
    args = ["export", examples / "scenarios" / "g1_deadline.yaml", "--out", out]
    assert_input_error([*args, "--period", "0.1", *extra], capsys, monkeypatch, *needles)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_export_on_lossy_links(tmp_path, examples, capsys, monkeypatch):
    args = ["export", examples / "scenarios" / "g1_deadline.yaml", "--out", tmp_path / "c"]
    extra = ["--period", "0.1", "--loss", "0.1", "--loss-policy", "rescale", "--json"]
    code, text, err = run_cli([*args, *extra], capsys, monkeypatch)
    doc = json.loads(text)
    assert code == 0 and doc["loss_policy"] == "rescale", err
    assert "#define NTC_POLICY 2" in (tmp_path / "c" / "ntc_protocol.h").read_text()


@pytest.mark.hostile
def test_export_refuses_a_certificate_that_does_not_verify(tmp_path, examples, capsys, monkeypatch):
    doc = json.loads((examples.parent / "certificates" / "g1.json").read_text())
    doc["subject"]["modes"]["G1"]["x0"][0] += 1.0
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    out = tmp_path / "o"
    args = ["export", bad, "--out", out, "--period", "0.1"]
    assert_input_error(args, capsys, monkeypatch, str(bad), "the certificate does not verify")
    assert not out.exists()


@pytest.mark.hostile
def test_export_refuses_a_folder_with_other_files(tmp_path, examples, capsys, monkeypatch):
    out = tmp_path / "o"
    out.mkdir()
    (out / "mine.txt").write_text("x")
    args = ["export", examples / "scenarios" / "g1_deadline.yaml", "--out", out, "--period", "0.1"]
    assert_input_error(
        args, capsys, monkeypatch, "--out:", "holds 'mine.txt', which no earlier export wrote"
    )
    assert [p.name for p in out.iterdir()] == ["mine.txt"]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--noise-f", "inf"], "--noise-f: must be finite, got inf"),
        (["--f", "inf"], "--f: must be finite, got inf"),  # the old spelling, named as typed
        (["--noise-sigma", "-1"], "--noise-sigma: must be >= 0, got -1"),
        (["--noise-sigma", "nan"], "--noise-sigma: must be finite"),
        (["--sigma", "0.4", "--noise-sigma", "0.4"], "--sigma: the old spelling of --noise-sigma"),
    ],
)
def test_export_noise_flags_are_checked_first(
    tmp_path, examples, capsys, monkeypatch, extra, needle
):
    args = ["export", examples / "scenarios" / "g1_deadline.yaml", "--out", tmp_path / "o"]
    assert_input_error([*args, "--period", "0.1", *extra], capsys, monkeypatch, needle)
    assert list(tmp_path.iterdir()) == []


def test_export_noise_flags_share_certifys_names(capsys, monkeypatch):
    import re

    helps = {}
    for command in ("certify", "export"):
        _, text, _ = run_cli([command, "--help"], capsys, monkeypatch)
        helps[command] = set(re.findall(r"--noise-[a-z]+|--sigma\b|--f\b", text))
    assert helps["export"] == helps["certify"] == {"--noise-sigma", "--noise-f"}


def test_export_reads_the_old_noise_spellings_with_a_note(tmp_path, examples, capsys, monkeypatch):
    seen = {}

    def fake_export(file, lang, out, options, agent=None):
        seen.update(sigma=options.sigma, f=options.f)
        raise nd.InputError("stands for the library's name of the flag", field="sigma")

    monkeypatch.setattr("ntc_design.export.run.export", fake_export)
    sc = examples / "scenarios" / "g1_deadline.yaml"
    base = ["export", sc, "--out", tmp_path / "o", "--period", "0.1"]
    code, _, err = run_cli([*base, "--sigma", "0.5", "--f", "0.2"], capsys, monkeypatch)
    assert seen == {"sigma": 0.5, "f": 0.2} and code == 2
    assert err.splitlines()[:2] == [
        "note: --sigma is deprecated; it is --noise-sigma",
        "note: --f is deprecated; it is --noise-f",
    ]
    assert err.splitlines()[2].startswith("error: --sigma: stands for")
    code, _, err = run_cli([*base, "--noise-sigma", "0.5"], capsys, monkeypatch)
    assert err.strip() == "error: --noise-sigma: stands for the library's name of the flag"


def test_examples_lists_and_copies_the_bundled_files(tmp_path, capsys, monkeypatch):
    from ntc_design.model.paper import example_files, example_path

    code, out, err = run_cli(["examples"], capsys, monkeypatch)
    assert code == 0, err
    assert f"the bundled examples are in {example_path()}:" in out
    assert [ln.strip() for ln in out.splitlines()[1:-1]] == example_files()
    code, out, err = run_cli(
        ["examples", "--copy", tmp_path / "mine", "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    doc = json.loads(out)
    assert doc["files"] == example_files() and doc["copied_to"] == str(tmp_path / "mine")
    assert (
        sorted(
            p.relative_to(tmp_path / "mine").as_posix()
            for p in (tmp_path / "mine").rglob("*")
            if p.is_file()
        )
        == example_files()
    )
    # the copy is a user's to run, as the checkout's examples are
    code, _, err = run_cli(
        ["design", tmp_path / "mine" / "g1.yaml", "--theta", "1,2,-1"], capsys, monkeypatch
    )
    assert code == 0, err


@pytest.mark.hostile
@pytest.mark.parametrize("as_json", [False, True])
@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda p: (p.mkdir(), (p / "notes.txt").write_text("mine")), "the folder is not empty"),
        (lambda p: p.write_text("mine"), "exists and is not a folder"),
        (lambda p: p.symlink_to(p.parent / "gone"), "a link to "),
    ],
    ids=["non-empty folder", "a file", "a dangling link"],
)
def test_examples_copy_refuses_to_overwrite(tmp_path, capsys, monkeypatch, make, needle, as_json):
    dest = tmp_path / "dest"
    make(dest)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    args = ["examples", "--copy", dest, *(["--json"] if as_json else [])]
    assert_input_error(args, capsys, monkeypatch, f"{dest}: {needle}")
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_robust_and_verify_name_the_per_edge_radii(tmp_path, capsys, monkeypatch):
    from tests.support.robust import TRI, TRI_SET

    (tmp_path / "tri.yaml").write_text(TRI, encoding="utf-8")
    out = tmp_path / "c.json"
    code, text, err = run_cli(
        ["robust", tmp_path / "tri.yaml", "--theta", "1", "--out", out], capsys, monkeypatch
    )
    assert code == 0, err
    assert text.splitlines()[0] == f"tri: robust brackets for {TRI_SET}"
    code, shown, err = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0, err
    assert shown.count(f"for {TRI_SET})") == 2  # the decay and the offset, beside them
    for said in (text, shown):
        assert "at ρ = 0.5" not in said and "ρ = 0.5)" not in said


@pytest.mark.parametrize("radius", ["0", "0.05"])
def test_robust_proves_brackets_where_certify_proves_the_nominal_case(
    radius, tmp_path, capsys, monkeypatch
):
    # the network: a weight v vᵀ whose kernel rounding lost left every bracket
    # end unproven, ρ = 0 included; at ρ = 0 the LMI is the nominal Lyapunov inequality
    net, out = tmp_path / "g.yaml", tmp_path / "c.json"
    args = ["generate", "--agents", "6", "--dim", "2", "--seed", "11", "--out", net]
    assert run_cli(args, capsys, monkeypatch)[0] == 0
    assert run_cli(["certify", net, "--theta", "1,-1"], capsys, monkeypatch)[0] == 0
    code, text, err = run_cli(
        ["robust", net, "--theta", "1,-1", "--radius", radius, "--out", out, "--json"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    doc = json.loads(text)
    assert doc["valid"] is True
    # ρ = 0: the nominal rate to 0.005/2³ (robust's docstring); ρ = 0.05: 0.558354 here
    floor = (1 - 0.005 / 8) * (1 - 1e-12) if radius == "0" else 0.9
    assert doc["decay"]["lower"] >= floor * doc["nominal_decay"]
    assert doc["offset"]["upper"] is not None and doc["margin"]["lower"] > 0.5
    code, text, err = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0 and "VALID" in text, err


# -- a network with no informed agent: nothing can be designed --------------------------

COOPERATIVE = """name: coop
dim: 2
agents: 3
edges:
  - {from: 1, to: 2, weight: {diag: [1, 1]}}
  - {from: 2, to: 3, weight: {diag: [1, 2]}}
  - {from: 3, to: 1, weight: {diag: [2, 1]}}
"""


@pytest.mark.parametrize("extra", [[], ["--json"], ["--out", "design.json"]])
def test_design_without_an_informed_agent_exits_1_with_the_fix(
    tmp_path, capsys, monkeypatch, extra
):
    p = tmp_path / "coop.yaml"
    p.write_text(COOPERATIVE, encoding="utf-8")
    extra = [str(tmp_path / x) if x.endswith(".json") else x for x in extra]
    code, out, err = run_cli(["design", p, "--theta", "21,42", *extra], capsys, monkeypatch)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 1 and len(lines) == 1, err
    assert lines[0].startswith("not designed: the network has no informed agent")
    assert "an antagonistic edge (A_ij negative definite) into an agent makes it informed" in err
    assert not (tmp_path / "design.json").exists()  # nothing designed, nothing written
    if "--json" in extra:
        assert json.loads(out)["informed"] == []
    else:
        # the rate is L's, exactly 0 (L(1⊗v) = 0), not rounding noise such as 8.9e-17
        assert "best decay rate" in out and "e-1" not in out.split("best decay rate")[1][:60]


def test_switching_design_names_the_mode_without_an_informed_agent(
    tmp_path, capsys, monkeypatch, examples
):
    (tmp_path / "coop.yaml").write_text(COOPERATIVE, encoding="utf-8")
    sw = tmp_path / "sw.yaml"
    sw.write_text(
        "modes:\n  a: coop.yaml\n  b: coop.yaml\nschedule:\n  - {mode: a, duration: 1}\n"
        "  - {mode: b, duration: 1}\n",
        encoding="utf-8",
    )
    code, _, err = run_cli(["design", sw, "--theta", "1,2"], capsys, monkeypatch)
    assert code == 1 and "not designed: mode(s) a, b have no informed agent" in err


@pytest.mark.parametrize("extra", [[], ["--json"], ["--period", "0.1"]])
def test_certify_without_an_informed_agent_says_so_with_the_fix(
    tmp_path, capsys, monkeypatch, extra
):
    p = tmp_path / "coop.yaml"
    p.write_text(COOPERATIVE, encoding="utf-8")
    out = tmp_path / "c.json"
    args = ["certify", p, "--theta", "1,2", "--gain", "1/(1+t)", "--out", out, *extra]
    code, text, err = run_cli(args, capsys, monkeypatch)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 1 and len(lines) == 1, err  # no "warning: Matrix is exactly singular"
    assert lines[0].startswith("not certified: the network has no informed agent (U is empty)")
    assert "an antagonistic edge (A_ij negative definite) into an agent makes it informed" in err
    assert lines[0].endswith(f"; nothing written to {out}") and not out.exists()
    if "--json" in extra:
        assert json.loads(text) == {"ok": False, "proven": False, "informed": []}


@pytest.mark.hostile
def test_export_without_an_informed_agent_says_so_with_the_fix(tmp_path, capsys, monkeypatch):
    (tmp_path / "coop.yaml").write_text(COOPERATIVE, encoding="utf-8")
    sc = tmp_path / "sc.yaml"
    sc.write_text("topology: coop.yaml\ntheta: [1, 2]\ngain: 1/(1+t)\nT: 2\n", encoding="utf-8")
    args = ["export", sc, "--out", tmp_path / "o", "--period", "0.1"]
    line = assert_input_error(args, capsys, monkeypatch, "the network has no informed agent")
    assert "makes it informed; nothing exported" in line and "P_lyapunov" not in line
    assert not (tmp_path / "o").exists()


def test_design_with_informed_agents_still_exits_0(examples, capsys, monkeypatch):
    code, _, err = run_cli(
        ["design", examples / "g3.yaml", "--theta", "1,2,-1"], capsys, monkeypatch
    )
    assert code == 0, err  # Assumption 2 fails in G3, but U is not empty: a design exists


@pytest.mark.hostile
@pytest.mark.parametrize("command", ["design", "certify", "robust"])
def test_theta_that_overflows_x0_names_the_flag(command, capsys, monkeypatch):
    from tests.cli_helpers import assert_input_error

    # k1 = 1 + 2/δ = 1.27609 for G1: 1.7e308·k1 is beyond the float range (it passed as
    # θ, then the certificate check named 'subject.modes.G1.x0')
    args = [command, EXAMPLES / "g1.yaml", "--theta", "1.7e308,2,-1"]
    args += ["--radius", "0.01"] if command == "robust" else []
    line = assert_input_error(
        args,
        capsys,
        monkeypatch,
        "error: --theta: x0 = k1·θ overflows",
        "k1 = 1 + 2/δ = 1.27609",
        "every |θ_i| must be below 1.409e+308",
    )
    assert "subject" not in line


def test_theta_just_below_the_x0_bound_designs(capsys, monkeypatch):
    import ntc_design as nd

    d = nd.design(nd.load(EXAMPLES / "g1.yaml"), [1.4e308, 2, -1])
    assert np.isfinite(d.x0).all() and d.x0[0] == pytest.approx(1.4e308 * d.k1)


@pytest.mark.hostile
@pytest.mark.parametrize(("drop", "field"), [("initial", "initial: missing"), ("T", "T: missing")])
def test_certify_deadline_names_the_missing_field(
    tmp_path, examples, capsys, monkeypatch, drop, field
):
    src = (examples / "scenarios" / "g1_deadline.yaml").read_text()
    text = "\n".join(ln for ln in src.splitlines() if not ln.startswith(f"{drop}:"))
    scen = tmp_path / "s.yaml"
    scen.write_text(text.replace("../g1.yaml", str(examples / "g1.yaml")))
    out = tmp_path / "c.json"
    assert_input_error(["certify", scen, "--deadline", "--out", out], capsys, monkeypatch, field)
    assert not out.exists()


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--period", "1e-6", "--deadline"], "--deadline: the proven moments take"),
        (["--deadline", "-1"], "--deadline: T must be > 0"),
    ],
)
def test_certify_deadline_refusals(examples, capsys, monkeypatch, extra, needle):
    scen = examples / "scenarios" / "g1_deadline.yaml"
    assert_input_error(["certify", scen, *extra], capsys, monkeypatch, needle)


def test_certify_deadline_json_states_the_figures(tmp_path, examples, capsys, monkeypatch):
    scen = _cycle_scenario(tmp_path)  # G1's delay line: tests/certify/test_deadline*.py
    out = tmp_path / "c.json"
    args = ["certify", scen, "--period", "0.1", "--delay", "1", "--deadline", "1.05"]
    code, text, _ = run_cli([*args, "--out", out, "--json"], capsys, monkeypatch)
    assert code == 0
    figures = json.loads(text)["deadline"]
    assert figures["T"] == 1.05 and figures["peak_bound"] >= figures["ms_error_bound"] > 0
    assert verify(json.loads(out.read_text())).valid


@pytest.mark.slow
def test_certify_period_warns_beside_the_continuous_figures(examples, capsys, monkeypatch):
    scen = examples / "scenarios" / "g1_deadline.yaml"
    code, out, err = run_cli(["certify", scen, "--period", "5", "--deadline"], capsys, monkeypatch)
    assert code == 0
    line = next(ln for ln in out.splitlines() if ln.startswith("proven at T = 10"))
    assert "continuous design <= 2.91" in line
    warnings_ = [ln for ln in err.splitlines() if ln.startswith("warning:")]
    assert len(warnings_) == 1 and "--period auto" in warnings_[0]
    # the longest safe period named: within 10 % at T (alone 0.1744 on G1, docs/guide) and
    # the peak within 10× the continuous one (119.7), which binds first here
    safe = float(warnings_[0].split("longest safe period is h = ")[1].split()[0])
    assert 0.12 < safe < 0.1745


@pytest.mark.slow  # a switching set certified, its sampled and continuous figures proven
def test_certify_deadline_on_a_switching_schedule_bounds_the_exact_moments(
    tmp_path, examples, capsys, monkeypatch
):
    scen = examples / "scenarios" / "switching.yaml"
    out = tmp_path / "c.json"
    args = ["certify", scen, "--period", "0.01", "--deadline", "2", "--out", out, "--json"]
    code, text, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    figures = json.loads(text)["deadline"]
    assert verify(json.loads(out.read_text())).valid
    sim = ["simulate", scen, "--T", "2", "--period", "0.01", "--method", "exact", "--json"]
    code, text, _ = run_cli([*sim, "--out", tmp_path / "run"], capsys, monkeypatch)
    assert code == 0
    run = json.loads(text)
    exact = sum(run["final_ms_error_exact"].values())
    # the ball recursion encloses the float one: above it, within 1e-9 relative
    # (the float figures rounded: 1e-12 relative below)
    assert exact * (1 - 1e-12) <= figures["ms_error_bound"] <= exact * (1 + 1e-9)
    peak = run["digital"]["ms_error_peak"]
    assert peak * (1 - 1e-12) <= figures["peak_bound"] <= peak * (1 + 1e-9)
    cont = run["digital"]["continuous_final_ms_error"]  # the Taylor enclosure: within 5 %
    assert cont * (1 - 1e-9) <= figures["continuous"]["ms_error_bound"] <= 1.05 * cont
