"""Tests of :mod:`ntc_design.simulate.result`."""

import json

import numpy as np
import pandas as pd
import pytest

from ntc_design.io import files
from ntc_design.model import paper
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    NoiseModel,
    SimulationDiverged,
    simulate,
)
from ntc_design.simulate.scenario import write_outputs
from tests.conftest import X0


def test_tidy_dataframe_and_long_csv(tmp_path):

    res = simulate(
        paper.g1(),
        paper.THETA,
        noise=NoiseModel(0.4, 0.3),
        T=0.5,
        paths=40,
        seed=3,
        save_every=0.1,
        workers=1,
    )
    df = res.to_pandas()
    assert list(df.columns) == ["t", "agent", "mc", "lo", "hi", "exact"]
    assert len(df) == res.save_times.size * 7
    assert not df.isna().any().any()
    row = df[(df.agent == "4") & np.isclose(df.t, 0.3)].iloc[0]
    k = int(np.argmin(np.abs(res.save_times - 0.3)))
    assert row.mc == res.mc.mean[k, 3] and row.exact == res.exact.ms_error[k, 3]
    assert (df.lo <= df.mc).all() and (df.mc <= df.hi).all()
    # pivoting back gives the wide matrix
    wide = df.pivot(index="t", columns="agent", values="exact")[[str(a) for a in res.labels]]
    assert np.array_equal(wide.to_numpy(), res.exact.ms_error)
    write_outputs(res, tmp_path)
    back = pd.read_csv(tmp_path / "ms_error_long.csv", dtype={"agent": str})
    pd.testing.assert_frame_equal(back, df, check_exact=True)
    exact_only = simulate(paper.g1(), paper.THETA, T=0.2, method="exact", save_every=0.1)
    assert exact_only.to_pandas()["mc"].isna().all()


def test_energy_gain_paths_keep_fluctuating(g1):
    """c = (1+t)^(-1/3): the stored paths still move late in the run; with 1/(1+t) they
    settle. Same seed, same paths, only the gain differs."""
    kw = dict(
        T=30.0, dt=2e-3, paths=20, seed=7, initial=X0, save_every=0.5, method="mc", store_paths=10
    )
    wild = simulate(g1, THETA, gain="(1+t)^(-1/3)", **kw).summary()["sample_paths"]
    calm = simulate(g1, THETA, gain="1/(1+t)", **kw).summary()["sample_paths"]
    assert wild["stored"] == 10
    assert wild["late_fluctuation_mean"] > 2.5 * calm["late_fluctuation_mean"]
    assert wild["late_fluctuation_mean"] > 0.5


def test_divergence_names_time_and_agent_and_keeps_results(g1):
    blow = lambda x: 50.0 * x * np.abs(x) ** 3  # noqa: E731 - violates Assumption 1 on purpose
    with pytest.raises(SimulationDiverged, match=r"diverged .* by t = .* at agent \d") as exc:
        simulate(
            g1,
            THETA,
            T=5.0,
            dt=1e-3,
            paths=50,
            initial=X0,
            noise=NoiseModel(0.4, blow),
            save_every=0.01,
            workers=1,
        )
    res = exc.value.result
    assert 0 < res.save_times.size < 501
    assert np.all(np.isfinite(res.mc.mean))
    assert res.failure.t > 0


def test_one_path_has_no_band(g1):
    res = simulate(g1, THETA, T=0.1, paths=1, save_every=0.05, workers=1, method="mc")
    assert np.all(np.isnan(res.mc.lo)) and np.all(np.isnan(res.mc.hi))
    summ = json.loads(json.dumps(files.jsonable(res.summary())))
    assert all(v == [None, None] for v in summ["final_ms_error_mc_band"].values())
    assert summ["sample_paths"]["final_error_norm_spread"] is None
    two = simulate(g1, THETA, T=0.1, paths=2, save_every=0.05, workers=1, method="mc")
    assert np.all(two.mc.hi[1:] > two.mc.lo[1:])
