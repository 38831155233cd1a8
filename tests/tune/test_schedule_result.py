"""Tests of :mod:`ntc_design.tune.schedule_result`."""

import dataclasses

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import SimulationSpec, simulate
from ntc_design.simulate.options import SaveAt
from ntc_design.tune.schedule import _monte_carlo
from tests.conftest import ROOT


def test_the_monte_carlo_check_is_the_simulation_with_common_random_numbers():
    top = nd.load(ROOT / "examples" / "g1.yaml")
    spec = SimulationSpec.build(THETA, T=5.0, dt=1e-3, paths=8, seed=3, workers=1)
    gains = {"a": ("1/(1+t)", None), "b": ("0.5/(1+t)", None), "c": ("2/(1+t)", 12.0)}
    exact = {"a": 10.0, "b": 20.0, "c": 30.0}
    notes: list[str] = []
    got = _monte_carlo(top, spec, 0.5, gains, exact, 40, notes)
    assert set(got) == {"a", "b", "c"}
    # δ = 12 with 2/(1+t) is beyond the explicit step's limit at dt = 1e-3: implicit, said
    assert notes == ["Monte Carlo of c: the drift-implicit scheme (explicit unstable)"]
    assert got["c"].lo < got["c"].mean < got["c"].hi and got["c"].paths == 40
    for key in ("a", "b"):
        g, delta = gains[key]
        ref = simulate(
            top,
            spec=spec.replace(
                T=0.5, method="mc", gain=g, delta=delta, save=SaveAt(times=np.array([0.0, 0.5])),
                mc=dataclasses.replace(spec.mc, paths=40, store_paths=0),
            ),
        ).mc  # fmt: skip
        c = got[key]
        assert c.paths == 40 and c.exact == exact[key]
        assert c.mean == pytest.approx(float(ref.mean[-1].sum()), rel=1e-12)
        half = float(np.sum(ref.hi[-1] - ref.mean[-1]))
        assert c.hi - c.mean == pytest.approx(half * 2.5758293035489 / 1.959963984540054, rel=1e-9)
        assert c.lo < c.mean < c.hi
