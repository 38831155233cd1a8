"""ntc_design.reports.figlist and the reports built on it: the facts are computed first,
rendering certifies and simulates nothing, and a report's figures are one list (adding a
figure is one function)."""

import functools

import pytest

from ntc_design.reports import aggregate, parts, report, style
from ntc_design.reports.figlist import Drawn, FigureSpec, first, render_figures
from ntc_design.reports.rundata import load_run

from .cli_helpers import run_cli
from .conftest import ROOT


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


def _no_certify(*a, **k):
    raise AssertionError("rendering certified")


def test_rendering_certifies_nothing_and_draws_the_whole_list(g1_facts, tmp_path, monkeypatch):
    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",)))
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


def test_a_new_figure_is_one_function_in_the_list(g1_facts, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",)))
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


def test_render_figures_keeps_every_slot_and_first_reads_one():
    calls = []

    def none(f, gid):
        calls.append((f, gid))
        return []

    out = render_figures(
        [FigureSpec("a", 1.0, none), FigureSpec("b", 1.0, none)], "F", None, "k", None, True
    )
    assert out == {"a": [], "b": []} and calls == [("F", "k"), ("F", "k")]
    assert first([]) is None and first(["x"]) == "x"


def test_the_aggregate_report_renders_from_its_facts_alone(tmp_path, capsys, monkeypatch):
    from ntc_design.generate import random_network, write_topology

    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",)))
    top = random_network(aggregate.AGGREGATE_ABOVE + 2, 2, seed=11)
    write_topology(top, tmp_path / "net.yaml")
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: net.yaml\ntheta: [1, -1]\ngain: '1/(1+t)'\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.1\ndt: 0.0005\npaths: 6\n"
        "save_every: 0.05\nworkers: 1\nmethod: mc\n"
    )
    code, _, err = run_cli(["simulate", sc, "--out", tmp_path / "run"], capsys, monkeypatch)
    assert code == 0, err
    run = load_run(tmp_path / "run")
    f = aggregate.aggregate_facts(run, tmp_path)
    assert f.kind == "MC" and f.ms.shape[1] == top.n and f.first.topology.n == top.n
    monkeypatch.setattr(parts, "certify", _no_certify)
    figs = render_figures(aggregate.AGGREGATE_FIGURES, f, tmp_path, "a", tmp_path)
    assert [d.id for d in figs["topology"]][:2] == ["a-fig-degrees", "a-fig-sparsity"]
    assert [d.id for d in figs["ms"]] == ["a-fig-ms_quantiles"]
    assert [d.id for d in figs["paths"]][-1] == "a-fig-final_hist"
