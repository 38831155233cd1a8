"""What a simulation returns: :class:`SimulationResult` (curves, designs, parameters,
run statistics) and its JSON summary."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from ..errors import optional_module, quote
from ..present.rows import Table, fmt
from ..present.svg import curve_svg
from ..protocol import ProtocolDesign
from ..protocol.lemma1 import DESIGN_KEYS
from .digital import DigitalRun
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


@dataclass(frozen=True, eq=False)
class MeanSquareBand:
    """A Monte Carlo estimate of E‖x_i − θ‖² at the save times with its 95 % band (what a
    figure draws; also read back from a run's CSV).

    Attributes
    ----------
    mean, lo, hi : numpy.ndarray
        (S, N): the sample mean of ‖x_i − θ‖² and its 95 % band (NaN with one path).
    """

    mean: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


@dataclass(frozen=True, eq=False)
class MonteCarloCurves(MeanSquareBand):
    """The Monte Carlo statistics at the save times: E‖x_i − θ‖² with its 95 % band, the
    mean state, the stored sample paths.

    Attributes
    ----------
    mean, lo, hi : numpy.ndarray
        (S, N): the sample mean of ‖x_i − θ‖² and its 95 % band (NaN with one path).
    mean_state : numpy.ndarray
        (S, Nd): the sample mean of x.
    paths : numpy.ndarray
        (k, S, Nd): the first k sample paths.
    count : int
        The number of paths.
    valid_saves : int
        The save times every path reached with a finite state.
    """

    mean_state: np.ndarray
    paths: np.ndarray
    count: int
    valid_saves: int

    def truncated(self, k: int) -> MonteCarloCurves:
        """The curves at the first ``k`` save times.

        Parameters
        ----------
        k : int
            Save times kept.

        Returns
        -------
        MonteCarloCurves
        """
        return replace(
            self,
            mean=self.mean[:k],
            lo=self.lo[:k],
            hi=self.hi[:k],
            mean_state=self.mean_state[:k],
            paths=self.paths[:, :k],
        )


@dataclass(frozen=True)
class Failure:
    """Where a Monte Carlo run stopped: the first non-finite state.

    Attributes
    ----------
    t : float
        The time of the first non-finite state.
    agent : object
        The agent's label (its index inside the kernels).
    path : int
        The sample path.
    save_index : int
        The save times recorded before it.
    """

    t: float
    agent: Any
    path: int
    save_index: int

    def to_dict(self) -> dict:
        """The failure as JSON data.

        Returns
        -------
        dict
            ``t``, ``agent``, ``path``, ``save_index``.
        """
        return asdict(self)


@dataclass(frozen=True)
class RunStats:
    """What a simulation run cost.

    Attributes
    ----------
    steps : int
        Time steps of the grid.
    path_steps : int
        Steps × paths.
    mc_seconds, path_steps_per_second : float or None
        Monte Carlo wall time and throughput (None without Monte Carlo).
    exact_seconds : float or None
        Wall time of the exact moments.
    exact_rk4_steps : int or None
        RK4 steps of the exact moments.
    engine : dict or None
        The remote engine's description, when one ran the paths.
    """

    steps: int
    path_steps: int
    mc_seconds: float | None = None
    path_steps_per_second: float | None = None
    exact_seconds: float | None = None
    exact_rk4_steps: int | None = None
    engine: dict | None = None

    def to_dict(self) -> dict:
        """The statistics as JSON data, without the ones not measured.

        Returns
        -------
        dict
        """
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """A simulation's outcome: the mean-square error curves E‖x_i − θ‖² (Monte Carlo with a
    95 % band, and exact moments where the noise is linear) at the save times, the designs
    per mode, the parameters, run statistics, notes and any failure."""

    labels: tuple
    theta: np.ndarray
    save_times: np.ndarray
    designs: dict[str, ProtocolDesign]
    mc: MonteCarloCurves | None
    exact: Moments | None
    parameters: dict
    stats: RunStats
    notes: tuple[str, ...] = ()
    failure: Failure | None = None
    grid: TimeGrid | None = None
    digital: DigitalRun | None = None  # the sampled protocol's figures (a digital run)

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
            "run": self.stats.to_dict(),
            "notes": list(self.notes),
            "failure": self.failure.to_dict() if self.failure is not None else None,
        }
        if self.mc is not None:
            out["final_ms_error_mc"] = dict(zip(lab, self.mc.mean[-1].tolist(), strict=True))
            out["final_ms_error_mc_band"] = {
                a: [lo, hi]
                for a, lo, hi in zip(
                    lab, self.mc.lo[-1].tolist(), self.mc.hi[-1].tolist(), strict=True
                )
            }
            out["sample_paths"] = path_spread(self)
        if self.exact is not None:
            out["final_ms_error_exact"] = dict(
                zip(lab, self.exact.ms_error[-1].tolist(), strict=True)
            )
            out["min_ms_error_exact"] = float(np.min(self.exact.ms_error.sum(axis=1)))
        if self.digital is not None:
            out["digital"] = self.digital.to_dict()
        return out

    def __repr__(self) -> str:
        methods = [m for m, x in (("Monte Carlo", self.mc), ("exact", self.exact)) if x is not None]
        t_end = float(self.save_times[-1]) if self.save_times.size else 0.0
        failed = f", diverged at t = {self.failure.t:.6g}" if self.failure is not None else ""
        return (
            f"SimulationResult(N={len(self.labels)}, T={t_end:g}, {len(self.save_times)} save "
            f"times, {' and '.join(methods) or 'no curves'}{failed})"
        )

    def table(self) -> Table:
        """The run in brief, as every face shows it: the methods and the total error
        Σ_i E‖x_i − θ‖² at the first and last save times (Monte Carlo with its band, exact).

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows: list[tuple] = [("agents N", len(self.labels)), ("save times", self.save_times.size)]
        if self.save_times.size:
            rows.append(("horizon T", f"{float(self.save_times[-1]):g}"))
        if self.mc is not None and self.save_times.size:
            rows.append(("Monte Carlo paths", self.mc.count))
            for k, when in ((0, "t = 0"), (-1, "T")):
                band = (
                    f" [{fmt(float(np.sum(self.mc.lo[k])))}, {fmt(float(np.sum(self.mc.hi[k])))}]"
                )
                rows.append(
                    (
                        f"Σ_i E‖x_i − θ‖² at {when} (Monte Carlo)",
                        fmt(float(self.mc.mean[k].sum())) + band,
                    )
                )
        if self.exact is not None and self.save_times.size:
            for k, when in ((0, "t = 0"), (-1, "T")):
                rows.append(
                    (f"Σ_i E‖x_i − θ‖² at {when} (exact)", float(self.exact.ms_error[k].sum()))
                )
        dg = self.digital
        if dg is not None:
            ks = f"K = {dg.steps}"
            if dg.partial_step > 0:  # the run ends at T with part of a period
                ks += f" and a partial step of {dg.partial_step:.6g}"
            rows.append(("sampling", f"period h = {dg.period:g}, delay D = {dg.delay}, {ks}"))
            if dg.ms_error_peak is not None:
                rows.append(("peak of Σ_i E‖x_i − θ‖² (exact, sampled)", dg.ms_error_peak))
            if dg.continuous_final_ms_error is not None:
                rows.append(
                    ("Σ_i E‖x_i − θ‖² at T (exact, continuous)", dg.continuous_final_ms_error)
                )
        if self.failure is not None:
            rows.append(("diverged", f"t = {self.failure.t:.6g}, agent {self.failure.agent}"))
        return Table.build("simulation", ("quantity", "value"), rows, self.notes)

    def _repr_html_(self) -> str:
        curves = []
        if self.mc is not None:
            curves.append(("Monte Carlo Σ_i", self.mc.mean.sum(axis=1), "#1f5fbf"))
        if self.exact is not None:
            curves.append(("exact Σ_i", self.exact.ms_error.sum(axis=1), "#c8322d"))
        return curve_svg(self.save_times, curves) + self.table().html()

    def to_pandas(self):
        """The curves as a tidy table; see :func:`simulation_frame`.

        Returns
        -------
        pandas.DataFrame
            Columns t, agent, mc, lo, hi, exact; one row per save time and agent.
        """
        return simulation_frame(self)


def tidy_columns(res: SimulationResult) -> dict[str, np.ndarray]:
    """The tidy table's columns (see :func:`simulation_frame`), as NumPy arrays.

    Parameters
    ----------
    res
        A :class:`ntc_design.simulate.SimulationResult`.

    Returns
    -------
    dict of str to numpy.ndarray
        :data:`TIDY_COLUMNS`, in order, one entry per (save time, agent).
    """
    t = np.asarray(res.save_times, dtype=float)
    labels = [str(a) for a in res.labels]
    s, n = t.size, len(labels)
    nan = np.full((s, n), math.nan)
    mc = res.mc
    return {
        "t": np.repeat(t, n),
        "agent": np.tile(np.array(labels, dtype=object), s),
        "mc": (mc.mean if mc is not None else nan).reshape(-1),
        "lo": (mc.lo if mc is not None else nan).reshape(-1),
        "hi": (mc.hi if mc is not None else nan).reshape(-1),
        "exact": (res.exact.ms_error if res.exact is not None else nan).reshape(-1),
    }


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
    pd = optional_module("pandas", "tables", "a data frame of the result")

    return pd.DataFrame(tidy_columns(res), columns=list(TIDY_COLUMNS))


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
    paths = res.mc.paths
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


def mc_summary(part: PartialStats) -> MonteCarloCurves:
    """Mean of ‖x_i − θ‖² and its 95% confidence band (normal approximation). With fewer
    than two paths there is no band: ``lo`` and ``hi`` are NaN (shown as none), never a
    zero-width band.

    Parameters
    ----------
    part : PartialStats
        The Monte Carlo sums over the paths.

    Returns
    -------
    MonteCarloCurves
    """
    p = part.count
    mean = part.sq / p
    if p < 2:
        lo = hi = np.full_like(mean, np.nan)
    else:
        var = part.m2 / (p - 1)  # Chan's merged squared deviations: >= 0, 0 for equal paths
        half = Z95 * np.sqrt(var / p)
        lo, hi = np.maximum(mean - half, 0.0), mean + half
    return MonteCarloCurves(
        mean=mean,
        lo=lo,
        hi=hi,
        mean_state=part.state / p,
        paths=part.stored,
        count=p,
        valid_saves=part.valid_saves,
    )


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
        A new result; ``res`` is unchanged.
    """
    exact = res.exact
    if exact is not None:
        exact = Moments(exact.t[:k], exact.mean[:k], exact.ms_error[:k], exact.second, exact.steps)
    return replace(
        res,
        mc=res.mc.truncated(k) if res.mc is not None else None,
        exact=exact,
        save_times=res.save_times[:k],
    )


def finish(res: SimulationResult, part: PartialStats | None) -> SimulationResult:
    """The result, or :class:`SimulationDiverged` when a path met NaN or overflow: the
    result is then cut to the save times every path reached, with the failure's agent
    named by its label (one message for every kind of topology).

    Parameters
    ----------
    res : SimulationResult
        The complete result (its ``failure`` None).
    part : PartialStats or None
        The Monte Carlo sums, None without Monte Carlo.

    Returns
    -------
    SimulationResult
        ``res`` when no path failed.

    Raises
    ------
    SimulationDiverged
        A path met NaN or overflow; the truncated result is attached.
    """
    raw = part.failure if part is not None else None
    if raw is None:
        return res
    lab = res.labels[raw["agent"]]
    fail = Failure(
        t=float(raw["t"]), agent=lab, path=int(raw["path"]), save_index=int(raw["save_index"])
    )
    cut = replace(truncate_result(res, fail.save_index), failure=fail)
    kept = (
        f"results kept up to t = {cut.save_times[-1]:.6g}"
        if cut.save_times.size
        else "no results kept"
    )
    raise SimulationDiverged(
        f"simulation diverged (NaN or overflow) by t = {fail.t:.6g} at agent "
        f"{quote(lab)} (path {fail.path}); {kept}",
        cut,
    )
