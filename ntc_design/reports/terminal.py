"""The terminal face: the console the CLI prints to, presentation tables
(:mod:`ntc_design.present.rows`) rendered with rich, and progress on stderr (a bar on a terminal,
plain lines in a batch job)."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ..errors import format_seconds, one_line
from ..present.rows import Cell
from ..present.rows import Table as RowsTable

PLAIN_EVERY = 10.0  # seconds between progress lines when stderr is not a terminal

_CONTROL = {c: c.encode("unicode_escape").decode("ascii") for c in map(chr, range(32)) if c != "\n"}
_CONTROL.update({"\x7f": "\\x7f"})
_CONTROL_TABLE = str.maketrans(_CONTROL)


def safe(text: Any) -> str:
    """``text`` for the terminal: every control character but the newline escaped (an ESC
    sequence in a label is shown, never obeyed). Values that come from files (labels,
    names) go through :func:`ntc_design.errors.one_line` as well, which escapes the
    newline too, so that no label can print a line of its own.

    Parameters
    ----------
    text : Any
        Converted with ``str``.

    Returns
    -------
    str
    """
    t = str(text).translate(_CONTROL_TABLE)
    if t.isascii():
        return t
    # C1 controls (U+009B is a CSI), bidi overrides and the like: escaped like one_line
    return "".join(
        ch if ch.isprintable() or ch in "\n " else ch.encode("unicode_escape").decode("ascii")
        for ch in t
    )


class SafeConsole(Console):
    """A rich console that escapes control characters in every string it is given (its
    own colour codes, added when rendering, are untouched)."""

    def print(self, *objects: Any, **kwargs: Any) -> None:  # noqa: D102 - rich's print
        super().print(*(safe(o) if isinstance(o, str) else o for o in objects), **kwargs)


# Off a terminal (pipes, CI logs) rich would wrap at 80 columns and split result lines:
# print each line whole, and let tables use up to 120 columns.
out = SafeConsole(
    highlight=False, soft_wrap=not sys.stdout.isatty(), width=None if sys.stdout.isatty() else 120
)


def _v(x: Any) -> str:
    """A value from a file (a label, a name) for a rich string: one line, markup escaped."""
    return escape(one_line(str(x)))


_VERDICT_STYLE = {True: "green", False: "red", None: "yellow"}


def _rich_cell(c: Cell) -> str:
    """A cell for rich: the verdict word coloured, markup in the text escaped."""
    text = escape(one_line(c.plain().replace("\n", "; ")))
    if c.judged:
        word = escape(c.verdict_word)
        return text.replace(word, f"[{_VERDICT_STYLE[c.verdict]}]{word}[/]", 1)
    return text


def print_table(t: RowsTable) -> None:
    """One presentation table on the terminal: a grid, or ``label: value`` lines for a
    list-layout table (the theorem verdicts), then its notes.

    Parameters
    ----------
    t : ntc_design.present.rows.Table
        The table.
    """
    if t.layout == "list":
        if t.title:
            out.print(f"[bold]{_v(t.title)}[/bold]")
        for line in t.list_lines():
            out.print(escape(safe(line)))
    else:
        g = Table(title=escape(one_line(t.title)) if t.title else t.title)
        for c in t.columns:
            g.add_column(c)
        for r in t.rows:
            g.add_row(*[_rich_cell(c) for c in r])
        out.print(g)
    for n in t.notes:
        out.print(f"  note: {escape(safe(n))}")


class Progress:
    """Progress on stderr: a rich bar on a terminal; otherwise (a batch job, a pipe) a plain
    line every ``every`` seconds from a heartbeat thread, so that a long run is never
    silent, and one line when a later stage starts."""

    def __init__(self, what: str, every: float = 5.0, tty: bool | None = None):
        self.what, self.every = what, every
        self.tty = sys.stderr.isatty() if tty is None else tty
        self.t0 = time.monotonic()
        self.state = "starting"
        self.tasks: dict[str, int] = {}
        self._stop = threading.Event()
        self._bar: Any = None  # a rich progress bar on a terminal
        self._thread: threading.Thread | None = None
        self._printed = 0.0  # when the last plain line was printed

    def __enter__(self) -> Progress:
        if self.tty:
            from rich.progress import BarColumn, TextColumn, TimeRemainingColumn
            from rich.progress import Progress as Bar

            self._bar = Bar(
                TextColumn("{task.description}", markup=False),  # text, never markup
                BarColumn(),
                TextColumn("{task.percentage:>3.0f}%"),
                TimeRemainingColumn(),
                console=Console(stderr=True),
            )
            self._bar.__enter__()
        else:
            self._thread = threading.Thread(target=self._beat, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._bar is not None:
            self._bar.__exit__(*exc)

    def _line(self, text: str) -> None:
        self._printed = time.monotonic()
        print(
            f"{self.what}: [{time.monotonic() - self.t0:.0f} s] {text}", file=sys.stderr, flush=True
        )

    def _beat(self) -> None:
        while not self._stop.wait(self.every):
            if time.monotonic() - self._printed >= 0.5 * self.every:
                self._line(self.state)

    def stage(self, text: str, transient: bool = False) -> None:
        """A new stage (e.g. 'g1: figures and report'); off a terminal it is printed at
        once only after the first ``every`` seconds, so that a quick run, or bad input
        refused at the start, prints nothing but its result or its one error line.

        Parameters
        ----------
        text : str
            What the run is doing now.
        transient : bool, optional
            A frequent update within a stage (an evaluation count): off a terminal only
            the heartbeat prints it, so a fast loop does not print a line per call.
        """
        self.state = text
        if self._bar is not None:  # a terminal: the stage on its own line, pulsing
            shown = one_line(text)  # a path or a label from a file: one line, escaped
            if "stage" not in self.tasks:
                self.tasks["stage"] = self._bar.add_task(shown, total=None)
            self._bar.update(self.tasks["stage"], description=shown)
        elif not transient and time.monotonic() - self.t0 >= self.every:
            self._line(text)

    def tick(self, key: str, done: int, total: int) -> None:
        """``done`` of ``total`` units of Monte Carlo work (path-steps) of run ``key``.

        Parameters
        ----------
        key : str
            The run.
        done, total : int
            Path-steps done and in all.
        """
        frac = done / max(total, 1)
        left = (time.monotonic() - self.t0) * (1 - frac) / frac if frac > 0 else None
        eta = f", about {format_seconds(left)} left" if left is not None else ""
        self.state = f"{key}: Monte Carlo {100 * frac:.{0 if frac >= 0.1 else 2}f}% done{eta}"
        if self._bar is not None:
            if key not in self.tasks:
                self.tasks[key] = self._bar.add_task(one_line(key), total=total)
            self._bar.update(self.tasks[key], completed=done, total=total)


def sweep_progress():
    """A bar for points and path-steps on a terminal, otherwise a plain line on stderr
    every PLAIN_EVERY seconds (and at the end), for batch jobs.

    Returns
    -------
    (callable, context manager)
        The callback :func:`ntc_design.sweep.run_sweep` calls, and what to enter around it.
    """
    if not sys.stderr.isatty():
        last = [0.0]

        def plain(st) -> None:
            now = time.monotonic()
            if now - last[0] >= PLAIN_EVERY or st.points_done == st.points_total:
                last[0] = now
                print(st.line(), file=sys.stderr, flush=True)

        return plain, contextlib.nullcontext()
    from rich.progress import BarColumn, TaskID, TextColumn, TimeRemainingColumn
    from rich.progress import Progress as Bar

    prog = Bar(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
    )
    ids: dict[str, TaskID] = {}

    def bar(st) -> None:
        if not ids:
            ids["p"] = prog.add_task("points", total=st.points_total)
            ids["s"] = prog.add_task("path-steps", total=max(st.path_steps_total, 1))
        prog.update(ids["p"], completed=st.points_done, total=st.points_total)
        prog.update(ids["s"], completed=st.path_steps_done, total=max(st.path_steps_total, 1))

    return bar, prog


def _safe_print(text: str) -> None:
    """One line of plain output (no rich markup: a certificate's text is shown as
    written), control characters escaped, newlines too: one line per call."""
    sys.stdout.write(one_line(text) + "\n")


def print_verification(doc: dict) -> None:
    """Print ``ntc verify``'s account of a certificate
    (:func:`ntc_design.certify.checks.verification_tables`, as every face shows it).

    Parameters
    ----------
    doc : dict
        :meth:`ntc_design.certify.Verification.to_dict`'s mapping.
    """
    from ..certify.checks import verification_tables

    for t in verification_tables(doc):
        print_table(t)


__all__ = [
    "PLAIN_EVERY",
    "Progress",
    "out",
    "print_table",
    "print_verification",
    "safe",
    "sweep_progress",
]
