""":func:`tune`: one entry for both questions a deadline asks, the best power law
(:func:`.power.tune_power`) or the best schedule (:func:`.schedule.tune_schedule`), and
:func:`tuned_scenario`, the scenario that either result writes."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, cast

from ..choices import Schedule, TuneMethod, choices
from ..errors import InputError, Option
from ..simulate import SimulationSpec
from ..simulate.prepare import AnyTopology
from .options import PowerOptions, ScheduleOptions
from .power import tune_power
from .power_result import TuneResult
from .schedule import ScheduleTuneResult, tune_schedule

#: What ``schedule`` may be.
SCHEDULES = choices(Schedule)


def tune(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    options: PowerOptions | ScheduleOptions | None = None,
    progress: Callable[..., None] | None = None,
) -> TuneResult | ScheduleTuneResult:
    """Tune the gain for a deadline T: minimise E Σ_i ‖x_i(T) − θ‖² over the family
    c(t) = a·(b + t)^(−γ) (and δ) with :class:`~.options.PowerOptions`, or with
    :class:`~.options.ScheduleOptions` over every schedule c(t) on [0, T] by optimal
    control of the exact moment equations.

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario: θ, noise, x(0), δ or ΔC, and for Monte Carlo the paths, seed, dt.
    horizon : float
        The deadline T.
    options : PowerOptions or ScheduleOptions, optional
        What to tune and how (each validated on construction); default: the power law,
        ``PowerOptions()``.
    progress : callable, optional
        Called with a line per stage.

    Returns
    -------
    TuneResult or ScheduleTuneResult

    Raises
    ------
    InputError
        A bad horizon, or a scenario the objective refuses.

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.tune import PowerOptions, tune
    >>> from ntc_design.simulate import NoiseModel, SimulationSpec
    >>> spec = SimulationSpec.build([1, 2, -1], noise=NoiseModel(0.4, 0.3))
    >>> opts = PowerOptions(max_evaluations=30, landscape=False, certificate=False)
    >>> r = tune(nd.load("examples/g1.yaml"), spec, 2.0, opts)
    >>> r.ms_error_T["tuned"] <= r.ms_error_T["baseline"]
    True
    """
    if isinstance(options, ScheduleOptions):
        return tune_schedule(topology, spec, horizon, options, progress)
    if options is not None and not isinstance(options, PowerOptions):
        raise InputError(
            f"expected PowerOptions or ScheduleOptions, got {type(options).__name__}",
            field="options",
        )
    return tune_power(topology, spec, horizon, options, progress)


def options_for(
    schedule: str, method: str = "auto", **fields: Any
) -> PowerOptions | ScheduleOptions:
    """The options of a tuner named by a string, from flat fields (what the command line
    gives: ``--schedule`` and one flag per field).

    Parameters
    ----------
    schedule : {"power", "optimal"}
        The tuner.
    method : {"auto", "exact", "mc"}, optional
        The power law's objective (the schedule always uses exact moments).
    **fields
        The fields of :class:`~.options.PowerOptions` or :class:`~.options.ScheduleOptions`.

    Returns
    -------
    PowerOptions or ScheduleOptions

    Raises
    ------
    InputError
        An unknown tuner, ``mc`` for the schedule, or a bad field.
    """
    if schedule not in SCHEDULES:
        raise InputError(f"expected power or optimal, got {schedule!r}", field="schedule")
    if schedule == "power":
        if fields.pop("max_peak", None) is not None:
            raise InputError("applies to ", Option("schedule", "optimal"), field="max_peak")
        return PowerOptions(method=cast("TuneMethod", method), **fields)
    if method not in ("auto", "exact"):
        raise InputError(
            "uses exact moments (",
            Option("method", "mc"),
            " is for ",
            Option("schedule", "power"),
            ")",
            field="schedule",
            value="optimal",
        )
    return ScheduleOptions(**fields)


def tuned_scenario(
    document: Mapping[str, Any],
    source: str | Path,
    out: str | Path,
    result: TuneResult | ScheduleTuneResult,
) -> dict[str, Any]:
    """The scenario document with the tuned gain (and δ) and T = the horizon, its
    topology path made relative to the folder it will be written in.

    Parameters
    ----------
    document : mapping
        The scenario as read.
    source : str or Path
        The scenario file (its topology path is relative to it).
    out : str or Path
        The folder the new scenario goes to.
    result : TuneResult or ScheduleTuneResult
        The tuning (a schedule is written as ``gain: {schedule: schedule.csv, tail}``).

    Returns
    -------
    dict
    """
    doc = dict(document)
    topo = (Path(source).parent / str(doc["topology"])).resolve()
    doc["topology"] = os.path.relpath(topo, Path(out).resolve())
    doc["gain"] = result.scenario_gain()
    value, how = result.headline
    doc["T"] = result.horizon
    if result.stepping:
        doc.update(result.stepping)
    if result.delta is not None:
        doc["delta"] = result.delta
        doc.pop("margin", None)
    doc["description"] = (
        f"{document.get('description', document.get('name', 'scenario'))} — gain tuned by "
        f"ntc tune for T = {result.horizon:g}: E Σ‖x_i(T) − θ‖² = {value:.6g} ({how})"
    )
    return doc


__all__ = ["SCHEDULES", "options_for", "tune", "tuned_scenario"]
