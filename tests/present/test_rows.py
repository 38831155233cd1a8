"""Tests of :mod:`ntc_design.present.rows`."""

import numpy as np
import pytest

from ntc_design.certify import certify
from ntc_design.gain.conditions import analyse_gain
from ntc_design.present.rows import Cell, Table, fmt, matrix, verdict
from tests.support.rows import _squash, _text


def test_fmt_is_the_one_number_format():
    assert fmt(7.244) == "7.2440"
    assert fmt(2.5e-7) == "2.5e-07"
    assert fmt(0.0) == "0.0000"
    assert fmt(float("inf")) == "∞" and fmt(float("-inf")) == "−∞"
    assert fmt(float("nan")) == "NaN" and fmt(None) == "—" and fmt(True) == "yes"
    assert fmt([1, 2.5]) == "[1, 2.5000]"
    assert fmt(np.float64(1234567.0)) == "1.235e+06"


@pytest.mark.parametrize(
    "value", [{"verdict": True, "text": "ok"}, {"dominance": 3}, {1, 2}, frozenset()]
)
def test_a_mapping_or_a_set_is_no_cell(value):
    # its Python form ({'verdict': True, …}) is no text for a user: the table that shows
    # it says how (a verdict cell, a link, words), so fmt and Table.build refuse it
    with pytest.raises(TypeError, match="is not shown as Python"):
        fmt(value)
    with pytest.raises(TypeError, match="is not shown as Python"):
        Table.build("t", ("a", "b"), [("label", value)])


def test_cells_render_alike_in_text_and_html():
    t = Table.build(
        "t",
        ("a", "b"),
        [("x", verdict(False, "because")), ("m", matrix([[1, -0.0], [2, 3]])), ("v", 0.5)],
        ["a note"],
    )
    assert t.labels == ("x", "m", "v")
    text = t.text()
    assert "no because" in text and "[[1, 0], [2, 3]]" in text and "0.5000" in text
    assert "note: a note" in text
    h = t.html()
    assert '<span class="bad">no</span>' in h and 'class="matrix"' in h
    assert "because" in _text(h) and "a note" in _text(h)
    with pytest.raises(ValueError):
        Table.build("t", ("a", "b"), [("only one",)])
    assert Cell(text="<b>").html() == "&lt;b&gt;"  # escaped, never markup from data


def test_notebook_representations_show_the_terminal_numbers(g1, switching_set, theta):
    """Every object a researcher holds in Jupyter has a short repr and an HTML view whose
    visible text holds the numbers of its table (the terminal's)."""
    from ntc_design.simulate import simulate

    res = certify(g1, theta, gain="1/(1+t)")
    run = simulate(g1, theta, T=0.5, paths=20, seed=1)
    objects = [g1, switching_set, res.design, res, res.verification, run, analyse_gain("1/(1+t)")]
    for obj in objects:
        page = _text(obj._repr_html_())
        tables = obj.tables() if hasattr(obj, "tables") else (obj.table(),)
        for t in tables:
            for label, row in zip(t.labels, t.rows, strict=True):
                assert _squash(label) in page, (type(obj).__name__, label)
                if not row[-1].matrix:
                    assert _squash(row[-1].plain().split("\n")[0]) in page, (label, row[-1].plain())
        assert len(repr(obj)) < 300 and "array(" not in repr(obj), repr(obj)
    assert "<svg" in g1._repr_html_() and "<svg" in run._repr_html_()  # the network, the curves
    assert repr(g1) == "Topology('G1', N=7, d=3, 8 edges (3 antagonistic), U={2, 3})"


def test_counted_says_one_agent_not_one_agents(tmp_path, capsys, monkeypatch):
    from ntc_design.present.rows import counted
    from tests.cli_helpers import run_cli

    assert [counted(n, "agent") for n in (0, 1, 2)] == ["0 agents", "1 agent", "2 agents"]
    assert (
        counted(1, "matrix", "matrices") == "1 matrix"
        and counted(3, "matrix", "matrices") == "3 matrices"
    )
    # agent 3 alone is neither informed nor in-degree-dominated (in 1 < out 5)
    p = tmp_path / "one.yaml"
    p.write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 2, to: 1, weight: -1}\n"
        "  - {from: 1, to: 2, weight: -1}\n  - {from: 1, to: 3, weight: 1}\n"
        "  - {from: 3, to: 1, weight: 5}\n"
    )
    _, out, _ = run_cli(["check", p], capsys, monkeypatch)
    assert "Assumption 2: fails (1 agent violates it)" in out and "1 agents" not in out
