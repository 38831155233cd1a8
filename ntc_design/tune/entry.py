""":func:`tune`: one entry for both questions a deadline asks, the best power law
(:func:`.run.tune_power`) or the best schedule (:func:`.deadline.tune_schedule`), and
:func:`tuned_scenario`, the scenario that either result writes."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from ..errors import InputError, Option
from ..simulate import SimulationSpec
from ..simulate.prepare import AnyTopology
from .deadline import CHECK_PATHS, ScheduleTuneResult, tune_schedule
from .problem import DEFAULT_MAX_GAIN
from .result import TuneResult
from .run import MAX_EVALUATIONS, tune_power

#: What ``schedule`` may be.
SCHEDULES = ("power", "optimal")


def tune(
    topology: AnyTopology,
    spec: SimulationSpec,
    horizon: float,
    *,
    require: str = "both",
    tune_delta: bool = False,
    eps: float | None = None,
    method: str = "auto",
    max_evaluations: int = MAX_EVALUATIONS,
    landscape: bool = True,
    certificate: bool = True,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    family: str = "power",
    schedule: str = "power",
    max_gain: float = DEFAULT_MAX_GAIN,
    max_peak: float | None = None,
    check_paths: int = CHECK_PATHS,
    progress: Callable[..., None] | None = None,
) -> TuneResult | ScheduleTuneResult:
    """Tune the gain for a deadline T: minimise E Σ_i ‖x_i(T) − θ‖² over the family
    c(t) = a·(b + t)^(−γ) (and δ), or with ``schedule="optimal"`` over every schedule
    c(t) on [0, T] by optimal control of the exact moment equations.

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario: θ, noise, x(0), δ or ΔC, and for Monte Carlo the paths, seed, dt.
    horizon : float
        The deadline T.
    require : {"both", "mean-square"}, optional
        The theorems the power law must satisfy: γ ∈ [0.51, 1] for both (mean square and
        almost sure), γ ∈ [0.05, 1] for mean square only.
    tune_delta : bool, optional
        Also choose a common δ in :func:`.run.delta_range`.
    eps : float, optional
        Report when each gain first reaches E Σ‖x_i − θ‖² ≤ ε.
    method : {"auto", "exact", "mc"}, optional
        The power family's objective (auto: exact moments where they apply); the
        schedule always uses exact moments.
    max_evaluations : int, optional
        The power family's search budget.
    landscape : bool, optional
        The power family's contour map over (a, γ).
    certificate : bool, optional
        Certify the tuned design.
    bounds : mapping of str to (float, float), optional
        The power family's narrower ranges for ``a``, ``b``, ``gamma`` or ``delta``.
    family : {"power"}, optional
        The gain family: a·(b + t)^(−γ) (the only one).
    schedule : {"power", "optimal"}, optional
        ``optimal``: the schedule on [0, T] with an admissible tail (see
        :mod:`.optimal`).
    max_gain : float, optional
        ``optimal``: the upper bound on c.
    max_peak : float, optional
        ``optimal``: the bound M on sup_t E Σ‖x_i(t) − θ‖².
    check_paths : int, optional
        ``optimal``: Monte Carlo paths of the evidence (0: none).
    progress : callable, optional
        ``optimal``: called with a line per stage.

    Returns
    -------
    TuneResult or ScheduleTuneResult

    Raises
    ------
    InputError
        A bad option, or a scenario the objective refuses.

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.tune import tune
    >>> from ntc_design.simulate import NoiseModel, SimulationSpec
    >>> spec = SimulationSpec.build([1, 2, -1], noise=NoiseModel(0.4, 0.3))
    >>> r = tune(nd.load("examples/g1.yaml"), spec, 2.0, max_evaluations=30,
    ...          landscape=False, certificate=False)
    >>> r.ms_error_T["tuned"] <= r.ms_error_T["baseline"]
    True
    """
    if family != "power":
        raise InputError(
            f"only 'power' (a·(b + t)^(−γ)) is available, got {family!r}", field="family"
        )
    if schedule not in SCHEDULES:
        raise InputError(f"expected power or optimal, got {schedule!r}", field="schedule")
    if schedule == "power":
        if max_peak is not None:
            raise InputError("applies to ", Option("schedule", "optimal"), field="max_peak")
        return tune_power(
            topology,
            spec,
            horizon,
            require=require,
            tune_delta=tune_delta,
            eps=eps,
            method=method,
            max_evaluations=max_evaluations,
            landscape=landscape,
            certificate=certificate,
            bounds=bounds,
            progress=progress,
        )
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
    return tune_schedule(
        topology,
        spec,
        horizon,
        require=require,
        tune_delta=tune_delta,
        eps=eps,
        max_gain=max_gain,
        max_peak=max_peak,
        certificate=certificate,
        check_paths=check_paths,
        progress=progress,
    )


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


__all__ = ["SCHEDULES", "tune", "tuned_scenario"]
