"""The gain c(t) as the exported agents compute it: one scalar evaluation, by the same
operations in the toolkit (:meth:`GainCode.value`), in C and in Python
(:mod:`ntc_design.export`).

An expression is a :class:`~ntc_design.expr.code.ScalarProgram`. A tabulated schedule
(:class:`~ntc_design.gain.schedule.ScheduleGain`) is its table and its tail's program, with
:meth:`ScheduleGain.__call__`'s rule written out for one t (NumPy's ``np.interp`` for a
linear table, ``searchsorted`` for a step one):

- t >= T (the table's last time): the tail;
- linear: j = the last index with t_j <= t (j = −1 before the table: c_0);
  c_j when t = t_j; else ``s·(t − t_j) + c_j`` with the slope
  ``s = (c_{j+1} − c_j)/(t_{j+1} − t_j)`` (and, as ``np.interp``, ``s·(t − t_{j+1}) +
  c_{j+1}`` if that is NaN, then c_j if still NaN and c_j = c_{j+1});
- previous: c_j for the last j with t_j <= t (c_0 before the table).

The vectorised gain the simulator uses (NumPy's ufuncs) may round differently in the last
bit; the tests hold the two within 1e-13 relative.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

from ..errors import InputError
from ..expr.code import ScalarProgram, scalar_program
from .schedule import ScheduleGain


@dataclass(frozen=True)
class GainCode:
    """c(t) as scalar code: an expression, or a table with its tail.

    Attributes
    ----------
    label : str
        The gain as shown (the expression, or the schedule's one-line label).
    program : ScalarProgram
        The expression, or the schedule's tail.
    t, c : tuple of float
        The schedule's table (empty for an expression).
    interpolation : str
        ``linear`` or ``previous`` (an expression: ``""``).

    Examples
    --------
    >>> GainCode.of("1/(1+t)").value(1.0)
    0.5
    >>> g = GainCode.of(ScheduleGain([0, 1, 2], [2.0, 1.0, 0.5], tail="1.5/(1 + t)"))
    >>> g.value(0.5), g.value(5.0)
    (1.5, 0.25)
    """

    label: str
    program: ScalarProgram
    t: tuple[float, ...] = ()
    c: tuple[float, ...] = ()
    interpolation: str = ""

    @classmethod
    def of(cls, gain: str | ScheduleGain, field: str = "gain") -> GainCode:
        """The code of an expression or of a schedule.

        Parameters
        ----------
        gain : str or ScheduleGain
            c(t).
        field : str, optional
            Named in messages.

        Returns
        -------
        GainCode

        Raises
        ------
        InputError
            Not an expression or a schedule (a Python callable cannot be exported), or
            the expression is not a whitelisted one.
        """
        if isinstance(gain, ScheduleGain):
            return cls(
                gain.text,
                scalar_program(gain.tail, f"{field}.tail"),
                tuple(float(x) for x in gain.t.tolist()),
                tuple(float(x) for x in gain.c.tolist()),
                gain.interpolation,
            )
        if isinstance(gain, str):
            return cls(gain, scalar_program(gain, field))
        raise InputError(
            f"expected an expression in t or a schedule, got "
            f"{type(gain).__name__} (a Python function cannot be exported)",
            field=field,
        )

    @property
    def is_schedule(self) -> bool:
        """Whether c is a table with a tail."""
        return bool(self.t)

    @property
    def end(self) -> float:
        """The table's last time T (−inf for an expression: the tail everywhere)."""
        return self.t[-1] if self.t else -math.inf

    def value(self, t: float) -> float:
        """c(t), by the operations the exported code performs.

        Parameters
        ----------
        t : float
            The time.

        Returns
        -------
        float
        """
        t = float(t)
        if not t < self.end:
            return self.program.evaluate(t)
        ts, cs = self.t, self.c
        j = bisect.bisect_right(ts, t) - 1  # the last j with t_j <= t
        if self.interpolation != "linear":
            return cs[max(j, 0)]
        if j < 0:
            return cs[0]
        if ts[j] == t:
            return cs[j]
        s = (cs[j + 1] - cs[j]) / (ts[j + 1] - ts[j])
        out = s * (t - ts[j]) + cs[j]
        if out != out:
            out = s * (t - ts[j + 1]) + cs[j + 1]
            if out != out and cs[j] == cs[j + 1]:
                out = cs[j]
        return out

    def values(self, times) -> list[float]:
        """c at each time (:meth:`value` one by one).

        Parameters
        ----------
        times : iterable of float
            The times.

        Returns
        -------
        list of float
        """
        return [self.value(t) for t in times]


__all__ = ["GainCode"]
