"""The HTML face of the reports: the Jinja2 environment (autoescaped templates in
``templates/``), the cell, figure and section records the templates read, and the
conversion of the presentation tables (:mod:`ntc_design.present.rows`) into them."""

from __future__ import annotations

import base64
import os
from dataclasses import dataclass, field
from pathlib import Path

from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape
from markupsafe import Markup, escape

from ..io.outputs import write_atomic
from ..present.rows import Table as RowsTable
from . import style

# ------------------------------------------------------------------------- rendering


@dataclass(frozen=True)
class Table:
    """A table for the templates: header texts and rows of cells; a cell is text (escaped by
    the template) or the Markup of :meth:`ntc_design.present.rows.Cell.html` (:func:`html_table`)."""

    headers: tuple[str, ...]
    rows: list
    id: str | None = None

    def __post_init__(self) -> None:
        # a cell is text or Markup, never a value the template would print as Python
        # (a dict, a bool, None): build such a cell as a ntc_design.present.rows.Cell
        for r in self.rows:
            for c in r:
                if not isinstance(c, str):
                    raise TypeError(
                        f"report table cell {c!r:.60}: expected text or Markup (a rows.Cell's "
                        f"html), not a {type(c).__name__}"
                    )


@dataclass(frozen=True)
class Figure:
    id: str
    caption: str
    alt: str
    png_b64: str
    width_px: int
    links: tuple[tuple[str, str], ...]
    svg: Markup | None = None


@dataclass(frozen=True)
class RunSection:
    key: str
    title: str
    rerun: str
    designs: list
    coupling: Figure | None  # None in the aggregate report (dense δ scans do not scale)
    certificate: Table
    checks: Table
    gain: Table
    gain_figure: Figure | None
    theorems: Table
    ms_figure: Figure
    convergence_note: str
    convergence: Table
    topology_figures: list
    path_figures: list
    final: Table
    spread: str
    data_links: list
    parameters: Table
    versions: Table
    interactive_agents: list
    robust: Table | None = None  # weight realisations against the proven brackets
    robust_figure: Figure | None = None
    robust_note: str = ""
    digital: Table | None = None  # the sampled protocol (a digital run)
    digital_figures: list = field(default_factory=list)
    digital_note: str = ""
    loss: Table | None = None  # lossy links (a digital run that loses messages)
    loss_figures: list = field(default_factory=list)
    loss_text: str = ""

    def toc(self) -> dict:
        sub = [
            ("design", "Protocol design"),
            ("coupling", "Coupling δ"),
            ("certificate", "Certificate"),
            ("gain", "Gain"),
            ("theorems", "Theorems"),
            ("convergence", "Convergence"),
            ("figures", "Topology and sample paths"),
            ("final", "Final errors"),
            ("robust", "Weights within ρ"),
            ("digital", "Digital protocol"),
            ("loss", "Lossy links"),
            ("data", "Data files"),
            ("parameters", "Parameters"),
        ]
        if self.coupling is None:
            sub = [x for x in sub if x[0] != "coupling"]
        if self.robust is None:
            sub = [x for x in sub if x[0] != "robust"]
        if self.digital is None:
            sub = [x for x in sub if x[0] != "digital"]
        if self.loss is None:
            sub = [x for x in sub if x[0] != "loss"]
        return {
            "id": self.key,
            "title": self.title,
            "children": [{"id": f"{self.key}-{k}", "title": t} for k, t in sub],
        }


ENV = Environment(
    loader=PackageLoader("ntc_design.reports", "templates"),
    autoescape=select_autoescape(["html"]),
    undefined=StrictUndefined,
    trim_blocks=True,
    lstrip_blocks=True,
)


def render(template: str, **context) -> str:
    """Render one of the package's Jinja2 templates (autoescaped)."""
    return ENV.get_template(template).render(**context)


def write_html(path: Path, text: str) -> None:
    """Write atomically (:func:`ntc_design.io.outputs.write_atomic`: no temporary file is left
    when the write fails)."""
    write_atomic(path, text, option="report")


def rel(path: Path, base: Path) -> str:
    """A link from a report in ``base`` to ``path`` (relative, forward slashes)."""
    return Path(os.path.relpath(path, base)).as_posix()


def figure_block(
    saved: style.SavedFigure,
    fid: str,
    caption: str,
    base: Path,
    width_in: float,
    interactive: bool = False,
) -> Figure:
    links = tuple((f.upper(), rel(p, base)) for f, p in saved.files.items())
    svg = None
    if interactive and "svg" in saved.files:
        text = saved.files["svg"].read_text(encoding="utf-8")
        svg = Markup(text[text.index("<svg") :])  # our own matplotlib output
    return Figure(
        fid,
        caption,
        caption,
        base64.b64encode(saved.png).decode(),
        int(round(width_in * 110)),
        links,
        svg,
    )


def html_table(t: RowsTable, table_id: str | None = None) -> Table:
    """A presentation table (:mod:`ntc_design.present.rows`) for the templates: the same labels
    and cells as the terminal, each cell rendered once by :meth:`ntc_design.present.rows.Cell.html`.

    Parameters
    ----------
    t : ntc_design.present.rows.Table
        The table.
    table_id : str, optional
        An ``id`` for the table element.

    Returns
    -------
    Table
    """
    rows: list[tuple] = [tuple(Markup(c.html()) for c in r) for r in t.rows]
    rows += [
        (Markup(f'<span class="note">note: {escape(n)}</span>'), *[""] * (len(t.columns) - 1))
        for n in t.notes
    ]
    return Table(t.columns, rows, table_id)


__all__ = ["html_table"]
