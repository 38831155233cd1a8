"""Every kind of report reads as text for a user, never as Python: no dict, no True,
False or None, no ``name=value`` keyword, in the terminal or in the HTML.

Each report is made by the commands a user runs, on small inputs: a run (with a tabulated
gain schedule, whose certificate checks its tail), a robust study (a scenario's
``robust:``), a run above the aggregate size (a hurwitz-scale certificate, the critical
couplings left out), a sweep and a tuning. The HTML is read as a browser shows it: scripts,
styles and inline SVG dropped, tags and their attribute values (links, the PNG data)
removed, entities decoded.
"""

from __future__ import annotations

import html
import re

import pytest
import yaml

from tests.cli_helpers import run_cli, without_progress
from tests.conftest import ROOT


@pytest.fixture(autouse=True)
def _png_figures(monkeypatch):
    """Figures as PNG at 72 dpi: the pages' text is what is read here (the PNG data and the
    links are dropped from it); the SVG and PDF copies are tests/reports' (CI time)."""
    import functools

    from ntc_design.reports import style

    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",), dpi=72))


#: What Python writes and a user should never read.
PYTHON = re.compile(r"\{'|\bTrue\b|\bFalse\b|\bNone\b|=True\b|=False\b|=None\b")


def visible_text(page: str) -> str:
    """The text of an HTML page as it is read: no script, style or SVG, no tags (so no
    attribute values), comments dropped, entities decoded."""
    page = re.sub(r"<(script|style|svg)\b.*?</\1\s*>", " ", page, flags=re.S | re.I)
    page = re.sub(r"<!--.*?-->", " ", page, flags=re.S)
    page = re.sub(r"<[^>]*>", " ", page)
    return html.unescape(page)


def python_in(text: str) -> list[str]:
    """Each place Python shows through, with some context."""
    return [text[max(0, m.start() - 60) : m.end() + 40] for m in PYTHON.finditer(text)]


@pytest.mark.parametrize(
    "text, found",
    [
        ("certificate {'href': 'c.json'}", 1),
        ("{'verdict': True, 'text': 'ok'}", 2),
        ("holds: False; tail: None", 2),
        ("thresholds=True in Python", 1),
        ("Nonexistent, Falsey and untrue words, a set {1, 2}", 0),
    ],
)
def test_the_scan_finds_python_and_only_python(text, found):
    assert len(python_in(text)) == found


def test_visible_text_drops_markup_scripts_and_attribute_values():
    page = (
        '<p title="True">shown <a href="x?a=True">link</a></p><script>var x = None;</script>'
        "<style>.False{}</style><svg><text>None</text></svg><!-- True -->&lt;ok&gt;"
    )
    assert python_in(visible_text(page)) == []
    assert "shown" in visible_text(page) and "<ok>" in visible_text(page)


_BASE = {
    "theta": [1, 2, -1],
    "margin": 0.1,
    "noise": {"sigma": 0.4, "f": 0.3},
    "initial": {"uniform": [-3, 3], "seed": 1},
    "T": 0.5,
    "dt": 0.01,
    "paths": 10,
    "save_every": 0.1,
    "workers": 1,
}


def _scenario(path, **fields):
    path.write_text(yaml.safe_dump({**_BASE, **fields}, sort_keys=False), encoding="utf-8")
    return path


class _Said:
    """What the commands of one report printed, and the pages they wrote."""

    def __init__(self, capsys, monkeypatch):
        self.capsys, self.monkeypatch, self.text = capsys, monkeypatch, []

    def __call__(self, *args) -> None:
        code, out, err = run_cli(list(args), self.capsys, self.monkeypatch)
        assert code == 0, (args, err)
        self.text.append(f"$ ntc {' '.join(map(str, args))}\n{out}{without_progress(err)}")

    def assert_no_python(self, *pages) -> None:
        shown = {"terminal": "\n".join(self.text)}
        for page in pages:
            shown[str(page)] = visible_text(page.read_text(encoding="utf-8"))
        found = {where: python_in(text) for where, text in shown.items()}
        assert {k: v for k, v in found.items() if v} == {}
        assert all(len(shown[str(p)]) > 500 for p in pages)  # the pages are there, not empty


G1 = str(ROOT / "examples" / "g1.yaml")


def test_a_run_report_with_a_gain_schedule(tmp_path, capsys, monkeypatch):
    # the certificate table (a link, a verdict), the checks of the schedule's tail
    (tmp_path / "c.csv").write_text("t,c\n0,1.0\n0.5,0.8\n1,0.5\n")
    sched = {"schedule": "c.csv", "tail": "1/(1 + t)", "interpolation": "linear"}
    ntc = _Said(capsys, monkeypatch)
    ntc(
        "simulate",
        _scenario(tmp_path / "run.yaml", topology=G1, gain=sched),
        "--out",
        tmp_path / "run",
    )
    ntc("report", tmp_path / "run")
    page = tmp_path / "run" / "report.html"
    assert "tail admissible" in page.read_text(encoding="utf-8")
    ntc.assert_no_python(page)


def test_a_robust_study_report(tmp_path, capsys, monkeypatch):
    from tests.support.tune import PAIR

    (tmp_path / "pair.yaml").write_text(PAIR, encoding="utf-8")
    sc = _scenario(
        tmp_path / "rob.yaml",
        topology="pair.yaml",
        theta=[1.0],
        gain="1/(1+t)",
        robust={"realizations": 2, "radius": 0.05, "seed": 1},
    )
    ntc = _Said(capsys, monkeypatch)
    ntc("simulate", sc, "--out", tmp_path / "rob")
    ntc("report", tmp_path / "rob")
    page = tmp_path / "rob" / "report.html"
    assert "Weights within ρ" in page.read_text(encoding="utf-8")
    ntc.assert_no_python(page)


def test_a_report_above_the_aggregate_and_dense_sizes(tmp_path, capsys, monkeypatch):
    # quantiles over the agents, a hurwitz-scale certificate (its methods), the critical
    # couplings not computed (their note)
    from ntc_design.model.generate import random_network, write_topology
    from ntc_design.reports.aggregate import AGGREGATE_ABOVE

    write_topology(random_network(AGGREGATE_ABOVE + 2, 3, seed=3), tmp_path / "net.yaml")
    sc = _scenario(
        tmp_path / "big.yaml",
        topology="net.yaml",
        theta=[1, -1, 2],
        gain="1/(1+t)",
        T=0.1,
        dt=0.0005,
        save_every=0.05,
        method="mc",
    )
    ntc = _Said(capsys, monkeypatch)
    ntc("simulate", sc, "--out", tmp_path / "big")
    ntc("report", tmp_path / "big")
    page = tmp_path / "big" / "report.html"
    text = visible_text(page.read_text(encoding="utf-8"))
    assert "hurwitz-scale" in text and "critical couplings δ_H, δ_S not computed" in text
    assert re.search(r"by dominance \d+, symmetric \d+, lyapunov \d+, none \d+", text)
    ntc.assert_no_python(page)


def test_a_sweep_report(sweep_reference, capsys, monkeypatch):
    ntc = _Said(capsys, monkeypatch)
    ntc("report", sweep_reference)
    ntc.assert_no_python(sweep_reference / "report.html")


def test_a_tune_report(tmp_path, capsys, monkeypatch):
    from tests.support.tune import PAIR

    (tmp_path / "pair.yaml").write_text(PAIR, encoding="utf-8")
    sc = _scenario(tmp_path / "tune.yaml", topology="pair.yaml", theta=[1.0], gain="1/(1+t)", T=1)
    ntc = _Said(capsys, monkeypatch)
    ntc("tune", sc, "--horizon", "1", "--evaluations", "20", "--out", tmp_path / "tune")
    ntc.assert_no_python(tmp_path / "tune" / "tune.html")


def test_a_tune_report_of_a_gain_schedule(tmp_path):
    # tune.html of the optimal schedule (its evidence, refinement and the certificate of
    # the design with the schedule, whose checks judge the tail): the result is built here,
    # an optimisation takes tens of seconds
    import numpy as np

    import ntc_design as nd
    from ntc_design.certify import certify
    from ntc_design.gain.schedule import ScheduleGain, analyse_schedule
    from ntc_design.reports.tune import write_tune_report
    from ntc_design.tune import BASELINE, PowerGain, ScheduleTuneResult
    from ntc_design.tune.objective import Curve
    from ntc_design.tune.optimal import Level, ScheduleSolution
    from tests.support.tune import PAIR

    (tmp_path / "pair.yaml").write_text(PAIR, encoding="utf-8")
    sched = ScheduleGain([0.0, 0.5, 1.0], [1.0, 0.8, 0.5], tail="1/(1 + t)")
    t = np.linspace(0.0, 1.0, 21)
    sol = ScheduleSolution(
        t=sched.t, c=sched.c, value=0.2, optimality=1e-4, max_gain=50.0, binds=(),
        levels=(Level(2, 0.21, 10, 0.1, 100), Level(4, 0.2, 20, 0.2, 200)),
        peak=(4.0, 0.0), converged=True, message="ok",
    )  # fmt: skip
    res = ScheduleTuneResult(
        schedule=sched, power=PowerGain(1.5, 2.0, 0.7), baseline=BASELINE, delta=None,
        power_delta=None, horizon=1.0, require="both", method="optimal control (by hand)",
        curves={k: Curve(t, (1 + j) * np.exp(-t)) for j, k in
                enumerate(("optimal", "power", "baseline"))},
        solution=sol, max_peak=None, gain_analysis=analyse_schedule(sched),
        certificate=certify(nd.load(tmp_path / "pair.yaml"), [1.0], gain=sched),
        monte_carlo={}, seconds=1.0, stepping={"stepping": "intrinsic", "scheme": "implicit"},
    )  # fmt: skip
    page = write_tune_report(res, tmp_path, "sc.yaml", [])
    text = visible_text(page.read_text(encoding="utf-8"))
    assert "gain schedule: tail admissible" in text
    assert python_in(text) == []
