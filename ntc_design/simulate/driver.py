"""The simulation driver: a topology and a :class:`SimulationSpec` in, a
:class:`SimulationResult` out.

Steps: designs per mode (Lemma 1, re-designed per mode of a switching file or every
``resample`` time units for a topology given as functions of t); size check before any
large allocation (:mod:`.budget`); the time grid; the gain checked on it; the
Euler–Maruyama step-size guard; Monte Carlo (:func:`.montecarlo.run`) and/or the exact
moments (:func:`.moments.exact_moments`).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import cast

import numpy as np

from ..errors import InputError, Option, warn_user
from ..model import SwitchingTopology, TimeVaryingTopology, Topology
from ..protocol import ProtocolDesign
from ..protocol.agents import require_sampled
from ..protocol.digital import Digital
from .budget import (
    check_exact_work,
    check_gain,
    estimate_exact_steps,
    gain_samples,
)
from .digital import (
    DigitalMoments,
    DigitalRun,
    check_digital_moments,
    digital_grid,
    digital_moments,
)
from .gpu import GpuEngine, load_cuda
from .grid import TimeGrid
from .loss_mc import LossMonteCarloSpec, lossy_mc_spec
from .loss_run import loss_plan, topology_losses
from .modes import FixedModes
from .moments import Moments, generator_radius
from .montecarlo import MonteCarloSpec
from .prepare import (
    AnyTopology,
    PreparedModes,
    check_size,
    is_expression_topology,
    make_gain,
    prepare_modes,
    step_mode,
)
from .result import SimulationResult
from .spec import SimulationSpec
from .steps import Runs, finish_run, run_exact, run_monte_carlo, run_parameters, spec_grid
from .system import ModeSystem, StepCheck, check_step_size


def _step_size_guard(
    systems: Sequence[ModeSystem],
    grid: TimeGrid,
    c_grid: np.ndarray,
    notes: list[str],
    scheme: str = "explicit",
) -> None:
    """Refuse an unstable Euler–Maruyama grid, warn within a factor 2
    (:func:`.system.check_step_size`: drift eigenvalues and the mean-square limit)."""
    check = check_step_size(systems, grid, c_grid, scheme)
    if check.warning:
        notes.append(check.warning)
        warn_user(check.warning, UserWarning)


def _check_exact_work(
    systems: Sequence[ModeSystem], spec: SimulationSpec, cfun: Callable, gain_text: str, n_seg: int
) -> None:
    """Refuse, before the time grid is built and before any Monte Carlo, exact moments
    that would take too long (:func:`.budget.check_exact_work`; ρ is the largest over the
    modes, and every switch and save time is a step)."""
    rho = np.array([generator_radius(s) for s in systems])
    ts = gain_samples(spec.T)
    c = check_gain(cfun, gain_text, ts)
    events = spec.save.count(spec.T) + n_seg
    steps = estimate_exact_steps(ts, c, float(rho[:, 0].max()), float(rho[:, 1].max()), events)
    check_exact_work(steps, systems[0].nd)


def simulate(
    topology: AnyTopology,
    theta: Sequence[float] | SimulationSpec | None = None,
    spec: SimulationSpec | None = None,
    *,
    progress: Callable[[int, int], None] | None = None,
    engine=None,
    protocol: ProtocolDesign | None = None,
    **options,
) -> SimulationResult:
    """Simulate the SAN with compound noise under the Lemma 1 protocol by Monte Carlo
    Euler–Maruyama (``method`` mc), exact moments (exact, linear f only) or both.

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.
    theta : sequence of float or SimulationSpec
        θ, with the other options as keywords; or a whole spec.
    spec : SimulationSpec, optional
        Instead of ``theta`` and keywords.
    progress : callable(done, total), optional
        Called with path-steps done.
    engine : optional
        Runs the Monte Carlo blocks elsewhere: an object with ``run_mc(spec, progress)``
        and ``describe()``, e.g. :class:`ntc_design.sweep.engines.DaskEngine` or
        :class:`ntc_design.simulate.gpu.GpuEngine`. None: on ``workers`` local processes,
        or on the GPU with ``device="gpu"``. The result is the same either way (to
        rounding on the GPU).
    protocol : ProtocolDesign, optional
        For one fixed topology: the protocol (informed agents, B_i, δ, x0) to run instead
        of Lemma 1's design of ``topology`` (its ``topology`` must be ``topology``), e.g.
        a nominal design kept on realised weights.
    **options
        The flat options of :meth:`SimulationSpec.build` (T, dt, paths, seed, ...).

    Returns
    -------
    SimulationResult

    Raises
    ------
    InputError
        For a bad option, a run too big for the machine, an unstable step size.
    SimulationDiverged
        NaN or overflow in the Monte Carlo (the partial result is attached).

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.simulate import simulate
    >>> run = simulate(nd.load("examples/g1.yaml"), [1, 2, -1], T=1, method="exact")
    >>> round(float(run.exact.ms_error[-1].sum()), 4)  # E Σ_i ‖x_i(1) − θ‖² from x(0) = 0
    15.5132
    """
    spec = _resolve_spec(theta, spec, options)
    if spec.theta.size != topology.dim:
        raise InputError(
            f"expected {topology.dim} numbers (the state dimension d), got {spec.theta.size}",
            field="theta",
        )
    engine = device_engine(spec, engine)
    cfun, gain_text = make_gain(spec.gain)
    workers = min(spec.mc.workers, os.cpu_count() or 1)
    if is_expression_topology(topology):  # A(t)
        from .timevarying import simulate_expression

        if spec.digital is not None:
            require_sampled(topology)
        if spec.delta is not None:
            raise InputError(
                "a topology given as expressions of t takes Lemma 1's δ(t) at every t; "
                "an explicit δ does not apply",
                field="delta",
            )
        check_size(topology, spec, cfun, 1, 1, workers)
        gpu = engine if isinstance(engine, GpuEngine) else None  # A(t) runs locally otherwise
        return simulate_expression(topology, spec, cfun, gain_text, workers, progress, gpu)
    fixed = cast("Topology | SwitchingTopology | TimeVaryingTopology", topology)  # not A(t)
    return _simulate_modes(fixed, spec, cfun, gain_text, workers, progress, engine, protocol)


def check_stepping(topology: AnyTopology, spec: SimulationSpec) -> StepCheck | None:
    """The step-size guard :func:`simulate` applies to a Monte Carlo run of ``spec``
    before any path, alone: the designs and their spectra (once), the grid of the spec's
    stepping, c on it and :func:`.system.check_step_size`. No path is drawn and no kernel
    compiled, so a caller choosing a stable scheme pays for eigenvalues, not for a run.

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The run (its stepping and scheme; ``method`` is taken as ``mc``).

    Returns
    -------
    StepCheck or None
        The guard's outcome; None where this guard does not decide alone (the sampled
        protocol has no step to choose; a topology given as expressions of t is checked
        by its own simulator: run it).

    Raises
    ------
    InputError
        The step is unstable for the scheme (as :func:`simulate` says it), or the spec
        is refused before the guard.
    """
    if spec.digital is not None or is_expression_topology(topology):
        return None
    if spec.theta.size != topology.dim:
        raise InputError(
            f"expected {topology.dim} numbers (the state dimension d), got {spec.theta.size}",
            field="theta",
        )
    cfun, gain_text = make_gain(spec.gain)
    fixed = cast("Topology | SwitchingTopology | TimeVaryingTopology", topology)
    pm = prepare_modes(fixed, spec.replace(method="mc"), cfun)
    grid = spec_grid(spec, cfun, pm.segments)
    c_grid = check_gain(cfun, gain_text, grid.t[:-1])
    check = check_step_size(pm.systems, grid, c_grid, spec.stepping.scheme)
    if check.warning:  # as the run would warn
        warn_user(check.warning, UserWarning)
    return check


def device_engine(spec: SimulationSpec, engine):
    """The engine of a run: ``engine`` as given, or :class:`.gpu.GpuEngine` for
    ``device: gpu`` once the GPU is known to be usable (before any design is computed).

    Parameters
    ----------
    spec : SimulationSpec
        The run's options (``mc.device``, ``method``).
    engine : object or None
        The engine given to :func:`simulate`.

    Returns
    -------
    object or None

    Raises
    ------
    InputError
        ``device: gpu`` with no usable GPU (one line naming what is missing), or with a
        Dask engine.
    """
    if spec.mc.device != "gpu" or spec.method == "exact" or isinstance(engine, GpuEngine):
        return engine
    if engine is not None:
        raise InputError(
            "gpu runs the paths on this machine's GPU; it does not combine with a scheduler (use ",
            Option("device", "cpu", document=True),
            " there)",
            field="device",
        )
    load_cuda()
    return GpuEngine()


def _simulate_modes(
    topology: Topology | SwitchingTopology | TimeVaryingTopology,
    spec: SimulationSpec,
    cfun: Callable,
    gain_text: str,
    workers: int,
    progress,
    engine,
    protocol: ProtocolDesign | None = None,
) -> SimulationResult:
    """:func:`simulate` for one topology, a switching set or a sampled A(t): one design
    per mode, checks, the grid, the runs."""
    pm = prepare_modes(topology, spec, cfun, workers, protocol)
    systems, segments, notes, n, d = pm.systems, pm.segments, pm.notes, pm.n, pm.d
    if spec.digital is not None:
        # exact moments alone are exact between samples too; Monte Carlo records at samples
        grid, more = digital_grid(
            spec.digital,
            spec.T,
            spec.save.resolve(spec.T),
            step_mode(topology, pm, spec.digital.period),
            between=spec.method == "exact",
            steps=spec.digital_steps,
        )
        notes.extend(more)
        check_gain(cfun, gain_text, grid.t[:-1])
        if spec.method != "mc" and spec.noise.linear:
            check_digital_moments(n * d, spec.digital.delay, grid.n_steps)
    else:
        if spec.method != "mc" and spec.noise.linear:
            _check_exact_work(systems, spec, cfun, gain_text, len(segments))
        grid = spec_grid(spec, cfun, segments)
        c_grid = check_gain(cfun, gain_text, grid.t[:-1])
        if spec.method != "exact":
            _step_size_guard(systems, grid, c_grid, notes, spec.stepping.scheme)
    spec.noise.term.check(d, systems[0].n_edges)
    lossy = loss_plan(
        spec.digital,
        systems,
        pm.theta,
        isinstance(topology, Topology),
        topology_losses(topology),
        spec.mc.device,
    )
    if lossy is not None and spec.method != "mc" and spec.noise.linear:
        lossy.check(spec.digital.delay if spec.digital is not None else 0)
    params = run_parameters(spec, pm.theta, gain_text, pm.x_init, workers, grid, pm.names)
    if isinstance(topology, SwitchingTopology):
        params["schedule"] = [{"mode": m, "duration": t} for m, t in topology.schedule]
    mspec = MonteCarloSpec(
        modes=FixedModes(tuple(systems)),
        grid=grid,
        gain=cfun,
        theta=pm.theta,
        x_init=pm.x_init,
        n_agents=n,
        dim=d,
        paths=spec.mc.paths,
        seed=spec.mc.seed,
        block_size=spec.mc.block_size,
        store_paths=spec.mc.store_paths,
        agent_labels=tuple(topology.labels),
        scheme=spec.stepping.scheme,
        rng=spec.mc.rng,
        delay=spec.digital.delay if spec.digital is not None else 0,
    )
    runner: MonteCarloSpec | LossMonteCarloSpec = mspec
    if lossy is not None and spec.method != "exact":  # lossy links run their own blocks
        on_gpu = isinstance(engine, GpuEngine)
        runner = lossy_mc_spec(mspec, lossy, "gpu" if on_gpu else "cpu")
        workers, engine = (1, None) if on_gpu else (workers, engine)
    part, mc_stats = run_monte_carlo(spec, runner, workers, progress, engine, notes)
    if spec.digital is None:
        exact, exact_stats = run_exact(spec, notes, lambda: pm.moments(cfun, grid.save_times))
        runs = Runs(part=part, exact=exact, mc_stats=mc_stats, exact_stats=exact_stats)
        return finish_run(
            tuple(topology.labels), pm.theta, grid, pm.designs, params, spec, runs, notes
        )
    found: list[DigitalMoments] = []
    delay = spec.digital.delay

    def moments() -> Moments:
        if lossy is not None:
            dm = lossy.moments(grid, cfun, pm.eps0, delay)
        else:
            dm = digital_moments(pm, grid, cfun, delay)
        found.append(dm)
        return dm.moments

    exact, exact_stats = run_exact(spec, notes, moments)
    summary = digital_summary(
        spec.digital, grid, found[0] if found else None, pm, cfun, spec.T, spec.digital_steps
    )
    if lossy is not None:
        summary = replace(summary, loss=lossy.block())
        notes.extend(n for n in [lossy.note(pm.n)] if n)
    runs = Runs(part=part, exact=exact, mc_stats=mc_stats, exact_stats=exact_stats)
    return finish_run(
        tuple(topology.labels), pm.theta, grid, pm.designs, params, spec, runs, notes, summary
    )


def digital_summary(
    digital: Digital,
    grid: TimeGrid,
    found: DigitalMoments | None,
    pm: PreparedModes,
    cfun: Callable,
    t_end: float | None = None,
    steps: tuple[int, float] | None = None,
) -> DigitalRun:
    """What a digital run reports beside its curves: the period, the delay, K, the last
    partial step, the peak of the exact E‖e(t)‖² over [0, T] and the continuous design's
    exact error at T (None where the exact moments did not run).

    Parameters
    ----------
    digital : Digital
        The period and delay.
    grid : TimeGrid
        The sampling grid.
    found : DigitalMoments or None
        The digital exact moments, if they ran.
    pm : PreparedModes
        The modes (for the continuous moments).
    cfun : callable
        Vectorised c(t).
    t_end : float, optional
        T (default: the grid's end); the continuous design's moments are taken there.
    steps : (int, float), optional
        K and s to ``t_end`` as the spec decided them (``SimulationSpec.digital_steps``);
        None: :meth:`Digital.steps` at the horizon.

    Returns
    -------
    DigitalRun
    """
    horizon = float(grid.t[-1]) if t_end is None else float(t_end)
    # the continuous moments end at the modes' horizon: never past it (K·h rounding)
    horizon = min(horizon, float(pm.segments[-1][1]))
    continuous = None
    if found is not None:
        cont = pm.moments(cfun, np.array([0.0, horizon]))
        continuous = float(cont.ms_error[-1].sum())
    k_full, part = steps if steps is not None else digital.steps(horizon)
    return DigitalRun(
        period=digital.period,
        delay=digital.delay,
        steps=k_full,
        partial_step=part,
        ms_error_peak=found.peak if found is not None else None,
        peak_time=found.peak_time if found is not None else None,
        continuous_final_ms_error=continuous,
    )


def _resolve_spec(theta, spec: SimulationSpec | None, options: dict) -> SimulationSpec:
    """The spec from ``simulate``'s arguments: a spec, or θ with flat options."""
    if isinstance(theta, SimulationSpec):
        theta, spec = None, theta
    if spec is None:
        if theta is None:
            raise InputError("missing", field="theta")
        return SimulationSpec.build(theta, **options)
    if theta is not None or options:
        raise InputError("give a SimulationSpec or theta with options, not both", field="simulate")
    return spec
