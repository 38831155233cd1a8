"""The digital protocol's recursion (:mod:`ntc_design.protocol.digital`): its time grid, its
exact first and second moments, and a reference implementation fed given normals.

Exact moments. With the augmented state z_k = (e_k, e_{k−1}, …, e_{k−D}), the recursion is
z_{k+1} = A_k z_k + (noise in the first block), so m_k = E[z_k] and Z_k = E[z_k z_kᵀ]
follow exactly (no sampling error, linear f):

    (Z_{k+1})_00 = Z_00 − τ(L Z_D0 + Z_0D Lᵀ) + τ² L Z_DD Lᵀ + h c_k² Σ_e (g_e g_eᵀ + G_e Z_DD G_eᵀ)
    (Z_{k+1})_0b = Z_0,b−1 − τ L Z_D,b−1      (b = 1 … D)
    (Z_{k+1})_ab = Z_a−1,b−1                  (a, b >= 1)

with τ = h c_k and L = L_B of the step's mode; E‖x_i − θ‖² is the trace of agent i's
d×d block of Z_00. The noise term is :meth:`.moments.MomentRhs.noise`, the one the
continuous moment equations use. Memory: about four ((D+1)·Nd)² matrices, checked
before anything is allocated (:func:`check_digital_moments`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, format_bytes
from ..numerics.memory import available_memory
from ..protocol.digital import Digital
from .grid import TimeGrid
from .moments import MOMENTS_MAX_ND, MomentRecorder, MomentRhs, Moments
from .system import ModeSystem

#: Dense ((D+1)·Nd)² matrices alive during a step of the digital moments.
DIGITAL_COPIES = 4
#: Share of the available memory the digital moments may take.
MEMORY_SHARE = 0.5
#: Estimated seconds above which the digital moments are refused (per step: a fixed
#: overhead plus the dense products).
MAX_SECONDS = 900.0
STEP_OVERHEAD = 4e-5  # seconds of NumPy call overhead per step (measured on G1)
FLOP_SECONDS = 2e-10  # seconds per multiply-add of the dense products


def digital_grid(
    digital: Digital,
    t_end: float,
    save_times: np.ndarray,
    step_mode: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[TimeGrid, list[str]]:
    """The sampling grid t_k = k·h, k = 0 … K (K = round(T/h)), the mode of each step and
    the save times moved to the nearest sample (0 and K·h always among them).

    Parameters
    ----------
    digital : Digital
        The period and delay.
    t_end : float
        The horizon T.
    save_times : numpy.ndarray
        The save times asked for.
    step_mode : callable, optional
        The mode index at each sample time t_k (:func:`~ntc_design.protocol.digital.step_modes`
        for a switching schedule); None: one mode.

    Returns
    -------
    (TimeGrid, list of str)
        The grid and notes (T not a whole number of periods).

    Raises
    ------
    InputError
        h > T, or too many steps.
    """
    k_steps, note = digital.steps(t_end)
    h = digital.period
    t = np.arange(k_steps + 1, dtype=float) * h
    modes = (
        np.asarray(step_mode(t[:-1]), dtype=np.int64)
        if step_mode is not None
        else np.zeros(k_steps, dtype=np.int64)
    )
    idx = np.rint(np.clip(np.asarray(save_times, dtype=float), 0.0, None) / h)
    steps = np.unique(np.concatenate([[0, k_steps], np.clip(idx, 0, k_steps).astype(np.int64)]))
    return TimeGrid(t, modes, steps, t[steps]), [note] if note else []


def digital_moments_bytes(nd_: int, delay: int) -> float:
    """Bytes the exact moments of the delayed recursion need (about).

    Parameters
    ----------
    nd_ : int
        N·d.
    delay : int
        D.

    Returns
    -------
    float
    """
    w = (delay + 1) * nd_
    return DIGITAL_COPIES * 8.0 * w * w


def check_digital_moments(nd_: int, delay: int, k_steps: int) -> None:
    """Refuse, before anything is allocated, digital moments that would not fit in memory
    or would take too long (one line with the estimate).

    Parameters
    ----------
    nd_ : int
        N·d.
    delay : int
        D.
    k_steps : int
        K.

    Raises
    ------
    InputError
        Naming ``digital.delay`` (memory) or ``digital.period`` (work).
    """
    if nd_ > MOMENTS_MAX_ND:
        raise InputError(
            f"method: exact moments at Nd = {nd_} exceed the limit Nd <= {MOMENTS_MAX_ND}; "
            "use method: mc"
        )
    need = digital_moments_bytes(nd_, delay)
    avail = MEMORY_SHARE * available_memory()
    if need > avail:
        raise InputError(
            f"digital.delay: the exact moments of the delayed recursion hold "
            f"((D+1)·Nd)² = ({delay + 1}·{nd_})² numbers, about {format_bytes(need)}, more "
            f"than {format_bytes(avail)} ({MEMORY_SHARE:.0%} of the memory available); "
            "lower the delay or use method: mc"
        )
    w = (delay + 1) * nd_
    secs = k_steps * (STEP_OVERHEAD + FLOP_SECONDS * 3.0 * w * nd_ * min(nd_, 64))
    if secs > MAX_SECONDS:
        raise InputError(
            f"digital.period: the exact moments take K = {k_steps} steps of a "
            f"{w}×{w} recursion, roughly {secs:.3g} s (limit {MAX_SECONDS:g} s); "
            "raise the period, shorten T or use method: mc"
        )


@dataclass(frozen=True)
class DigitalMoments:
    """The digital recursion's exact moments at the save times, with the peak of
    E‖e_k‖² = Σ_i E‖x_i(kh) − θ‖² over every step k = 0 … K and when it happened."""

    moments: Moments
    peak: float
    peak_time: float


@dataclass(frozen=True)
class DigitalRun:
    """What a run of the digital protocol reports beside its curves.

    Attributes
    ----------
    period : float
        h.
    delay : int
        D.
    steps : int
        K = round(T/h).
    ms_error_peak : float or None
        max over k = 0 … K of the exact E‖e_k‖² (None without exact moments).
    peak_time : float or None
        t_k at the peak.
    continuous_final_ms_error : float or None
        The continuous design's exact Σ_i E‖x_i − θ‖² at K·h.
    loss : dict or None
        On lossy links (:mod:`.loss_run`): ``policy``, ``p`` and ``offset``
        (‖lim E x − 1⊗θ‖); None without loss.
    """

    period: float
    delay: int
    steps: int
    ms_error_peak: float | None = None
    peak_time: float | None = None
    continuous_final_ms_error: float | None = None
    loss: dict | None = None

    def to_dict(self) -> dict:
        """The summary's ``digital`` block.

        Returns
        -------
        dict
        """
        return {
            "period": self.period,
            "delay": self.delay,
            "steps": self.steps,
            "ms_error_peak": self.ms_error_peak,
            "peak_time": self.peak_time,
            "continuous_final_ms_error": self.continuous_final_ms_error,
            **({"loss": self.loss} if self.loss is not None else {}),
        }


def digital_moments(
    systems: Sequence[ModeSystem],
    grid: TimeGrid,
    gain: Callable[[np.ndarray], np.ndarray],
    eps0: np.ndarray,
    n: int,
    d: int,
    delay: int,
    abort_above: float | None = None,
) -> DigitalMoments:
    """Exact moments of the sampled, delayed recursion from a deterministic start (the
    initial state held for k < 0).

    Parameters
    ----------
    systems : sequence of ModeSystem
        One system per mode.
    grid : TimeGrid
        The sampling grid (:func:`digital_grid`).
    gain : callable
        Vectorised c(t); c_k = c(t_k).
    eps0 : numpy.ndarray
        e_0 = x(0) − 1⊗θ, length Nd.
    n, d : int
        Agents and state dimension.
    delay : int
        D.
    abort_above : float, optional
        Stop once E‖e_k‖² exceeds it (the remaining save times +∞): a period search
        discards such a candidate without integrating its growth to the end.

    Returns
    -------
    DigitalMoments

    Raises
    ------
    InputError
        Too large (:func:`check_digital_moments`).
    """
    nd_ = n * d
    k_steps = grid.n_steps
    check_digital_moments(nd_, delay, k_steps)
    rhs = [MomentRhs(s, n, d) for s in systems]
    lo = delay * nd_  # the block of e_{k−D}
    z0 = np.tile(np.asarray(eps0, dtype=float), delay + 1)
    zz, m = np.outer(z0, z0), z0.copy()
    nxt = np.empty_like(zz)
    c_all = np.asarray(gain(grid.t[:-1]), dtype=float) * np.ones(k_steps)
    h_all = np.diff(grid.t)
    rec = MomentRecorder(grid.save_times, n, d)
    save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
    if 0 in save_at:
        rec.put(save_at[0], m[:nd_], zz[:nd_, :nd_])
    peak, peak_k = float(np.trace(zz[:nd_, :nd_])), 0
    for k in range(k_steps):
        f = rhs[grid.mode[k]]
        c, h = float(c_all[k]), float(h_all[k])
        tau = c * h
        r = zz[:nd_, :] - tau * (f.l @ zz[lo:, :])  # E[e_{k+1} z_kᵀ]
        top = r[:, :nd_] - tau * (f.l @ r[:, lo:].T).T + (c * c * h) * f.noise(zz[lo:, lo:])
        nxt[:nd_, :nd_] = 0.5 * (top + top.T)
        m0 = m[:nd_] - tau * (f.l @ m[lo:])
        if delay:
            nxt[:nd_, nd_:] = r[:, :lo]
            nxt[nd_:, :nd_] = r[:, :lo].T
            nxt[nd_:, nd_:] = zz[:lo, :lo]
            m[nd_:] = m[:lo].copy()
        m[:nd_] = m0
        zz, nxt = nxt, zz
        tr = float(np.trace(zz[:nd_, :nd_]))
        if not tr <= peak:  # NaN counts as a new peak
            peak, peak_k = tr, k + 1
        if abort_above is not None and not tr <= abort_above:
            rec.ms[rec.k :] = np.inf
            rec.means[rec.k :] = np.nan
            return DigitalMoments(rec.result(zz[:nd_, :nd_], k + 1), math.inf, float(grid.t[k + 1]))
        if k + 1 in save_at:
            rec.put(save_at[k + 1], m[:nd_], zz[:nd_, :nd_])
            rec.k = save_at[k + 1] + 1
    return DigitalMoments(rec.result(zz[:nd_, :nd_].copy(), k_steps), peak, float(grid.t[peak_k]))


__all__ = [
    "DigitalMoments",
    "DigitalRun",
    "check_digital_moments",
    "digital_grid",
    "digital_moments",
    "digital_moments_bytes",
]
