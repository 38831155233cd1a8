"""Tests of :mod:`ntc_design.simulate.options`."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    MonteCarlo,
    NoiseModel,
    SaveAt,
    SimulationSpec,
    Stepping,
    UniformInitial,
)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: SaveAt(), "save_every"),
        (lambda: SaveAt(every=0.1, times=[1.0]), "save_every"),
        (lambda: SaveAt(every=0.0), "save_every"),
        (lambda: SaveAt(every=float("nan")), "save_every"),
        (lambda: SaveAt(times=[]), "save_times"),
        (lambda: SaveAt(times=[-1.0]), "save_times"),
        (lambda: SaveAt(times=[[1.0]]), "save_times[0]"),
        (lambda: SaveAt(times=[float("inf")]), "save_times[0]"),
        (lambda: Stepping(kind="rk4"), "stepping"),
        (lambda: Stepping(dt=0), "dt"),
        (lambda: Stepping(kind="intrinsic", ds=0), "ds"),
        (lambda: Stepping(kind="intrinsic", ds=-1e-3), "ds"),
        (lambda: Stepping(kind="intrinsic", ds=float("nan")), "ds"),
        (lambda: MonteCarlo(paths=0), "paths"),
        (lambda: MonteCarlo(paths=2.0), "paths"),
        (lambda: MonteCarlo(paths=True), "paths"),
        (lambda: MonteCarlo(seed=1.5), "seed"),
        (lambda: MonteCarlo(seed=-1), "seed"),
        (lambda: MonteCarlo(seed=2**200), "seed"),
        (lambda: MonteCarlo(store_paths=-1), "store_paths"),
        (lambda: MonteCarlo(block_size=0), "block_size"),
        (lambda: MonteCarlo(workers=0), "workers"),
        (lambda: MonteCarlo(workers=10**9), "workers"),
        (lambda: UniformInitial(1, -1, 0), "initial.uniform"),
        (lambda: UniformInitial(0, float("nan"), 0), "initial.uniform[1]"),
        (lambda: UniformInitial(0, 1, 0.5), "initial.seed"),
        (lambda: SimulationSpec.build([[1, 2], [3]]), "theta[0]"),
        (lambda: SimulationSpec.build([1, float("nan"), 2]), "theta[1]"),
        (lambda: SimulationSpec.build([0, 0, 0]), "theta"),
        (lambda: SimulationSpec.build(THETA, T=float("inf")), "T"),
        (lambda: SimulationSpec.build(THETA, margin=-1), "margin"),
        (lambda: SimulationSpec.build(THETA, gain=3.0), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="t" * 20000), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="__import__('os')"), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="1/(1+"), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="x + t"), "gain"),
        (lambda: SimulationSpec.build(THETA, method="magic"), "method"),
        (lambda: SimulationSpec.build(THETA, resample=0), "resample"),
        (lambda: SimulationSpec.build(THETA, colour=1), "colour"),
        (lambda: SimulationSpec.build(THETA, initial=[1, float("inf")]), "initial[1]"),
        (lambda: SimulationSpec.build(THETA, T=1.0, save_times=[2.0]), "save_times"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(-0.1)), "noise.sigma"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(float("nan"))), "noise.sigma"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, True)), "noise.f"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, np.ones(3))), "noise.f"),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, np.full((3, 3), np.nan))),
            "noise.f",
        ),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3, {(1, 2): -1.0})),
            "noise.sigma_edges 1->2",
        ),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3, {(1, 2): np.nan})),
            "noise.sigma_edges 1->2",
        ),
        # issue 41, item 7: integers beyond the float range raised OverflowError, and a
        # subnormal T halved to 0 in the gain's samples
        (lambda: SimulationSpec.build([1, 10**400, 2]), "theta[1]: an integer of 401 digits"),
        (lambda: SimulationSpec.build(THETA, T=10**400), "T: an integer of 401 digits"),
        (lambda: SimulationSpec.build(THETA, T=5e-324), "T: 5e-324 is shorter than"),
        (lambda: SimulationSpec.build(THETA, margin=10**400), "margin: an integer"),
        (lambda: SimulationSpec.build(THETA, dt=10**400), "dt: an integer"),
        (lambda: SimulationSpec.build(THETA, save_every=10**400), "save_every: an integer"),
        (lambda: SimulationSpec.build(THETA, initial=[0, 10**400]), "initial[1]: an integer"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(10**400)), "noise.sigma: an"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, 10**400)), "noise.f: an"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, [[10**400]])), "noise.f: an"),
        (lambda: MonteCarlo(paths=10**400), "paths: must be at most"),
        (lambda: MonteCarlo(block_size=10**400), "block_size: must be at most"),
        (lambda: MonteCarlo(store_paths=10**400), "store_paths: must be at most"),
        (lambda: UniformInitial(-(10**400), 1, 0), "initial.uniform"),
    ],
)
def test_option_objects_check_themselves(make, needle):
    with pytest.raises(InputError) as exc:
        make()
    msg = str(exc.value)
    assert msg.startswith(needle), msg
    assert "\n" not in msg
