"""Reports: `ntc reproduce paper` at the paper's settings, `ntc report`, and the HTML in a
real headless Chromium."""

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from ntc_design.reports.reproduce import reproduce_paper

from .cli_helpers import assert_input_error, run_cli
from .conftest import ROOT

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    """The paper's Section 5 at its settings (1000 paths, ds = dt = 1e-3, T = 100)."""
    out = tmp_path_factory.mktemp("paper")
    path, ok, wall = reproduce_paper(out)
    return out, path, ok, wall


def _rows(html: str) -> list[str]:
    body = html.split('<h2 id="summary">Summary', 1)[1].split("</table>", 1)[0]
    return body.split("<tr>")[2:]


def _links(path: Path) -> tuple[list[str], set[str]]:
    """Every href of a report and every id it defines."""
    html = path.read_text()
    return re.findall(r'href="([^"]+)"', html), set(re.findall(r'id="([^"]+)"', html))


def _assert_links_resolve(path: Path) -> int:
    hrefs, ids = _links(path)
    files = [h for h in hrefs if not h.startswith("#")]
    for h in hrefs:
        if h.startswith("#"):
            assert h[1:] in ids, h
        else:
            assert "://" not in h, h
            assert (path.parent / h).is_file(), h
    return len(files)


@pytest.mark.slow
def test_reproduce_paper_summary_matches(paper_run):
    out, path, ok, wall = paper_run
    html = path.read_text()
    rows = _rows(html)
    assert len(rows) == 17
    assert all('class="ok">✓' in r for r in rows), [r for r in rows if "✓" not in r]
    assert ok
    for s in (
        "7.1440",
        "7.2440",
        "7.0495",
        "3.1000",
        "[1.2761, 2.5522, -1.2761]",
        "[1.6452, 3.2903, -1.6452]",
    ):
        assert s in html
    for key in ("g1", "switching", "gain_vanishing", "gain_energy"):
        for name in ("summary.json", "ms_error.csv", "paths.npz", "certificate.json"):
            assert (out / key / name).is_file()
    for stem in (
        "g1_ms_error",
        "g1_states",
        "g1_coupling",
        "g1_gain",
        "switching_topology_G2",
        "switching_schedule",
        "gain_energy_states",
    ):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 10_000
        assert (out / "figures" / f"{stem}.svg").read_text().lstrip().startswith("<?xml")
        assert (out / "figures" / f"{stem}.pdf").read_bytes().startswith(b"%PDF")
    assert wall < 900  # a gross-regression guard only: speed is measured in benchmarks/


@pytest.mark.slow
def test_reproduce_report_structure(paper_run):
    """The α(δ) figure, the table of contents, data links that resolve, a re-run command that
    runs, parameters as a table, no empty table header."""
    out, path, _, _ = paper_run
    html = path.read_text()
    assert html.count('<nav class="toc"') == 1
    toc = html.split('<nav class="toc"', 1)[1].split("</nav>", 1)[0]
    for key in ("summary", "g1", "switching", "gain_vanishing", "gain_energy"):
        assert f'href="#{key}"' in toc
    for sub in ("coupling", "convergence", "data", "parameters"):
        assert f'href="#g1-{sub}"' in toc
    for key in ("g1", "switching", "gain_vanishing", "gain_energy"):
        assert f'id="{key}-fig-coupling"' in html
        assert f'href="figures/{key}_coupling.pdf"' in html
        for name in ("summary.json", "ms_error.csv", "ms_error_long.csv", "certificate.json"):
            assert f'href="{key}/{name}"' in html
    assert "decay rate −max Re λ(−L_B(δ))" in html.replace("Decay rate", "decay rate")
    assert _assert_links_resolve(path) > 80
    assert "<th></th>" not in html and "<pre>" not in html
    assert html.count("ntc reproduce paper --out " + str(out)) >= 5
    assert "ntc simulate ntc reproduce" not in html
    assert '<table class="matrix">' in html
    # convergence: the fitted decay exponent of the exact curve against the prediction
    doc = json.loads((out / "paper_summary.json").read_text())
    conv = doc["convergence"]
    assert conv["g1"]["predicted"] == 1.0
    assert abs(conv["g1"]["fits"]["all (Σ_i)"]["exact"] - 1.0) < 0.15
    assert abs(conv["gain_energy"]["predicted"] - 1 / 3) < 1e-12
    assert abs(conv["gain_energy"]["fits"]["all (Σ_i)"]["exact"] - 1 / 3) < 0.1
    assert conv["gain_vanishing"]["predicted"] == 0.0
    assert abs(conv["gain_vanishing"]["fits"]["all (Σ_i)"]["exact"]) < 0.1  # E → E∞ + K/(1+t)
    assert len(doc["rows"]) == 17 and all(r["match"] for r in doc["rows"])
    fine = np.load(out / "gain_energy" / "paths_fine.npz")
    coarse = np.load(out / "gain_energy" / "paths.npz")
    assert fine["t"].size > 4 * coarse["t"].size


def test_a_short_reproduction_in_the_fast_lane(tmp_path, monkeypatch):
    """The paper's Section 5 at T = 2 with 40 paths: every design and certification row
    matches at any horizon; only the three rows about the limit t → ∞ need the full T.
    Figures as PNG only (the vector copies are what the slow full-size run checks)."""
    import functools

    from ntc_design.reports import style

    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",)))
    path, ok, _ = reproduce_paper(tmp_path, T=2.0, paths=40, workers=2)
    doc = json.loads((tmp_path / "paper_summary.json").read_text())
    missed = [r["quantity"] for r in doc["rows"] if not r["match"]]
    assert len(doc["rows"]) == 17 and not ok
    assert len(missed) == 3 and all("→" in q or "no consensus" in q for q in missed), missed
    html = path.read_text()
    for s in ("7.1440", "7.2440", "[1.2761, 2.5522, -1.2761]"):
        assert s in html
    hrefs, ids = _links(path)
    files = [h for h in hrefs if not h.startswith("#") and not h.endswith((".svg", ".pdf"))]
    assert len(files) > 40 and all((path.parent / h).is_file() for h in files)
    assert all(h[1:] in ids for h in hrefs if h.startswith("#"))
    assert html.count("ntc reproduce paper --out " + str(tmp_path)) >= 5
    assert (tmp_path / "figures" / "switching_schedule.png").stat().st_size > 10_000


@pytest.mark.slow  # it opens the full-size paper report (the module's paper_run, ~40 s)
@pytest.mark.skipif(
    CHROMIUM is None, reason="Debian's chromium is not installed (.ci/run installs it where it can)"
)
def test_report_opens_in_headless_chromium(paper_run, tmp_path):
    _, path, _, _ = paper_run
    dom = subprocess.run(
        [
            CHROMIUM,
            *FLAGS,
            f"--user-data-dir={tmp_path / 'profile'}",
            "--virtual-time-budget=10000",
            "--dump-dom",
            path.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    n = path.read_text().count("<img ")
    assert n == 23
    assert f'data-images-loaded="{n}/{n}"' in dom
    shot = tmp_path / "shot.png"
    subprocess.run(
        [
            CHROMIUM,
            *FLAGS,
            f"--user-data-dir={tmp_path / 'profile2'}",
            "--window-size=1200,1600",
            f"--screenshot={shot}",
            path.as_uri(),
        ],
        capture_output=True,
        timeout=120,
    )
    assert shot.stat().st_size > 50_000


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


def test_report_missing_files_are_named(tmp_path, capsys, monkeypatch):
    assert_input_error(
        ["report", tmp_path / "nothing"],
        capsys,
        monkeypatch,
        "no such directory",
        "ntc simulate SCENARIO --out",
    )
    (tmp_path / "partial").mkdir()
    (tmp_path / "partial" / "summary.json").write_text("{}")
    assert_input_error(
        ["report", tmp_path / "partial"],
        capsys,
        monkeypatch,
        "missing ms_error.csv",
        "ntc simulate SCENARIO --out",
    )
    assert not (tmp_path / "partial" / "report.html").exists()


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


def test_progress_heartbeat_off_a_terminal(capsys):
    import time

    from ntc_design.reports.terminal import Progress

    with Progress("ntc x", every=1.0, tty=False) as p:
        p.stage("g1: simulating")  # not printed at once: quick runs stay quiet
        assert capsys.readouterr().err == ""
        p.tick("g1", 1, 2)
        seen = ""
        for _ in range(300):  # the heartbeat prints the current state (wait up to 30 s)
            seen += capsys.readouterr().err
            if "g1: Monte Carlo 50% done" in seen:
                break
            time.sleep(0.1)
        assert "ntc x: [" in seen and "g1: Monte Carlo 50% done" in seen.rstrip().splitlines()[-1]
        p.stage("g1: report")  # after the first interval: printed at once
        assert capsys.readouterr().err.rstrip().endswith("g1: report")


def test_gain_labels_are_mathtext_from_the_parsed_expression():
    from ntc_design.reports.figures import gain_latex

    assert gain_latex("(1+t)^(-1/3)") == "$c(t) = (t + 1)^{-1/3}$"
    assert gain_latex("1/(1+t)") == r"$c(t) = \dfrac{1}{t + 1}$"
    assert gain_latex("(1+t)**-2") == r"$c(t) = \dfrac{1}{(t + 1)^{2}}$"


def test_save_times_on_switching_instants_keep_their_paths():
    """save_every equal to the dwell: save times within rounding of a switching instant are
    still recorded (they were once left as zeros)."""
    from ntc_design import paper
    from ntc_design.simulate import simulate

    res = simulate(
        paper.switching(),
        paper.THETA,
        initial=np.linspace(-3, 3, 21),
        T=20,
        paths=2,
        method="mc",
        save_every=0.02,
        stepping="intrinsic",
        ds=1e-3,
        workers=1,
        block_size=2,
        store_paths=2,
    )
    assert np.all(np.diff(res.grid.save_steps) > 0)
    assert not np.any(np.all(res.mc.paths[0] == 0, axis=1))
    assert np.all(res.mc.mean[1:].sum(axis=1) > 0)


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
    from ntc_design.generate import random_network, write_topology

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
    from ntc_design.generate import random_network, write_topology
    from ntc_design.reports.aggregate import AGGREGATE_ABOVE

    top = random_network(AGGREGATE_ABOVE + 2, 2, seed=11)
    write_topology(top, tmp_path / "net.yaml")
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: net.yaml\ntheta: [1, -1]\ngain: '1/(1+t)'\nnoise: {sigma: 0.4, f: 0.3}\n"
        "initial: {uniform: [-3, 3], seed: 1}\nT: 0.1\ndt: 0.0005\npaths: 12\n"
        "save_every: 0.05\nworkers: 1\nmethod: mc\n"
    )
    _aggregate_report(tmp_path, sc, AGGREGATE_ABOVE + 2, capsys, monkeypatch)


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


def test_agent_styles_tell_agents_apart_in_a_colour_blind_safe_palette():
    from ntc_design.reports.style import PALETTE, agent_style

    styles = [agent_style(k) for k in range(28)]
    assert len({(s.colour, s.linestyle, s.marker) for s in styles}) == 28
    for a, b in zip(styles, styles[1:], strict=False):  # neighbours differ in each
        assert a.colour != b.colour and a.linestyle != b.linestyle and a.marker != b.marker
    assert {s.colour for s in styles} <= set(PALETTE) and "#F0E442" not in PALETTE
