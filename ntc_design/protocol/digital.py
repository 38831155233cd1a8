"""The digital (sampled, delayed) protocol: each agent samples its neighbours' noisy
relative measurements every h seconds, holds its input until the next sample, and its
measurements arrive D samples late.

With e = x − 1⊗θ, period h, delay D, c_k = c(kh) and ξ independent standard normals,
two per edge (the additive and the multiplicative one),

    e_{k+1} = e_k − h c_k L_B e_{k−D} + c_k √h Σ_e ( g_e ξ_{k,e,1} + G_e e_{k−D} ξ_{k,e,2} ),

where g_e and G_e are the additive and multiplicative noise terms of edge e exactly as in
the continuous model, and before the start the initial state is held (e_{−j} = e_0).
D = 0 is the Euler–Maruyama step at dt = h. Between samples an agent integrates its held
input, x(t) = x_k + (t − kh)·u_k (u_k with its noise), so the protocol is defined at every
time: a run to T takes K = ⌊T/h⌋ whole steps and, when s = T − K·h > 0, a partial one,

    e(T) = e_K − s c_K L_B e_{K−D} + (s/√h) c_K Σ_e ( g_e ξ_{K,e,1} + G_e e_{K−D} ξ_{K,e,2} ),

with the normals step K would draw (T within :data:`WHOLE_RTOL` of a whole number of
periods counts as one).

:class:`Digital` is that option, validated on construction (the pattern of diffrax's
``SaveAt``); :func:`step_modes` is the mode each step uses on a switching schedule (the
mode active at t_k = k·h, by one rule that the simulator, the certificate and the
exported code share).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import accumulate
from typing import Any

import numpy as np

from ..choices import LossPolicy
from ..errors import InputError, require_int, require_number
from ..present.rows import Table
from .loss import POLICIES, require_loss, require_policy

#: The largest delay D in samples (the augmented state holds D + 1 copies of the state).
MAX_DELAY = 10_000
#: The most steps K = ⌊T/h⌋ a digital run may take.
MAX_STEPS = 10**9
#: T is a whole number of periods when |K·h − T| <= this times T.
WHOLE_RTOL = 1e-9


@dataclass(frozen=True)
class Digital:
    """The sampled protocol's period and delay.

    Attributes
    ----------
    period : float
        The sampling period h > 0.
    delay : int
        The measurement delay D >= 0, in samples.
    loss : float
        The probability p in [0, 1) that a message is lost (every edge, each step,
        independently; :mod:`.loss`).
    policy : str
        What an agent does with a lost message: ``skip``, ``rescale`` or ``hold``.

    Examples
    --------
    >>> Digital(0.1, 1).steps(10.0)
    (100, 0.0)
    >>> k, s = Digital(0.3).steps(1.0)
    >>> k, round(s, 12)
    (3, 0.1)
    """

    period: float
    delay: int = 0
    loss: float = 0.0
    policy: LossPolicy = "skip"

    def __post_init__(self) -> None:
        h = require_number("digital.period", self.period)
        if not h > 0:
            raise InputError(f"must be a positive number, got {h!r}", field="digital.period")
        object.__setattr__(self, "period", h)
        d = require_int("digital.delay", self.delay, minimum=0, maximum=MAX_DELAY)
        object.__setattr__(self, "delay", d)
        object.__setattr__(self, "loss", require_loss("digital.loss", self.loss))
        object.__setattr__(self, "policy", require_policy("digital.policy", self.policy))

    @property
    def lossy(self) -> bool:
        """Whether messages may be lost (p > 0)."""
        return self.loss > 0.0

    @classmethod
    def from_document(cls, doc: Any) -> Digital:
        """A scenario's ``digital: {period: h, delay: D, loss: p, policy: P}`` block.

        Parameters
        ----------
        doc : mapping
            The block as read.

        Returns
        -------
        Digital

        Raises
        ------
        InputError
            Not a mapping, an unknown or missing field, or a bad value.
        """
        if isinstance(doc, Digital):
            return doc
        if not isinstance(doc, Mapping):
            raise InputError("expected {period: h, delay: D}", field="digital")
        known = ("period", "delay", "loss", "policy")
        unknown = sorted(str(k) for k in set(doc) - set(known))
        if unknown:
            raise InputError(
                f"unknown field (known: {', '.join(known)})", field=f"digital.{unknown[0]}"
            )
        if "period" not in doc:
            raise InputError("missing", field="digital.period")
        return cls(
            doc["period"], doc.get("delay", 0), doc.get("loss", 0.0), doc.get("policy", "skip")
        )

    def steps(self, t_end: float) -> tuple[int, float]:
        """K = ⌊T/h⌋, the whole steps of a run to T, and s = T − K·h in [0, h), the
        partial step of the held input that ends it at T (0 when T is a whole number of
        periods within :data:`WHOLE_RTOL`, K = round(T/h) then).

        Parameters
        ----------
        t_end : float
            The horizon T.

        Returns
        -------
        (int, float)
            K and s.

        Raises
        ------
        InputError
            h > T, or more than :data:`MAX_STEPS` steps.
        """
        h = self.period
        if h > t_end:
            raise InputError(
                f"h = {h:g} is longer than the horizon T = {t_end:g}", field="digital.period"
            )
        ratio = t_end / h
        if not ratio <= MAX_STEPS:
            raise InputError(
                f"T/h = {ratio:.3g} steps exceed the limit {MAX_STEPS:.0e}; "
                "raise the period or shorten T",
                field="digital.period",
            )
        k = max(1, round(ratio))
        if abs(k * h - t_end) <= WHOLE_RTOL * t_end:
            return k, 0.0
        k = max(1, math.floor(ratio))
        return k, min(max(t_end - k * h, 0.0), h)

    def to_dict(self) -> dict:
        """The block as a scenario writes it.

        Returns
        -------
        dict
            ``period`` and ``delay``, and ``loss`` and ``policy`` when messages may be
            lost or the policy is not the default (a lossless block reads as before).
        """
        out: dict = {"period": self.period, "delay": self.delay}
        if self.lossy or self.policy != POLICIES[0]:
            out.update(loss=self.loss, policy=self.policy)
        return out


@dataclass(frozen=True, eq=False)
class DigitalDesign:
    """A continuous Lemma 1 design (one topology or a switching set) run as the digital
    protocol, with what its certificate needs: the gain and the noise (σ per edge, f).

    Attributes
    ----------
    base : ProtocolDesign or SwitchingDesign
        The continuous design.
    digital : Digital
        The period and delay.
    gain : str or ScheduleGain
        c(t).
    sigma : float
        σ of every edge without its own.
    f : float or numpy.ndarray
        f(x) = f·x (a scale) or F x (a d×d matrix).
    sigma_edges : mapping of (str, str) to float
        Per-edge σ, keyed by (from, to) labels.
    """

    base: Any
    digital: Digital
    gain: Any
    sigma: float = 0.4
    f: Any = 0.3
    sigma_edges: Mapping[tuple[str, str], float] = field(default_factory=dict)

    def f_matrix(self, d: int) -> np.ndarray:
        """F as a d×d matrix (a scale s is s·I).

        Parameters
        ----------
        d : int
            The state dimension.

        Returns
        -------
        numpy.ndarray
        """
        arr = np.asarray(self.f, dtype=float)
        return float(arr) * np.eye(d) if arr.ndim == 0 else arr

    def noise_document(self) -> dict:
        """The noise as the certificate's subject states it.

        Returns
        -------
        dict
            ``sigma``, ``f`` (a number or a d×d list) and ``sigma_edges`` ({from, to, sigma}).
        """
        arr = np.asarray(self.f, dtype=float)
        return {
            "sigma": float(self.sigma),
            "f": float(arr) if arr.ndim == 0 else arr.tolist(),
            "sigma_edges": [
                {"from": str(a), "to": str(b), "sigma": float(v)}
                for (a, b), v in self.sigma_edges.items()
            ],
        }

    def table(self, title: str | None = None) -> Table:
        """The continuous design's table with the sampling rows.

        Parameters
        ----------
        title : str, optional
            The table's title.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        base = self.base.table(title)
        width = len(base.columns) - 1
        extra = [
            (label, *[value] * width)
            for label, value in (
                ("sampling period h", self.digital.period),
                ("measurement delay D (samples)", self.digital.delay),
                *(
                    (("message loss p", self.digital.loss), ("lost messages", self.digital.policy))
                    if self.digital.lossy
                    else ()
                ),
            )
        ]
        return Table.build(base.title, base.columns, [*base.rows, *extra], base.notes, base.layout)

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        return f"DigitalDesign({self.base!r}, h={self.digital.period:g}, D={self.digital.delay})"

    def to_dict(self) -> dict:
        """The design as a JSON-ready mapping: the continuous design and ``digital``.

        Returns
        -------
        dict
        """
        return {**self.base.to_dict(), "digital": self.digital.to_dict()}


def decimal_fraction(x: float) -> Fraction:
    """The exact rational of a number's shortest decimal (``repr``): 0.1 is 1/10, the
    value the user wrote, not the double nearest to it.

    Parameters
    ----------
    x : float
        A finite number.

    Returns
    -------
    fractions.Fraction

    Examples
    --------
    >>> decimal_fraction(0.013)
    Fraction(13, 1000)
    """
    return Fraction(repr(float(x)))


@dataclass(frozen=True)
class ScheduleTicks:
    """A periodic schedule and a sampling period on one integer clock of 1/L seconds: h,
    every duration and so every switching instant are their decimals
    (:func:`decimal_fraction`), L their common denominator, so t_k = k·h and the instants
    are compared exactly.

    Attributes
    ----------
    unit : int
        L (a tick is 1/L s).
    step : int
        h in ticks, reduced modulo the period (k·h mod P is k·step mod P).
    period : int
        P, the schedule's period, in ticks.
    ends : tuple of int
        The cumulative ends of the entries, in ticks (the last is P).
    """

    unit: int
    step: int
    period: int
    ends: tuple[int, ...]

    @classmethod
    def of(cls, schedule: Sequence[tuple[str, float]], period: float) -> ScheduleTicks:
        """The ticks of a schedule sampled every ``period`` seconds.

        Parameters
        ----------
        schedule : sequence of (str, float)
            (mode, duration) pairs.
        period : float
            h.

        Returns
        -------
        ScheduleTicks
        """
        h = decimal_fraction(period)
        ds = [decimal_fraction(d) for _, d in schedule]
        unit = math.lcm(h.denominator, *(d.denominator for d in ds))
        ends = tuple(accumulate(int(d * unit) for d in ds))
        return cls(unit, int(h * unit) % ends[-1], ends[-1], ends)

    def tau(self, steps: np.ndarray) -> np.ndarray:
        """τ_k = k·h mod P in ticks, exactly (int64 while P < 2^31, Python integers past it).

        Parameters
        ----------
        steps : numpy.ndarray
            k (integers >= 0).

        Returns
        -------
        numpy.ndarray
        """
        k = np.asarray(steps, dtype=np.int64)
        if self.period < 2**31:  # (k mod P)·step < 2^62: no overflow
            return (k % self.period) * self.step % self.period
        return np.array([int(x) * self.step % self.period for x in k.tolist()], dtype=object)


def step_modes(
    schedule: Sequence[tuple[str, float]], times: np.ndarray, names: Sequence[str], period: float
) -> np.ndarray:
    """The mode of each sample t_k = k·h on a periodic schedule, decided exactly: h and the
    durations are their decimals (0.1 is 1/10; :class:`ScheduleTicks`), τ = t_k mod P
    and the step runs the first entry whose cumulative end exceeds τ (a switching instant
    belongs to the next mode). The simulator, the replay and the exported code use this one
    rule (the exported code in integer ticks).

    Parameters
    ----------
    schedule : sequence of (str, float)
        The schedule's (mode, duration) pairs in order.
    times : numpy.ndarray
        The sample times t_k = k·h (as doubles; k = round(t_k / h)).
    names : sequence of str
        The modes, in the order the indices refer to.
    period : float
        h.

    Returns
    -------
    numpy.ndarray
        The index into ``names`` of the mode active at each time.

    Examples
    --------
    >>> t = np.arange(6) * 0.25
    >>> step_modes([("a", 0.5), ("b", 0.5)], t, ["a", "b"], 0.25).tolist()
    [0, 0, 1, 1, 0, 0]
    """
    ticks = ScheduleTicks.of(schedule, period)
    k = np.rint(np.asarray(times, dtype=float) / float(period)).astype(np.int64)
    tau = ticks.tau(k)
    slot = np.searchsorted(
        np.array(ticks.ends, dtype=object if tau.dtype == object else np.int64), tau, side="right"
    )
    slot = np.minimum(slot, len(ticks.ends) - 1)
    index = np.array([list(names).index(m) for m, _ in schedule], dtype=np.int64)
    return index[slot]


__all__ = [
    "MAX_DELAY",
    "MAX_STEPS",
    "Digital",
    "DigitalDesign",
    "ScheduleTicks",
    "decimal_fraction",
    "step_modes",
]
