"""Tests of :mod:`ntc_design.reports.figures`."""

import matplotlib
import numpy as np
import pytest

from ntc_design.model.paper import THETA
from ntc_design.reports import figures

matplotlib.use("Agg")


def test_the_mode_timeline_colours_every_segment_and_aggregates_short_ones():
    import matplotlib.pyplot as plt

    long_ = [(0.0, 1.0, "G1"), (1.0, 3.0, "G2"), (3.0, 4.0, "G1")]
    fig, ax = plt.subplots()
    handles = figures.mode_timeline(ax, long_)
    assert sorted(h.get_label() for h in handles) == ["mode G1", "mode G2"]
    spans = sorted((p.get_x(), p.get_x() + p.get_width()) for p in ax.patches)
    assert spans == [(0.0, 1.0), (1.0, 3.0), (3.0, 4.0)]  # one bar per segment, exact
    # 400 segments of 0.01 on a 200-bin axis: drawn as the share of each mode per bin
    short = [(k * 0.01, (k + 1) * 0.01, "G1" if k % 4 else "G2") for k in range(400)]
    fig2, ax2 = plt.subplots()
    order = [h.get_label() for h in figures.mode_timeline(ax2, short)]
    bars = ax2.patches  # 200 bins per mode, in the legend's order
    area = [sum(b.get_height() * b.get_width() for b in bars[k : k + 200]) for k in (0, 200)]
    active = {"mode G1": 3.0, "mode G2": 1.0}  # the time each mode is active
    assert area == pytest.approx([active[m] for m in order])
    heights = np.array([b.get_height() for b in bars]).reshape(2, 200)
    assert np.allclose(heights.sum(axis=0), 1.0)  # shares of each bin add up to one
    plt.close(fig)
    plt.close(fig2)


def test_states_and_mean_square_figures_with_a_switching_timeline():
    t = np.linspace(0.0, 2.0, 21)
    path = np.outer(np.exp(-t), np.arange(1.0, 7.0))  # 2 agents × d = 3
    segs = [(0.0, 1.0, "G1"), (1.0, 2.0, "G2")]
    fig = figures.states_figure(t, path, np.array(THETA), ["a", "b"], segments=segs)
    data = [ln.get_ydata() for ax in fig.axes for ln in ax.lines if len(ln.get_ydata()) == 21]
    assert any(np.allclose(y, path[:, 0]) for y in data)  # agent a, dimension 1, as given
    exact = np.exp(-np.outer(t, [1.0, 2.0]))
    fig2 = figures.ms_error_figure(t, None, exact, ["a", "b"], segments=segs)
    drawn = [ln.get_ydata() for ln in fig2.axes[0].lines]
    assert any(np.allclose(y, exact[:, 1]) for y in drawn)
    assert len(fig.axes) == 4 and len(fig2.axes) == 2  # panels + the mode timeline


def test_robust_figure_draws_each_bracket_end_it_is_given():
    from types import SimpleNamespace

    from ntc_design.certify.robust import Bracket

    def rep(rho, a_lo, a_hi, o_lo, o_hi):
        return SimpleNamespace(
            radius=rho,
            decay=Bracket(a_lo, a_hi, None, "lower", "LMI"),
            offset=Bracket(o_lo, o_hi, None, "upper", "S-procedure"),
        )

    reps = [rep(0.02, 0.81, 0.82, 0.03, 0.031), rep(0.05, 0.80, 0.815, 0.07, 0.08)]
    fig = figures.robust_figure(reps, margin=(0.5, 0.9))
    dec, off = fig.axes[:2]
    assert np.allclose(dec.lines[0].get_xdata(), [0.02, 0.05])
    assert np.allclose(dec.lines[0].get_ydata(), [0.81, 0.80])  # the proven lower ends
    assert np.allclose(dec.lines[1].get_ydata(), [0.82, 0.815])  # the attained ones
    assert np.allclose(off.lines[0].get_ydata(), [0.031, 0.08])  # the proven upper ends
    assert np.allclose(off.lines[1].get_ydata(), [0.03, 0.07])
    assert dec.get_xlim()[1] == pytest.approx(0.9)  # the axis reaches the margin's far end
    gap = figures.robust_figure([rep(0.1, None, 0.7, 0.1, None)])  # an end not proven
    assert np.isnan(gap.axes[0].lines[0].get_ydata()[0])


def test_realisations_figure_puts_each_realisation_and_the_proven_lines():
    rows = [{"decay_rate": 0.80 + 0.01 * k, "offset": 0.02 * k} for k in range(5)]
    study = {
        "rows": rows,
        "radius": 0.05,
        "brackets": {"decay": {"lower": 0.79}, "offset": {"upper": 0.2}, "nominal_decay": 0.82},
    }
    fig = figures.realisations_figure(study)
    ax = fig.axes[0]
    pts = ax.lines[0]
    assert np.allclose(pts.get_xdata(), [r["decay_rate"] for r in rows])
    assert np.allclose(pts.get_ydata(), [r["offset"] for r in rows])
    assert ax.lines[1].get_xdata()[0] == pytest.approx(0.79)  # the vertical proven decay
    assert ax.lines[2].get_ydata()[0] == pytest.approx(0.2)  # the horizontal proven offset
    assert "ρ = 0.05" in ax.get_title()
    without = figures.realisations_figure({"rows": rows, "radius": 0.1})
    assert len(without.axes[0].lines) == 1  # no brackets: the points only


def test_gain_labels_are_mathtext_from_the_parsed_expression():
    from ntc_design.reports.figures import gain_latex

    assert gain_latex("(1+t)^(-1/3)") == "$c(t) = (t + 1)^{-1/3}$"
    assert gain_latex("1/(1+t)") == r"$c(t) = \dfrac{1}{t + 1}$"
    assert gain_latex("(1+t)**-2") == r"$c(t) = \dfrac{1}{(t + 1)^{2}}$"
