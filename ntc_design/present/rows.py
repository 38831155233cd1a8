"""The presentation model: typed tables that every face renders the same way.

A :class:`Table` is a title, column headers and rows of :class:`Cell` (text, a verdict, a
matrix or several lines). The objects that have something to show build their own tables
(``ProtocolDesign.table()``, ``GainAnalysis.table()``, the theorem verdicts, a certificate's
results), so each label is written once, beside the quantity it names; the terminal
(:meth:`Table.text`, or rich in the CLI), the HTML report and notebooks
(:meth:`Table.html`, ``_repr_html_``) only render them.

Numbers are shown by :func:`fmt`, the one formatter of the package.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

#: How a verdict reads (the colour comes from the face).
VERDICT_TEXT = {True: "yes", False: "no", None: "undetermined"}


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """A count with its noun in the right number: ``1 agent``, ``2 agents``.

    Parameters
    ----------
    n : int
        The count.
    noun : str
        The singular (``agent``, ``mode``).
    plural : str, optional
        The plural (default: the singular with an ``s``).

    Returns
    -------
    str

    Examples
    --------
    >>> counted(1, "agent"), counted(0, "agent"), counted(2, "mode")
    ('1 agent', '0 agents', '2 modes')
    """
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def fmt(x: Any, digits: int = 4) -> str:
    """A number (or a list of numbers, a bool, None) as shown to a user.

    Fixed-point with ``digits`` decimals between 1e-3 and 1e6, else ``digits``
    significant digits in exponent form; ∞ and NaN as words; None as "—".

    Parameters
    ----------
    x : object
        The value.
    digits : int, optional
        Decimals (fixed) or significant digits (exponent form).

    Returns
    -------
    str

    Raises
    ------
    TypeError
        A mapping or a set: it has no one way to be read (build the text, or a
        :class:`Cell`, where it is shown), and its Python form is no text for a user.

    Examples
    --------
    >>> fmt(7.244), fmt(2.5e-7), fmt(None), fmt([1, 2.0]), fmt(float("inf"))
    ('7.2440', '2.5e-07', '—', '[1, 2.0000]', '∞')
    """
    if isinstance(x, (Mapping, set, frozenset)):
        raise TypeError(f"fmt: a {type(x).__name__} is not shown as Python ({x!r:.60})")
    if x is None:
        return "—"
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (float, np.floating)):
        x = float(x)
        if math.isnan(x):
            return "NaN"
        if math.isinf(x):
            return "∞" if x > 0 else "−∞"
        return f"{x:.{digits}f}" if 1e-3 <= abs(x) < 1e6 or x == 0 else f"{x:.{digits}g}"
    if isinstance(x, (list, tuple, np.ndarray)):
        return "[" + ", ".join(fmt(v, digits) for v in x) + "]"
    return str(x)


def set_text(xs: Iterable[Any], most: int | None = None) -> str:
    """Agent labels as a set, ``{1, 2, 5}``; with ``most``, the first ``most`` and how
    many there are in all (``{1, 2, …; 3000 agents}``).

    Parameters
    ----------
    xs : iterable
        The labels.
    most : int, optional
        How many to name.

    Returns
    -------
    str
    """
    items = [str(x) for x in xs]
    if most is not None and len(items) > most:
        return "{" + ", ".join(items[:most]) + f", …; {len(items)} agents}}"
    return "{" + ", ".join(items) + "}"


@dataclass(frozen=True)
class Cell:
    """One cell: text, optionally a verdict (coloured by the face), a matrix or several
    lines, or a link.

    Attributes
    ----------
    text : str
        The text (after the verdict word when there is one).
    verdict : bool or None
        True, False or None (undetermined) when ``judged``.
    judged : bool
        Whether the cell carries a verdict.
    matrix : tuple of tuple of str, optional
        Entries of a matrix, already formatted.
    lines : tuple of str
        Several lines (shown one under the other).
    href : str, optional
        A link target for the text.
    word : str, optional
        The verdict's word when not yes/no/undetermined (e.g. "guaranteed").
    """

    text: str = ""
    verdict: bool | None = None
    judged: bool = False
    matrix: tuple[tuple[str, ...], ...] | None = None
    lines: tuple[str, ...] = ()
    href: str | None = None
    word: str | None = None

    @property
    def verdict_word(self) -> str:
        """The verdict as a word ("" when the cell has none).

        Returns
        -------
        str
        """
        if not self.judged:
            return ""
        if self.word is not None:
            return self.word
        return VERDICT_TEXT[self.verdict]

    def plain(self) -> str:
        """The cell as plain text (one line per line of a multi-line cell).

        Returns
        -------
        str
        """
        if self.matrix is not None:
            if len(self.matrix) == 1:  # a vector
                return "[" + ", ".join(self.matrix[0]) + "]"
            return "[" + ", ".join("[" + ", ".join(r) + "]" for r in self.matrix) + "]"
        parts = [p for p in (self.verdict_word, self.text) if p]
        head = " ".join(parts)
        return "\n".join([head, *self.lines] if head else list(self.lines))

    def html(self) -> str:
        """The cell's content as HTML (escaped).

        Returns
        -------
        str
        """
        if self.matrix is not None:
            body = "".join(
                "<tr>" + "".join(f"<td>{html.escape(v)}</td>" for v in r) + "</tr>"
                for r in self.matrix
            )
            return f'<table class="matrix">{body}</table>'
        out = []
        if self.judged:
            cls = {True: "ok", False: "bad", None: "und"}[self.verdict]
            out.append(f'<span class="{cls}">{html.escape(self.verdict_word)}</span>')
        if self.text:
            t = html.escape(self.text)
            out.append(f'<a href="{html.escape(self.href)}">{t}</a>' if self.href else t)
        text = " ".join(out)
        if self.lines:
            text = "<br>".join(([text] if text else []) + [html.escape(x) for x in self.lines])
        return text


def cell(x: Any) -> Cell:
    """A cell from a value: a :class:`Cell` as it is, anything else through :func:`fmt`.

    Parameters
    ----------
    x : object
        The value.

    Returns
    -------
    Cell

    Raises
    ------
    TypeError
        A mapping or a set (:func:`fmt`): a typed cell is built as a :class:`Cell`
        (:func:`verdict`, a link by ``href``), never from a dict.
    """
    return x if isinstance(x, Cell) else Cell(text=fmt(x))


def verdict(value: bool | None, text: str = "", word: str | None = None) -> Cell:
    """A verdict cell (yes / no / undetermined, or ``word``).

    Parameters
    ----------
    value : bool or None
        The verdict (None: undetermined).
    text : str, optional
        What follows the verdict.
    word : str, optional
        The word for the verdict, when not yes/no/undetermined.

    Returns
    -------
    Cell
    """
    return Cell(text=text, verdict=value, judged=True, word=word)


def matrix(m: Any, digits: int = 4) -> Cell:
    """A matrix cell, entries to ``digits`` significant digits (−0 shown as 0).

    Parameters
    ----------
    m : array_like
        A vector or a matrix.
    digits : int, optional
        Significant digits.

    Returns
    -------
    Cell
    """
    a = np.atleast_2d(np.asarray(m, dtype=float))
    return Cell(matrix=tuple(tuple(f"{v + 0.0:.{digits}g}" for v in row) for row in a))


def lines(items: Sequence[str]) -> Cell:
    """A cell of several lines.

    Parameters
    ----------
    items : sequence of str
        The lines.

    Returns
    -------
    Cell
    """
    return Cell(lines=tuple(items))


@dataclass(frozen=True)
class Table:
    """A titled table of cells with its notes, rendered alike by every face.

    Attributes
    ----------
    title : str
        What the table shows.
    columns : tuple of str
        Column headers.
    rows : tuple of tuple of Cell
        The rows, each as long as ``columns``.
    notes : tuple of str
        Lines shown under the table.
    layout : str
        ``"grid"`` (a table on every face) or ``"list"`` (the terminal prints each row as
        ``label: value`` with the last cell's lines indented under it; for verdicts).
    """

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Cell, ...], ...]
    notes: tuple[str, ...] = ()
    layout: str = "grid"

    @classmethod
    def build(
        cls,
        title: str,
        columns: Sequence[str],
        rows: Iterable[Sequence[Any]],
        notes: Iterable[str] = (),
        layout: str = "grid",
    ) -> Table:
        """A table from rows of values or cells (values go through :func:`fmt`).

        Parameters
        ----------
        title : str
            What the table shows.
        columns : sequence of str
            Column headers.
        rows : iterable of sequences
            The rows.
        notes : iterable of str, optional
            Lines under the table.
        layout : str, optional
            ``"grid"`` or ``"list"`` (see the class).

        Returns
        -------
        Table

        Raises
        ------
        ValueError
            A row whose length differs from the columns', or an unknown layout.
        TypeError
            A value that is a mapping or a set (:func:`cell`).
        """
        built = tuple(tuple(cell(x) for x in r) for r in rows)
        for r in built:
            if len(r) != len(columns):
                raise ValueError(f"row of {len(r)} cells for {len(columns)} columns")
        if layout not in ("grid", "list"):
            raise ValueError(f"layout: {layout!r} is not grid or list")
        return cls(title, tuple(columns), built, tuple(notes), layout)

    @property
    def labels(self) -> tuple[str, ...]:
        """The first cell of every row as text (the row labels).

        Returns
        -------
        tuple of str
        """
        return tuple(r[0].plain() for r in self.rows)

    def list_lines(self) -> list[str]:
        """The rows as ``label: value`` lines, a row's last cell's further lines indented
        under it (the terminal's list layout).

        Returns
        -------
        list of str
        """
        out = []
        for r in self.rows:
            head = [c.plain().split("\n")[0] for c in r[:-1]] if len(r) > 2 else [r[0].plain()]
            last = r[-1].plain().split("\n") if len(r) > 1 else []
            if len(r) > 2:
                out.append(f"{head[0]}: {' '.join(h for h in head[1:] if h)}")
                out += [f"  {x}" for x in last if x]
            else:
                out.append(f"{head[0]}: {last[0] if last else ''}".rstrip())
                out += [f"  {x}" for x in last[1:]]
        return out

    def text(self) -> str:
        """The table as plain text: the title, aligned columns (or ``label: value`` lines
        in the list layout), the notes.

        Returns
        -------
        str
        """
        if self.layout == "list":
            return "\n".join(
                ([self.title] if self.title else [])
                + self.list_lines()
                + [f"note: {x}" for x in self.notes]
            )
        grid = [list(self.columns)] + [
            [c.plain().replace("\n", "; ") for c in r] for r in self.rows
        ]
        widths = [max(len(r[k]) for r in grid) for k in range(len(self.columns))]
        out = [self.title] if self.title else []
        for n, r in enumerate(grid):
            out.append("  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip())
            if n == 0:
                out.append("  ".join("-" * w for w in widths))
        out += [f"note: {x}" for x in self.notes]
        return "\n".join(out)

    def __str__(self) -> str:
        return self.text()

    def html(self, table_id: str | None = None) -> str:
        """The table as HTML (escaped; the report's classes ok, bad, und, matrix).

        Parameters
        ----------
        table_id : str, optional
            An ``id`` for the table element.

        Returns
        -------
        str
        """
        ident = f' id="{html.escape(table_id)}"' if table_id else ""
        head = "".join(f"<th>{html.escape(c)}</th>" for c in self.columns)
        body = "".join(
            "<tr>" + "".join(f"<td>{c.html()}</td>" for c in r) + "</tr>" for r in self.rows
        )
        cap = f"<caption>{html.escape(self.title)}</caption>" if self.title else ""
        notes = "".join(f'<p class="note">note: {html.escape(x)}</p>' for x in self.notes)
        return (
            f"<table{ident}>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>{notes}"
        )

    def _repr_html_(self) -> str:
        return self.html()


__all__ = [
    "Cell",
    "Table",
    "VERDICT_TEXT",
    "cell",
    "counted",
    "fmt",
    "lines",
    "matrix",
    "set_text",
    "verdict",
]
