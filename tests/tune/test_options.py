"""Tests of :mod:`ntc_design.tune.options`: the options of both tuners, written once and
validated when made."""

import dataclasses
import inspect

import pytest

from ntc_design.errors import InputError
from ntc_design.tune import PowerOptions, ScheduleOptions, TuneOptions, options_for, tune
from ntc_design.tune.deadline import tune_schedule
from ntc_design.tune.run import tune_power


def test_the_tuning_signature_is_written_once():
    """tune, tune_power and tune_schedule take the topology, the spec, T, the options and
    a progress callback (at most 6 parameters; issue 48: tune took 17); every option is
    a field of one dataclass."""
    for f in (tune, tune_power, tune_schedule):
        names = list(inspect.signature(f).parameters)
        assert names == ["topology", "spec", "horizon", "options", "progress"], f
    shared = [f.name for f in dataclasses.fields(TuneOptions)]
    assert shared == ["require", "tune_delta", "eps", "certificate"]
    power = [f.name for f in dataclasses.fields(PowerOptions)][len(shared) :]
    schedule = [f.name for f in dataclasses.fields(ScheduleOptions)][len(shared) :]
    assert power == ["method", "max_evaluations", "landscape", "bounds", "family"]
    assert schedule == ["max_gain", "max_peak", "check_paths", "levels"]
    assert PowerOptions().max_evaluations == 160 and ScheduleOptions().check_paths == 200


@pytest.mark.hostile
@pytest.mark.parametrize(
    "make, line",
    [
        (lambda: PowerOptions(require="sure"), "require"),  # type: ignore[arg-type]
        (lambda: PowerOptions(eps=-1.0), "eps: must be a positive number"),
        (lambda: PowerOptions(method="both"), "method: expected auto, exact or mc, got 'both'"),  # type: ignore[arg-type]
        (lambda: PowerOptions(max_evaluations=5), "max_evaluations: expected an integer"),
        (lambda: PowerOptions(max_evaluations=True), "max_evaluations: expected an integer"),
        (lambda: PowerOptions(family="exp"), "family: only 'power'"),  # type: ignore[arg-type]
        (lambda: ScheduleOptions(max_gain=-1.0), "max_gain: expected a number in"),
        (lambda: ScheduleOptions(max_peak=0.0), "max_peak: must be a positive number"),
        (lambda: ScheduleOptions(check_paths=-1), "check_paths: expected an integer in [0,"),
        (lambda: options_for("best"), "schedule: expected power or optimal, got 'best'"),
        (lambda: options_for("optimal", "mc"), 'schedule="optimal": uses exact moments (method="mc" is for schedule="power")'),
        (lambda: options_for("power", max_peak=1.0), 'max_peak: applies to schedule="optimal"'),
    ],
)
def test_a_bad_option_is_refused_when_made(make, line):
    with pytest.raises(InputError) as exc:
        make()
    assert str(exc.value).startswith(line) or line in str(exc.value), str(exc.value)


def test_options_for_picks_the_tuner_by_its_name():
    assert options_for("power", "mc", max_evaluations=20) == PowerOptions(
        method="mc", max_evaluations=20
    )
    assert options_for("optimal", "auto", check_paths=0) == ScheduleOptions(check_paths=0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        PowerOptions().method = "mc"  # type: ignore[misc]
