"""Tune the gain c(t) (and δ) of a scenario for a deadline: :func:`tune`."""

from .deadline import MonteCarloCheck, ScheduleTuneResult, tune_schedule
from .entry import options_for, tune, tuned_scenario
from .family import BASELINE, PowerGain
from .objective import (
    OBJECTIVES,
    Curve,
    ExactObjective,
    ExpressionObjective,
    MonteCarloObjective,
    Objective,
    objective_for,
)
from .options import PowerOptions, ScheduleOptions, TuneOptions
from .result import Landscape, TuneResult
from .run import delta_range, tune_power
from .search import Dimension, Trace, search

__all__ = [
    "BASELINE",
    "OBJECTIVES",
    "Curve",
    "Dimension",
    "ExactObjective",
    "ExpressionObjective",
    "Landscape",
    "MonteCarloCheck",
    "MonteCarloObjective",
    "Objective",
    "PowerGain",
    "PowerOptions",
    "ScheduleOptions",
    "ScheduleTuneResult",
    "Trace",
    "TuneOptions",
    "TuneResult",
    "delta_range",
    "objective_for",
    "options_for",
    "search",
    "tune",
    "tune_power",
    "tune_schedule",
    "tuned_scenario",
]
