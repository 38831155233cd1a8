"""One figure list per report: each entry draws from facts computed beforehand (never
certifying or simulating itself), and one loop saves and embeds them. Adding a figure to
a report is one function in its list."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import style
from .html import Figure, figure_block


@dataclass(frozen=True)
class Drawn:
    """One drawn figure: its file stem and element id (after the section's key), its
    caption and the matplotlib figure."""

    stem: str
    fid: str
    caption: str
    figure: Any


@dataclass(frozen=True)
class FigureSpec:
    """An entry of a report's figure list.

    Parameters
    ----------
    slot : str
        Where the section shows it (``coupling``, ``topology``, ``ms``, ``paths``, ...).
    width : float
        The width in inches (:data:`ntc_design.reports.style.ONE_COLUMN` or ``TWO_COLUMN``).
    draw : callable
        ``draw(facts, gid)`` -> the figures drawn from the facts (none when they do not
        apply); ``gid`` is the interactive page's group id, or None.
    interactive : bool, optional
        Whether it may be embedded as SVG with per-agent toggles.
    """

    slot: str
    width: float
    draw: Callable[[Any, str | None], Iterable[Drawn]]
    interactive: bool = True


def render_figures(
    specs: Sequence[FigureSpec],
    facts: Any,
    figdir: Path,
    key: str,
    base: Path,
    interactive: bool = False,
) -> dict[str, list[Figure]]:
    """Draw, save (PNG, SVG, PDF under ``figdir``) and embed every figure of a list.

    Parameters
    ----------
    specs : sequence of FigureSpec
        The report's figure list, in order.
    facts : object
        The computed facts the entries draw from.
    figdir : pathlib.Path
        Where the files are written (``{key}_{stem}.png`` and so on).
    key : str
        The section's key (file prefix and element ids ``{key}-fig-{fid}``).
    base : pathlib.Path
        The folder links are relative to.
    interactive : bool, optional
        SVG figures with per-agent toggles where an entry allows it.

    Returns
    -------
    dict of str to list of Figure
        The embedded figures per slot (every slot of the list present, possibly empty).
    """
    out: dict[str, list[Figure]] = {s.slot: [] for s in specs}
    gid = key if interactive else None
    for spec in specs:
        for d in spec.draw(facts, gid):
            saved = style.save(d.figure, figdir / f"{key}_{d.stem}")
            out[spec.slot].append(
                figure_block(
                    saved,
                    f"{key}-fig-{d.fid}",
                    d.caption,
                    base,
                    spec.width,
                    interactive and spec.interactive,
                )
            )
    return out


def first(figs: list[Figure]) -> Figure | None:
    """The slot's figure, for a slot that holds at most one.

    Parameters
    ----------
    figs : list of Figure
        A slot of :func:`render_figures`.

    Returns
    -------
    Figure or None
    """
    return figs[0] if figs else None


__all__ = ["Drawn", "FigureSpec", "first", "render_figures"]
