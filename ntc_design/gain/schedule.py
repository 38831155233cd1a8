"""A tabulated gain schedule with an analytic tail: c(t) from a table on [0, T], then a
closed form for t >= T.

What :func:`ntc_design.tune.tune` returns with ``ScheduleOptions``, and a gain wherever
one is accepted (a scenario's ``gain: {schedule: schedule.csv, tail: "…"}``,
``ntc certify`` with a schedule CSV as its gain, ``simulate``). Theorems 1-4 ask of c only what
happens as t → ∞ (∫c = ∞, c → 0, ∫c² < ∞) besides c being continuous and non-negative
(Niu & Wu, eqs. (13), (16)); a finite, non-negative table changes none of the integrals'
convergence, so the theorems hold for the schedule exactly when

- the table is finite, non-negative and its times start at 0 and strictly increase;
- it is continuous: ``interpolation: linear`` (a ``previous``, step, table is not);
- the tail is one of the admissible gains (analysed symbolically,
  :func:`ntc_design.gain.conditions.analyse_gain`, e.g. a·(b + t)^(−γ) with γ ∈ (½, 1]);
- the tail joins the table at its last time: ``|tail(T) − c(T)| <= JOIN_RTOL·c(T)``.

:func:`analyse_schedule` decides these in the four conditions of a
:class:`~ntc_design.gain.conditions.GainAnalysis`; :func:`schedule_checks` re-checks a schedule
stored in a certificate, in exact rational arithmetic for the table.

The CSV form has a header ``t,c`` and one row per time; comment lines
``# tail: EXPRESSION`` and ``# interpolation: linear|previous`` carry the rest, so one
file is a whole gain.
"""

from __future__ import annotations

import math
import re
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..choices import Interpolation, choices
from ..errors import InputError, real_float
from ..expr.tree import numeric_function
from ..present.rows import VERDICT_TEXT

if TYPE_CHECKING:  # SymPy (through .gain) loads only for an analysis, not to simulate
    from .conditions import Condition, GainAnalysis

#: Interpolation between the table's points: linear (continuous) or previous (a step
#: at every time; not continuous).
INTERPOLATIONS = choices(Interpolation)
#: Bounds on a table read from a file: points, bytes, and |c|.
MAX_POINTS = 100_000
MAX_BYTES = 16 * 2**20
MAX_VALUE = 1e6
#: The tail must meet the table's last value to this relative tolerance.
JOIN_RTOL = 1e-9
#: ASCII digits only: \d alone also matches "٣" and "３", which float() reads as 3.
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d{1,3})?", re.ASCII)


def _number(text: str, where: str) -> float:
    s = text.strip()
    if not _NUMBER.fullmatch(s):
        raise InputError(f"expected a number, got {s[:30]!r}", field=where)
    return float(s)


@dataclass(frozen=True, eq=False)
class ScheduleGain:
    """c(t): the table (t_k, c_k) on [0, t_K], then ``tail`` for t >= t_K.

    Attributes
    ----------
    t, c : numpy.ndarray
        Times (t_0 = 0, strictly increasing) and values (finite, >= 0, <= ``MAX_VALUE``).
    interpolation : {"linear", "previous"}
        Between table times.
    tail : str
        c(t) for t >= t_K, an expression in t.

    Examples
    --------
    >>> g = ScheduleGain([0, 1, 2], [2.0, 1.0, 0.5], tail="1.5/(1 + t)")
    >>> [float(v) for v in g([0.5, 2.0, 5.0])]
    [1.5, 0.5, 0.25]
    """

    t: Any
    c: Any
    interpolation: Interpolation = "linear"
    tail: str = "1/(1+t)"
    field: str = "gain"

    def __post_init__(self) -> None:
        f = self.field
        try:
            t = np.array(self.t, dtype=float).reshape(-1)
            c = np.array(self.c, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError("expected lists of numbers t and c", field=f"{f}.schedule") from None
        except OverflowError:  # an integer beyond the float range, from a document
            for name, values in (("t", self.t), ("c", self.c)):
                for k, v in enumerate(values):
                    real_float(f"{f}.schedule: {name}[{k}]", v)
            raise  # pragma: no cover - one of them overflowed
        if t.size != c.size:
            raise InputError(f"{t.size} times but {c.size} values", field=f"{f}.schedule")
        if not 2 <= t.size <= MAX_POINTS:
            raise InputError(
                f"expected 2 to {MAX_POINTS} points, got {t.size}", field=f"{f}.schedule"
            )
        for name, arr in (("t", t), ("c", c)):
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                raise InputError(f"{name}[{bad[0]}] is not finite", field=f"{f}.schedule")
        if t[0] != 0.0:
            raise InputError(f"t[0] must be 0, got {t[0]:g}", field=f"{f}.schedule")
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            k = int(bad[0]) + 1
            raise InputError(
                f"times must increase strictly; t[{k}] = {t[k]:g} after t[{k - 1}] = {t[k - 1]:g}",
                field=f"{f}.schedule",
            )
        bad = np.flatnonzero((c < 0) | (c > MAX_VALUE))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"c[{k}] = {c[k]:g} at t = {t[k]:g} is outside [0, {MAX_VALUE:g}]",
                field=f"{f}.schedule",
            )
        if self.interpolation not in INTERPOLATIONS:
            raise InputError(
                f"expected one of {', '.join(INTERPOLATIONS)}, got {self.interpolation!r}",
                field=f"{f}.interpolation",
            )
        if not isinstance(self.tail, str) or not self.tail.strip():
            raise InputError("expected an expression in t", field=f"{f}.tail")
        t.setflags(write=False)
        c.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "_fn", numeric_function(self.tail, f"{f}.tail"))

    def _tail(self, t: np.ndarray) -> np.ndarray:
        return self._fn(t)  # type: ignore[attr-defined]

    @property
    def end(self) -> float:
        """The table's last time T."""
        return float(self.t[-1])

    @property
    def text(self) -> str:
        """A one-line label: the table's size and span, then the tail."""
        return (
            f"schedule ({self.t.size} points on [0, {self.end:g}], {self.interpolation}) "
            f"then {self.tail}"
        )

    def __call__(self, t) -> np.ndarray:
        """c(t), vectorised (the tail for t >= T)."""
        t = np.asarray(t, dtype=float)
        flat = t.reshape(-1)
        out = np.empty_like(flat)
        inside = flat < self.end
        x = flat[inside]
        if self.interpolation == "linear":
            out[inside] = np.interp(x, self.t, self.c)
        else:
            k = np.clip(np.searchsorted(self.t, x, side="right") - 1, 0, self.t.size - 1)
            out[inside] = self.c[k]
        if np.any(~inside):
            with np.errstate(all="ignore"):
                tail = np.asarray(self._tail(flat[~inside]), dtype=float)
                out[~inside] = tail * np.ones(int(np.sum(~inside)))
        return out.reshape(t.shape)

    def integrals(self, t_end: float) -> tuple[float, float]:
        """∫₀ᵀ c dt and ∫₀ᵀ c² dt (the table exactly for linear interpolation, the tail by
        a fine trapezoid rule): what a step-count estimate needs.

        Parameters
        ----------
        t_end : float
            T.

        Returns
        -------
        (float, float)
        """
        grid = np.union1d(self.t[self.t < t_end], np.linspace(0.0, t_end, 2001))
        grid = np.append(grid[grid < t_end], t_end)
        v = self(grid)
        h = np.diff(grid)
        if self.interpolation == "previous":
            return float(np.sum(h * v[:-1])), float(np.sum(h * v[:-1] ** 2))
        a, b = v[:-1], v[1:]
        return float(np.sum(h * (a + b) / 2)), float(np.sum(h * (a * a + a * b + b * b) / 3))

    def to_document(self) -> dict[str, Any]:
        """The schedule as a JSON-ready mapping (what a certificate and ``--json`` hold).

        Returns
        -------
        dict
            ``t``, ``c``, ``interpolation`` and ``tail``.
        """
        return {
            "t": self.t.tolist(),
            "c": self.c.tolist(),
            "interpolation": self.interpolation,
            "tail": self.tail,
        }

    def csv_text(self) -> str:
        """The schedule as a CSV file (header ``t,c``, the tail and interpolation in
        comment lines): what :func:`read_schedule` reads back, digit for digit.

        Returns
        -------
        str
        """
        lines = [f"# tail: {self.tail}", f"# interpolation: {self.interpolation}", "t,c"]
        lines += [f"{a!r},{b!r}" for a, b in zip(self.t.tolist(), self.c.tolist(), strict=True)]
        return "\n".join(lines) + "\n"


def schedule_from_document(doc: Any, field: str = "gain") -> ScheduleGain:
    """A :class:`ScheduleGain` from a mapping ``{t: [...], c: [...], interpolation, tail}``
    (what :meth:`ScheduleGain.to_document` writes).

    Parameters
    ----------
    doc : mapping
        The schedule.
    field : str, optional
        Named in messages.

    Returns
    -------
    ScheduleGain

    Raises
    ------
    InputError
        A missing or malformed field, naming it.
    """
    if not isinstance(doc, Mapping):
        raise InputError("expected a mapping with t, c, interpolation and tail", field=field)
    unknown = sorted(set(doc) - {"t", "c", "interpolation", "tail"})
    if unknown:
        raise InputError(
            "unknown field (known: t, c, interpolation, tail)", field=f"{field}.{unknown[0]}"
        )
    for key in ("t", "c", "tail"):
        if key not in doc:
            raise InputError("missing", field=f"{field}.{key}")
    for key in ("t", "c"):
        v = doc[key]
        if not isinstance(v, list) or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in v
        ):
            raise InputError("expected a list of numbers", field=f"{field}.{key}")
    if not isinstance(doc["tail"], str):
        raise InputError("expected an expression in t (a string)", field=f"{field}.tail")
    return ScheduleGain(
        doc["t"], doc["c"], doc.get("interpolation", "linear"), doc["tail"], field=field
    )


def read_schedule(
    path: str | Path,
    tail: str | None = None,
    interpolation: str | None = None,
    field: str = "gain",
) -> ScheduleGain:
    """Read a schedule CSV (header ``t,c``; ``# tail:`` and ``# interpolation:`` comment
    lines), bounded in size; ``tail`` and ``interpolation`` given here must agree with
    the file's when both say.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    tail : str, optional
        The tail, when the file has none.
    interpolation : {"linear", "previous"}, optional
        Likewise (default linear).
    field : str, optional
        Named in messages.

    Returns
    -------
    ScheduleGain

    Raises
    ------
    InputError
        ``FILE: line K: what is wrong``, or a missing tail.
    """
    p = Path(path)
    try:
        st = p.stat()  # stat, never open: opening a FIFO waits for a writer
    except OSError as exc:
        what = "no such file" if isinstance(exc, FileNotFoundError) else "cannot read"
        raise InputError(f"{what} {str(p)!r}", field=f"{field}.schedule") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError(
            f"{str(p)!r} is a directory, not a schedule file", field=f"{field}.schedule"
        )
    if not stat.S_ISREG(st.st_mode):
        raise InputError(
            f"{str(p)!r} is not a regular file (a FIFO, device or socket)",
            field=f"{field}.schedule",
        )
    if st.st_size > MAX_BYTES:
        raise InputError(f"larger than {MAX_BYTES // 2**20} MB", field=str(p))
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read ({exc.__class__.__name__})", field=str(p)) from None
    meta: dict[str, str] = {}
    where: dict[str, int] = {}  # the line of each comment field
    ts: list[float] = []
    cs: list[float] = []
    header = False
    for k, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            key, sep, value = line[1:].partition(":")
            if sep and key.strip() in ("tail", "interpolation"):
                if key.strip() in meta:  # a second one: which would apply is a guess
                    raise InputError(
                        f"line {k}: a second '# {key.strip()}:' line (line {where[key.strip()]} "
                        "gave one already)",
                        field=str(p),
                    )
                meta[key.strip()] = value.strip()
                where[key.strip()] = k
            continue
        if not header:
            if [x.strip().lower() for x in line.split(",")] != ["t", "c"]:
                raise InputError(
                    f"line {k}: expected the header 't,c', got {line[:40]!r}", field=str(p)
                )
            header = True
            continue
        parts = line.split(",")
        if len(parts) != 2:
            raise InputError(f"line {k}: expected two numbers t,c, got {line[:40]!r}", field=str(p))
        if len(ts) >= MAX_POINTS:
            raise InputError(f"more than {MAX_POINTS} rows", field=str(p))
        ts.append(_number(parts[0], f"{p}: line {k}: t"))
        cs.append(_number(parts[1], f"{p}: line {k}: c"))
    if not header:
        raise InputError("no header 't,c'", field=str(p))
    for key, given in (("tail", tail), ("interpolation", interpolation)):
        if (
            given is not None
            and key in meta
            and meta[key].replace(" ", "") != given.replace(" ", "")
        ):
            raise InputError(
                f"{given!r} differs from the file's {meta[key]!r} ({p})", field=f"{field}.{key}"
            )
    tail_text = tail if tail is not None else meta.get("tail")
    if tail_text is None:
        raise InputError(
            f"missing (give tail: \"a*(b+t)**-g\" or a '# tail:' line in {p})",
            field=f"{field}.tail",
        )
    try:
        return ScheduleGain(
            ts,
            cs,
            cast("Interpolation", interpolation or meta.get("interpolation", "linear")),
            tail_text,
            field=field,
        )
    except InputError as exc:
        raise InputError(f"{exc}", field=str(p)) from None


def gain_from_option(text: str | None, field: str = "gain") -> str | ScheduleGain | None:
    """A gain as a user gives it on a command line: an expression in t, or a schedule CSV
    file (a name ending in ``.csv``, read by :func:`read_schedule`).

    Parameters
    ----------
    text : str or None
        The option's value.
    field : str, optional
        Named in messages.

    Returns
    -------
    str, ScheduleGain or None

    Raises
    ------
    InputError
        A schedule file that is missing or malformed.
    """
    if text is not None and text.strip().lower().endswith(".csv"):
        return read_schedule(text, field=field)
    return text


def join_tail(t_end: float, c_end: float, gamma: float = 1.0, b: float = 1.0) -> str:
    """The admissible tail a·(b + t)^(−γ) that meets c_end at t_end (a written to 12
    significant digits, well inside :data:`JOIN_RTOL`).

    Parameters
    ----------
    t_end, c_end : float
        The table's last time and value (c_end > 0).
    gamma : float, optional
        γ ∈ (½, 1]: both theorems hold for the tail.
    b : float, optional
        The offset, > 0.

    Returns
    -------
    str

    Raises
    ------
    InputError
        c_end <= 0, or γ outside (½, 1].

    Examples
    --------
    >>> join_tail(10.0, 0.05)
    '0.55/(1 + t)'
    """
    if not (math.isfinite(c_end) and c_end > 0):
        raise InputError(f"the schedule ends at c = {c_end:g}; a tail needs c(T) > 0", field="tail")
    if not 0.5 < gamma <= 1.0:
        raise InputError(f"γ = {gamma:g} is outside (1/2, 1]", field="tail")
    a = float(f"{c_end * (b + t_end) ** gamma:.12g}")
    if gamma == 1.0:
        return f"{a:.12g}/({b:g} + t)"
    return f"{a:.12g}*({b:g} + t)^(-{gamma:g})"


def _table_condition(g: ScheduleGain) -> Condition:
    from .conditions import Condition

    if g.interpolation != "linear":
        return Condition(
            False,
            "a step (previous) table is not continuous at its times; the theorems take c "
            "continuous (use interpolation: linear)",
        )
    return Condition(
        True,
        f"the table: {g.t.size} finite values >= 0 at increasing times from 0, linear between them",
    )


def _join(g: ScheduleGain) -> tuple[bool, str]:
    at_end = float(g._tail(np.array([g.end]))[0])
    last = float(g.c[-1])
    gap = abs(at_end - last)
    ok = math.isfinite(at_end) and gap <= JOIN_RTOL * max(abs(last), 1e-300)
    return ok, (
        f"the tail meets the table at t = {g.end:g}: tail(T) = {at_end:.12g}, c(T) = "
        f"{last:.12g} (gap {gap:.2g}, tolerance {JOIN_RTOL:g} relative)"
    )


@lru_cache(maxsize=32)
def _tail_analysis(tail: str, seconds: float | None) -> GainAnalysis:
    # certify, its own verification and the tune result analyse one tail three times; the
    # symbolic analysis is deterministic in its text and takes seconds
    from .conditions import analyse_gain

    return analyse_gain(tail) if seconds is None else analyse_gain(tail, seconds)


def analyse_schedule(g: ScheduleGain, seconds: float | None = None) -> GainAnalysis:
    """The Theorem 1-4 conditions for a schedule: the table's (finite, >= 0, continuous)
    and the join decide continuity; the tail's symbolic analysis decides the rest.

    Parameters
    ----------
    g : ScheduleGain
        The schedule.
    seconds : float, optional
        The tail analysis' time limit (:func:`ntc_design.gain.conditions.analyse_gain`'s default).

    Returns
    -------
    GainAnalysis
        Its ``expression`` is the schedule's label.

    Raises
    ------
    InputError
        The tail is negative or not finite on [0, ∞).
    """
    from .conditions import Condition, GainAnalysis, parse_gain

    tail = _tail_analysis(g.tail, seconds)
    table = _table_condition(g)
    ok, why = _join(g)
    cont = tail.continuous_nonnegative
    value = (
        False
        if table.value is False or not ok or cont.value is False
        else (None if cont.value is None else True)
    )
    reason = f"{table.reason}; {why}; the tail: {cont.reason}"

    def after(c: Condition) -> Condition:
        return Condition(c.value, f"the tail {g.tail} decides it: {c.reason}")

    return GainAnalysis(
        g.text,
        parse_gain(g.tail, "gain.tail"),
        Condition(value, reason),
        after(tail.integral_diverges),
        after(tail.tends_to_zero),
        after(tail.square_integrable),
        label=g.text,
    )


def analyse_any_gain(gain: Any) -> GainAnalysis:
    """:func:`analyse_gain` for an expression, :func:`analyse_schedule` for a schedule.

    Parameters
    ----------
    gain : str or ScheduleGain
        The gain.

    Returns
    -------
    GainAnalysis

    Raises
    ------
    InputError
        As the analysis it calls; a gain of another type.
    """
    from .conditions import analyse_gain

    if isinstance(gain, ScheduleGain):
        return analyse_schedule(gain)
    if isinstance(gain, str):
        return analyse_gain(gain)
    raise InputError(
        f"expected an expression in t or a schedule, got {type(gain).__name__}", field="gain"
    )


def schedule_checks(doc: Any, source: str = "certificate") -> list[tuple[str, bool, str]]:
    """Re-check a schedule stored in a certificate's ``gain`` field: the table in exact
    rational arithmetic (every value a finite number >= 0, times from 0 strictly
    increasing), linear interpolation, the join within :data:`JOIN_RTOL`, and the tail's
    conditions (symbolic). Nothing is read as a claim: every verdict is derived here.

    Parameters
    ----------
    doc : Any
        The ``gain`` field.
    source : str, optional
        The certificate's name in messages.

    Returns
    -------
    list of (str, bool, str)
        (check name, holds, detail).

    Raises
    ------
    InputError
        A field of the wrong type or shape (a malformed certificate).
    """
    try:
        g = schedule_from_document(doc, "gain")
    except InputError as exc:
        msg = str(exc)
        if any(w in msg for w in ("missing", "unknown field", "expected a", "expected lists")):
            raise InputError(f"{msg}", field=source) from None
        return [("gain schedule", False, msg)]
    exact_t = [Fraction(x) for x in doc["t"]]
    exact_c = [Fraction(x) for x in doc["c"]]
    ordered = exact_t[0] == 0 and all(b > a for a, b in zip(exact_t, exact_t[1:], strict=False))
    nonneg = all(v >= 0 for v in exact_c)
    out = [
        (
            "gain schedule: table",
            ordered and nonneg,
            f"{len(exact_t)} points; times from 0 strictly increasing, values >= 0 "
            "(exact rational arithmetic)",
        )
    ]
    try:
        a = analyse_schedule(g)
    except InputError as exc:
        return [*out, ("gain schedule: tail", False, str(exc))]
    out.append(
        (
            "gain schedule: continuous and >= 0",
            a.continuous_nonnegative.value is True,
            a.continuous_nonnegative.reason,
        )
    )
    conds = (a.integral_diverges.value, a.tends_to_zero.value, a.square_integrable.value)
    adm = all(v is True for v in conds)
    out.append(
        (
            "gain schedule: tail admissible",
            adm,
            f"∫c = ∞: {VERDICT_TEXT[a.integral_diverges.value]}, "
            f"c → 0: {VERDICT_TEXT[a.tends_to_zero.value]}, "
            f"∫c² < ∞: {VERDICT_TEXT[a.square_integrable.value]} ({g.tail})",
        )
    )
    return out


__all__ = [
    "INTERPOLATIONS",
    "JOIN_RTOL",
    "ScheduleGain",
    "analyse_any_gain",
    "analyse_schedule",
    "gain_from_option",
    "join_tail",
    "read_schedule",
    "schedule_checks",
    "schedule_from_document",
]
