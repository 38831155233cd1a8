"""Tests of :mod:`ntc_design.reports.figlist`."""

from ntc_design.reports.figlist import FigureSpec, first, render_figures


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
