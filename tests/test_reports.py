"""Reports: `ntc reproduce paper` at the paper's settings, `ntc report`, and the HTML in a
real headless Chromium."""

import shutil
import subprocess
from pathlib import Path

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
    body = html.split("<h2>Summary", 1)[1].split("</table>", 1)[0]
    return body.split("<tr>")[2:]


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
    for stem in ("g1_ms_error", "g1_states", "switching_topology_G2", "gain_energy_states"):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 10_000
        assert (out / "figures" / f"{stem}.svg").read_text().lstrip().startswith("<?xml")
    assert wall < 300


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
    assert n == 14
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
    assert html.count("<img ") == 5  # three modes, the error curves, the states
    assert "7.0495" in html and "Theorem 3" in html and "Theorem 4" in html
    assert "certificate.json" in html and (out / "certificate.json").is_file()
    assert "&quot;seed&quot;: 0" in html and "&quot;numpy&quot;" in html


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
