"""The largest tolerable message loss of the digital protocol (``ntc tune`` with the loss ``auto``):
the largest uniform loss p such that every loss in [0, p] keeps the exact
E Σ_i ‖x_i(T) − θ‖² of the lossy sampled recursion (:mod:`ntc_design.simulate.loss`, one
policy) within (1 + tolerance) of the lossless sampled protocol's at the same period h and
delay D.

Search: the exact moments at the losses 0, ``STEP``, 2·``STEP``, … below 1 (a dense
scan); the last loss before the first that fails is refined by bisection against that
failure to ``ATOL``. Every scanned loss below the answer passed: that is the evidence for
"every smaller loss" (between scan points, ``STEP`` apart, the curve is not evaluated; the
table shows the scan).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..choices import LossPolicy
from ..errors import InputError, require_horizon, require_number
from ..model import Topology
from ..present.rows import Table, fmt, verdict
from ..protocol.digital import Digital
from ..protocol.loss import require_policy
from ..simulate import SimulationSpec
from ..simulate.loss import loss_moments
from ..simulate.prepare import make_gain, prepare_modes, sampled_grid

#: The spacing of the dense scan of losses.
STEP = 0.01
#: The bisection stops when the bracket is this narrow.
ATOL = 1e-4


@dataclass(frozen=True)
class LossPoint:
    """One evaluated loss: the final error, the peak and the offset, and whether the
    final error is within the bound."""

    loss: float
    final: float
    peak: float
    offset: float
    ok: bool

    def to_dict(self) -> dict:
        """The point as JSON data.

        Returns
        -------
        dict
        """
        return {
            "loss": self.loss,
            "final_ms_error": self.final,
            "peak": self.peak,
            "offset": self.offset,
            "ok": self.ok,
        }


@dataclass(frozen=True)
class LossTuning:
    """The largest tolerable loss and the curve behind it.

    Attributes
    ----------
    loss : float or None
        The largest uniform loss p whose scan up to it passed (None when even the
        smallest positive one fails).
    policy : str
        The policy.
    period, delay, horizon, tolerance : float
        h, D, T and the tolerance.
    lossless_final : float
        The lossless sampled protocol's E Σ‖x_i(T) − θ‖².
    curve : list of LossPoint
        Every loss evaluated, in increasing order.
    notes : list of str
        What backs the answer.
    """

    loss: float | None
    policy: str
    period: float
    delay: int
    horizon: float
    tolerance: float
    lossless_final: float
    curve: list[LossPoint] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def table(self) -> Table:
        """The answer and the curve as every face shows it.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows: list[tuple[Any, ...]] = [
            (fmt(p.loss), fmt(p.final), fmt(p.peak), fmt(p.offset), verdict(p.ok))
            for p in self.curve
        ]
        where = f"{self.policy}, h = {self.period:g}, D = {self.delay}"
        head = (
            f"largest tolerable loss p = {fmt(self.loss)} ({where})"
            if self.loss is not None
            else f"no tolerable loss found ({where})"
        )
        notes = [
            f"bound: E Σ‖x_i(T) − θ‖² <= (1 + {self.tolerance:g})·{fmt(self.lossless_final)} "
            f"(the lossless sampled protocol's at T = {self.horizon:g})",
            *self.notes,
        ]
        return Table.build(
            head,
            ("loss p", "E Σ‖x_i(T) − θ‖²", "peak", "offset ‖x* − 1⊗θ‖", "within the bound"),
            rows,
            notes,
        )

    def to_dict(self) -> dict:
        """What ``ntc tune`` prints as JSON for the loss ``auto``.

        Returns
        -------
        dict
        """
        return {
            "loss": self.loss,
            "policy": self.policy,
            "period": self.period,
            "delay": self.delay,
            "horizon": self.horizon,
            "tolerance": self.tolerance,
            "lossless_final_ms_error": self.lossless_final,
            "curve": [p.to_dict() for p in self.curve],
            "notes": list(self.notes),
        }


def largest_tolerable_loss(
    topology: Any,
    spec: SimulationSpec,
    horizon: float,
    digital: Digital,
    policy: LossPolicy = "skip",
    tolerance: float = 0.1,
) -> LossTuning:
    """The largest uniform loss whose exact error at T, and every smaller loss's, stays
    within (1 + tolerance) of the lossless sampled protocol's (see the module docstring).

    Parameters
    ----------
    topology : Topology
        One fixed topology.
    spec : SimulationSpec
        The scenario (θ, a linear f, x(0), the gain).
    horizon : float
        T.
    digital : Digital
        The period h and delay D (its loss is ignored).
    policy : str, optional
        ``skip``, ``rescale`` or ``hold``.
    tolerance : float, optional
        The allowed relative excess.

    Returns
    -------
    LossTuning

    Raises
    ------
    InputError
        Not one fixed topology, a non-linear f, or a bad option (naming the parameter).
    """
    t_end = require_horizon("horizon", horizon)
    tol = require_number("tolerance", tolerance, minimum=0.0)
    policy = require_policy("policy", policy)
    if not isinstance(topology, Topology):
        raise InputError("lossy links are modelled on one fixed topology", field="loss")
    base = spec.replace(T=t_end, digital=None, method="exact")
    if not base.noise.linear:
        raise InputError("the exact moments need a linear f (a scalar or a matrix)", field="loss")
    gain = make_gain(base.gain)[0]
    pm = prepare_modes(topology, base, gain)
    s = pm.systems[0]
    delay = digital.delay
    grid = sampled_grid(topology, pm, digital, t_end, np.array([t_end]))  # h: its loss aside

    def run(p: float) -> tuple[float, float, float]:
        with np.errstate(all="ignore"):
            lm = loss_moments(
                s, grid, gain, pm.eps0, pm.theta, delay, np.full(s.n_edges, p), policy
            )
        return float(lm.moments.ms_error[-1].sum()), lm.peak, lm.offset

    lossless = run(0.0)[0]
    bound = (1.0 + tol) * lossless
    curve: list[LossPoint] = []

    def point(p: float) -> LossPoint:
        final, peak, off = run(p)
        pt = LossPoint(float(p), final, peak, off, bool(final <= bound))
        curve.append(pt)
        return pt

    n_scan = int(round(1.0 / STEP))
    last_ok, first_bad = 0.0, None
    point(0.0)
    for m in range(1, n_scan):
        p = m * STEP
        if point(p).ok:
            last_ok = p
        else:
            first_bad = p
            break
    notes = [
        f"scanned p = 0, {STEP:g}, {2 * STEP:g}, … (every {STEP:g}) up to the first loss "
        "that fails; between scan points the curve is not evaluated"
    ]
    if first_bad is None:
        notes.append(f"every scanned loss up to {last_ok:g} passes")
        answer: float | None = last_ok
    else:
        lo, hi = last_ok, first_bad
        while hi - lo > ATOL:
            mid = 0.5 * (lo + hi)
            if point(mid).ok:
                lo = mid
            else:
                hi = mid
        notes.append(
            f"refined by bisection between {last_ok:g} (passes) and {first_bad:g} (fails) "
            f"to {ATOL:g}"
        )
        answer = lo if lo > 0 else None
    curve.sort(key=lambda q: q.loss)
    return LossTuning(answer, policy, digital.period, delay, t_end, tol, lossless, curve, notes)


__all__ = ["ATOL", "STEP", "LossPoint", "LossTuning", "largest_tolerable_loss"]
