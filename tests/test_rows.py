"""One presentation model: the terminal, the HTML report and notebooks show the same
tables (ntc_design.rows) with the same labels and numbers."""

import html
import re
import shutil

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.gain import analyse_gain
from ntc_design.rows import Cell, Table, fmt, matrix, verdict

from .cli_helpers import run_cli
from .conftest import EXAMPLES


def _text(html_text: str) -> str:
    """The visible text of an HTML fragment, entities decoded, whitespace collapsed."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", html_text)).split())


def _squash(s: str) -> str:
    return " ".join(s.split())


def test_fmt_is_the_one_number_format():
    assert fmt(7.244) == "7.2440"
    assert fmt(2.5e-7) == "2.5e-07"
    assert fmt(0.0) == "0.0000"
    assert fmt(float("inf")) == "∞" and fmt(float("-inf")) == "−∞"
    assert fmt(float("nan")) == "NaN" and fmt(None) == "—" and fmt(True) == "yes"
    assert fmt([1, 2.5]) == "[1, 2.5000]"
    assert fmt(np.float64(1234567.0)) == "1.235e+06"


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


def test_design_labels_are_the_same_in_the_terminal_and_the_notebook(capsys, monkeypatch):
    top = nd.load(EXAMPLES / "g1.yaml")
    des = nd.design(top, [1, 2, -1], 0.1)
    table = des.table()
    code, out, _ = run_cli(
        ["design", EXAMPLES / "g1.yaml", "--theta", "1,2,-1"], capsys, monkeypatch
    )
    assert code == 0
    flat = _squash(out)
    page = _text(des._repr_html_())
    for label, row in zip(table.labels, table.rows, strict=True):
        assert label in flat and label in page, label
        value = row[1].plain()
        assert _squash(value) in flat, (label, value)
        # a matrix is a grid in HTML: the same entries in the same order
        entries = value.replace("[", " ").replace("]", " ").replace(",", " ")
        assert _squash(entries) in page if row[1].matrix else _squash(value) in page, label
    assert fmt(des.delta) == "7.2440" and "7.2440" in flat and "7.2440" in page


def test_the_terminal_verdict_names_a_failing_assumption(capsys, monkeypatch):
    args = ["certify", EXAMPLES / "switching.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    for th in ("Theorem 3 (mean square): guaranteed", "Theorem 4 (almost sure): guaranteed"):
        block = out.split(th)[1].split("Theorem")[0]
        assert "replaced: Assumption 2" in block and "fails in mode(s) G3" in block
    res = certify(nd.load(EXAMPLES / "switching.yaml"), [1, 2, -1], gain="1/(1+t)")
    page = _text(res._repr_html_())
    assert "replaced: Assumption 2" in page  # the notebook and the report say it too


@pytest.mark.parametrize("expr", ["(1+t)^(-1/3)", "1/(1+t)", "exp(-t)", "t^2/(1+t^3)"])
def test_no_sympy_spelling_of_an_expression_reaches_a_user(expr, capsys, monkeypatch):
    _, out, _ = run_cli(["gain", expr], capsys, monkeypatch)
    text = out + analyse_gain(expr).table().text()
    assert "oo" not in text.replace("root", "") and "**" not in text
    assert "gain c(t) =" in out


def test_gain_table_html_holds_the_terminal_verdicts():
    g = analyse_gain("(1+t)^(-1/3)")
    t = g.table()
    page = _text(g._repr_html_())
    assert [r[1].verdict_word for r in t.rows] == ["yes", "yes", "yes", "no", "yes", "no"]
    for label in t.labels:
        assert label in page


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
