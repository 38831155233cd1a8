"""Tests of :mod:`ntc_design.reports.graph_figure`."""

import math

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_rgba
from matplotlib.patches import Circle, ConnectionStyle, FancyArrowPatch

from ntc_design import Topology
from ntc_design.reports import graph_figure as gf
from ntc_design.reports.style import BLUE, GREEN, RED

matplotlib.use("Agg")  # files only, whatever the machine's display


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def bezier(p0, ctrl, p1, k=400):
    s = np.linspace(0.0, 1.0, k)[:, None]
    return (1 - s) ** 2 * p0 + 2 * (1 - s) * s * ctrl + s**2 * p1


def arc3_control(p0, p1, rad):
    """matplotlib's own arc3 control point (its connect(), before any shrinking)."""
    path = ConnectionStyle.Arc3(rad=rad).connect(tuple(p0), tuple(p1))
    return np.asarray(path.vertices[1])


def arrows(fig):
    return [p for p in fig.axes[0].patches if isinstance(p, FancyArrowPatch)]


def circles(fig):
    return [p for p in fig.axes[0].patches if isinstance(p, Circle)]


# -- weight_label ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "w, text",
    [
        ([[2.0]], "2"),
        ([[-0.5]], "−0.5"),  # a typographic minus
        ([[1.23456]], "1.23"),  # 3 significant digits
        (-0.5 * np.eye(3), "−0.5I"),
        (np.diag([1.0, 1.0, 0.0]), "diag(1, 1, 0)"),
        (np.diag([2.0, -3.0]), "diag(2, −3)"),
        ([[1.0, 2.0], [2.0, -3.0]], "[1 2; 2 −3]"),
        ([[1e-4, 0.0], [0.0, 1e-4]], "0.0001I"),
    ],
)
def test_weight_label(w, text):
    assert gf.weight_label(np.asarray(w)) == text


# -- the layout -----------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 3, 7])
def test_agents_sit_on_the_unit_circle_clockwise_from_the_top(n):
    pos, ang, _ = gf._layout(n, [0])
    for i in range(n):
        # agent i at 2πi/n clockwise from 12 o'clock
        expect = (math.sin(2 * math.pi * i / n), math.cos(2 * math.pi * i / n))
        assert pos[i] == pytest.approx(expect, abs=1e-12)
    if n == 3:
        assert pos[1][0] > 0 > pos[2][0]  # clockwise: the second agent to the right


def test_the_signal_sits_outside_towards_the_informed_agents():
    pos, _, phi = gf._layout(4, [0, 1])  # at 12 and 3 o'clock: x0 towards half past 1
    assert pos[-1] == pytest.approx(1.62 * np.array([1.0, 1.0]) / math.sqrt(2))
    assert phi == pytest.approx(math.pi / 4)
    pos, _, _ = gf._layout(4, [])  # no informed agent: below the circle
    assert pos[-1] == pytest.approx((0.0, -1.62), abs=1e-12)
    pos, _, _ = gf._layout(4, [1, 3])  # opposite agents cancel: beside the first one
    assert pos[-1] == pytest.approx((1.62, 0.0), abs=1e-12)


@pytest.mark.parametrize("rad", [0.0, 0.3, -0.45])
def test_arc_is_matplotlibs_arc3_curve(rad):
    p0, p1 = np.array([0.2, -1.0]), np.array([1.5, 0.7])
    pts = gf._arc(p0, p1, rad, k=41)
    assert pts[0] == pytest.approx(p0) and pts[-1] == pytest.approx(p1)
    ref = bezier(p0, arc3_control(p0, p1, rad), p1, k=41)
    np.testing.assert_allclose(pts, ref, atol=1e-12)


def test_clear_rad_keeps_the_asked_bend_when_nothing_is_in_the_way():
    pos, _, _ = gf._layout(1, [0])
    assert gf._clear_rad(pos, pos[-1], 0, 0.37) == 0.37
    pos, _, _ = gf._layout(6, [0])  # a short straight edge to the nearest agent is free
    assert gf._clear_rad(pos, pos[-1], 0, 0.0) == 0.0


def test_clear_rad_bends_around_an_agent_in_the_way():
    pos, _, _ = gf._layout(6, [0, 3])  # x0 above agent 0; agent 3 at the bottom
    p0 = pos[-1]
    # the straight chord to agent 3 crosses agent 0's circle
    straight = bezier(p0, 0.5 * (p0 + pos[3]), pos[3])
    assert np.min(np.linalg.norm(straight - pos[0], axis=1)) < gf.R_VERTEX
    rad = gf._clear_rad(pos, p0, 3, 0.0)
    assert rad != 0.0
    pts = bezier(p0, arc3_control(p0, pos[3], rad), pos[3])[5:-5]
    others = np.array([pos[k] for k in (0, 1, 2, 4, 5)])
    dist = np.linalg.norm(pts[:, None, :] - others[None], axis=2)
    assert dist.min() > 1.5 * gf.R_VERTEX


# -- the figure -----------------------------------------------------------------------------

PSD = np.diag([1.0, 0.0])
PD = np.array([[2.0, 1.0], [1.0, 2.0]])  # eigenvalues 1 and 3


@pytest.fixture
def small():
    """1 -> 2 positive semidefinite, 2 -> 1 negative definite (a mutual pair), 3 -> 1
    positive definite, 3 -> 2 zero (not drawn)."""
    return Topology.from_edges(
        3, 2, [(1, 2, PSD), (2, 1, -np.eye(2)), (3, 1, PD), (3, 2, np.zeros((2, 2)))]
    )


def test_edges_are_coloured_by_sign_and_dashed_when_semidefinite(small):
    fig = gf.topology_figure(small, [0, 2], {0: np.eye(2), 2: PSD})
    pos, _, _ = gf._layout(3, [0, 2])
    got = {}
    for a in arrows(fig):
        (ax_, ay), (bx, by) = a._posA_posB
        src = min(pos, key=lambda k: np.hypot(pos[k][0] - ax_, pos[k][1] - ay))
        dst = min(pos, key=lambda k: np.hypot(pos[k][0] - bx, pos[k][1] - by))
        got[(src, dst)] = (a.get_edgecolor(), a.get_linestyle(), a.get_connectionstyle().rad)
    # from -> to (agents 0-based, x0 = −1); the mutual pair 0 <-> 1 is bent, 2 -> 0 not
    assert got == {
        (0, 1): (to_rgba(BLUE), "--", 0.18),
        (1, 0): (to_rgba(RED), "-", 0.18),
        (2, 0): (to_rgba(BLUE), "-", 0.0),
        (-1, 0): (to_rgba(GREEN), "-", got[(-1, 0)][2]),  # B = I: definite
        (-1, 2): (to_rgba(GREEN), "--", got[(-1, 2)][2]),  # B semidefinite
    }


def test_vertices_labels_limits_and_legend(small):
    fig = gf.topology_figure(small, [0, 2], {0: np.eye(2), 2: PSD}, title="Ĝ")
    ax = fig.axes[0]
    pos, _, _ = gf._layout(3, [0, 2])
    centres = sorted(tuple(np.round(c.center, 12)) for c in circles(fig))
    assert centres == sorted(tuple(np.round(pos[k], 12)) for k in (-1, 0, 1, 2))
    assert all(c.radius == gf.R_VERTEX for c in circles(fig))
    assert sorted(t.get_text() for t in ax.texts) == ["0", "1", "2", "3"]
    assert ax.get_title() == "Ĝ"
    xy = np.array(list(pos.values()))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= xy[:, 0].min() - 0.3 + 1e-12 and x1 >= xy[:, 0].max() + 0.3 - 1e-12
    assert y0 <= xy[:, 1].min() - 0.3 + 1e-12 and y1 >= xy[:, 1].max() + 0.3 - 1e-12
    assert not ax.axison
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names[:4] == [
        "positive definite", "negative definite", "positive semidef.", "negative semidef."
    ]  # fmt: skip
    assert len(names) == 6


def test_weights_label_every_drawn_edge(small):
    fig = gf.topology_figure(small, [0, 2], {0: np.eye(2), 2: PSD}, weights=True)
    texts = sorted(t.get_text() for t in fig.axes[0].texts)
    # three agent edges (the zero one is not drawn), two couplings, four vertex names
    assert texts == sorted(
        ["diag(1, 0)", "−1I", "[2 1; 1 2]", "B=1I", "B=diag(1, 0)", "0", "1", "2", "3"]
    )
    assert not fig.axes[0].get_title()


def test_width_sets_the_figure_size(small):
    fig = gf.topology_figure(small, [0], {0: np.eye(2)}, width=5.0)
    assert tuple(fig.get_size_inches()) == pytest.approx((5.0, 4.75))


@pytest.mark.parametrize("n, informed", [(5, [0, 2]), (6, [0, 3]), (7, [1, 4, 6]), (8, [0, 4])])
def test_no_signal_edge_runs_through_another_agent(n, informed):
    """x0's arcs, read back from the drawn patches, keep clear of every other agent."""
    edges = [(i + 1, (i + 1) % n + 1, np.eye(1)) for i in range(n)]  # a directed ring
    top = Topology.from_edges(n, 1, edges)
    fig = gf.topology_figure(top, informed, {i: np.eye(1) for i in informed})
    pos, _, _ = gf._layout(n, informed)
    green = [a for a in arrows(fig) if a.get_edgecolor() == to_rgba(GREEN)]
    assert len(green) == len(informed)
    for a in green:
        p0, p1 = (np.array(p) for p in a._posA_posB)
        assert p0 == pytest.approx(pos[-1])
        i = next(k for k in informed if np.allclose(pos[k], p1))
        pts = bezier(p0, arc3_control(p0, p1, a.get_connectionstyle().rad), p1)[8:-8]
        others = np.array([pos[k] for k in range(n) if k != i])
        assert np.linalg.norm(pts[:, None] - others[None], axis=2).min() > 1.5 * gf.R_VERTEX


def test_clear_rad_keeps_the_asked_bend_when_no_bend_clears():
    # 40 agents 0.157 apart on the unit circle, closer than 1.6 radii: every arc ending at
    # agent 0 grazes a neighbour, so the asked bend is kept
    pos, _, _ = gf._layout(40, [0])
    assert np.linalg.norm(pos[0] - pos[1]) < 1.6 * gf.R_VERTEX
    assert gf._clear_rad(pos, pos[-1], 0, 0.2) == 0.2
