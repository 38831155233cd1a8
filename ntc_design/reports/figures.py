"""Figures in the paper's conventions (matplotlib, Agg backend; PNG and SVG).

* Topology Ĝ: agents on a circle, the external signal x0 as vertex 0 in the middle with
  its edges to the informed agents; positive edges blue, negative red; definite solid,
  semidefinite dashed; arrows give the direction j -> i (i listens to j).
* States of all agents over time, one panel per dimension, θ marked (almost-sure figures).
* E‖x_i − θ‖² per agent on a log scale: Monte Carlo mean with its 95% band, exact curve.
* For a switching run the active mode is shaded along the time axis.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, FancyArrowPatch, Patch  # noqa: E402

from ..linalg import Definiteness, classify  # noqa: E402
from ..model import Topology  # noqa: E402

BLUE, RED = "#1f5fbf", "#c8322d"
MODE_COLOURS = ["#8ecae6", "#ffb703", "#90be6d", "#f4a3c4", "#bdb2ff", "#cdb4db"]


def _style(cls: Definiteness) -> tuple[str, str]:
    colour = BLUE if cls.sign > 0 else RED
    return colour, ("-" if cls.definite else "--")


def _arrow(ax, a, b, colour: str, ls: str, **kw) -> None:
    ax.add_patch(
        FancyArrowPatch(a, b, arrowstyle="-|>", color=colour, linestyle=ls, shrinkB=18, **kw)
    )


def topology_figure(top: Topology, informed: Sequence[int], b: dict, title: str):
    """Ĝ: the topology with the external signal (vertex 0) and its couplings B_i."""
    n = top.n
    ang = np.pi / 2 - 2 * np.pi * np.arange(n) / n
    pos = {i: np.array([np.cos(a), np.sin(a)]) for i, a in enumerate(ang)}
    pos[-1] = np.array([0.0, 0.0])
    fig, ax = plt.subplots(figsize=(5.2, 5.2))
    r = 0.11
    pairs = set(top.edges)
    for (i, j), cls in top.classes.items():
        if cls.sign == 0:
            continue
        colour, ls = _style(cls)
        rad = 0.18 if (j, i) in pairs else 0.0
        _arrow(
            ax,
            pos[j],
            pos[i],
            colour,
            ls,
            mutation_scale=14,
            linewidth=1.6,
            shrinkA=18,
            connectionstyle=f"arc3,rad={rad}",
        )
    for i in informed:
        colour, ls = _style(classify(np.asarray(b[i])))
        _arrow(
            ax, pos[-1], pos[i], colour, ls, mutation_scale=12, linewidth=1.2, alpha=0.8, shrinkA=16
        )
    for i in range(n):
        ax.add_patch(
            Circle(pos[i], r, facecolor="white", edgecolor="black", linewidth=1.2, zorder=3)
        )
        ax.text(*pos[i], str(top.labels[i]), ha="center", va="center", fontsize=11, zorder=4)
    ax.add_patch(
        Circle(
            pos[-1],
            r,
            facecolor="#eeeeee",
            edgecolor="black",
            linewidth=1.2,
            zorder=3,
            linestyle=":",
        )
    )
    ax.text(0, 0, "0", ha="center", va="center", fontsize=11, zorder=4)
    ax.set_xlim(-1.3, 1.3)
    ax.set_ylim(-1.3, 1.3)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title, fontsize=11)
    ax.legend(
        handles=[
            Line2D([], [], color=BLUE, label="positive definite"),
            Line2D([], [], color=BLUE, ls="--", label="positive semidefinite"),
            Line2D([], [], color=RED, label="negative definite"),
            Line2D([], [], color=RED, ls="--", label="negative semidefinite"),
        ],
        loc="lower center",
        bbox_to_anchor=(0.5, -0.12),
        ncol=2,
        fontsize=8,
        frameon=False,
    )
    fig.tight_layout()
    return fig


def shade_modes(ax, segments: Sequence[tuple[float, float, str]] | None) -> list:
    """Shade the active mode along the time axis (a strip at the bottom of the axes);
    returns legend handles for the modes."""
    if not segments:
        return []
    names = sorted({m for _, _, m in segments})
    col = {m: MODE_COLOURS[k % len(MODE_COLOURS)] for k, m in enumerate(names)}
    for a, b, m in segments:
        ax.axvspan(a, b, ymin=0.0, ymax=0.035, color=col[m], linewidth=0)
    return [Patch(color=col[m], label=f"active mode {m}") for m in names]


def states_figure(t, path: np.ndarray, theta: np.ndarray, labels, title: str, segments=None):
    """One sample path: x_i^(k)(t) for every agent i, one panel per dimension k, θ dashed."""
    d = theta.size
    n = len(labels)
    x = path.reshape(t.size, n, d)
    fig, axes = plt.subplots(d, 1, figsize=(7.5, 2.2 * d + 1.2), sharex=True)
    axes = np.atleast_1d(axes)
    cmap = plt.get_cmap("tab10")
    handles = []
    for k, ax in enumerate(axes):
        for i in range(n):
            ax.plot(t, x[:, i, k], lw=0.9, color=cmap(i % 10), label=f"agent {labels[i]}")
        ax.axhline(theta[k], color="black", ls="--", lw=1.0)
        ax.set_ylabel(f"$x_i^{{({k + 1})}}$  (θ = {theta[k]:g})")
        handles = shade_modes(ax, segments)
    axes[-1].set_xlabel("t")
    agents = [Line2D([], [], color=cmap(i % 10), label=f"agent {labels[i]}") for i in range(n)]
    agents.append(Line2D([], [], color="black", ls="--", label="θ"))
    fig.suptitle(title, fontsize=11)
    fig.legend(
        handles=agents,
        loc="upper center",
        ncol=min(len(agents), 8),
        fontsize=7,
        frameon=False,
        bbox_to_anchor=(0.5, 0.955),
    )
    if handles:
        fig.legend(
            handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False
        )
    fig.tight_layout(rect=(0, 0.03 if handles else 0, 1, 0.93))
    return fig


def ms_error_figure(
    t, mc: dict | None, exact: np.ndarray | None, labels, title: str, segments=None
):
    """E‖x_i − θ‖² per agent, log scale: MC mean with its 95% band, exact curve dashed."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    cmap = plt.get_cmap("tab10")
    pos_floor = 1e-12
    for i, a in enumerate(labels):
        colour = cmap(i % 10)
        if mc is not None:
            ax.plot(
                t, np.maximum(mc["mean"][:, i], pos_floor), color=colour, lw=1.0, label=f"agent {a}"
            )
            ax.fill_between(
                t,
                np.maximum(mc["lo"][:, i], pos_floor),
                np.maximum(mc["hi"][:, i], pos_floor),
                color=colour,
                alpha=0.2,
                lw=0,
            )
        if exact is not None:
            ax.plot(
                t,
                np.maximum(exact[:, i], pos_floor),
                color=colour,
                lw=1.2,
                ls="--",
                label=None if mc is not None else f"agent {a}",
            )
    ax.set_yscale("log")
    ax.set_xlabel("t")
    ax.set_ylabel(r"$E\|x_i - \theta\|^2$")
    ax.set_title(
        title
        + (
            "  (solid: Monte Carlo with 95% band, dashed: exact)"
            if mc is not None and exact is not None
            else ""
        ),
        fontsize=10,
    )
    ax.legend(fontsize=7, ncol=4, frameon=False, loc="upper right")
    handles = shade_modes(ax, segments)
    if handles:
        fig.legend(
            handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False
        )
    fig.tight_layout(rect=(0, 0.04 if handles else 0, 1, 1))
    return fig


def save(fig, stem: Path) -> tuple[Path, Path, bytes]:
    """Write stem.png and stem.svg; return both paths and the PNG bytes (for inlining)."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    png = buf.getvalue()
    stem.with_suffix(".png").write_bytes(png)
    fig.savefig(stem.with_suffix(".svg"), format="svg")
    plt.close(fig)
    return stem.with_suffix(".png"), stem.with_suffix(".svg"), png
