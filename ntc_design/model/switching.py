"""Topologies that change: a switching set (modes and a periodic schedule) and a
topology given as functions of t (sampled by the simulator)."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..io import files
from ..present.rows import Table
from .topology import Label, Topology


class ExpressionFamily:
    """The base of a topology whose weights are expressions of t
    (:class:`ntc_design.model.timevarying.ExpressionTopology`): what code that must not load
    SymPy for the other topologies tests against."""

    __slots__ = ()


@dataclass(frozen=True, eq=False)
class SwitchingTopology:
    """Modes (topologies over the same agents and d) and a periodic schedule of
    ``(mode, duration)``; G(t) = mode active at ``t mod period``, intervals half-open."""

    modes: Mapping[str, Topology]
    schedule: tuple[tuple[str, float], ...]
    source: str | None = None

    def __post_init__(self) -> None:
        where = f"{self.source}: " if self.source else ""
        if not self.modes:
            raise InputError("at least one mode is needed", field=f"{where}modes")
        first_name, first = next(iter(self.modes.items()))
        for name, top in self.modes.items():
            if top.dim != first.dim or top.n != first.n:
                raise InputError(
                    f"has N={top.n}, d={top.dim} but mode {first_name} "
                    f"has N={first.n}, d={first.dim}; all modes must share the agents",
                    field=f"{where}modes.{name}",
                )
            if [str(a) for a in top.labels] != [str(a) for a in first.labels]:
                raise InputError(
                    f"agent labels differ from mode {first_name}", field=f"{where}modes.{name}"
                )
        if not self.schedule:
            raise InputError("must not be empty", field=f"{where}schedule")
        for k, (m, dur) in enumerate(self.schedule):
            if m not in self.modes:
                raise InputError(
                    f"unknown mode {m!r} (modes: {', '.join(self.modes)})",
                    field=f"{where}schedule[{k}]",
                )
            if not (dur > 0 and math.isfinite(dur)):
                raise InputError(
                    f"must be a finite positive number, got {dur}",
                    field=f"{where}schedule[{k}].duration",
                )
        # every switching instant must be a distinct float: a period that overflows to
        # infinity, or a duration lost in rounding (1e308 + 0.02), would silently drop modes
        ends = np.cumsum([d for _, d in self.schedule])
        if not math.isfinite(float(ends[-1])):
            raise InputError(
                "the period (sum of durations) overflows to infinity", field=f"{where}schedule"
            )
        starts = np.concatenate([[0.0], ends[:-1]])
        lost = np.flatnonzero(ends <= starts)
        if lost.size:
            k = int(lost[0])
            raise InputError(
                f"{self.schedule[k][1]!r} is lost in rounding "
                f"next to the other durations: its switching instants collide at {float(starts[k])!r}",
                field=f"{where}schedule[{k}].duration",
            )

    @classmethod
    def from_data(cls, data: files.SwitchingData) -> SwitchingTopology:
        """Build from a parsed switching file.

        Parameters
        ----------
        data : ntc_design.io.files.SwitchingData
            As :func:`ntc_design.io.files.parse_switching` returns it.

        Returns
        -------
        SwitchingTopology
            The validated modes and schedule.

        Raises
        ------
        InputError
            Modes over different agents or d, an unknown mode or a non-positive duration
            in the schedule, or an invalid weight in a mode.
        """
        modes = {k: Topology.from_data(v) for k, v in data.modes.items()}
        return cls(modes, data.schedule, data.source)

    @property
    def labels(self) -> tuple[Label, ...]:
        """The agent labels (shared by every mode)."""
        return next(iter(self.modes.values())).labels

    @property
    def dim(self) -> int:
        """The weight size d."""
        return next(iter(self.modes.values())).dim

    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)

    @property
    def period(self) -> float:
        """The schedule's period (the sum of its durations)."""
        return float(sum(d for _, d in self.schedule))

    def __repr__(self) -> str:
        sched = ", ".join(f"{m} {d:g}" for m, d in self.schedule)
        return (
            f"SwitchingTopology(modes={list(self.modes)}, N={self.n}, d={self.dim}, "
            f"schedule=[{sched}], period={self.period:g})"
        )

    def table(self) -> Table:
        """The modes and the schedule, as every face shows them.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows: list[tuple] = [("agents N", self.n), ("state dimension d", self.dim)]
        rows += [(f"mode {k}", repr(m)) for k, m in self.modes.items()]
        rows.append(("schedule (one period)", ", ".join(f"{m} {d:g}" for m, d in self.schedule)))
        rows.append(("period", f"{self.period:g}"))
        return Table.build("switching topology", ("quantity", "value"), rows)

    def _repr_html_(self) -> str:
        return self.table().html()

    def segments(self, t_end: float, t_start: float = 0.0) -> list[tuple[float, float, str]]:
        """The schedule unrolled on [t_start, t_end).

        Switch times are ``k·period + offset`` (no drift from repeated addition), and each
        segment stops exactly where the next one starts.

        Parameters
        ----------
        t_end : float
            End of the horizon.
        t_start : float, optional
            Its start.

        Returns
        -------
        list of (float, float, str)
            ``(start, stop, mode)`` triples covering the horizon.
        """
        offsets = np.concatenate([[0.0], np.cumsum([d for _, d in self.schedule])[:-1]])
        per = self.period
        m_n = len(self.schedule)

        def start(k: int, m: int) -> float:
            k, m = k + m // m_n, m % m_n
            return float(k * per + offsets[m])

        out: list[tuple[float, float, str]] = []
        k = int(np.floor(t_start / per))
        while True:
            for m, (mode, _) in enumerate(self.schedule):
                a, b = start(k, m), start(k, m + 1)
                if b <= t_start:
                    continue
                if a >= t_end:
                    return out
                out.append((max(a, t_start), min(b, t_end), mode))
            k += 1

    def mode_at(self, t: float) -> str:
        """The mode active at time t.

        Parameters
        ----------
        t : float
            A time (a switching instant belongs to the next mode).

        Returns
        -------
        str
            The mode's name.
        """
        per = self.period
        tau = t - np.floor(t / per) * per
        ends = np.cumsum([d for _, d in self.schedule])
        k = min(int(np.searchsorted(ends, tau, side="right")), len(self.schedule) - 1)
        return self.schedule[k][0]


@dataclass(frozen=True, eq=False)
class TimeVaryingTopology:
    """A topology whose weights are functions of time: ``weights[(from, to)] = A(t)``,
    keyed by agent labels, each ``A(t)`` a d×d symmetric matrix of one sign at every t.
    ``at(t)`` freezes it into a :class:`Topology` (validated at that t)."""

    labels: tuple[Label, ...]
    dim: int
    weights: Mapping[tuple[Label, Label], Callable[[float], np.ndarray]]
    name: str | None = None

    def at(self, t: float) -> Topology:
        """The topology frozen at time t.

        Parameters
        ----------
        t : float
            The time.

        Returns
        -------
        Topology
            The weights A(t), validated at that t.

        Raises
        ------
        InputError
            An edge names an unknown label, or a weight is not symmetric and of one sign
            at t.
        """
        index = {str(a): k for k, a in enumerate(self.labels)}
        w, fields = {}, {}
        for (j, i), fn in self.weights.items():
            if str(j) not in index or str(i) not in index:
                raise InputError(f"edge {j}->{i}: unknown agent label")
            key = (index[str(i)], index[str(j)])
            w[key] = np.asarray(fn(t), dtype=float)
            fields[key] = f"edge {j}->{i} at t={t:g}"
        return Topology(self.labels, self.dim, w, self.name, None, fields)

    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)
