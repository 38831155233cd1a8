"""The steps every simulation shares, whatever its topology (fixed, switching, sampled or
A(t)): the time grid of a spec, the parameters a result records, the Monte Carlo and
exact-moment runs with their statistics."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .digital import DigitalRun
from .grid import TimeGrid, build_grid
from .moments import Moments
from .montecarlo import PartialStats, run
from .result import RunStats, SimulationResult, finish, mc_summary
from .spec import SimulationSpec


def spec_grid(spec: SimulationSpec, cfun: Callable, segments) -> TimeGrid:
    """The time grid of a run: the spec's horizon, step, save times and step control,
    with a grid point at every switching time.

    Parameters
    ----------
    spec : SimulationSpec
        The run's options.
    cfun : callable
        Vectorised c(t) (the intrinsic step control follows it).
    segments : list of (t0, t1, mode) or None
        Switching segments; None for one topology.

    Returns
    -------
    TimeGrid
    """
    st = spec.stepping
    return build_grid(
        spec.T,
        st.dt,
        spec.save.resolve(spec.T),
        segments,
        gain=cfun,
        intrinsic_ds=st.intrinsic_ds,
        h_max=st.max_step,
    )


def run_parameters(
    spec: SimulationSpec,
    theta: np.ndarray,
    gain_text: str,
    x_init: np.ndarray,
    workers: int,
    grid: TimeGrid,
    modes: list[str],
) -> dict:
    """The parameters a result records: the spec's options and what was resolved from them.

    Parameters
    ----------
    spec : SimulationSpec
        The run's options.
    theta : numpy.ndarray
        θ.
    gain_text : str
        The gain as written.
    x_init : numpy.ndarray
        x(0), length Nd.
    workers : int
        Processes used.
    grid : TimeGrid
        The time grid.
    modes : list of str
        The names of the designs.

    Returns
    -------
    dict
    """
    params = spec.options()
    params.update(
        {
            "theta": theta.tolist(),
            # a schedule is recorded whole (spec.options), an expression as written
            "gain": params["gain"] if isinstance(params["gain"], dict) else gain_text,
            "initial": x_init.tolist(),
            "workers": workers,
            "save_times": int(grid.save_times.size),
            "modes": list(modes),
        }
    )
    return params


def run_stats(grid: TimeGrid, paths: int, mc: dict, exact: dict) -> RunStats:
    """A run's statistics from the grid and what the two methods measured.

    Parameters
    ----------
    grid : TimeGrid
        The time grid.
    paths : int
        Monte Carlo paths.
    mc, exact : dict
        Keyword arguments of :class:`RunStats` measured by each method (may be empty).

    Returns
    -------
    RunStats
    """
    return RunStats(steps=grid.n_steps, path_steps=grid.n_steps * paths, **mc, **exact)


def run_monte_carlo(
    spec: SimulationSpec, mspec, workers: int, progress, engine, notes: list[str]
) -> tuple[PartialStats | None, dict]:
    """The Monte Carlo paths, locally or on ``engine``, when the spec asks for them.

    Parameters
    ----------
    spec : SimulationSpec
        The run's options (``method``).
    mspec : PathBlocks
        What the kernels run.
    workers : int
        Local processes.
    progress : callable(done, total) or None
        Called with path-steps done.
    engine : object or None
        A remote engine (``run_mc``, ``describe``).
    notes : list of str
        Appended to (one path: no band).

    Returns
    -------
    (PartialStats or None, dict)
        The sums over the paths and the :class:`RunStats` fields measured.
    """
    if spec.method not in ("mc", "both"):
        return None, {}
    stats: dict = {}
    t0 = time.perf_counter()
    if engine is not None:
        part = engine.run_mc(mspec, progress)
        stats["engine"] = engine.describe()
    else:
        part = run(mspec, workers, mspec.chunk_blocks, progress)
    sec = max(time.perf_counter() - t0, 1e-9)
    stats.update(
        {"mc_seconds": sec, "path_steps_per_second": mspec.grid.n_steps * mspec.paths / sec}
    )
    if mspec.paths < 2:
        notes.append("one sample path: no confidence band")
    return part, stats


def run_exact(
    spec: SimulationSpec, notes: list[str], moments: Callable[[], Moments]
) -> tuple[Moments | None, dict]:
    """The exact moments when the spec asks for them and f is linear (their work is
    estimated before the grid is built).

    Parameters
    ----------
    spec : SimulationSpec
        The run's options (``method``, ``noise``).
    notes : list of str
        Appended to (moments skipped for a non-linear f).
    moments : callable() -> Moments
        Integrates the moment equations.

    Returns
    -------
    (Moments or None, dict)
        The moments and the :class:`RunStats` fields measured.

    Raises
    ------
    InputError
        ``method: exact`` with a non-linear f, or moments that overflow.
    """
    if spec.method not in ("exact", "both"):
        return None, {}
    if not spec.noise.linear:
        if spec.method == "exact":
            raise InputError("exact moments need a linear f (a scalar or a matrix)", field="method")
        notes.append("exact moments skipped: f is not linear")
        return None, {}
    t0 = time.perf_counter()
    exact = moments()
    stats = {"exact_seconds": time.perf_counter() - t0, "exact_rk4_steps": exact.steps}
    if not (np.all(np.isfinite(exact.ms_error)) and np.all(np.isfinite(exact.mean))):
        raise InputError(
            "the exact moments overflow (not finite) on [0, T]; the noise is too "
            "strong for this gain and horizon (use method: mc, or a shorter T)",
            field="method",
        )
    return exact, stats


@dataclass(frozen=True, eq=False)
class Runs:
    """What the two methods produced: the Monte Carlo sums and the moments, with the
    statistics each measured."""

    part: PartialStats | None
    exact: Moments | None
    mc_stats: dict
    exact_stats: dict


def finish_run(
    labels: tuple,
    theta: np.ndarray,
    grid: TimeGrid,
    designs: dict,
    params: dict,
    spec: SimulationSpec,
    runs: Runs,
    notes: list[str],
    digital: DigitalRun | None = None,
) -> SimulationResult:
    """The result of a run, or :class:`~.result.SimulationDiverged` (one path for every
    kind of topology, :func:`.result.finish`).

    Parameters
    ----------
    labels : tuple
        The agent labels.
    theta : numpy.ndarray
        θ.
    grid : TimeGrid
        The time grid.
    designs : dict
        The designs by mode.
    params : dict
        The parameters recorded (:func:`run_parameters`).
    spec : SimulationSpec
        The run's options.
    runs : Runs
        What the methods produced.
    notes : list of str
        The notes.
    digital : DigitalRun, optional
        The sampled protocol's figures (a digital run).

    Returns
    -------
    SimulationResult

    Raises
    ------
    SimulationDiverged
        A path met NaN or overflow (the truncated result attached).
    """
    res = SimulationResult(
        labels=labels,
        theta=theta,
        save_times=grid.save_times,
        designs=designs,
        mc=mc_summary(runs.part) if runs.part is not None else None,
        exact=runs.exact,
        parameters=params,
        stats=run_stats(grid, spec.mc.paths, runs.mc_stats, runs.exact_stats),
        notes=tuple(notes),
        grid=grid,
        digital=digital,
    )
    return finish(res, runs.part)
