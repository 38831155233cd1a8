"""The one figure style of the toolkit: journal sizes (``ONE_COLUMN`` 3.5 in,
``TWO_COLUMN`` 7.16 in), fonts of 8-9 pt, no titles (captions say what a figure shows),
agents told apart by colour, line style and marker, and every figure written as a 300-dpi
PNG beside vector SVG and PDF (:func:`save`). Every module that draws uses it."""

from __future__ import annotations

import io
from collections.abc import Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

# no matplotlib.use() here: a notebook keeps its inline backend (the CLI sets MPLBACKEND)
import matplotlib.pyplot as plt

ONE_COLUMN = 3.5  # inches (IEEE/Elsevier single column)
TWO_COLUMN = 7.16  # inches (full text width)
DPI = 300
FORMATS = ("png", "svg", "pdf")
BLUE, RED, GREEN = "#1f5fbf", "#c8322d", "#2a7d4f"
GREY = "0.45"
MODE_COLOURS = ["#8ecae6", "#ffb703", "#90be6d", "#f4a3c4", "#bdb2ff", "#cdb4db"]
LINESTYLES = ("-", "--", "-.", ":")
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "<", ">")
RC: dict[str, Any] = {
    "font.size": 8,
    "axes.labelsize": 9,
    "axes.titlesize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "lines.linewidth": 1.0,
    "svg.fonttype": "none",  # text stays text in the SVG
    "pdf.fonttype": 42,  # TrueType in the PDF (editable, journal-friendly)
    "axes.spines.top": False,
    "axes.spines.right": False,
}


@contextmanager
def paper_style():
    """The rc settings of every figure of the toolkit, for the duration of a ``with``.

    Yields
    ------
    None
    """
    with plt.rc_context(cast(Any, RC)):  # matplotlib types its keys as literals
        yield


@dataclass(frozen=True)
class AgentStyle:
    """How one agent's lines look: colour, line style and marker."""

    colour: str
    linestyle: str
    marker: str


#: Okabe & Ito's palette for colour-blind readers (yellow left out: too light on white).
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#000000")


def agent_style(k: int) -> AgentStyle:
    """Agent k's colour (a colour-blind-safe palette), line style and marker: no two of
    the first 28 agents share all three, and neighbours differ in each.

    Parameters
    ----------
    k : int
        The agent's position (0-based).

    Returns
    -------
    AgentStyle
    """
    p = len(PALETTE)
    return AgentStyle(PALETTE[k % p], LINESTYLES[k % 4], MARKERS[(k + k // p) % len(MARKERS)])


def markevery(k: int, n_points: int, count: int = 8):
    """Markers spread over the curve, shifted per agent so that they do not pile up.

    Parameters
    ----------
    k : int
        The agent's position.
    n_points : int
        Points of the curve.
    count : int, optional
        Markers per curve.

    Returns
    -------
    tuple of int
        matplotlib's ``markevery`` (start, step).
    """
    step = max(n_points // count, 1)
    return (int((k * step) // 7) % step, step)


# ---------------------------------------------------------------------------- topology


@dataclass(frozen=True)
class SavedFigure:
    """A figure written to disk: its stem, the file per format, and the PNG bytes."""

    stem: Path
    files: dict[str, Path]  # format -> path
    png: bytes


def save(fig, stem: Path, formats: Sequence[str] = FORMATS, dpi: int = DPI) -> SavedFigure:
    """Write ``stem.png`` (``dpi``), ``stem.svg`` and ``stem.pdf``; return the paths and
    the PNG bytes (for inlining).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    stem : pathlib.Path
        The path without suffix.
    formats : sequence of str, optional
        The formats to write.
    dpi : int, optional
        The PNG resolution.

    Returns
    -------
    SavedFigure
    """
    stem.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    png = buf.getvalue()
    # the layout is settled: the vector formats reuse it rather than solving it again
    fig.set_layout_engine("none")
    files = {}
    for f in formats:
        p = stem.with_suffix(f".{f}")
        if f == "png":
            p.write_bytes(png)
        else:
            # a fixed hash salt: SVG clip-path ids (random by default) repeat run to run
            with plt.rc_context({"svg.hashsalt": "ntc-design"}):
                fig.savefig(
                    p,
                    format=f,
                    metadata={"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(f),
                )
        files[f] = p
    plt.close(fig)
    return SavedFigure(stem, files, png)


__all__ = [
    "AgentStyle",
    "DPI",
    "FORMATS",
    "ONE_COLUMN",
    "SavedFigure",
    "TWO_COLUMN",
    "agent_style",
    "markevery",
    "paper_style",
    "save",
]
