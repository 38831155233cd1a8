"""The digital (sampled, delayed) protocol: each agent samples its neighbours' noisy
relative measurements every h seconds, holds its input until the next sample, and its
measurements arrive D samples late.

With e = x − 1⊗θ, period h, delay D, c_k = c(kh) and ξ independent standard normals,
two per edge (the additive and the multiplicative one),

    e_{k+1} = e_k − h c_k L_B e_{k−D} + c_k √h Σ_e ( g_e ξ_{k,e,1} + G_e e_{k−D} ξ_{k,e,2} ),

where g_e and G_e are the additive and multiplicative noise terms of edge e exactly as in
the continuous model, and before the start the initial state is held (e_{−j} = e_0).
D = 0 is the Euler–Maruyama step at dt = h. A run to T takes K = round(T/h) steps.

:class:`Digital` is that option, validated on construction (the pattern of diffrax's
``SaveAt``); :func:`step_modes` is the mode each step uses on a switching schedule (the
mode active at t_k = k·h, by one rule that the simulator, the certificate and the
exported code share).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, require_int, require_number
from ..present.rows import Table
from .loss import POLICIES, require_loss, require_policy

#: The largest delay D in samples (the augmented state holds D + 1 copies of the state).
MAX_DELAY = 10_000
#: The most steps K = round(T/h) a digital run may take.
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
    (100, None)
    >>> Digital(0.3).steps(1.0)[0]
    3
    """

    period: float
    delay: int = 0
    loss: float = 0.0
    policy: str = "skip"

    def __post_init__(self) -> None:
        h = require_number("digital.period", self.period)
        if not h > 0:
            raise InputError(f"digital.period: must be a positive number, got {h!r}")
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
            raise InputError("digital: expected {period: h, delay: D}")
        known = ("period", "delay", "loss", "policy")
        unknown = sorted(str(k) for k in set(doc) - set(known))
        if unknown:
            raise InputError(f"digital.{unknown[0]}: unknown field (known: {', '.join(known)})")
        if "period" not in doc:
            raise InputError("digital.period: missing")
        return cls(
            doc["period"], doc.get("delay", 0), doc.get("loss", 0.0), doc.get("policy", "skip")
        )

    def steps(self, t_end: float) -> tuple[int, str | None]:
        """K = round(T/h), the steps of a run to T, and a note when T is not a whole
        number of periods.

        Parameters
        ----------
        t_end : float
            The horizon T.

        Returns
        -------
        (int, str or None)

        Raises
        ------
        InputError
            h > T, or more than :data:`MAX_STEPS` steps.
        """
        h = self.period
        if h > t_end:
            raise InputError(f"digital.period: h = {h:g} is longer than the horizon T = {t_end:g}")
        ratio = t_end / h
        if not ratio <= MAX_STEPS:
            raise InputError(
                f"digital.period: T/h = {ratio:.3g} steps exceed the limit {MAX_STEPS:.0e}; "
                "raise the period or shorten T"
            )
        k = max(1, round(ratio))
        note = None
        if abs(k * h - t_end) > WHOLE_RTOL * t_end:
            note = (
                f"T = {t_end:g} is not a whole number of periods h = {h:g}: the run takes "
                f"K = round(T/h) = {k} steps, to t = K·h = {k * h:g}"
            )
        return k, note

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


def step_modes(
    schedule: Sequence[tuple[str, float]], times: np.ndarray, names: Sequence[str]
) -> np.ndarray:
    """The mode of each sample time on a periodic schedule: with τ = t − ⌊t / P⌋·P (P the
    schedule's period, the plain sum of its durations) the first entry whose cumulative
    end exceeds τ (a switching instant belongs to the next mode). The simulator, the
    certificate and the exported code use this one rule at t_k = k·h.

    Parameters
    ----------
    schedule : sequence of (str, float)
        The schedule's (mode, duration) pairs in order.
    times : numpy.ndarray
        The sample times t_k = k·h.
    names : sequence of str
        The modes, in the order the indices refer to.

    Returns
    -------
    numpy.ndarray
        The index into ``names`` of the mode active at each time.

    Examples
    --------
    >>> t = np.arange(6) * 0.25
    >>> step_modes([("a", 0.5), ("b", 0.5)], t, ["a", "b"]).tolist()
    [0, 0, 1, 1, 0, 0]
    """
    durations = [float(d) for _, d in schedule]
    period = float(sum(durations))  # as SwitchingTopology.period sums them
    ends = np.cumsum(durations)
    t = np.asarray(times, dtype=float)
    tau = t - np.floor(t / period) * period
    slot = np.minimum(np.searchsorted(ends, tau, side="right"), len(durations) - 1)
    index = np.array([list(names).index(m) for m, _ in schedule], dtype=np.int64)
    return index[slot]


__all__ = ["MAX_DELAY", "MAX_STEPS", "Digital", "DigitalDesign", "step_modes"]
