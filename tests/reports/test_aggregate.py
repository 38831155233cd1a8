"""Tests of :mod:`ntc_design.reports.aggregate`."""

import json

import numpy as np
import pytest

from ntc_design.reports import aggregate, parts
from ntc_design.reports.figlist import render_figures
from ntc_design.reports.rundata import load_run
from tests.cli_helpers import run_cli
from tests.support.figlist import _no_certify
from tests.support.reports import stand_in_save


def test_the_aggregate_report_renders_from_its_facts_alone(tmp_path, capsys, monkeypatch):
    from ntc_design.model.generate import random_network, write_topology

    # the figures' ids are what is read: built, not drawn (test_report_above_... draws)
    saved = stand_in_save(monkeypatch)
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
    assert len(saved) == sum(len(v) for v in figs.values()) and saved[0].name == "a_degrees"


def _aggregate_report(tmp_path, sc, n_agents, capsys, monkeypatch, exts=("png",)):
    """Simulate and report ``sc``; check the aggregate report's parts (quantiles, no
    per-agent legend, the pictures, the worst agent named); return (out, html)."""
    out = tmp_path / "run"
    code, _, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run_cli(["report", out], capsys, monkeypatch)
    assert code == 0, err
    html = (out / "report.html").read_text()
    assert "median agent" in html and "90 % of agents below" in html
    assert f"agent {n_agents}" not in html  # no per-agent legend or curve
    for stem in ("ms_quantiles", "final_hist", "degrees", "sparsity", "spectrum"):
        for ext in exts:
            assert (out / "figures" / f"run_{stem}.{ext}").is_file(), (stem, ext)
    table = json.loads((out / "summary.json").read_text())["final_ms_error_mc"]
    worst = max(table, key=table.get)
    assert f"<td>{worst}</td>" in html  # the worst agent is named in the final-error table
    return out, html


@pytest.mark.slow
def test_report_on_a_switching_set_above_the_dense_size(tmp_path, capsys, monkeypatch):
    """Nd = 75 > 60: the certificate is switching-scale, its proven bounds are reported; 25
    agents (> AGGREGATE_ABOVE) give the aggregate report: quantiles, worst agents, the
    topology and spectrum pictures, no per-agent legend."""
    from ntc_design.model.generate import random_network, write_topology

    for k, seed in (("a", 3), ("b", 4)):
        t = random_network(25, 3, seed=seed)
        write_topology(t, tmp_path / f"{k}.yaml")
    (tmp_path / "sw.yaml").write_text(
        "modes: {A: a.yaml, B: b.yaml}\n"
        "schedule: [{mode: A, duration: 0.1}, {mode: B, duration: 0.2}]\n"
    )
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: sw.yaml\ntheta: [1, 2, 3]\ngain: '1/(1+t)'\nnoise: {sigma: 0.4, f: 0.0}\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.2\ndt: 0.0002\npaths: 20\n"
        "save_every: 0.05\nworkers: 1\nmethod: mc\n"
    )
    out, html = _aggregate_report(tmp_path, sc, 25, capsys, monkeypatch, ("png", "svg", "pdf"))
    cert = json.loads((out / "certificate.json").read_text())
    assert cert["kind"] == "switching-scale"
    for k, lo in cert["proofs"].items():
        assert f"{k}: {lo['lower']:.6g}" in html  # the proven bound, per mode
    assert "Theorem 3" in html and ("λ_min &gt; ℓ" in html or "λ_min > ℓ" in html)


def test_report_above_the_aggregate_size_in_the_fast_lane(tmp_path, capsys, monkeypatch):
    """22 agents (> AGGREGATE_ABOVE): quantile curves, the final-error histogram, the
    topology and spectrum pictures, the worst agents named, no per-agent legend; the
    quantiles agree with the run's own per-agent table."""
    from ntc_design.model.generate import random_network, write_topology
    from ntc_design.reports.aggregate import AGGREGATE_ABOVE

    top = random_network(AGGREGATE_ABOVE + 2, 2, seed=11)
    write_topology(top, tmp_path / "net.yaml")
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: net.yaml\ntheta: [1, -1]\ngain: '1/(1+t)'\nnoise: {sigma: 0.4, f: 0.3}\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.1\ndt: 0.0005\npaths: 12\n"
        "save_every: 0.05\nworkers: 1\nmethod: mc\n"
    )
    # the quantile curves drawn for real; the other pictures are stand-in files (the slow
    # tests above draw them all, in every format)
    stand_in_save(monkeypatch, draw=("ms_quantiles",))
    out, _ = _aggregate_report(tmp_path, sc, AGGREGATE_ABOVE + 2, capsys, monkeypatch)
    assert (out / "figures" / "run_ms_quantiles.png").stat().st_size > 1000


def test_total_band_is_conservative():
    """The total's band adds the per-agent half-widths: never narrower than the widest
    agent's, and it contains the sum of the means."""
    from ntc_design.reports.aggregate import total_band
    from ntc_design.simulate.result import MeanSquareBand

    rng = np.random.default_rng(np.random.SeedSequence(3))
    mean = rng.uniform(1, 2, size=(4, 30))
    half = rng.uniform(0, 0.5, size=(4, 30))
    tb = total_band(MeanSquareBand(mean=mean, lo=mean - half, hi=mean + half))
    np.testing.assert_allclose(tb.mean[:, 0], mean.sum(axis=1))
    np.testing.assert_allclose(tb.hi[:, 0] - tb.mean[:, 0], half.sum(axis=1))
    assert np.all(tb.hi[:, 0] - tb.lo[:, 0] >= 2 * half.max(axis=1))
