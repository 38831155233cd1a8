"""Tests of :mod:`ntc_design.present.svg`."""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ntc_design.present.svg import BLUE, GREEN, GREY, MAX_DRAWN, RED, curve_svg, network_svg

NS = {"s": "http://www.w3.org/2000/svg"}


def _parse(svg: str) -> ET.Element:
    """The picture as XML: it must be well-formed (escaped labels included)."""
    root = ET.fromstring(svg)
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    return root


def _centres(root: ET.Element) -> list[tuple[float, float]]:
    return [(float(c.get("cx")), float(c.get("cy"))) for c in root.findall("s:circle", NS)]


# -- network_svg -----------------------------------------------------------------------


@pytest.mark.parametrize("n", [0, MAX_DRAWN + 1])
def test_network_too_small_or_too_large_is_empty(n):
    assert network_svg(list(range(n)), []) == ""


def test_network_at_the_limit_is_drawn():
    root = _parse(network_svg(list(range(MAX_DRAWN)), []))
    assert len(root.findall("s:circle", NS)) == MAX_DRAWN


@pytest.mark.parametrize("size", [260, 400])
def test_agents_sit_clockwise_on_a_circle_from_the_top(size):
    n = 4
    root = _parse(network_svg(["a", "b", "c", "d"], [], size=size))
    assert root.get("width") == root.get("height") == str(size)
    c, r = size / 2, size / 2 - 22
    # 0 at the top, then right, bottom, left (screen y grows downwards)
    expected = [(c, c - r), (c + r, c), (c, c + r), (c - r, c)]
    for (x, y), (ex, ey) in zip(_centres(root), expected, strict=True):
        assert abs(x - ex) <= 0.051 and abs(y - ey) <= 0.051
    texts = [t.text for t in root.findall("s:text", NS)]
    assert texts == ["a", "b", "c", "d"]
    assert len(root.findall("s:circle", NS)) == n


def test_edges_are_coloured_dashed_and_shortened():
    labels = [1, 2, 3]
    # (i, j, sign, definite): 0 -> 1 positive definite, 1 -> 2 negative semidefinite
    edges = [(1, 0, 1, True), (2, 1, -1, False)]
    root = _parse(network_svg(labels, edges))
    lines = root.findall("s:line", NS)
    assert len(lines) == 2
    assert lines[0].get("stroke") == BLUE and lines[0].get("stroke-dasharray") is None
    assert lines[1].get("stroke") == RED and lines[1].get("stroke-dasharray") == "4 3"
    assert all(ln.get("marker-end") == "url(#ah)" for ln in lines)
    centres = _centres(root)
    for ln, (i, j, _, _) in zip(lines, edges, strict=True):
        x1, y1, x2, y2 = (float(ln.get(k)) for k in ("x1", "y1", "x2", "y2"))
        (sx, sy), (tx, ty) = centres[j], centres[i]
        # the arrow starts on the source's rim (radius 10) and stops 1 px off the target's
        assert math.hypot(x1 - sx, y1 - sy) == pytest.approx(10, abs=0.15)
        assert math.hypot(x2 - tx, y2 - ty) == pytest.approx(11, abs=0.15)
        # and points from j towards i
        d = np.array([tx - sx, ty - sy])
        v = np.array([x2 - x1, y2 - y1])
        assert np.dot(d, v) / (np.linalg.norm(d) * np.linalg.norm(v)) == pytest.approx(1, abs=1e-4)


def test_informed_agents_are_ringed_in_green():
    root = _parse(network_svg(["x", "y", "z"], [], informed=[2, 0]))
    circles = root.findall("s:circle", NS)
    assert [c.get("stroke") for c in circles] == [GREEN, "black", GREEN]
    assert [c.get("stroke-width") for c in circles] == ["2", "1", "2"]


def test_labels_are_escaped():
    nasty = '<b>&"x"</b>'
    root = _parse(network_svg([nasty, "ok"], [(0, 1, 1, True)]))
    assert [t.text for t in root.findall("s:text", NS)] == [nasty, "ok"]
    assert "<b>" not in network_svg([nasty], [])


# -- curve_svg ---------------------------------------------------------------------------


WIDTH, HEIGHT, LEFT, BOTTOM, TOP, RIGHT = 420, 200, 50, 28, 10, 10


def _points(poly: ET.Element) -> np.ndarray:
    pts = poly.get("points").split()
    return np.array([[float(a) for a in p.split(",")] for p in pts]).reshape(-1, 2)


@pytest.mark.parametrize(
    "t, ys",
    [
        (np.linspace(0, 1, 3), [("a", np.array([0.0, -1.0, np.nan]), BLUE)]),
        (np.linspace(0, 1, 3), []),
        (np.array([0.0]), [("a", np.array([1.0]), BLUE)]),
        (np.linspace(0, 1, 2), [("a", np.array([np.inf, 0.0]), BLUE)]),
    ],
)
def test_curve_without_a_positive_value_or_two_times_is_empty(t, ys):
    assert curve_svg(t, ys) == ""


def test_curve_log_axis_maps_the_extremes_to_the_frame():
    t = np.array([0.0, 1.0, 2.0, 4.0])
    y = np.array([1e-2, 1.0, np.nan, 1e2])  # NaN skipped; 1 is the geometric middle
    root = _parse(curve_svg(t, [("ms", y, GREY)]))
    assert root.get("width") == str(WIDTH) and root.get("height") == str(HEIGHT)
    (poly,) = root.findall("s:polyline", NS)
    assert poly.get("stroke") == GREY
    pts = _points(poly)
    assert pts.shape == (3, 2)
    x_of = lambda tt: LEFT + tt / 4 * (WIDTH - LEFT - RIGHT)  # noqa: E731
    np.testing.assert_allclose(pts[:, 0], [x_of(0), x_of(1), x_of(4)], atol=0.051)
    bottom, top = HEIGHT - BOTTOM, TOP
    np.testing.assert_allclose(pts[:, 1], [bottom, (bottom + top) / 2, top], atol=0.051)
    texts = [e.text for e in root.findall("s:text", NS)]
    assert format(100.0, ".2g") in texts and format(0.01, ".2g") in texts
    assert "t = 0" in texts and "t = 4" in texts and "ms" in texts


def test_curve_keeps_each_curve_and_escapes_its_label():
    t = np.linspace(0.0, 1.0, 5)
    ys = [("a<b", np.full(5, 2.0), BLUE), ("c&d", np.array([1.0, 0, -1, 3, 4]), RED)]
    root = _parse(curve_svg(t, ys))
    polys = root.findall("s:polyline", NS)
    assert [p.get("stroke") for p in polys] == [BLUE, RED]
    assert [len(_points(p)) for p in polys] == [5, 3]  # zero and negative values are skipped
    labels = [e.text for e in root.findall("s:text", NS) if e.get("fill") in (BLUE, RED)]
    assert labels == ["a<b", "c&d"]


def test_curve_of_one_level_spans_a_decade():
    # all values equal: the axis is [v, 10 v] and the curve lies on its bottom edge
    t = np.array([1.0, 2.0, 3.0])
    root = _parse(curve_svg(t, [("flat", np.full(3, 5.0), BLUE)], width=300, height=120))
    pts = _points(root.find("s:polyline", NS))
    np.testing.assert_allclose(pts[:, 1], 120 - BOTTOM, atol=0.051)
    np.testing.assert_allclose(pts[[0, -1], 0], [LEFT, 300 - RIGHT], atol=0.051)
    texts = [e.text for e in root.findall("s:text", NS)]
    assert format(50.0, ".2g") in texts and format(5.0, ".2g") in texts


def test_curve_with_a_single_time_repeated_does_not_divide_by_zero():
    t = np.array([2.0, 2.0])
    root = _parse(curve_svg(t, [("a", np.array([1.0, 10.0]), BLUE)]))
    pts = _points(root.find("s:polyline", NS))
    np.testing.assert_allclose(pts[:, 0], LEFT, atol=0.051)
