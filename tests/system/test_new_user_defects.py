"""What a new user and a hostile tester met (issue 29), one test per defect: each fails on
the code before its fix."""

import copy
import json
import os
import subprocess
import sys
import zipfile

import numpy as np
import pytest
import scipy.io as sio

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.certify.format import digest, document_hash
from ntc_design.io.edgelist import write_npz
from ntc_design.simulate.scenario import output_bytes, stored_paths
from tests.cli_helpers import assert_input_error, run_cli
from tests.conftest import EXAMPLES, ROOT

hostile = pytest.mark.hostile
G1 = EXAMPLES / "g1.yaml"


def scenario(tmp_path, **over):
    doc = {
        "topology": str(G1),
        "theta": [1, 2, -1],
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3},
        "T": 0.2,
        "dt": 0.01,
        "paths": 10,
        "save_every": 0.1,
        **over,
    }
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(doc))
    return p


# -- 2, 14: work bounded before it starts ----------------------------------------------


@hostile
@pytest.mark.parametrize(
    "args, needles",
    [
        (["--agents", "10000000"], ["--agents:", "1000000"]),
        (["--agents", "100", "--dim", "1001"], ["--dim:", "1000"]),
        (["--agents", "1000000", "--dim", "100"], ["--agents:", "memory"]),  # 6 GiB pinned
        (["--agents", "100", "--family", "nope"], ["--family:"]),
    ],
)
def test_generate_refuses_at_once(tmp_path, capsys, monkeypatch, args, needles):
    out = tmp_path / "net.npz"
    assert_input_error(["generate", *args, "--out", out], capsys, monkeypatch, *needles)
    assert not out.exists()


def test_generate_size_estimate_bounds_the_edges():
    from ntc_design.model.generate import generation_size, random_network

    for family in ("random", "ring", "grid", "small-world", "scale-free"):
        top = random_network(300, 2, seed=1, family=family)
        edges, need = generation_size(300, 2, family, 0.1, 4)
        assert len(top.weights) <= edges  # an upper estimate
        assert need >= len(top.weights) * 2 * 2 * 8


def test_a_long_simulation_says_how_long_before_it_starts(tmp_path, capsys, monkeypatch):
    # 10⁹ path-steps on G1: weeks of work; stopped by the test right after the warning
    from ntc_design.simulate import prepare

    def stop(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(prepare, "mode_system", stop)  # after the size checks
    sc = scenario(tmp_path, paths=10**7, T=100.0, dt=0.001, method="mc")
    code, out, err = run_cli(["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 130
    line = next(ln for ln in err.splitlines() if ln.startswith("warning: paths:"))
    assert "path-steps" in line and "roughly" in line and ("days" in line or " h " in line)
    assert not (tmp_path / "o").exists()


# -- 3: the re-run command keeps the overrides -----------------------------------------


def test_rerun_command_keeps_the_command_line(tmp_path, capsys, monkeypatch):
    from ntc_design.reports.rundata import load_run

    sc = scenario(tmp_path)
    out = tmp_path / "run"
    args = ["simulate", sc, "--out", out, "--paths", "7", "--horizon", "0.1"]
    code, _, err = run_cli(args, capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overrides"] == {"paths": 7, "T": 0.1}
    assert "--paths 7" in summary["command"] and "--horizon 0.1" in summary["command"]
    rerun = load_run(out).rerun
    assert rerun.startswith("ntc simulate ") and "--paths 7" in rerun
    assert rerun.endswith(f"ntc report {out}")


# -- 4: the gallery runs anywhere and shows its figures --------------------------------


def test_example_path_finds_every_bundled_file():
    for p in EXAMPLES.rglob("*.yaml"):
        rel = p.relative_to(EXAMPLES).as_posix()
        assert nd.example_path(rel).read_bytes() == p.read_bytes()
    assert nd.load(nd.example_path("g1.yaml")).n == 7


@hostile
@pytest.mark.parametrize("name", ["../pyproject.toml", "/etc/passwd", "nope.yaml"])
def test_example_path_refuses_what_is_not_an_example(name):
    with pytest.raises(nd.InputError, match="example_path"):
        nd.example_path(name)


def test_the_wheel_ships_the_examples_and_every_subpackage():
    import tomllib

    from setuptools import find_packages

    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert set(cfg["packages"]) == {*find_packages(str(ROOT), include=["ntc_design*"])} | {
        "ntc_design.examples"
    }
    assert cfg["package-dir"]["ntc_design.examples"] == "examples"
    globs = cfg["package-data"]["ntc_design.examples"]
    shipped = {p for g in globs for p in EXAMPLES.glob(g)}
    wanted = {p for s in ("yaml", "csv", "mat") for p in EXAMPLES.rglob(f"*.{s}")}
    assert wanted <= shipped


def test_importing_the_figures_keeps_the_users_backend():
    # a notebook's inline backend must survive `import ntc_design.reports.figures`
    code = (
        "import matplotlib; matplotlib.use('svg');"
        "import ntc_design.reports.figures, ntc_design.reports.style;"
        "print(matplotlib.get_backend())"
    )
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    got = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert got.stdout.strip() == "svg"


def test_gallery_scripts_locate_examples_through_the_package_and_show_figures():
    for f in sorted((ROOT / "docs" / "gallery").glob("plot_*.py")):
        text = f.read_text()
        assert "Path.cwd()" not in text, f.name
        if "examples" in text.lower() and "EXAMPLES" in text:
            assert "nd.example_path()" in text, f.name
        if "figure(" in text or "plt.subplots" in text:
            assert text.rstrip().splitlines()[-1].startswith("plt.show()"), f.name


def test_a_gallery_script_runs_outside_the_checkout(tmp_path):
    script = ROOT / "docs" / "gallery" / "plot_02_switching.py"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    got = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, env=env
    )
    assert got.returncode == 0, got.stderr[-2000:]
    assert "Traceback" not in got.stderr


def test_a_gallery_script_needing_an_extra_names_it_in_a_core_install(tmp_path):
    # networkx made unimportable, as in a core install: one line naming the interop extra,
    # not a raw ModuleNotFoundError
    script = ROOT / "docs" / "gallery" / "plot_04_networkx.py"
    run = (
        "import runpy, sys\n"
        "sys.modules['networkx'] = None  # import networkx raises ImportError\n"
        f"runpy.run_path({str(script)!r}, run_name='__main__')"
    )
    env = {**os.environ, "MPLBACKEND": "Agg"}
    got = subprocess.run(
        [sys.executable, "-c", run], cwd=tmp_path, capture_output=True, text=True, env=env
    )
    last = got.stderr.strip().splitlines()[-1]
    assert got.returncode == 1 and "ModuleNotFoundError" not in got.stderr
    assert last == (
        "ntc_design.errors.InputError: this example needs networkx, which the core install "
        'leaves out: pip install "ntc-design[interop]"'
    )


def test_the_gallery_numbers_are_distinct():
    numbers = [f.name.split("_")[1] for f in (ROOT / "docs" / "gallery").glob("plot_[0-9]*.py")]
    assert len(numbers) == len(set(numbers)) == 11, sorted(numbers)


# -- 6: big-network runs and reports ---------------------------------------------------


def test_large_runs_keep_the_paths_of_the_worst_agents():
    from ntc_design.model.generate import random_network
    from ntc_design.simulate import simulate

    top = random_network(40, 2, seed=3)
    res = simulate(
        top, [1.0, -1.0], gain="1/(1+t)", T=0.05, dt=0.005, paths=3, seed=0, save_every=0.025,
        method="both", stepping="intrinsic", scheme="implicit",
    )  # fmt: skip
    agents, paths = stored_paths(res)
    final = res.exact.ms_error[-1]
    worst = set(np.argsort(-final)[:8].tolist())
    assert set(agents.tolist()) == worst and list(agents) == sorted(agents)
    d = 2
    for k, i in enumerate(agents):  # the columns are those agents' states
        np.testing.assert_array_equal(
            paths[:, :, k * d : (k + 1) * d], res.mc.paths[:, :, i * d : (i + 1) * d]
        )


def test_output_size_is_said_within_a_factor_of_two(tmp_path, capsys, monkeypatch):
    sc = scenario(tmp_path, paths=40, T=1.0, save_every=0.01, method="both")
    out = tmp_path / "o"
    code, _, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0, err
    real = sum(p.stat().st_size for p in out.iterdir())
    said = output_bytes(7, 3, 101, 10, True, True, len(nd.load(G1).weights))
    assert 0.5 < said / real < 2.0


def test_short_window_caution_is_given_by_both_reports():
    from ntc_design.reports.parts import window_warning

    assert window_warning(1.0, 100.0) == ""  # log10(101/2) > 1
    assert "0.26 decades" in window_warning(1.0, 2.6)  # log10(3.6/2)
    src = (ROOT / "ntc_design" / "reports" / "aggregate.py").read_text()
    assert "window_warning(" in src


def test_mu_picture_is_a_log_quantile_plot_with_the_smallest_marked():
    from ntc_design.certify import scale_certificate
    from ntc_design.model.generate import random_network
    from ntc_design.reports.aggregate import certificate_picture

    top = random_network(60, 2, seed=2)
    des = nd.design(top, [1.0, -1.0], thresholds=False)
    cert = scale_certificate(des)
    fig = certificate_picture(cert, des)
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    (line,) = [ln for ln in ax.get_lines() if len(ln.get_ydata()) == top.n]
    y = np.asarray(line.get_ydata())
    assert np.all(np.diff(y) >= 0) and y[0] > 0
    red = [ln for ln in ax.get_lines() if len(ln.get_ydata()) == 2]
    assert red and np.isclose(red[0].get_ydata()[0], y[0])


# -- 7, 16, 18: the wrong kind of file, internal errors left ---------------------------


@hostile
@pytest.mark.parametrize(
    "args, needles",
    [
        (["simulate", G1, "--out", "o"], ["this is a topology file", "topology:", "g1_fixed"]),
        (["verify", G1], ["a YAML file", "expected a certificate"]),
        (["verify", EXAMPLES / "g1.csv"], ["a .csv file", "expected a certificate"]),
        (["certify", EXAMPLES, "--theta", "1,2,-1"], ["is a folder", "expected a file"]),
        (["check", EXAMPLES], ["is a folder"]),
        (["verify", EXAMPLES], ["is a folder", "certificate"]),
    ],
)
def test_the_wrong_kind_of_file_is_named(tmp_path, capsys, monkeypatch, args, needles):
    monkeypatch.chdir(tmp_path)
    assert_input_error(args, capsys, monkeypatch, *needles)


def _mat(tmp_path, name, **arrays):
    p = tmp_path / name
    sio.savemat(p, arrays)
    return p


def _csv(tmp_path, name, text):
    p = tmp_path / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return p


@hostile
@pytest.mark.parametrize(
    "make, needles",
    [
        (lambda t: _mat(t, "nan.mat", A=np.zeros((2, 2)), dim=np.nan), ["dim", "nan"]),
        (lambda t: _mat(t, "inf.mat", A=np.zeros((2, 2)), dim=np.inf), ["dim", "inf"]),
        (lambda t: _csv(t, "nul.csv", b"from,to,a11\n1,2,-1\x00\n2,3,1\n"), ["row 2", "NUL"]),
        (
            lambda t: _csv(t, "wide.csv", "from,to," + ",".join(["a"] * 600_000) + "\n"),
            ["row 1", "header is longer"],
        ),
        (
            lambda t: _csv(
                t,
                "d101.csv",
                "from,to,"
                + ",".join(f"a{r}_{c}" for r in range(1, 102) for c in range(1, 102))
                + "\n",
            ),
            ["row 1", "d = 101"],
        ),  # fmt: skip
    ],
)
def test_malformed_tables_are_bad_input(tmp_path, capsys, monkeypatch, make, needles):
    p = make(tmp_path)
    assert_input_error(["check", p], capsys, monkeypatch, str(p), *needles)


def test_a_csv_header_with_spaces_reads(tmp_path):
    p = _csv(tmp_path, "sp.csv", "from , to , a11\n1,2,-1\n2,3,1\n")
    top = nd.load(p)
    assert top.n == 3 and top.weights[(1, 0)][0, 0] == -1.0


@hostile
@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_non_regular_table_files_are_refused(tmp_path, capsys, monkeypatch, kind):
    p = tmp_path / "net.csv"
    if kind == "fifo":
        os.mkfifo(p)
    else:
        p.symlink_to("/dev/zero")
    assert_input_error(["check", p], capsys, monkeypatch, "not a regular file")


@hostile
def test_a_mat_decompression_bomb_is_refused_before_inflating(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", "60M")  # the limit: 10 MiB inflated
    p = tmp_path / "bomb.mat"
    sio.savemat(p, {"A": np.zeros((1500, 1500)), "dim": 1.0}, do_compression=True)
    assert p.stat().st_size < 100_000  # 18 MB of zeros in a small file
    assert_input_error(
        ["check", p],
        capsys,
        monkeypatch,
        "A: a 1500×1500 double array needs 17.2 MiB",
        "10.0 MiB allowed",
    )


def test_switching_files_take_csv_and_mat_modes(tmp_path):
    sw = tmp_path / "sw.yaml"
    sw.write_text(
        f"modes: {{A: {EXAMPLES / 'g1.csv'}, B: {EXAMPLES / 'g1.mat'}, C: {G1}}}\n"
        "schedule: [{mode: A, duration: 1}, {mode: B, duration: 1}, {mode: C, duration: 1}]\n"
    )
    s = nd.load(sw)
    g1 = nd.load(G1)
    for m in s.modes.values():
        assert m.n == 7 and set(m.weights) == set(g1.weights)


@hostile
@pytest.mark.parametrize("damage", ["garbage", "no-t", "nested", "pickled"])
def test_a_damaged_sweep_point_is_computed_again(tmp_path, damage):
    from ntc_design.sweep.point import PointResult, PointRow
    from ntc_design.sweep.store import load_point, save_point

    row = PointRow.from_dict({"point": "p1"})
    assert row is not None
    res = PointResult(
        "p1", {"seed": 0}, row, np.array([0.0, 1.0]), ["1", "2"],
        np.ones((2, 2)), np.ones((2, 2)), np.ones((2, 2)), None,
    )  # fmt: skip
    save_point(tmp_path, res)
    assert load_point(tmp_path, "p1") is not None  # the intact point is reused
    npz, js = tmp_path / "points" / "p1.npz", tmp_path / "points" / "p1.json"
    if damage == "garbage":
        npz.write_bytes(b"PK\x03\x04 not a zip at all")
    elif damage == "no-t":
        np.savez_compressed(npz, labels=np.array(["1", "2"]))
        os.replace(tmp_path / "points" / "p1.npz.npz", npz) if not npz.exists() else None
    elif damage == "nested":
        js.write_text("[" * 100_000 + "]" * 100_000)
    else:
        np.savez(npz, t=np.array([0.0, 1.0]), labels=np.array([{"x": 1}], dtype=object))
    assert load_point(tmp_path, "p1") is None


def test_report_on_a_sweep_without_points_is_bad_input(tmp_path, capsys, monkeypatch):
    import pandas as pd

    (tmp_path / "sweep.json").write_text(json.dumps({"kind": "sweep", "keys": ["seed"]}))
    empty = pd.DataFrame({"seed": pd.Series([], dtype=float)})
    empty.to_parquet(tmp_path / "results.parquet")
    empty.to_parquet(tmp_path / "curves.parquet")
    (tmp_path / "results.csv").write_text("seed\n")
    assert_input_error(["report", tmp_path], capsys, monkeypatch, "no points")


@hostile
def test_json_errors_are_json_on_stdout(tmp_path, capsys, monkeypatch):
    code, out, err = run_cli(
        ["design", tmp_path / "nope.yaml", "--theta", "1", "--json"], capsys, monkeypatch
    )
    assert code == 2 and err.startswith("error: ")
    doc = json.loads(out)
    assert doc["ok"] is False and doc["exit_code"] == 2 and "nope.yaml" in doc["error"]


# -- 8: a network with no informed agent ------------------------------------------------


def test_no_informed_agent_messages_agree(tmp_path, capsys, monkeypatch):
    p = tmp_path / "noinf.yaml"
    p.write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: 1}\n"
    )
    code, out, err = run_cli(["design", p, "--theta", "1"], capsys, monkeypatch)
    assert code == 1 and "not designed" in err  # nothing can be designed (issue 41, item 10)
    assert "the rate grows with δ" not in out
    assert "does not depend on δ" in out and "antagonistic edge" in out
    code, out, err = run_cli(
        ["certify", p, "--theta", "1", "--gain", "1/(1+t)"], capsys, monkeypatch
    )
    # certify says what design says, in one line, before any matrix (issue 47, item 11)
    assert code == 1 and out == "" and "\ncertificate (hurwitz)" not in out
    assert err.splitlines() == [
        "not certified: the network has no informed agent (U is empty), so L_B = L does not "
        "depend on δ and Lemma 1 cannot bring the agents to θ; an antagonistic edge (A_ij "
        "negative definite) into an agent makes it informed"
    ]


# -- 9: design.mat holds Δ and the identity checks as a MATLAB user would ---------------


def test_design_mat_checks_lemma1_identity_by_hand(tmp_path, capsys, monkeypatch):
    out = tmp_path / "design.mat"
    code, text, err = run_cli(
        ["design", G1, "--theta", "1,2,-1", "--out", out], capsys, monkeypatch
    )
    assert code == 0, err
    assert f"wrote {out}" in text
    m = sio.loadmat(out)
    th = m["theta"].ravel()
    n = m["delta_i"].shape[0]
    e = np.kron(np.ones(n), th)
    lhs = m["L_B"] @ e
    assert np.linalg.norm(lhs - m["k1"].item() * (m["Delta"] @ (m["B_all"] @ th))) <= 1e-12 * (
        np.linalg.norm(lhs)
    )
    # Δ is δ exactly on the informed agents (1-based in the file), zero elsewhere
    delta_i = m["delta_i"].ravel()
    informed = m["informed"].ravel().astype(int) - 1
    assert np.all(delta_i[informed] == m["delta"].item())
    assert np.count_nonzero(delta_i) == informed.size
    # without Δ the residual is as large as L_B itself (what the user met)
    assert np.linalg.norm(lhs - m["k1"].item() * (m["B_all"] @ th).ravel()) > 1.0


# -- 10, 11: help texts and names --------------------------------------------------------


def test_help_shows_no_bool_metavar_and_names_every_format(capsys, monkeypatch):
    for cmd in ("check", "tune", "report", "design"):
        code, out, _ = run_cli([cmd, "--help"], capsys, monkeypatch)
        assert code == 0 and "<bool>" not in out, cmd
    _, out, _ = run_cli(["check", "--help"], capsys, monkeypatch)
    assert ".csv" in out and ".mat" in out and ".npz" in out


def test_horizon_is_one_name_with_t_as_alias(tmp_path, capsys, monkeypatch):
    for flag in ("--horizon", "--T"):
        out = tmp_path / flag.strip("-")
        code, _, err = run_cli(
            ["simulate", scenario(tmp_path), "--out", out, flag, "0.1"], capsys, monkeypatch
        )
        assert code == 0, err
        assert json.loads((out / "summary.json").read_text())["parameters"]["T"] == 0.1


def test_landscape_marks_what_scored_infinity_and_the_baseline_only_on_its_slice():
    from types import SimpleNamespace

    from ntc_design.reports.tune import landscape_figure
    from ntc_design.tune.family import PowerGain

    a = np.geomspace(0.1, 10, 5)
    g = np.linspace(0.51, 1.0, 4)
    vals = np.outer(g, a) + 1.0
    vals[:, -2:] = np.inf  # too stiff
    for b, baseline in ((1.0, True), (0.37, False)):
        land = SimpleNamespace(a=a, gamma=g, b=b, values=vals)
        res = SimpleNamespace(landscape=land, tuned=PowerGain(1.0, b, 1.0), ms_error_T={})
        fig = landscape_figure(res)
        labels = fig.legends[0].get_texts()
        names = [t.get_text() for t in labels]
        assert any("+∞" in n for n in names)
        assert any("baseline" in n for n in names) is baseline
        tuned = [ln for ln in fig.axes[0].get_lines() if ln.get_label() == "tuned"][0]
        assert tuned.get_clip_on() is False


# -- 12: --out that is not a regular file ------------------------------------------------


@hostile
@pytest.mark.parametrize(
    "args",
    [
        ["certify", G1, "--theta", "1,2,-1"],
        ["design", G1, "--theta", "1,2,-1"],
        ["generate", "--agents", "20"],
    ],
)
def test_out_that_is_a_fifo_is_refused_and_left_alone(tmp_path, capsys, monkeypatch, args):
    fifo = tmp_path / ("x.json" if args[0] != "generate" else "x.npz")
    os.mkfifo(fifo)
    assert_input_error([*args, "--out", fifo], capsys, monkeypatch, "--out", "not a regular file")
    assert fifo.is_fifo()


@hostile
def test_tune_out_that_cannot_be_created_is_refused_before_the_search(
    tmp_path, capsys, monkeypatch
):
    from ntc_design import tune as tune_pkg

    monkeypatch.setattr(tune_pkg, "tune", lambda *a, **k: pytest.fail("the search ran"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    sc = scenario(tmp_path)
    assert_input_error(
        ["tune", sc, "--horizon", "1", "--out", blocker / "sub" / "o"],
        capsys,
        monkeypatch,
        "--out",
    )


# -- 13: labels read exactly --------------------------------------------------------------


W = "-1,0,0,0,-1,0,0,0,-1"


@hostile
@pytest.mark.parametrize(
    "first, second",
    [("1", "01"), ("1", "+1"), ("0", "-0"), ("1", "١"), ("7", "007")],
)
def test_two_spellings_of_one_number_are_refused(tmp_path, capsys, monkeypatch, first, second):
    header = "from,to,a11,a12,a13,a21,a22,a23,a31,a32,a33\n"
    csv = _csv(tmp_path, "al.csv", f"{header}{first},2,{W}\n{second},3,{W}\n")
    assert_input_error(["design", csv, "--theta", "1,2,-1"], capsys, monkeypatch, first, second)
    npz = tmp_path / "al.npz"
    write_npz(npz, [first, second, "2"], 1, np.array([1]), np.array([0]), -np.ones((1, 1, 1)))
    assert_input_error(["check", npz], capsys, monkeypatch, "two spellings")
    mat = _mat(
        tmp_path, "al.mat", A=np.array([[0.0, 0, 0], [-1, 0, 0], [0, 0, 0]]), dim=1.0,
        labels=np.array([first, second, "x"], dtype=object),
    )  # fmt: skip
    assert_input_error(["check", mat], capsys, monkeypatch, "two spellings")


def test_labels_are_kept_as_written_when_unambiguous(tmp_path):
    header = "from,to,a11\n"
    top = nd.load(_csv(tmp_path, "ok.csv", f"{header}01,x,-1\nx,7,1\n"))
    assert top.labels == ("01", "x", 7)


# -- 15: check scales ---------------------------------------------------------------------


def test_check_summarises_a_large_network(tmp_path, capsys, monkeypatch):
    from ntc_design.model.generate import random_network, write_topology

    net = tmp_path / "net.npz"
    top = random_network(400, 2, seed=5)
    write_topology(top, net)
    code, out, _ = run_cli(["check", net], capsys, monkeypatch)
    assert code == 0
    assert "structure (summary)" in out and "400, 2" in out
    assert len(out.splitlines()) < 40  # not one row per agent
    code, out, _ = run_cli(["check", net, "--json"], capsys, monkeypatch)
    doc = json.loads(out)
    assert doc["N"] == 400 and doc["E"] == len(top.weights)
    assert sum(doc["edge_classes"].values()) == doc["E"]
    assert doc["assumption_holds"] is True and doc["V1_count"] + doc["V2_count"] == 400
    code, out, _ = run_cli(["check", net, "--full", "--json"], capsys, monkeypatch)
    assert len(json.loads(out)["per_agent"]) == 400


# -- 17: terminal injection through labels --------------------------------------------------


@hostile
def test_labels_cannot_write_lines_or_escape_sequences(tmp_path, capsys, monkeypatch):
    p = tmp_path / "inj.npz"
    labels = ["a\nerror: forged", "b\x1b[31mred", "c"]
    write_npz(p, labels, 1, np.array([1, 2]), np.array([0, 1]), np.array([[[-1.0]], [[1.0]]]))
    code, out, _ = run_cli(["check", p], capsys, monkeypatch)
    assert code == 0
    assert "\x1b" not in out
    assert not any(ln.startswith("error:") for ln in out.splitlines())
    assert "a\\nerror: forged" in out and "b\\x1b[31mred" in out


# -- 18: a certificate's subject is what Lemma 1 defines -------------------------------------


@hostile
@pytest.mark.parametrize("margin", [-0.1, 0.0])
def test_a_resealed_non_positive_margin_does_not_verify(margin):
    doc = copy.deepcopy(json.loads((ROOT / "certificates" / "g1.json").read_text()))
    for sub in doc["subject"]["modes"].values():
        sub["margin"] = margin
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    ver = verify(doc)
    assert not ver.valid
    bad = [c for c in ver.checks if not c.ok]
    assert [c.name for c in bad] == ["G1: margin ΔC > 0"]


def test_scale_certificates_check_the_margin():
    from ntc_design.certify import scale_certificate
    from ntc_design.model.generate import random_network

    des = nd.design(random_network(30, 2, seed=4), [1.0, -1.0], thresholds=False)
    cert = scale_certificate(des)
    assert verify(cert).valid
    forged = copy.deepcopy(cert)
    for sub in forged["subject"]["modes"].values():
        sub["margin"] = -1.0
    forged["subject_digest"] = document_hash(forged["subject"])
    forged["digest"] = digest(forged)
    ver = verify(forged)
    assert not ver.valid and any("margin" in c.name and not c.ok for c in ver.checks)


def test_stored_npz_members_are_bounded(tmp_path):
    # a run's paths.npz is read with its declared sizes checked (a zip bomb is refused)
    from ntc_design.reports.rundata import _read_npz

    p = tmp_path / "paths.npz"
    with zipfile.ZipFile(p, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("t.npy", b"\0" * 50_000_000)
    os.environ["NTC_AVAILABLE_MEMORY"] = "60M"
    try:
        with pytest.raises(nd.InputError, match="unpacks to"):
            _read_npz(p, tmp_path)
    finally:
        os.environ["NTC_AVAILABLE_MEMORY"] = "6G"


# -- 10: the docs site ---------------------------------------------------------------------


def test_every_guide_page_is_in_the_guide_section():
    index = (ROOT / "docs" / "guide" / "index.md").read_text()
    block = index.split("```{toctree}")[1].split("```")[0].splitlines()
    toc = {ln.strip() for ln in block if ln.strip() and not ln.strip().startswith(":")}
    pages = {p.stem for p in (ROOT / "docs" / "guide").glob("*.md")} - {"index"}
    assert pages == toc
    assert "guide/index" in (ROOT / "docs" / "index.rst").read_text()
    css = (ROOT / "docs" / "_static" / "custom.css").read_text()
    assert "table.autosummary" in css and "white-space: normal" in css
    assert "custom.css" in (ROOT / "docs" / "conf.py").read_text()


# -- the review of this work -------------------------------------------------------------


def test_an_explicit_delta_states_no_margin(g1, theta):
    from ntc_design.certify import certify

    des = nd.design(g1, theta)
    res = certify(g1, theta, delta=0.5 * des.C)  # δ < C: not Lemma 1's design
    sub = res.certificate["subject"]["modes"]["G1"]
    assert sub["margin"] is None and res.verification.valid
    check = next(c for c in res.verification.checks if "margin" in c.name)
    assert check.ok and "given directly" in check.detail
    assert certify(g1, theta).certificate["subject"]["modes"]["G1"]["margin"] == 0.1


@hostile
def test_a_corrupt_compressed_mat_variable_is_bad_input(tmp_path, capsys, monkeypatch):
    import struct

    p = tmp_path / "bad.mat"
    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    p.write_bytes(head + struct.pack("<II", 15, 16) + b"x\x9c" + b"\xff" * 14)
    assert_input_error(["check", p], capsys, monkeypatch, "not a readable MATLAB file")


@hostile
def test_a_mat_of_junk_tags_is_left_to_loadmat_at_once(tmp_path, capsys, monkeypatch):
    import struct

    p = tmp_path / "junk.mat"
    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    p.write_bytes(head + b"\0" * 5_000_000)  # 625,000 zero tags: not one is a variable
    from ntc_design.io.tablefiles import _mat_inflated_bytes

    _mat_inflated_bytes(p, 2**30)  # returns at the first tag (no loop over the file)
    assert_input_error(["check", p], capsys, monkeypatch, str(p))


@hostile
def test_progress_shows_file_text_as_text_on_a_terminal(capsys):
    from ntc_design.reports.terminal import Progress

    # the old bar read its descriptions as rich markup: "[/]" raised MarkupError and
    # "[draft]" vanished; now each is the text, on one line, control characters escaped
    with Progress("ntc x", tty=True) as prog:
        prog.stage("simulating runs/[draft]/s.yaml [/] \x1b[31m")
        prog.tick("mode [bold]", 1, 2)
        shown = [t.description for t in prog._bar.tasks]
    assert shown == ["simulating runs/[draft]/s.yaml [/] \\x1b[31m", "mode [bold]"]
    column = prog._bar.columns[0]
    assert column.markup is False


def test_the_package_design_can_be_patched(monkeypatch):
    import ntc_design as pkg
    from ntc_design.protocol import lemma1

    def fake(*a, **k):
        return "fake"

    monkeypatch.setattr(pkg, "design", fake)
    assert pkg.design is fake
    monkeypatch.undo()
    assert pkg.design is lemma1.design
    import ntc_design.protocol

    assert pkg.design is lemma1.design


def test_switching_design_mat_files_have_safe_names(tmp_path, capsys, monkeypatch):
    sw = tmp_path / "sw.yaml"
    sw.write_text(
        f"modes: {{'a/b': {G1}, 'c d': {G1}}}\n"
        "schedule: [{mode: 'a/b', duration: 1}, {mode: 'c d', duration: 1}]\n"
    )
    code, out, err = run_cli(
        ["design", sw, "--theta", "1,2,-1", "--out", tmp_path / "d.mat"], capsys, monkeypatch
    )
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.glob("d_*.mat")) == ["d_a_b.mat", "d_c_d.mat"]


@hostile
def test_an_unknown_rate_method_is_refused_before_the_work(capsys, monkeypatch):
    from ntc_design import certify as cert_pkg

    monkeypatch.setattr(cert_pkg, "certify", lambda *a, **k: pytest.fail("it ran"))
    assert_input_error(
        ["certify", G1, "--theta", "1,2,-1", "--rate-method", "sdp"],
        capsys,
        monkeypatch,
        "--rate-method",
    )


def test_safe_escapes_c1_and_bidi_controls():
    from ntc_design.reports.terminal import safe

    shown = safe("a\x9b31mb\u202ec\nd")
    assert "\x9b" not in shown and "\u202e" not in shown and "\n" in shown
    assert "\\x9b" in shown and "\\u202e" in shown


def test_the_recorded_command_is_the_one_given_to_main(tmp_path, monkeypatch):
    from ntc_design.cli import main

    out = tmp_path / "run"
    monkeypatch.setattr(sys, "argv", ["something", "else"])
    with pytest.raises(SystemExit) as exc:
        main(["simulate", str(scenario(tmp_path)), "--out", str(out), "--paths", "5"])
    assert exc.value.code == 0
    cmd = json.loads((out / "summary.json").read_text())["command"]
    assert cmd.startswith("ntc simulate ") and cmd.endswith("--paths 5")
