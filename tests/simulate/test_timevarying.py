"""Tests of :mod:`ntc_design.simulate.timevarying`."""

import numpy as np

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, simulate
from tests.conftest import ROOT, X0


def test_monte_carlo_matches_exact_moments_with_a_of_t(g1tv):
    from tests.support.simulate import assert_mc_matches_exact

    res = simulate(
        g1tv, THETA, T=2.0, dt=1e-3, paths=2000, seed=3, initial=X0, save_every=0.1, workers=1
    )
    assert res.mc.count == 2000 and res.exact is not None
    # over seeds 0-5 the fraction of (time, agent) pairs outside the 95 % band ranged
    # 0.03-0.12 with NumPy's normals and 0.01-0.17 with the kernel's (save times share
    # their paths); the median and worst standardised errors are the sharper checks
    assert_mc_matches_exact(res, max_outside=0.2)
    # the moments really depend on t: frozen at t = 0 they differ
    frozen = simulate(
        g1tv.at(0.0), THETA, T=2.0, paths=1, seed=3, initial=X0, save_every=0.1, method="exact"
    )
    gap = np.abs(frozen.exact.ms_error - res.exact.ms_error) / res.exact.ms_error
    assert np.max(gap[1:]) > 1e-3


def test_compiled_and_numpy_time_varying_steps_agree():
    """A(t) Monte Carlo: the compiled edge kernel (linear f) and the NumPy step (the same f
    as a callable) take the same random numbers and give the same statistics."""
    from ntc_design.simulate import simulate

    top = nd.load(ROOT / "examples" / "g1_tv.yaml")
    kw = dict(T=0.3, dt=1e-3, paths=64, workers=1, method="mc", seed=3)
    a = simulate(top, [1, 2, -1], noise=NoiseModel(sigma=0.4, f=0.3), **kw)
    b = simulate(top, [1, 2, -1], noise=NoiseModel(sigma=0.4, f=lambda z: 0.3 * z), **kw)
    np.testing.assert_allclose(a.mc.mean, b.mc.mean, rtol=1e-12)
    assert np.all(np.diff(a.mc.mean.sum(axis=1)[:5]) != 0)  # the state really moves
