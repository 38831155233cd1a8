"""Simulation layer: Monte Carlo Euler–Maruyama of the noisy SAN and its exact moments."""

from .driver import simulate
from .grid import TimeGrid, build_grid
from .implicit import ImplicitSolver, SolverCache
from .modes import FixedModes
from .moments import Moments, exact_moments
from .montecarlo import MonteCarloSpec, PartialStats, merge, run, run_chunk
from .noise import NoiseModel
from .options import MonteCarlo, Noise, SaveAt, Stepping, UniformInitial
from .prepare import make_gain
from .result import SimulationDiverged, SimulationResult, path_spread
from .spec import SCENARIO_KEYS, SimulationSpec
from .system import ModeSystem, mode_system

__all__ = [
    "SCENARIO_KEYS",
    "FixedModes",
    "ImplicitSolver",
    "ModeSystem",
    "MonteCarlo",
    "MonteCarloSpec",
    "Moments",
    "Noise",
    "NoiseModel",
    "PartialStats",
    "SaveAt",
    "SimulationDiverged",
    "SimulationResult",
    "SimulationSpec",
    "SolverCache",
    "Stepping",
    "TimeGrid",
    "UniformInitial",
    "build_grid",
    "exact_moments",
    "make_gain",
    "merge",
    "mode_system",
    "path_spread",
    "run",
    "run_chunk",
    "simulate",
]
