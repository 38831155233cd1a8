"""The prepared modes of a run: the designs per mode (Lemma 1, re-designed per mode of a
switching file or every ``resample`` time units for a topology given as functions of t),
the mode systems, the segments on [0, T) and x(0), after the size checks and before any
time grid (:func:`prepare_modes`, a :class:`PreparedModes`); the digital protocol's
sampling grid on them (:func:`sampled_grid`); c(t) from an expression or a callable
(:func:`make_gain`). :func:`.driver.simulate` runs them; the tuners and the reports
evaluate them. :class:`PreparedModes` is defined beside the moment engines that take it
whole (:mod:`.moments`, which this module imports) and imported from here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, TypeAlias, TypeGuard, cast

import numpy as np

from ..errors import LONG_WORK_SECONDS, InputError, format_seconds, quote, warn_user
from ..expr.tree import numeric_function
from ..model import ExpressionFamily, SwitchingTopology, TimeVaryingTopology, Topology
from ..protocol import ProtocolDesign, design_topology
from ..protocol.agents import require_sampled
from ..protocol.digital import Digital, step_modes
from .budget import (
    check_budget,
    estimate,
    estimate_steps,
    mc_seconds,
)
from .digital import (
    digital_grid,
)
from .grid import TimeGrid

# PreparedModes is defined beside the moment engines that take it (which this module imports)
from .moments import PreparedModes, check_moments_size
from .spec import SimulationSpec
from .system import mode_system

if TYPE_CHECKING:
    from ..model.timevarying import ExpressionTopology

# A string: ExpressionTopology's module loads SymPy, which a fixed topology does not need.
AnyTopology: TypeAlias = "Topology | SwitchingTopology | TimeVaryingTopology | ExpressionTopology"


def is_expression_topology(topology: object) -> TypeGuard[ExpressionTopology]:
    """Whether ``topology`` is an :class:`~ntc_design.model.timevarying.ExpressionTopology`
    (by its base in :mod:`ntc_design.model`: SymPy is not loaded for the other topologies).

    Parameters
    ----------
    topology : object
        Any topology.

    Returns
    -------
    bool
    """
    return isinstance(topology, ExpressionFamily)


MAX_SEGMENTS = 10_000_000  # switching segments on [0, T]
MAX_REDESIGNS = 100_000  # re-designs of a topology given as functions of t


def make_gain(
    gain: str | Callable, field_name: str = "gain"
) -> tuple[Callable[[np.ndarray], np.ndarray], str]:
    """A vectorised c(t) (array in, array of the same shape out) from an expression
    string or a callable, and a label for it.

    Parameters
    ----------
    gain : str or callable
        c(t) as an expression of t, or a function of t.
    field_name : str
        Named in error messages.

    Returns
    -------
    (callable, str)

    Raises
    ------
    InputError
        When the expression does not parse or ``gain`` is neither.
    """
    if isinstance(gain, str):
        return ExpressionGain(gain, field_name), gain
    if not callable(gain):
        raise InputError("expected an expression in t or a callable", field=field_name)

    def c(t):  # a constant expression returns a scalar: broadcast it
        with np.errstate(all="ignore"):  # overflow shows up as a non-finite value, checked
            return np.asarray(gain(np.asarray(t, dtype=float)), dtype=float) * np.ones(np.shape(t))

    return c, str(getattr(gain, "text", None) or getattr(gain, "__name__", "callable"))


class ExpressionGain:
    """c(t) from an expression: pickled as its text and rebuilt where it is unpickled, so
    a spec holding it ships by value to other processes and machines (no code)."""

    def __init__(self, text: str, field_name: str = "gain"):
        self.text, self.field_name = text, field_name
        self._fn = numeric_function(text, field_name)  # NumPy only: no SymPy to simulate

    def __reduce__(self):
        return (ExpressionGain, (self.text, self.field_name))

    def __call__(self, t):  # a constant expression returns a scalar: broadcast it
        with np.errstate(all="ignore"):  # overflow shows up as a non-finite value, checked
            return np.asarray(self._fn(np.asarray(t, dtype=float)), dtype=float) * np.ones(
                np.shape(t)
            )


def _modes(
    topology: AnyTopology, spec: SimulationSpec, protocol: ProtocolDesign | None = None
) -> tuple[
    list[str], Callable[[], dict[str, ProtocolDesign]], list[tuple[float, float, int]], list[str]
]:
    """Mode names, a thunk computing their designs, segments on [0, T), notes."""
    t_end, th, margin = spec.T, spec.theta, spec.margin
    if spec.resample is not None and not isinstance(topology, TimeVaryingTopology):
        raise InputError(
            "applies only to a topology given as functions of t, not to a fixed or switching topology",
            field="resample",
        )
    if isinstance(topology, SwitchingTopology):
        durs = np.array([dur for _, dur in topology.schedule], dtype=float)
        per = float(sum(durs.tolist()))  # Python floats overflow to inf without a warning
        if not np.isfinite(per):
            raise InputError(
                "the period (sum of durations) overflows to infinity", field="schedule"
            )
        if np.any(durs < 1e-12 * per):
            k = int(np.argmax(durs < 1e-12 * per))
            raise InputError(
                f"{durs[k]:g} is below 1e-12 of the period {per:g}; "
                "switching instants would collide in floating point",
                field=f"schedule[{k}].duration",
            )
        n_seg = np.ceil(t_end / per) * len(durs)
        if n_seg > MAX_SEGMENTS:
            raise InputError(
                f"{n_seg:.3g} switching segments on [0, T={t_end:g}] exceed the limit "
                f"{MAX_SEGMENTS:.0e}; shorten T or lengthen the durations",
                field="schedule",
            )
        names = list(topology.modes)
        segments = [(a, b, names.index(m)) for a, b, m in topology.segments(t_end)]
        return (
            names,
            lambda: {
                k: design_topology(topology.modes[k], th, margin, spec.delta, thresholds=False)
                for k in names
            },
            segments,
            [],
        )
    if isinstance(topology, TimeVaryingTopology):
        step = spec.resample if spec.resample is not None else 0.1
        count = np.ceil(t_end / step)
        if count > MAX_REDESIGNS:
            raise InputError(
                f"{count:.3g} re-designs on [0, T={t_end:g}] exceed the limit "
                f"{MAX_REDESIGNS}; raise resample or shorten T",
                field="resample",
            )
        ts = np.arange(0.0, t_end, step)
        names = [f"t={t:g}" for t in ts]
        if len(set(names)) != len(names):  # %g rounding: fall back to indices
            names = [f"t[{k}]" for k in range(ts.size)]
        segments = [(float(t), float(min(t + step, t_end)), k) for k, t in enumerate(ts)]
        note = (
            f"topology given as functions of t: sampled and re-designed every {step:g} time units"
        )
        return (
            names,
            lambda: {
                k: design_topology(topology.at(float(t)), th, margin, spec.delta, thresholds=False)
                for k, t in zip(names, ts, strict=True)
            },
            segments,
            [note],
        )
    if not isinstance(topology, Topology):
        raise InputError(f"expected a Topology, got {type(topology).__name__}", field="topology")
    name = topology.name or "topology"
    if protocol is not None:  # a kept protocol (B_i, δ, x0) on these weights
        if protocol.topology is not topology:
            raise InputError("its topology must be the topology simulated", field="protocol")
        return [name], lambda: {name: protocol}, [(0.0, t_end, 0)], []
    return (
        [name],
        lambda: {name: design_topology(topology, th, margin, spec.delta, thresholds=False)},
        [(0.0, t_end, 0)],
        [],
    )


def edge_count(topology: AnyTopology) -> int:
    """The edges of the topology, or of its largest mode.

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.

    Returns
    -------
    int
    """
    if isinstance(topology, SwitchingTopology):
        return max(len(m.edges) for m in topology.modes.values())
    if isinstance(topology, TimeVaryingTopology):
        return len(topology.weights)
    return len(topology.edges)


def check_size(
    topology: AnyTopology,
    spec: SimulationSpec,
    cfun: Callable,
    n_modes: int,
    n_segments: int,
    workers: int,
) -> None:
    """Estimate memory and work from the input and refuse before allocating (and warn,
    once, of a Monte Carlo that would take long).

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The run's options.
    cfun : callable
        Vectorised c(t) (the steps follow it with intrinsic stepping).
    n_modes, n_segments : int
        Modes and segments on [0, T).
    workers : int
        Processes the Monte Carlo will use.

    Raises
    ------
    InputError
        A run too big for the machine.
    """
    saves = spec.save.count(spec.T)
    st = spec.stepping
    if spec.digital_steps is not None:  # one step per sample
        steps = float(spec.digital_steps[0])
    else:
        steps = estimate_steps(
            spec.T, st.dt, st.intrinsic_ds, st.max_step, cfun, saves + 2 * n_segments
        )
    est = estimate(
        n=topology.n,
        d=topology.dim,
        edges=edge_count(topology),
        modes=n_modes,
        segments=n_segments,
        saves=saves,
        steps=steps,
        paths=spec.mc.paths,
        block_size=spec.mc.block_size,
        store_paths=spec.mc.store_paths,
        workers=workers,
        mc=spec.method != "exact",
        exact=spec.method != "mc",
        mode_field="resample" if isinstance(topology, TimeVaryingTopology) else "topology",
        delay=spec.digital.delay if spec.digital is not None else 0,
    )
    check_budget(est)
    nd = topology.n * topology.dim
    secs = mc_seconds(
        est, nd, edge_count(topology) * topology.dim**2, workers, st.scheme == "implicit"
    )
    # the estimate is the CPU kernel's: a GPU's rate is not known here
    if spec.method != "exact" and spec.mc.device == "cpu" and secs > LONG_WORK_SECONDS:
        warn_user(
            f"paths: {est.path_steps:.3g} path-steps ({spec.mc.paths} paths × "
            f"{est.steps:.3g} steps) on N·d = {nd}: roughly {format_seconds(secs)} with "
            f"{workers} worker(s); fewer paths, a shorter T or a larger dt shorten it "
            "(Ctrl-C stops cleanly, writing nothing)",
            UserWarning,
        )


def prepare_modes(
    topology: Topology | SwitchingTopology | TimeVaryingTopology,
    spec: SimulationSpec,
    cfun: Callable,
    workers: int = 1,
    protocol: ProtocolDesign | None = None,
) -> PreparedModes:
    """The designs (Lemma 1, or the spec's δ), the systems, the segments and x(0) of a
    run, after the size checks and before any time grid.

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network.
    spec : SimulationSpec
        The run's options.
    cfun : callable
        Vectorised c(t) (the work estimate follows it).
    workers : int, optional
        Processes the Monte Carlo will use (memory estimate).
    protocol : ProtocolDesign, optional
        A fixed topology's protocol instead of Lemma 1's design (:func:`simulate`).

    Returns
    -------
    PreparedModes

    Raises
    ------
    InputError
        A run too big for the machine, a bad initial state, exact moments too large.
    """
    names, make_designs, segments, notes = _modes(topology, spec, protocol)
    if workers < spec.mc.workers:
        notes.append(f"workers: {spec.mc.workers} asked, {workers} used (the machine's CPUs)")
    check_size(topology, spec, cfun, len(names), len(segments), workers)
    n, d = topology.n, topology.dim
    if spec.method != "mc" and spec.noise.linear:
        check_moments_size(n * d)
    designs = make_designs()
    for k, des in designs.items():
        if not des.assumption_holds:
            notes.append(
                f"mode {quote(k)}: Assumption 2 fails (the design is used as Lemma 1 gives it)"
            )
    th = next(iter(designs.values())).theta
    systems = [mode_system(designs[k], spec.noise, k) for k in names]
    x_init, ini_notes = spec.initial_state(n, d)
    notes.extend(ini_notes)
    return PreparedModes(names, designs, systems, segments, x_init, th, n, d, notes)


def sampled_grid(
    topology: AnyTopology,
    pm: PreparedModes,
    digital: Digital,
    t_end: float,
    save_times: np.ndarray,
) -> TimeGrid:
    """The sampling grid of the digital protocol on these modes (the mode of each sample
    by the schedule's rule).

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network the modes were prepared from.
    pm : PreparedModes
        Its modes.
    digital : Digital
        The period and delay.
    t_end : float
        T.
    save_times : numpy.ndarray
        Where to record (moved to the nearest sample).

    Returns
    -------
    TimeGrid

    Raises
    ------
    InputError
        h > T or too many steps.
    """
    require_sampled(topology)
    fixed = cast("Topology | SwitchingTopology | TimeVaryingTopology", topology)
    return digital_grid(digital, t_end, save_times, step_mode(fixed, pm, digital.period))[0]


def step_mode(
    topology: Topology | SwitchingTopology | TimeVaryingTopology, pm: PreparedModes, period: float
) -> Callable[[np.ndarray], np.ndarray] | None:
    """The mode index at each sample time: the schedule's rule for a switching set
    (:func:`~ntc_design.protocol.digital.step_modes`), the re-design segment for a sampled
    A(t), None for one topology.

    Parameters
    ----------
    topology : Topology, SwitchingTopology or TimeVaryingTopology
        The network the modes were prepared from.
    pm : PreparedModes
        Its modes.
    period : float
        The sampling period h.

    Returns
    -------
    callable or None
        Sample times to mode indices.
    """
    if isinstance(topology, SwitchingTopology):
        schedule = topology.schedule
        return lambda t: step_modes(schedule, t, pm.names, period)
    if isinstance(topology, TimeVaryingTopology):
        starts = np.array([a for a, _, _ in pm.segments])
        index = np.array([m for _, _, m in pm.segments], dtype=np.int64)
        return lambda t: index[np.clip(np.searchsorted(starts, t, side="right") - 1, 0, None)]
    return None
