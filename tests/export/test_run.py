"""Tests of :mod:`ntc_design.export.run`: the folder an export writes (all or nothing),
its README, and its example, which the compiled program and the module reproduce byte for
byte."""

import subprocess
import sys

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.export import run
from ntc_design.export.run import export, read_state, state_text, stdin_text
from ntc_design.export.source import ExportOptions
from ntc_design.simulate.replay import replay
from tests.conftest import EXAMPLES, ROOT
from tests.support.export import CC, CFLAGS, g1_d1_certified, needs_cc

DEADLINE = EXAMPLES / "scenarios" / "g1_deadline.yaml"


@pytest.fixture(scope="module")
def c_export(tmp_path_factory, g1, g1_digital_d1):
    """G1's scenario exported to C at h = 0.1, D = 1; its certificate is the session's
    g1_digital_d1 once the export's certify call is checked to be that one."""
    out = tmp_path_factory.mktemp("exp") / "g1-c"
    with pytest.MonkeyPatch.context() as mp:
        g1_d1_certified(mp, g1, g1_digital_d1)
        return export(DEADLINE, "c", out, ExportOptions(period=0.1, delay=1))


def test_the_folder(c_export):
    names = sorted(p.name for p in c_export.folder.iterdir())
    assert (
        names
        == sorted([*c_export.files, run.MANIFEST])
        == sorted(
            ["ntc_protocol.h", "ntc_protocol.c", "ntc_replay.c", "README.txt", run.MANIFEST]
            + list(run.EXAMPLES)
        )
    )
    listed = (c_export.folder / run.MANIFEST).read_text().splitlines()[1:]
    assert listed == [*c_export.files, "ntc_replay"]
    text = (c_export.folder / "README.txt").read_text()
    for needle in (
        "cc -std=c99 -O2 -ffp-contract=off",
        "./ntc_replay < example_input.txt | diff - example_output.txt",
        "x(0): N*d numbers, agent by agent",
        "its additive xi1, then its multiplicative xi2",
        "mode 'G1' (8 edges): 2->1, 1->2, 5->6, 2->5, 6->7, 6->2, 6->3, 3->4",
        "Period h = 0.10000000000000001, delay D = 1 samples",
    ):
        assert needle in text, needle


def test_the_example_is_the_replay(c_export):
    law = c_export.source.law
    words = (c_export.folder / "example_input.txt").read_text().split()
    x0 = np.array([float(w) for w in words[:21]])
    k = int(words[21])
    z = np.array([float(w) for w in words[22:]])
    assert k == run.EXAMPLE_STEPS and z.size == 16 * k
    assert (x0 == c_export.source.initial).all()
    want = replay(law, x0, z, k)
    out = (c_export.folder / "example_output.txt").read_text()
    assert (read_state(out, 21) == want).all() and out == state_text(want, 3)


@needs_cc
def test_the_compiled_program_reproduces_the_example_byte_for_byte(c_export, tmp_path):
    exe = tmp_path / "ntc_replay"
    src = [str(c_export.folder / n) for n in ("ntc_replay.c", "ntc_protocol.c")]
    res = subprocess.run([CC, *CFLAGS, "-o", str(exe), *src, "-lm"], capture_output=True)
    assert res.returncode == 0, res.stderr
    inp = (c_export.folder / "example_input.txt").read_text()
    out = subprocess.run([str(exe)], input=inp, capture_output=True, text=True).stdout
    assert out == (c_export.folder / "example_output.txt").read_text()


def test_a_python_export_reproduces_its_example(tmp_path):
    res = export(
        ROOT / "certificates" / "g1.json", "python", tmp_path / "py", ExportOptions(period=0.05)
    )
    folder = res.folder
    assert sorted(res.files) == sorted(["ntc_protocol.py", "README.txt", *run.EXAMPLES])
    inp = (folder / "example_input.txt").read_text()
    cmd = [sys.executable, str(folder / "ntc_protocol.py")]
    out = subprocess.run(cmd, input=inp, capture_output=True, text=True).stdout
    assert out == (folder / "example_output.txt").read_text()
    assert "python ntc_protocol.py < example_input.txt" in (folder / "README.txt").read_text()
    # an earlier export's folder is replaced (the language may change)
    again = export(
        ROOT / "certificates" / "g1.json", "c", tmp_path / "py", ExportOptions(period=0.05)
    )
    assert not (again.folder / "ntc_protocol.py").exists()


def test_stdin_and_state_texts_round_trip():
    x = np.array([0.1, -2.0, 1e-300, 3.0])
    text = stdin_text(x, 2, np.arange(10) / 3)
    words = text.split()
    assert [float(w) for w in words[:4]] == x.tolist() and words[4] == "2"
    assert [float(w) for w in words[5:]] == (np.arange(10) / 3).tolist()
    assert state_text(x, 2) == "0.10000000000000001 -2\n1e-300 3\n"
    assert (read_state(state_text(x, 2), 4) == x).all()


@pytest.mark.hostile
def test_refusals_write_nothing(tmp_path, monkeypatch):
    out = tmp_path / "o"
    with pytest.raises(InputError, match=r"^lang: expected one of c, python, got 'fortran'"):
        export(DEADLINE, "fortran", out, ExportOptions(period=0.1))
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    with pytest.raises(InputError, match=r"^out: .* holds 'notes.txt', which no earlier export"):
        export(DEADLINE, "c", mine, ExportOptions(period=0.1))
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    monkeypatch.setattr(run, "MAX_NUMBERS", 100)
    with pytest.raises(InputError, match=r"^export: the tables would hold"):
        export(DEADLINE, "c", out, ExportOptions(period=0.1))
    with pytest.raises(InputError, match=r"^output: expected 21 numbers, got 2"):
        read_state("1 2", 21)
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["mine"]


def _tree(folder):
    return sorted(
        (str(p.relative_to(folder)), p.read_text() if p.is_file() else None)
        for p in folder.rglob("*")
        if not p.is_fifo()
    )


@pytest.mark.hostile
@pytest.mark.parametrize("case", ["folder", "fifo", "unlisted", "forged-manifest", "link"])
def test_an_export_never_deletes_user_data(tmp_path, case):
    import os

    out = tmp_path / "out"
    out.mkdir()
    if case == "folder":  # a folder named like an output, a user's file inside
        (out / "README.txt").mkdir()
        (out / "README.txt" / "mine.txt").write_text("keep")
        needle = "'README.txt', which no earlier export wrote"
    elif case == "fifo":
        os.mkfifo(out / "ntc_protocol.c")
        needle = "'ntc_protocol.c', which no earlier export wrote"
    elif case == "unlisted":  # a file named like an output, but no manifest lists it
        (out / "README.txt").write_text("my notes")
        needle = "'README.txt', which no earlier export wrote"
    elif case == "forged-manifest":  # a manifest may list only an export's own names
        (out / run.MANIFEST).write_text("# x\nmine.txt\n")
        (out / "mine.txt").write_text("keep")
        needle = "'mine.txt', which no earlier export wrote"
    else:  # an output's name listed, but a link to the user's file
        (tmp_path / "mine.txt").write_text("keep")
        (out / run.MANIFEST).write_text("# x\nREADME.txt\n")
        (out / "README.txt").symlink_to(tmp_path / "mine.txt")
        needle = "'README.txt', which is not a regular file"
    before = _tree(out)
    with pytest.raises(InputError) as err:
        export(DEADLINE, "c", out, ExportOptions(period=0.1))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("out: ") and needle in msg, msg
    assert _tree(out) == before and sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["out", *(["mine.txt"] if case == "link" else [])]
    )
    assert (tmp_path / "mine.txt").read_text() == "keep" if case == "link" else True


def test_an_earlier_export_and_its_build_are_replaced(tmp_path):
    # the folder is what is checked: a 3-agent signed cycle's scenario (G1's is c_export)
    (tmp_path / "cycle.yaml").write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    sc = tmp_path / "s.yaml"
    sc.write_text("topology: cycle.yaml\ntheta: [1]\nT: 5\n")
    out = tmp_path / "out"
    first = export(sc, "c", out, ExportOptions(period=0.1))
    assert "ntc_protocol.c" in first.files
    (out / "ntc_replay").write_bytes(b"built")  # what the README's command makes
    again = export(sc, "python", out, ExportOptions(period=0.1))
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([*again.files, run.MANIFEST]) and "ntc_replay" not in names


@pytest.mark.hostile
def test_the_cli_refuses_a_folder_in_one_line(tmp_path, capsys, monkeypatch):
    from tests.cli_helpers import assert_input_error

    out = tmp_path / "out"
    (out / "README.txt").mkdir(parents=True)
    (out / "README.txt" / "mine.txt").write_text("keep")
    args = ["export", DEADLINE, "--out", out, "--period", "0.1"]
    assert_input_error(args, capsys, monkeypatch, "--out: ", "which no earlier export wrote")
    assert (out / "README.txt" / "mine.txt").read_text() == "keep"
    assert sorted(p.name for p in out.iterdir()) == ["README.txt"]


@pytest.mark.hostile
def test_names_and_labels_are_escaped_on_the_terminal_and_in_the_readme(
    tmp_path, capsys, monkeypatch
):
    import json

    from tests.cli_helpers import run_cli

    evil = "a\nBuild and check (a C99 compiler; no library but libm):\n  rm -rf ~"
    top = {
        "name": "net\x1b[2J\x1b]0;owned\x07\u202e",
        "dim": 1,
        "agents": [evil, "b"],
        "edges": [{"from": "b", "to": evil, "weight": -1}, {"from": evil, "to": "b", "weight": 1}],
    }
    (tmp_path / "t.json").write_text(json.dumps(top))
    sc = tmp_path / "s.yaml"
    sc.write_text(f"topology: {tmp_path / 't.json'}\ntheta: [1]\nT: 5\n")
    out = tmp_path / "out"
    code, stdout, err = run_cli(
        ["export", sc, "--out", out, "--period", "0.1"], capsys, monkeypatch
    )
    assert code == 0, err
    for bad in ("\x1b", "\x07", "\u202e"):
        assert bad not in stdout and bad not in (out / "README.txt").read_text()
    assert "net\\x1b[2J" in stdout
    text = (out / "README.txt").read_text()
    starts = [ln for ln in text.splitlines() if ln.startswith("Build and check")]
    assert len(starts) == 1  # the label's newline did not plant a second section
    assert not any(ln.strip() == "rm -rf ~" for ln in text.splitlines())
    assert "a\\nBuild and check" in text


@pytest.mark.hostile
def test_a_lone_surrogate_label_is_one_line_and_nothing_written(tmp_path, capsys, monkeypatch):
    from tests.cli_helpers import assert_input_error

    (tmp_path / "t.json").write_text(
        '{"dim": 1, "agents": ["\\ud800a", "b"], "edges": [{"from": "b", "to": "\\ud800a", '
        '"weight": -1}, {"from": "\\ud800a", "to": "b", "weight": 1}]}'
    )
    sc = tmp_path / "s.yaml"
    sc.write_text(f"topology: {tmp_path / 't.json'}\ntheta: [1]\nT: 5\n")
    out = tmp_path / "out"
    args = ["export", sc, "--out", out, "--period", "0.1"]
    assert_input_error(args, capsys, monkeypatch, "t.json", "lone surrogate")
    assert not out.exists()


@pytest.mark.hostile
@pytest.mark.parametrize("target", ["empty", "dangling"])
def test_an_out_folder_given_as_a_link_is_refused(tmp_path, capsys, monkeypatch, target):
    from tests.cli_helpers import assert_input_error

    real = tmp_path / "real"
    if target == "empty":
        real.mkdir()
    link = tmp_path / "link"
    link.symlink_to(real)
    args = ["export", DEADLINE, "--out", link, "--period", "0.1"]
    assert_input_error(args, capsys, monkeypatch, "--out: ", "link")
    # the link and its target are as they were, and no stray swap folder or link is left
    assert link.is_symlink() and (real.is_dir() if target == "empty" else not real.exists())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link"] + (["real"] * (target == "empty"))
    if target == "empty":
        assert list(real.iterdir()) == []


def test_one_agents_export_and_its_readme(tmp_path, c_export):
    out = tmp_path / "one"
    # G1 at h = 0.1, D = 1 as the shipped certificate proves it: the scenario's full export
    # is c_export's, so its delay line is not certified twice more here
    res = export(ROOT / "certificates" / "g1_digital.json", "c", out, agent="3")
    assert sorted(res.files) == ["README.txt", "ntc_protocol.c", "ntc_protocol.h"]
    assert "#define NTC_SELF 2" in (out / "ntc_protocol.h").read_text()
    text = (out / "README.txt").read_text()
    for needle in (
        "The tables of agent 3 only (index 2, ntc export --agent)",
        "antagonistic edge (sign -1):  m[a] = -r[a] - 2 xd[a]",
        "in the units of the",
        "ntc_agent_init(&s, i, x_i0)",
    ):
        assert needle in text, needle
    # the full export documents the same embedding
    assert "relative-position sensor" in (c_export.folder / "README.txt").read_text()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "lang, agent, needle",
    [
        ("c", "99", "--agent: no agent is labelled '99' (labels: 1, 2, 3"),
        ("python", "3", "--agent: one agent's tables are emitted in C only"),
    ],
)
def test_a_bad_agent_is_refused(tmp_path, capsys, monkeypatch, lang, agent, needle):
    from tests.cli_helpers import assert_input_error

    out = tmp_path / "o"
    args = ["export", DEADLINE, "--out", out, "--period", "0.1", "--lang", lang, "--agent", agent]
    assert_input_error(args, capsys, monkeypatch, needle)
    assert not out.exists()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--period", "0.5"], "--period: 0.5 differs from the certified value 0.1"),
        (["--noise-sigma", "5e-324"], "--noise-sigma: 5e-324 differs from the certified value 0.4"),
        (["--noise-f", "0.3", "--delay", "2"], "--delay: 2 differs from the certified value 1"),
    ],
)
def test_the_cli_refuses_an_option_that_differs_from_the_proof(
    tmp_path, capsys, monkeypatch, extra, needle
):
    from tests.cli_helpers import assert_input_error

    out = tmp_path / "o"
    args = ["export", ROOT / "certificates" / "g1_digital.json", "--out", out, *extra]
    assert_input_error(args, capsys, monkeypatch, needle)
    assert not out.exists()


@pytest.mark.hostile
def test_the_cli_refuses_a_resealed_certificate_with_an_added_gain(tmp_path, capsys, monkeypatch):
    import json

    from ntc_design.certify.format import finish
    from tests.cli_helpers import assert_input_error

    doc = json.loads((ROOT / "certificates" / "g1_digital.json").read_text())
    doc["gain"] = "50/(1+t)"
    for key in ("digest", "subject_digest", "versions"):
        doc.pop(key)
    p = tmp_path / "forged.json"
    p.write_text(json.dumps(finish(doc)))
    out = tmp_path / "o"
    assert_input_error(["verify", p], capsys, monkeypatch, "forged.json: gain")
    assert_input_error(["export", p, "--out", out], capsys, monkeypatch, "forged.json: gain")
    assert not out.exists()


@pytest.mark.slow
def test_a_lossy_export_reproduces_its_example_and_documents_the_flags(tmp_path):
    scen = tmp_path / "s.yaml"
    scen.write_text(
        f"topology: {EXAMPLES / 'g1.yaml'}\ntheta: [1, 2, -1]\nT: 5\n"
        "digital: {period: 0.1, loss: 0.1, policy: skip}\n"
    )
    res = export(scen, "python", tmp_path / "py")
    folder = res.folder
    inp = (folder / "example_input.txt").read_text()
    lines = inp.strip().split("\n")
    e = res.source.law.modes[0].n_edges
    flags = lines[2 + -(-2 * e // 8)].split()  # step 0's flags after its 2E normals
    assert len(flags) == e and set(flags) <= {"0", "1"} and "0" in inp.split("\n", 2)[2].split()
    cmd = [sys.executable, str(folder / "ntc_protocol.py")]
    out = subprocess.run(cmd, input=inp, capture_output=True, text=True).stdout
    assert out == (folder / "example_output.txt").read_text()
    readme = (folder / "README.txt").read_text()
    assert "after the 2E normals of step k, its E arrival flags, one per edge" in readme
    assert "in the same file order (below): 1 the message arrived, 0 it was lost" in readme
    assert "Lossy links, policy skip (compiled in; keep_e = 1 - p_e: " in readme
    assert "Edges in file order (the order of the normals and of the arrival flags):" in readme
    # hold is exported where its certificate proves it; with a gain it cannot prove, not
    with pytest.raises(InputError, match="lossy links with the hold policy are not proven"):
        export(scen, "c", tmp_path / "c", ExportOptions(policy="hold", gain="exp(-t)"))
    assert not (tmp_path / "c").exists()


@pytest.mark.slow
def test_a_delayed_lossy_export_is_certified_and_replays_bit_for_bit(tmp_path):
    # D = 1 on lossy links: proven by the digital_loss certificate's delay line, exported
    # from the scenario and from the certificate, the programs equal to the replay; on a
    # 3-agent signed cycle with 2×2 weights (its two certificates about 1 s, G1's 30 s; G1's
    # lossy delay line is tests/certify/kinds/test_digital_loss_delay.py's)
    import json

    from ntc_design.certify import certify
    from ntc_design.protocol.digital import Digital
    from tests.support.export import arrivals_for, normals_for, run_program

    (tmp_path / "cycle.yaml").write_text(
        "dim: 2\nagents: 3\nedges:\n"
        "  - {from: 1, to: 2, weight: [[1.0, 0.2], [0.2, 0.5]]}\n"
        "  - {from: 2, to: 3, weight: [[-0.8, 0.0], [0.0, -0.6]]}\n"
        "  - {from: 3, to: 1, weight: [[0.7, 0.1], [0.1, 0.9]]}\n"
    )
    scen = tmp_path / "s.yaml"
    scen.write_text(
        "topology: cycle.yaml\ntheta: [1, -0.5]\nT: 5\n"
        "digital: {period: 0.1, delay: 1, loss: 0.1, policy: skip}\n"
    )
    res = export(scen, "python", tmp_path / "py")
    law = res.source.law
    assert law.digital.delay == 1 and law.policy == "skip"
    assert np.all(law.modes[0].keep == 1.0 - 0.1)
    cmd = [sys.executable, str(res.folder / "ntc_protocol.py")]
    inp = (res.folder / "example_input.txt").read_text()
    out = subprocess.run(cmd, input=inp, capture_output=True, text=True).stdout
    assert out == (res.folder / "example_output.txt").read_text()
    steps, x0 = 120, np.linspace(-3.0, 3.0, 6)
    z, chi = normals_for(law, steps, 5), arrivals_for(law, steps, 5)
    assert 0 < chi.sum() < chi.size
    want = replay(law, x0, z, steps, arrivals=chi)
    assert (run_program(cmd, law, x0, steps, z, arrivals=chi) == want).all()
    # the certificate's own export: the same law, the C program equal to the replay
    import ntc_design as nd

    doc = certify(
        nd.load(tmp_path / "cycle.yaml"), [1, -0.5], 0.1, "1/(1+t)", None, noise_sigma=0.4,
        noise_f=0.3, digital=Digital(0.1, 1, 0.1),
    ).certificate  # fmt: skip
    assert doc["results"]["digital"]["bound"] == "delay_line"
    cert = tmp_path / "loss_d1.json"
    cert.write_text(json.dumps(doc))
    if CC is None:
        return
    res_c = export(cert, "c", tmp_path / "c")
    law_c = res_c.source.law
    assert law_c.digital.delay == 1 and np.all(law_c.modes[0].keep == 1.0 - 0.1)
    exe = res_c.folder / "ntc_replay"
    build = [CC, *CFLAGS, "-o", str(exe), "ntc_replay.c", "ntc_protocol.c", "-lm"]
    assert subprocess.run(build, cwd=res_c.folder, capture_output=True).returncode == 0
    want_c = replay(law_c, x0, z, steps, arrivals=chi)
    assert (run_program(exe, law_c, x0, steps, z, arrivals=chi) == want_c).all()


def test_a_certified_gain_given_again_with_spaces_is_the_same_gain(tmp_path, capsys, monkeypatch):
    # the certificate states 1/(1+t): the same text with spaces is no other gain, another is
    from tests.cli_helpers import assert_input_error, run_cli

    cert = ROOT / "certificates" / "g1_digital.json"
    code, _, err = run_cli(
        ["export", cert, "--out", tmp_path / "a", "--gain", " 1 / ( 1 + t ) "], capsys, monkeypatch
    )
    assert code == 0, err
    assert (tmp_path / "a" / "ntc_protocol.c").exists()
    args = ["export", cert, "--out", tmp_path / "b", "--gain", "2/(1+t)"]
    assert_input_error(args, capsys, monkeypatch, "--gain: '2/(1+t)' differs")
    assert not (tmp_path / "b").exists()


@pytest.mark.slow
def test_a_proven_hold_export_reproduces_its_example_and_says_how_to_hold(tmp_path):
    # a 3-agent signed cycle: its hold certificate is issued in about 2 s (G1's in 50 s)
    (tmp_path / "cycle.yaml").write_text(
        "dim: 2\nagents: 3\nedges:\n"
        "  - {from: 1, to: 2, weight: [[1.0, 0.2], [0.2, 0.5]]}\n"
        "  - {from: 2, to: 3, weight: [[-0.8, 0.0], [0.0, -0.6]]}\n"
        "  - {from: 3, to: 1, weight: [[0.7, 0.1], [0.1, 0.9]]}\n"
    )
    scen = tmp_path / "s.yaml"
    scen.write_text(
        "topology: cycle.yaml\ntheta: [1, -0.5]\nT: 5\ngain: 3/(1+t)\n"
        "digital: {period: 0.1, loss: 0.1, policy: hold}\n"
    )
    res = export(scen, "python", tmp_path / "py")
    assert res.source.law.policy == "hold"
    folder = res.folder
    inp = (folder / "example_input.txt").read_text()
    cmd = [sys.executable, str(folder / "ntc_protocol.py")]
    out = subprocess.run(cmd, input=inp, capture_output=True, text=True).stdout
    assert out == (folder / "example_output.txt").read_text()
    readme = (folder / "README.txt").read_text()
    assert "Lossy links, policy hold (compiled in; keep_e = 1 - p_e: 0.90000000000000002)" in readme
    assert "ntc_agent_init_held(&s, m0) after ntc_agent_init" in readme
