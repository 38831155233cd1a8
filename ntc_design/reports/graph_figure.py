"""The topology Ĝ drawn: agents on a circle, the external signal x0 (vertex 0) outside it
next to the informed agents, its edges curved around the agents; positive edges blue,
negative red, definite solid, semidefinite dashed; arrows j -> i (i listens to j)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrowPatch

from ..model import Topology
from ..numerics.linalg import Definiteness, classify
from .style import BLUE, GREEN, ONE_COLUMN, RED, paper_style


def _style(cls: Definiteness) -> tuple[str, str]:
    colour = BLUE if cls.sign > 0 else RED
    return colour, ("-" if cls.definite else "--")


def weight_label(a: np.ndarray) -> str:
    """A short text for a weight: ``2``, ``−0.5I``, ``diag(1, 1, 0)`` or its entries.

    Parameters
    ----------
    a : numpy.ndarray
        The d×d weight.

    Returns
    -------
    str
    """
    a = np.asarray(a, dtype=float)

    def num(x: float) -> str:
        return f"{x:.3g}".replace("-", "−")

    if a.shape == (1, 1):
        return num(a[0, 0])
    if np.array_equal(a, np.diag(np.diag(a))):
        dg = np.diag(a)
        if np.all(dg == dg[0]):
            return f"{num(dg[0])}I"
        return "diag(" + ", ".join(num(x) for x in dg) + ")"
    return "[" + "; ".join(" ".join(num(x) for x in row) for row in a) + "]"


def topology_figure(
    top: Topology,
    informed: Sequence[int],
    b: Mapping[int, np.ndarray],
    title: str | None = None,
    weights: bool = False,
    width: float = ONE_COLUMN,
):
    """Ĝ: the topology with the external signal x0 (vertex 0) and its couplings B_i.

    Parameters
    ----------
    top
        The topology.
    informed
        Indices of the informed agents (they receive x0).
    b
        ``{index: B_i}``.
    title
        An optional short title (captions are preferred).
    weights
        Label every edge with its weight (:func:`weight_label`).
    width
        Figure width in inches.

    Returns
    -------
    matplotlib.figure.Figure
    """
    pos, ang, phi = _layout(top.n, informed)
    with paper_style():
        fig, ax = plt.subplots(figsize=(width, width * 0.95), layout="constrained")
        _agent_edges(ax, top, pos, weights)
        extent = [pos[k] for k in pos] + _signal_edges(ax, pos, ang, phi, informed, b, weights)
        _vertices(ax, top, pos)
        xy = np.array(extent)
        ax.set_xlim(xy[:, 0].min() - 0.3, xy[:, 0].max() + 0.3)
        ax.set_ylim(xy[:, 1].min() - 0.3, xy[:, 1].max() + 0.3)
        ax.set_aspect("equal")
        ax.axis("off")
        if title:
            ax.set_title(title)
        fig.legend(
            handles=_legend_handles(),
            loc="outside lower center",
            ncol=2,
            frameon=False,
            fontsize=8,
            handlelength=1.8,
            columnspacing=1.0,
        )
    return fig


R_VERTEX = 0.13  # radius of an agent's circle (the unit circle holds the agents)


def _layout(n: int, informed: Sequence[int]) -> tuple[dict, np.ndarray, float]:
    """Agents on the unit circle (the first at the top, clockwise) and x0 (key −1) outside
    it, in the direction of the informed agents' mean position."""
    ang = np.pi / 2 - 2 * np.pi * np.arange(n) / n
    pos = {i: np.array([np.cos(a), np.sin(a)]) for i, a in enumerate(ang)}
    if informed:
        v = np.sum([pos[i] for i in informed], axis=0)
        phi = math.atan2(v[1], v[0]) if np.linalg.norm(v) > 1e-9 else float(ang[informed[0]])
    else:
        phi = -np.pi / 2
    pos[-1] = 1.62 * np.array([math.cos(phi), math.sin(phi)])
    return pos, ang, phi


def _arrow(ax, a: np.ndarray, b: np.ndarray, colour: str, ls: str, rad: float) -> None:
    ax.add_patch(
        FancyArrowPatch(
            (float(a[0]), float(a[1])),
            (float(b[0]), float(b[1])),
            arrowstyle="-|>",
            color=colour,
            linestyle=ls,
            mutation_scale=10,
            linewidth=1.1,
            shrinkA=12,
            shrinkB=12,
            connectionstyle=f"arc3,rad={rad}",
            zorder=2,
        )
    )


def _label(ax, at: np.ndarray, text: str, colour: str, size: float) -> None:
    ax.text(
        float(at[0]),
        float(at[1]),
        text,
        fontsize=size,
        ha="center",
        va="center",
        color=colour,
        zorder=5,
        bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.85},
    )


def _agent_edges(ax, top: Topology, pos: dict, weights: bool) -> None:
    """The edges j -> i between agents; an edge with a reverse partner is bent."""
    pairs = set(top.edges)
    for (i, j), cls in top.classes.items():
        if cls.sign == 0:
            continue
        colour, ls = _style(cls)
        rad = 0.18 if (j, i) in pairs else 0.0
        _arrow(ax, pos[j], pos[i], colour, ls, rad)
        if weights:  # at 30% from the target end, on the (curved) edge
            nrm = np.array([-(pos[i] - pos[j])[1], (pos[i] - pos[j])[0]])
            mid = 0.7 * pos[i] + 0.3 * pos[j] - 0.42 * rad * nrm
            _label(ax, mid, weight_label(top.weights[(i, j)]), colour, 5.5)


def _signal_edges(ax, pos, ang, phi, informed, b, weights: bool) -> list[np.ndarray]:
    """x0's edges to the informed agents, bent away from the centre so that they run
    around the agents' circle; the arcs' apexes (for the axis limits)."""
    p0 = pos[-1]
    apexes = []
    for i in informed:
        cls = classify(np.asarray(b[i]))
        chord = pos[i] - p0
        mid = 0.5 * (pos[i] + p0)
        nrm = np.array([-chord[1], chord[0]])
        side = 1.0 if np.dot(nrm, mid) > 0 else -1.0
        sep = abs(math.remainder(float(ang[i]) - phi, 2 * math.pi))
        rad = _clear_rad(pos, p0, i, -side * min(0.15 + 0.85 * sep / math.pi, 1.0))
        apexes.append(mid + rad * np.array([chord[1], -chord[0]]) / 2)  # arc3's apex
        _arrow(ax, p0, pos[i], GREEN, "-" if cls.definite else "--", rad)
        if weights:
            off = 0.25 * side * nrm / max(float(np.linalg.norm(nrm)), 1e-9)
            _label(ax, 0.5 * (pos[i] + p0) + off, f"B={weight_label(b[i])}", GREEN, 6)
    return apexes


def _arc(p0: np.ndarray, p1: np.ndarray, rad: float, k: int = 40) -> np.ndarray:
    """Points of matplotlib's arc3 connection from p0 to p1 (a quadratic Bézier whose
    control point is rad·|p1 − p0| off the chord's midpoint)."""
    chord = p1 - p0
    ctrl = 0.5 * (p0 + p1) + rad * np.array([chord[1], -chord[0]])
    s = np.linspace(0.0, 1.0, k)[:, None]
    return (1 - s) ** 2 * p0 + 2 * (1 - s) * s * ctrl + s**2 * p1


def _clear_rad(pos: dict, p0: np.ndarray, i: int, rad: float) -> float:
    """The bend closest to ``rad`` (same side first) whose arc from x0 to agent i passes
    no other agent's circle: an edge must never look as if it entered a wrong agent."""
    others = np.array([p for k, p in pos.items() if k not in (i, -1)])
    if others.size == 0:
        return rad
    sign = 1.0 if rad >= 0 else -1.0
    for cand in [
        rad,
        *[sign * (abs(rad) + 0.1 * k) for k in range(1, 10)],
        *[-sign * 0.15 * k for k in range(1, 8)],
    ]:
        pts = _arc(p0, pos[i], cand)[2:-2]
        if np.min(np.linalg.norm(pts[:, None, :] - others[None, :, :], axis=2)) > 1.6 * R_VERTEX:
            return cand
    return rad


def _vertices(ax, top: Topology, pos: dict) -> None:
    for i in range(top.n):
        xy = (float(pos[i][0]), float(pos[i][1]))
        ax.add_patch(
            Circle(xy, R_VERTEX, facecolor="white", edgecolor="black", linewidth=1.0, zorder=3)
        )
        ax.text(xy[0], xy[1], str(top.labels[i]), ha="center", va="center", fontsize=9, zorder=4)
    p0 = (float(pos[-1][0]), float(pos[-1][1]))
    ax.add_patch(
        Circle(p0, R_VERTEX, facecolor="#e3f1e8", edgecolor=GREEN, linewidth=1.2, zorder=3)
    )
    ax.text(p0[0], p0[1], "0", ha="center", va="center", fontsize=9, zorder=4, color=GREEN)


def _legend_handles() -> list[Line2D]:
    return [
        Line2D([], [], color=BLUE, label="positive definite"),
        Line2D([], [], color=RED, label="negative definite"),
        Line2D([], [], color=BLUE, ls="--", label="positive semidef."),
        Line2D([], [], color=RED, ls="--", label="negative semidef."),
        Line2D(
            [],
            [],
            color=GREEN,
            marker="o",
            markerfacecolor="#e3f1e8",
            label=r"$x_0$ (vertex 0) $\to$ informed, $B_i \succ 0$",
        ),
        Line2D([], [], color=GREEN, ls="--", label=r"$x_0 \to$ informed, $B_i$ semidefinite"),
    ]


__all__ = ["topology_figure", "weight_label"]
