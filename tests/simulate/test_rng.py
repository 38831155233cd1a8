"""Tests of :mod:`ntc_design.simulate.rng`."""

import math

import numpy as np
import pytest
from scipy import stats

from ntc_design.simulate.rng import ZIG_X, NormalSource, normals, path_states
from tests.support.rng import _run

N = 1_000_000


@pytest.fixture(scope="module")
def draws() -> np.ndarray:
    return normals(path_states(12345, 0, 10), N // 10).ravel()


def test_moments(draws):
    se = 1 / math.sqrt(draws.size)
    assert abs(draws.mean()) < 5 * se
    assert abs(draws.var() - 1) < 5 * math.sqrt(2) * se
    assert abs(stats.skew(draws)) < 5 * math.sqrt(6) * se
    assert abs(stats.kurtosis(draws)) < 5 * math.sqrt(24) * se


def test_distribution_and_tails(draws):
    ks = stats.kstest(draws, "norm")
    assert ks.statistic < 1.63 / math.sqrt(draws.size)  # the 1 % critical value
    # chi-square over 50 equiprobable bins
    edges = stats.norm.ppf(np.linspace(0, 1, 51))
    counts = np.histogram(draws, edges)[0]
    chi2 = ((counts - draws.size / 50) ** 2 / (draws.size / 50)).sum()
    assert stats.chi2.sf(chi2, 49) > 1e-3
    # the tail beyond R (the ziggurat's separate branch) and beyond 4.5
    for x in (ZIG_X[1], 4.5):
        p = 2 * stats.norm.sf(x)
        got = np.mean(np.abs(draws) > x)
        assert abs(got - p) < 5 * math.sqrt(p / draws.size)


def test_independence_between_paths_and_steps():
    z = normals(path_states(7, 3, 2000), 500)  # 2000 paths × 500 draws
    se = 1 / math.sqrt(z.size)
    # neighbouring paths (consecutive seeds words) and consecutive draws of one path
    assert abs(np.mean(z[:-1] * z[1:])) < 5 * se
    assert abs(np.mean(z[:, :-1] * z[:, 1:])) < 5 * se
    # the same path index in two blocks
    w = normals(path_states(7, 4, 2000), 500)
    assert abs(np.mean(z * w)) < 5 * se


def test_a_paths_stream_does_not_depend_on_the_block_width():
    a = normals(path_states(3, 1, 10), 50)
    b = normals(path_states(3, 1, 25), 50)
    np.testing.assert_array_equal(a, b[:10])
    assert not np.array_equal(a, normals(path_states(3, 2, 10), 50))


def test_fill_continues_the_stream():
    src = NormalSource("xoshiro", 5, 0, 4)
    one = np.empty((6, 4, 3))
    src.fill(one[:2])
    src.fill(one[2:])
    ref = normals(path_states(5, 0, 4), 18).reshape(4, 6, 3).transpose(1, 0, 2)
    np.testing.assert_array_equal(one, ref)


@pytest.mark.parametrize("rng", ["xoshiro", "numpy"])
def test_monte_carlo_agrees_with_the_exact_moments(g1, rng):
    r = _run(g1, rng=rng)
    mc, ex = r.mc.mean[-1].sum(), r.exact.ms_error[-1].sum()
    half = (r.mc.hi[-1] - r.mc.mean[-1]).sum()  # per-agent half-widths added: conservative
    assert abs(mc - ex) <= half


def test_the_two_generators_differ_and_numpy_keeps_its_streams(g1):
    a, b = _run(g1, rng="numpy"), _run(g1, rng="numpy")
    np.testing.assert_array_equal(a.mc.mean, b.mc.mean)
    assert not np.array_equal(a.mc.mean, _run(g1).mc.mean)
