"""The time grid: every switching instant and save time is a grid point, exactly.

Between consecutive events the step is either uniform (``h <= dt``, the event interval cut
into equal steps) or *intrinsic*: c(t) multiplies both drift and noise, so in the
intrinsic time s = ∫c dt the dynamics have unit gain; steps ``h_k = min(ds / c(t_k), h_max)``
are uniform in s, which makes long horizons cheap for decaying gains.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TimeGrid:
    """The integration grid: K+1 times, the mode of each step and where the save times
    fall on it."""

    t: np.ndarray  # K+1 grid times, t[0] = 0, t[-1] = T
    mode: np.ndarray  # K: mode index of each step [t_k, t_{k+1})
    save_steps: np.ndarray  # grid indices of the save times
    save_times: np.ndarray
    # the sampled protocol's last step when T is not a whole number of periods: a partial
    # step s = T − K·h of the held input, whose noise has variance s²/h (not s)
    noise_last: float | None = None

    @property
    def h(self) -> np.ndarray:
        """The K step sizes."""
        return np.diff(self.t)

    @property
    def n_steps(self) -> int:
        """The number of steps K."""
        return self.t.size - 1

    def noise_h(self) -> np.ndarray:
        """The variance factor of each step's noise: h_k, except a sampled protocol's
        last partial step s (its held noise, drawn for a whole period h, acts for s
        seconds: (s/√h)², :func:`.digital.digital_grid`).

        Returns
        -------
        numpy.ndarray
            K factors; c_k·√(factor) scales step k's normals.
        """
        h = self.h
        if self.noise_last is None or h.size == 0:
            return h
        h = h.copy()
        h[-1] = self.noise_last
        return h


@dataclass(frozen=True, eq=False)
class StepGains:
    """Each step's factors on a grid, computed once per run and shared by every block,
    the CPU and the GPU: c_k·h_k (the drift) and c_k·√(noise factor) (the noise; a
    sampled run's last partial step s has s/√h, :meth:`TimeGrid.noise_h`)."""

    ch: np.ndarray  # (K,) c_k h_k
    cs: np.ndarray  # (K,) c_k √h_k, or c_K s/√h on a sampled run's partial step

    @classmethod
    def of(cls, grid: TimeGrid, c: np.ndarray) -> StepGains:
        """The factors of ``grid`` for the gain's values ``c`` at its step starts.

        Parameters
        ----------
        grid : TimeGrid
            The run's grid.
        c : numpy.ndarray
            c(t_k) at the K step starts (a scalar is broadcast).

        Returns
        -------
        StepGains
        """
        c_all = np.asarray(c, dtype=float) * np.ones(grid.n_steps)
        return cls(c_all * grid.h, c_all * np.sqrt(grid.noise_h()))


def build_grid(
    t_end: float,
    dt: float,
    save_times: Sequence[float] | np.ndarray,
    segments: Sequence[tuple[float, float, int]] | None = None,
    gain: Callable[[np.ndarray], np.ndarray] | None = None,
    intrinsic_ds: float | None = None,
    h_max: float | None = None,
) -> TimeGrid:
    """Grid on [0, t_end] through every save time and every segment boundary.

    Parameters
    ----------
    t_end : float
        The horizon T.
    dt : float
        The uniform step bound (without ``intrinsic_ds``).
    save_times : sequence of float
        Times that must be grid points (clipped to [0, t_end]).
    segments : sequence of (float, float, int), optional
        (start, stop, mode index) covering [0, t_end]; one mode if None.
    gain : callable, optional
        Vectorised c(t), for intrinsic steps.
    intrinsic_ds : float, optional
        Steps h = min(ds / c(t), h_max, time to the next event).
    h_max : float, optional
        The largest intrinsic step.

    Returns
    -------
    TimeGrid
        The grid with every save time and switching instant on it.
    """
    segs = list(segments) if segments else [(0.0, t_end, 0)]
    saves = np.unique(np.clip(np.asarray(save_times, dtype=float), 0.0, t_end))
    events = np.unique(
        np.concatenate([[0.0, t_end], saves, [a for a, _, _ in segs], [b for _, b, _ in segs]])
    )
    events = events[(events >= 0) & (events <= t_end)]
    starts = np.array([a for a, _, _ in segs])
    modes = np.array([m for _, _, m in segs])
    ts: list[np.ndarray] = [np.array([0.0])]
    ms: list[np.ndarray] = []
    for a, b in zip(events[:-1], events[1:], strict=True):
        if b - a <= 1e-14 * max(1.0, b):
            continue
        mode = modes[max(np.searchsorted(starts, a, side="right") - 1, 0)]
        if intrinsic_ds is None:
            k = max(int(np.ceil((b - a) / dt - 1e-9)), 1)
            pts = a + (b - a) * np.arange(1, k + 1) / k
            pts[-1] = b
        else:
            pts_l = []
            t = a
            cap = h_max if h_max is not None else np.inf
            while b - t > 1e-14 * max(1.0, b):
                c = float(gain(np.array([t]))[0]) if gain is not None else 1.0
                h = min(intrinsic_ds / c if c > 0 else cap, cap, b - t)
                if b - t - h < 0.25 * h:  # no sliver step before the event
                    h = b - t
                t = b if h == b - t else t + h
                pts_l.append(t)
            pts = np.array(pts_l)
        ts.append(pts)
        ms.append(np.full(pts.size, mode, dtype=np.int64))
    t = np.concatenate(ts)
    # a save time within rounding of a switching instant (0.02·753 vs 15.06) was merged
    # with it above: look it up with the same tolerance, not at the next grid point
    save_steps = np.searchsorted(t, saves - 1e-14 * np.maximum(1.0, saves))
    save_steps = np.minimum(save_steps, t.size - 1)
    # save times are grid points by construction (equality up to rounding of the cut)
    return TimeGrid(
        t, np.concatenate(ms) if ms else np.zeros(0, np.int64), save_steps, t[save_steps]
    )
