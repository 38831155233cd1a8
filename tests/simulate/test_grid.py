"""Tests of :mod:`ntc_design.simulate.grid`."""

import numpy as np

from ntc_design.model.paper import THETA
from ntc_design.simulate import simulate
from tests.conftest import X0
from tests.support.simulate import assert_mc_matches_exact, em_exact


def test_save_times_on_switching_instants_keep_their_paths():
    """save_every equal to the dwell: save times within rounding of a switching instant are
    still recorded (they were once left as zeros)."""
    from ntc_design.model import paper
    from ntc_design.simulate import simulate

    res = simulate(
        paper.switching(),
        paper.THETA,
        initial=np.linspace(-3, 3, 21),
        T=20,
        paths=2,
        method="mc",
        save_every=0.02,
        stepping="intrinsic",
        ds=1e-3,
        workers=1,
        block_size=2,
        store_paths=2,
    )
    assert np.all(np.diff(res.grid.save_steps) > 0)
    assert not np.any(np.all(res.mc.paths[0] == 0, axis=1))
    assert np.all(res.mc.mean[1:].sum(axis=1) > 0)


def test_intrinsic_stepping_matches_exact_with_fewer_steps(g1):
    kw = dict(T=50.0, paths=2000, seed=9, initial=X0, save_every=2.5)
    res = simulate(g1, THETA, stepping="intrinsic", ds=1e-3, **kw)
    assert res.stats.steps < 50_000 / 8  # uniform dt = 1e-3 would take 50 000 steps
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em, max_outside=0.2)
    # the intrinsic-time Euler–Maruyama bias against the continuous moments stays O(ds)
    assert np.max(np.abs(em[1:] / res.exact.ms_error[1:] - 1)) < 0.02
