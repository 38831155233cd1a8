"""What a simulation returns: :class:`SimulationResult` (curves, designs, parameters,
run statistics) and its JSON summary."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..design import DESIGN_KEYS, ProtocolDesign
from .grid import TimeGrid
from .moments import Moments
from .montecarlo import PartialStats

#: The columns of the tidy table (``ms_error_long.csv``, ``SimulationResult.to_pandas``).
TIDY_COLUMNS = ("t", "agent", "mc", "lo", "hi", "exact")

Z95 = 1.959963984540054


class SimulationDiverged(RuntimeError):
    """NaN or overflow: the message names the time and the agent; ``result`` keeps what
    was computed until then."""

    def __init__(self, msg: str, result: SimulationResult):
        super().__init__(msg)
        self.result = result


@dataclass
class SimulationResult:
    """A simulation's outcome: the mean-square error curves E‖x_i − θ‖² (Monte Carlo with a
    95 % band, and exact moments where the noise is linear) at the save times, the designs
    per mode, the parameters, run statistics, notes and any failure."""

    labels: tuple
    theta: np.ndarray
    save_times: np.ndarray
    designs: dict[str, ProtocolDesign]
    mc: dict | None  # mean, lo, hi (S, N); mean_state (S, Nd); paths (k, S, Nd); count
    exact: Moments | None
    parameters: dict
    stats: dict
    notes: list[str] = field(default_factory=list)
    failure: dict | None = None
    grid: TimeGrid | None = None

    def summary(self) -> dict:
        """The JSON summary written as ``summary.json``.

        Returns
        -------
        dict
            Parameters, topologies, design briefs, save times, run statistics, notes,
            the failure, and the final mean-square errors (with band and sample-path
            spread) of each method.
        """
        lab = [str(a) for a in self.labels]
        out: dict = {
            "parameters": self.parameters,
            "topologies": {k: d.topology.to_dict() for k, d in self.designs.items()},
            "designs": {k: _design_brief(d) for k, d in self.designs.items()},
            "save_times": {
                "count": int(self.save_times.size),
                "first": float(self.save_times[0]),
                "last": float(self.save_times[-1]),
            },
            "run": self.stats,
            "notes": self.notes,
            "failure": self.failure,
        }
        if self.mc is not None:
            out["final_ms_error_mc"] = dict(zip(lab, self.mc["mean"][-1].tolist(), strict=True))
            out["final_ms_error_mc_band"] = {
                a: [lo, hi]
                for a, lo, hi in zip(
                    lab, self.mc["lo"][-1].tolist(), self.mc["hi"][-1].tolist(), strict=True
                )
            }
            out["sample_paths"] = path_spread(self)
        if self.exact is not None:
            out["final_ms_error_exact"] = dict(
                zip(lab, self.exact.ms_error[-1].tolist(), strict=True)
            )
            out["min_ms_error_exact"] = float(np.min(self.exact.ms_error.sum(axis=1)))
        return out

    def to_pandas(self):
        """The curves as a tidy table; see :func:`simulation_frame`.

        Returns
        -------
        pandas.DataFrame
            Columns t, agent, mc, lo, hi, exact; one row per save time and agent.
        """
        return simulation_frame(self)


def simulation_frame(res: SimulationResult):
    """A simulation result as a tidy DataFrame, one row per (save time, agent).

    Parameters
    ----------
    res
        A :class:`ntc_design.simulate.SimulationResult`.

    Returns
    -------
    pandas.DataFrame
        Columns ``t``, ``agent`` (label as text), ``mc`` (Monte Carlo E‖x_i − θ‖²),
        ``lo``, ``hi`` (its 95% band) and ``exact`` (the exact moment curve); a column
        that was not computed is NaN.
    """
    import pandas as pd

    t = np.asarray(res.save_times, dtype=float)
    labels = [str(a) for a in res.labels]
    s, n = t.size, len(labels)
    nan = np.full((s, n), math.nan)
    mc = res.mc
    cols = {
        "t": np.repeat(t, n),
        "agent": np.tile(np.array(labels, dtype=object), s),
        "mc": (mc["mean"] if mc is not None else nan).reshape(-1),
        "lo": (mc["lo"] if mc is not None else nan).reshape(-1),
        "hi": (mc["hi"] if mc is not None else nan).reshape(-1),
        "exact": (res.exact.ms_error if res.exact is not None else nan).reshape(-1),
    }
    return pd.DataFrame(cols, columns=list(TIDY_COLUMNS))


def _design_brief(d: ProtocolDesign) -> dict:
    full = d.to_dict()
    return {k: full[k] for k in DESIGN_KEYS}


def path_spread(res: SimulationResult, late_fraction: float = 0.2) -> dict:
    """How much the stored sample paths still move late in the run.

    Parameters
    ----------
    res : SimulationResult
        A result with Monte Carlo curves.
    late_fraction : float, optional
        The final fraction of the save times to look at.

    Returns
    -------
    dict
        Over the late window, per stored path, max − min of ‖x(t) − 1⊗θ‖ (largest and
        mean), and the mean and spread (std across stored paths) of ‖x(T) − 1⊗θ‖;
        ``{"stored": 0}`` when no path was stored.
    """
    if res.mc is None:
        return {"stored": 0}
    paths = res.mc["paths"]
    if paths.size == 0:
        return {"stored": 0}
    err = np.linalg.norm(paths - np.tile(res.theta, len(res.labels)), axis=2)  # (k, S)
    s = err.shape[1]
    late = err[:, int(np.floor((1 - late_fraction) * (s - 1))) :]
    return {
        "stored": int(paths.shape[0]),
        "late_window": [float(res.save_times[-late.shape[1]]), float(res.save_times[-1])],
        "late_fluctuation_max": float(np.max(late.max(axis=1) - late.min(axis=1))),
        "late_fluctuation_mean": float(np.mean(late.max(axis=1) - late.min(axis=1))),
        "final_error_norm_mean": float(err[:, -1].mean()),
        "final_error_norm_spread": float(err[:, -1].std()) if err.shape[0] > 1 else None,
    }


def mc_summary(part: PartialStats) -> dict:
    """Mean of ‖x_i − θ‖² and its 95% confidence band (normal approximation). With fewer
    than two paths there is no band: ``lo`` and ``hi`` are NaN (shown as none), never a
    zero-width band.

    Parameters
    ----------
    part : PartialStats
        The Monte Carlo sums over the paths.

    Returns
    -------
    dict
        ``mean``, ``lo``, ``hi`` (S, N), ``mean_state``, ``paths``, ``count``, ``valid_saves``.
    """
    p = part.count
    mean = part.sq / p
    if p < 2:
        lo = hi = np.full_like(mean, np.nan)
    else:
        var = np.maximum(part.sq2 / p - mean**2, 0.0) * (p / (p - 1))
        half = Z95 * np.sqrt(var / p)
        lo, hi = np.maximum(mean - half, 0.0), mean + half
    return {
        "mean": mean,
        "lo": lo,
        "hi": hi,
        "mean_state": part.state / p,
        "paths": part.stored,
        "count": p,
        "valid_saves": part.valid_saves,
    }


def truncate_result(res: SimulationResult, k: int) -> SimulationResult:
    """The result cut to its first ``k`` save times (after a divergence).

    Parameters
    ----------
    res : SimulationResult
        The result.
    k : int
        Save times kept.

    Returns
    -------
    SimulationResult
    """
    if res.mc is not None:
        res.mc = {
            key: (
                v[:k]
                if key in ("mean", "lo", "hi", "mean_state")
                else (v[:, :k] if key == "paths" else v)
            )
            for key, v in res.mc.items()
        }
    if res.exact is not None:
        res.exact = Moments(
            res.exact.t[:k],
            res.exact.mean[:k],
            res.exact.ms_error[:k],
            res.exact.second,
            res.exact.steps,
        )
    res.save_times = res.save_times[:k]
    return res
