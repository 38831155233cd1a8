"""Tests of :mod:`ntc_design.reports.report`."""

import json
import shutil

import pytest

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.reports import parts, report, style
from ntc_design.reports.figlist import Drawn, FigureSpec
from ntc_design.reports.rundata import load_run
from tests.cli_helpers import run_cli
from tests.conftest import EXAMPLES, ROOT
from tests.support.figlist import _no_certify
from tests.support.reports import _assert_links_resolve, stand_in_save
from tests.support.rows import _squash, _text


@pytest.fixture(scope="module")
def g1_run(tmp_path_factory):
    import sys

    tmp = tmp_path_factory.mktemp("figlist")
    sc = tmp / "sc.yaml"
    sc.write_text(
        f"topology: {ROOT / 'examples' / 'g1.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.2\npaths: 8\nsave_every: 0.05\nworkers: 1\n"
    )
    from ntc_design.cli import main

    argv = sys.argv
    sys.argv = ["ntc", "simulate", str(sc), "--out", str(tmp / "run")]
    try:
        main()
    except SystemExit as exc:
        assert not exc.code
    finally:
        sys.argv = argv
    return load_run(tmp / "run")


@pytest.fixture(scope="module")
def g1_facts(g1_run, tmp_path_factory):
    return report.run_facts(g1_run, tmp_path_factory.mktemp("facts"))


def test_rendering_certifies_nothing_and_draws_the_whole_list(g1_facts, tmp_path, monkeypatch):
    # every figure of the list is built and saved; only the coupling is drawn for real (the
    # slow test_ntc_report_on_a_simulation draws them all, in every format)
    stand_in_save(monkeypatch, draw=("coupling",))
    facts = g1_facts
    assert facts.cert["valid"] and facts.res.certificate["kind"] == "hurwitz"  # computed first
    monkeypatch.setattr(report, "certify", _no_certify)  # A(t)'s certificate
    monkeypatch.setattr(parts, "certify", _no_certify)  # the run's
    section = report.render_run(facts, tmp_path, "G1", "k", tmp_path)
    # coupling, G1's topology, the error curves, the states, the gain: five figures
    drawn = [section.coupling, *section.topology_figures, section.ms_figure,
             *section.path_figures, section.gain_figure]  # fmt: skip
    assert [f.id for f in drawn] == [
        "k-fig-coupling", "k-fig-topology-G1", "k-fig-ms", "k-fig-states", "k-fig-gain"
    ]  # fmt: skip
    assert sorted(p.name for p in tmp_path.glob("k_*.png")) == sorted(
        f"k_{s}.png" for s in ("coupling", "topology_G1", "ms_error", "states", "gain")
    )
    assert section.robust_figure is None and section.robust is None  # no robust study
    assert (tmp_path / "k_coupling.png").stat().st_size > 1000


def test_a_new_figure_is_one_function_in_the_list(g1_facts, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    stand_in_save(monkeypatch, draw=("final",))  # the new figure drawn, the others built
    facts = g1_facts

    def final_bars(f, gid):
        fig, ax = plt.subplots()
        ax.bar(range(len(f.run.labels)), f.exact[-1] if f.exact is not None else f.mc.mean[-1])
        return [Drawn("final", "final", "E‖x_i(T) − θ‖² per agent.", fig)]

    extra = (*report.RUN_FIGURES, FigureSpec("paths", style.ONE_COLUMN, final_bars))
    monkeypatch.setattr(report, "RUN_FIGURES", extra)
    section = report.render_run(facts, tmp_path, "G1", "k", tmp_path)
    assert [f.id for f in section.path_figures] == ["k-fig-states", "k-fig-final"]
    assert (tmp_path / "k_final.png").stat().st_size > 1000


@pytest.mark.slow
def test_ntc_report_on_a_simulation(tmp_path, capsys, monkeypatch):
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        f"topology: {ROOT / 'examples' / 'switching.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.5\npaths: 60\nsave_every: 0.05\nworkers: 1\n"
    )
    out = tmp_path / "run"
    code, _, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0, err
    code, text, err = run_cli(["report", out], capsys, monkeypatch)
    assert code == 0, err
    html = (out / "report.html").read_text()
    # coupling, three modes, one schedule period, the error curves, the states, the gain
    assert html.count("<img ") == 8
    assert "7.0495" in html and "Theorem 3" in html and "Theorem 4" in html
    assert 'href="certificate.json"' in html and (out / "certificate.json").is_file()
    assert "<td>seed</td><td>0</td>" in html and "<td>numpy</td>" in html
    assert "<th></th>" not in html
    assert f"ntc simulate {sc} --out {out} &amp;&amp; ntc report {out}" in html
    assert _assert_links_resolve(out / "report.html") >= 30
    code, text, err = run_cli(["report", out, "--json", "--interactive"], capsys, monkeypatch)
    assert code == 0, err
    doc = json.loads(text)
    assert doc["report"] == str(out / "report_interactive.html")
    assert any(f.endswith("run_coupling.pdf") for f in doc["figures"])
    static = (out / "report.html").read_text()
    assert static.count("<img ") == 8  # the static report is kept beside it
    html = (out / "report_interactive.html").read_text()
    assert html.count("<img ") == 0 and html.count("<svg") == 8
    assert 'class="agent-toggle" value="run-ag0"' in html and 'id="run-ag0-mc"' in html


@pytest.mark.slow
def test_report_tables_carry_the_terminal_labels(tmp_path, capsys, monkeypatch):
    """The HTML report of a run shows every row label the terminal prints for its design,
    gain and theorems, with the same verdict words."""
    sc = tmp_path / "sc.yaml"
    shutil.copy(EXAMPLES / "g1.yaml", tmp_path / "g1.yaml")
    sc.write_text(
        "topology: g1.yaml\ntheta: [1, 2, -1]\ngain: 1/(1+t)\nT: 1.0\ndt: 0.01\npaths: 20\n"
    )
    code, _, err = run_cli(["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run_cli(["report", tmp_path / "o"], capsys, monkeypatch)
    assert code == 0, err
    page = _text((tmp_path / "o" / "report.html").read_text(encoding="utf-8"))
    res = certify(nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], gain="1/(1+t)")
    for t in (res.design.table(), *res.tables()):
        for label in t.labels:
            assert _squash(label) in page, label
    assert "Theorem 1 (mean square) guaranteed" in page
    # the sample path is drawn from a companion run at 2000 steps, not the 0.1-s saves
    assert "companion run of the same scenario and seed" in page and "(2001 points)" in page
