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
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, format_bytes
from ..numerics.memory import available_memory
from ..protocol.digital import Digital
from .grid import TimeGrid
from .moments import MOMENTS_MAX_ND, MomentRecorder, MomentRhs, Moments, PreparedModes

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
    between: bool = False,
    steps: tuple[int, float] | None = None,
) -> tuple[TimeGrid, list[str]]:
    """The sampling grid t_k = k·h, k = 0 … K (K = ⌊T/h⌋), and T after a last partial
    step when T is not a whole number of periods (:meth:`Digital.steps`); the mode of each
    step; the save times moved to the nearest grid point (0 and T always among them), or,
    with ``between``, kept where they are (between samples: the exact moments evaluate the
    held input there; a Monte Carlo run records at grid points only).

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
    between : bool, optional
        Keep save times between samples (``save_steps``: the sample at or before each).
    steps : (int, float), optional
        K and s as :meth:`Digital.steps` gave them for ``t_end`` (a spec's
        ``digital_steps``: decided once per run); None: computed here.

    Returns
    -------
    (TimeGrid, list of str)
        The grid and notes (none today: the run ends at T).

    Raises
    ------
    InputError
        h > T, or too many steps.
    """
    k_full, part = steps if steps is not None else digital.steps(t_end)
    h = digital.period
    t = np.arange(k_full + 1, dtype=float) * h
    if part > 0:
        t = np.append(t, t_end)
    k_steps = t.size - 1
    modes = (
        np.asarray(step_mode(t[:-1]), dtype=np.int64)
        if step_mode is not None
        else np.zeros(k_steps, dtype=np.int64)
    )
    asked = np.clip(np.asarray(save_times, dtype=float), 0.0, t[-1])
    noise_last = part * part / h if part > 0 else None
    if between:
        # a save time within rounding of a grid point is that point (no sliver offset)
        hi = np.clip(np.searchsorted(t, asked), 1, k_steps)
        near = np.where(t[hi] - asked < asked - t[hi - 1], hi, hi - 1)
        asked = np.where(np.abs(t[near] - asked) <= 1e-9 * h, t[near], asked)
        saves = np.unique(np.concatenate([[0.0, t[-1]], asked]))
        at = np.clip(np.searchsorted(t, saves, side="right") - 1, 0, k_steps)
        return TimeGrid(t, modes, at, saves, noise_last), []
    idx = np.clip(np.rint(asked / h), 0, k_full)
    if part > 0:  # past the last sample: T when nearer to it
        idx = np.where(asked > k_full * h + 0.5 * part, k_steps, idx)
    saved = np.unique(np.concatenate([[0, k_steps], idx.astype(np.int64)]))
    return TimeGrid(t, modes, saved, t[saved], noise_last), []


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
            f"exact moments at Nd = {nd_} exceed the limit Nd <= {MOMENTS_MAX_ND}; use method: mc",
            field="method",
        )
    need = digital_moments_bytes(nd_, delay)
    avail = MEMORY_SHARE * available_memory()
    if need > avail:
        raise InputError(
            f"the exact moments of the delayed recursion hold "
            f"((D+1)·Nd)² = ({delay + 1}·{nd_})² numbers, about {format_bytes(need)}, more "
            f"than {format_bytes(avail)} ({MEMORY_SHARE:.0%} of the memory available); "
            "lower the delay or use method: mc",
            field="digital.delay",
        )
    w = (delay + 1) * nd_
    secs = k_steps * (STEP_OVERHEAD + FLOP_SECONDS * 3.0 * w * nd_ * min(nd_, 64))
    if secs > MAX_SECONDS:
        raise InputError(
            f"the exact moments take K = {k_steps} steps of a "
            f"{w}×{w} recursion, roughly {secs:.3g} s (limit {MAX_SECONDS:g} s); "
            "raise the period, shorten T or use method: mc",
            field="digital.period",
        )


@dataclass(frozen=True)
class DigitalMoments:
    """The digital recursion's exact moments at the save times, with the peak of
    E‖e(t)‖² = Σ_i E‖x_i(t) − θ‖² over [0, T] (at a sample or at T: convex between
    samples) and when it happened."""

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
        K = ⌊T/h⌋, the whole steps.
    ms_error_peak : float or None
        The largest exact E‖e(t)‖² over [0, T] (None without exact moments).
    peak_time : float or None
        When (a sample, or T).
    continuous_final_ms_error : float or None
        The continuous design's exact Σ_i E‖x_i − θ‖² at T.
    partial_step : float
        s = T − K·h, the last partial step of the held input (0: T is a whole number
        of periods).
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
    partial_step: float = 0.0
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
            "partial_step": self.partial_step,
            **({"loss": self.loss} if self.loss is not None else {}),
        }


def _held(
    zz: np.ndarray, m: np.ndarray, f: MomentRhs, tau: float, q: float, nd_: int, lo: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One move of the held input: the first block's mean and second moment after
    e ← e − τ L e_{−D} + noise of variance factor q (c²h for a whole step, c²s²/h for a
    part s of one), and E[e_new z_oldᵀ] (the delay line's new cross moments)."""
    r = zz[:nd_, :] - tau * (f.l @ zz[lo:, :])  # E[e_{k+1} z_kᵀ]
    top = r[:, :nd_] - tau * (f.l @ r[:, lo:].T).T + q * f.noise(zz[lo:, lo:])
    return m[:nd_] - tau * (f.l @ m[lo:]), 0.5 * (top + top.T), r


def digital_moments(
    modes: PreparedModes,
    grid: TimeGrid,
    gain: Callable[[np.ndarray], np.ndarray],
    delay: int,
    abort_above: float | None = None,
) -> DigitalMoments:
    """Exact moments of the sampled, delayed recursion from a deterministic start (the
    initial state held for k < 0), the held input included: the last partial step of a
    run to T that is not a whole number of periods, and save times between samples (a
    grid of :func:`digital_grid` with ``between``), at t_k + s from Z_k by the same step
    with τ = c_k s and noise factor c_k² s²/h.

    The peak is the largest E‖e(t)‖² over every grid point, T included: between samples
    E‖e(t_k + s)‖² = a + b s + c s² with c = c_k² (tr L Z_DD Lᵀ + tr 𝓝(Z_DD)/h) >= 0,
    convex in s, so its largest value on a step is at an end of it.

    Parameters
    ----------
    modes : PreparedModes
        The systems per mode and e_0 = x(0) − 1⊗θ
        (:meth:`~ntc_design.simulate.moments.PreparedModes.of` for systems built by hand).
    grid : TimeGrid
        The sampling grid (:func:`digital_grid`).
    gain : callable
        Vectorised c(t); c_k = c(t_k).
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
    n, d, eps0 = modes.n, modes.d, modes.eps0
    nd_ = n * d
    k_steps = grid.n_steps
    check_digital_moments(nd_, delay, k_steps)
    rhs = [MomentRhs(s, n, d) for s in modes.systems]
    lo = delay * nd_  # the block of e_{k−D}
    z0 = np.tile(np.asarray(eps0, dtype=float), delay + 1)
    zz, m = np.outer(z0, z0), z0.copy()
    nxt = np.empty_like(zz)
    c_all = np.asarray(gain(grid.t[:-1]), dtype=float) * np.ones(k_steps)
    h_all = np.diff(grid.t)
    q_all = grid.noise_h()
    period = float(grid.t[1] - grid.t[0]) if k_steps else 1.0  # a whole step comes first
    rec = MomentRecorder(grid.save_times, n, d)
    save_at: dict[int, list[int]] = {}
    for i, k in enumerate(grid.save_steps):
        save_at.setdefault(int(k), []).append(i)

    def record(k: int) -> None:
        for i in save_at.get(k, ()):
            part = float(grid.save_times[i] - grid.t[k])
            if part > 0 and k < k_steps:  # between samples: the held input for s
                c = float(c_all[k])
                f = rhs[grid.mode[k]]
                m0, top, _ = _held(zz, m, f, c * part, c * c * part * part / period, nd_, lo)
                rec.put(i, m0, top)
            else:
                rec.put(i, m[:nd_], zz[:nd_, :nd_])
            rec.k = i + 1

    record(0)
    peak, peak_k = float(np.trace(zz[:nd_, :nd_])), 0
    for k in range(k_steps):
        f = rhs[grid.mode[k]]
        c = float(c_all[k])
        m0, nxt[:nd_, :nd_], r = _held(zz, m, f, c * float(h_all[k]), c * c * q_all[k], nd_, lo)
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
        record(k + 1)
    return DigitalMoments(rec.result(zz[:nd_, :nd_].copy(), k_steps), peak, float(grid.t[peak_k]))


__all__ = [
    "DigitalMoments",
    "DigitalRun",
    "check_digital_moments",
    "digital_grid",
    "digital_moments",
    "digital_moments_bytes",
]
