"""Tests of :mod:`ntc_design.simulate.montecarlo`."""

from dataclasses import replace

import numpy as np

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    NoiseModel,
    kernels,
    modes,
)
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.kernels import tile_width
from ntc_design.simulate.modes import FixedModes
from ntc_design.simulate.montecarlo import MonteCarloSpec, run, run_chunk
from ntc_design.simulate.system import mode_system
from tests.conftest import X0
from tests.support.rng import _run


def _kernel_spec(system_, paths, block=500, scheme="explicit", t_end=0.3, grid=None):
    grid = grid or build_grid(t_end, 1e-3, np.arange(0, t_end + 1e-9, 0.1))
    gain = lambda t: 1.0 / (1.0 + t)  # noqa: E731
    return MonteCarloSpec(
        modes=FixedModes((system_,)), grid=grid, gain=gain, theta=np.array(THETA, float), x_init=X0,
        n_agents=7, dim=3, paths=paths, seed=11, block_size=block, store_paths=5, scheme=scheme,
    )  # fmt: skip


def test_few_paths_still_make_two_blocks(g1_system):
    _, s = g1_system
    for paths, blocks in ((1, 1), (2, 2), (30, 2), (200, 2), (1000, 2), (1001, 3), (2000, 4)):
        assert _kernel_spec(s, paths).n_blocks == blocks
    spec = _kernel_spec(s, 30)
    a, b = run(spec, workers=1), run(spec, workers=2)
    assert a.count == 30 and np.array_equal(a.sq, b.sq) and np.array_equal(a.stored, b.stored)


def test_batch_and_tile_sizes_do_not_change_results(g1_system, monkeypatch):
    _, s = g1_system
    spec = _kernel_spec(s, 40)
    ref = run_chunk(spec, [0, 1])
    monkeypatch.setattr(modes, "XI_BYTES", 8 * 20 * 16 * 3)  # 3 steps per batch
    monkeypatch.setattr(kernels, "TILE_MIN", 3)  # tiles of 3 paths (and a last one of 2)
    monkeypatch.setattr(kernels, "TILE_MAX", 3)
    assert tile_width(20, 21) == 3
    other = run_chunk(spec, [0, 1])
    for q, r in zip(ref, other, strict=True):
        assert np.array_equal(q.sq, r.sq) and np.array_equal(q.state, r.state)


def test_results_do_not_depend_on_workers(g1):
    a, b = _run(g1, workers=1), _run(g1, workers=2)
    np.testing.assert_array_equal(a.mc.mean, b.mc.mean)
    assert a.parameters["rng"] == "xoshiro"


def _spec(g1, paths=1100, block=250):
    des = nd.design(g1, THETA, thresholds=False)
    sysm = mode_system(des, NoiseModel())
    grid = build_grid(0.3, 1e-3, np.arange(0, 0.31, 0.1))
    gain = lambda t: 1.0 / (1.0 + t)  # noqa: E731
    return MonteCarloSpec(
        modes=FixedModes((sysm,)), grid=grid, gain=gain, theta=des.theta, x_init=X0, n_agents=7, dim=3,
        paths=paths, seed=11, block_size=block, store_paths=5,
    )  # fmt: skip


def test_same_seed_identical_across_workers_and_chunks(g1):
    spec = _spec(g1)
    a = run(spec, workers=1, blocks_per_chunk=5)
    b = run(spec, workers=2, blocks_per_chunk=1)
    c = run(spec, workers=2, blocks_per_chunk=2)
    for other in (b, c):
        assert np.array_equal(a.sq, other.sq) and np.array_equal(a.m2, other.m2)
        assert np.array_equal(a.centre, other.centre)
        assert np.array_equal(a.state, other.state) and np.array_equal(a.stored, other.stored)
    d = run(_spec(g1), workers=1)
    assert np.array_equal(a.sq, d.sq)
    e = run(replace(spec, seed=12), workers=1)
    assert not np.array_equal(a.sq, e.sq)


def test_merged_spread_is_the_exact_spread_of_all_paths():
    # values far from 0 with a spread of about 1: Σx² − (Σx)²/n loses every digit there
    from fractions import Fraction

    from ntc_design.simulate.montecarlo import PartialStats, centred_spread, merge

    rng = np.random.default_rng(np.random.SeedSequence(5))
    values = 1e8 + rng.standard_normal((261, 2))
    parts, start = [], 0
    for b, k in enumerate((1, 7, 250, 3)):  # uneven blocks, a single path among them
        chunk = values[start : start + k]
        centre, m2 = centred_spread(chunk)
        z = np.zeros((1, 2))
        parts.append(
            PartialStats([b], k, chunk.sum(0)[None], m2[None], centre[None], z, np.zeros((0, 1, 2)))
        )
        start += k
    got = merge(parts[::-1])  # merged in block order whatever the order given
    for c in range(2):
        col = [Fraction(v) for v in values[:, c]]
        mu = sum(col) / len(col)
        exact = float(sum((v - mu) ** 2 for v in col))
        # to the digits the data have: 1e8's ulp is 1.5e-8, the block means' δ carry it
        assert abs(got.m2[0, c] - exact) <= 1e-9 * exact, (got.m2[0, c], exact)
        assert abs(got.centre[0, c] - float(mu)) <= 2e-16 * float(mu)
        naive = float(np.sum(values[:, c] ** 2) - np.sum(values[:, c]) ** 2 / len(col))
        assert abs(naive - exact) > 1e-3 * exact  # what the old sums gave: no digit right


def test_identical_paths_have_a_zero_width_band_and_bands_do_not_depend_on_workers(g1):
    from ntc_design.simulate import simulate

    kw = dict(
        T=0.2, dt=1e-3, paths=37, seed=3, initial=X0, save_every=0.1, method="mc", block_size=8
    )
    a = simulate(g1, THETA, workers=1, **kw)
    b = simulate(g1, THETA, workers=2, **kw)
    # t = 0: every path starts at X0, so the band is the mean itself (it was 3e-7 wide)
    assert np.array_equal(a.mc.lo[0], a.mc.mean[0]) and np.array_equal(a.mc.hi[0], a.mc.mean[0])
    assert np.all(a.mc.hi[1:] - a.mc.lo[1:] > 1e-6 * a.mc.mean[1:])  # the noise spreads them
    for name in ("mean", "lo", "hi"):
        np.testing.assert_array_equal(getattr(a.mc, name), getattr(b.mc, name))
    again = simulate(g1, THETA, workers=1, **kw)
    np.testing.assert_array_equal(again.mc.hi, a.mc.hi)
