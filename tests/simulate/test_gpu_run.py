"""Tests of :mod:`ntc_design.simulate.gpu_run`: path for path, the GPU's paths are the
CPU kernel's (fixed G1 in both layouts, a switching set, a schedule-table gain, several
chunks, a delay D against a NumPy recursion, a divergence), and so are the statistics.
On numba-cuda's simulator unless NTC_GPU_TESTS=device (then larger: 1,000 steps)."""

import numpy as np
import pytest

from ntc_design.gain.schedule import schedule_from_document
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    FixedModes,
    MonteCarloSpec,
    NoiseModel,
    build_grid,
    montecarlo,
    simulate,
)
from ntc_design.simulate.gpu import GpuEngine
from ntc_design.simulate.gpu_run import ModeArrays, Schedule, check_batch
from ntc_design.simulate.grid import StepGains
from ntc_design.simulate.kernels import kernel_arrays, numpy_step
from ntc_design.simulate.prepare import prepare_modes
from ntc_design.simulate.rng import normals, path_states
from ntc_design.simulate.spec import SimulationSpec
from tests.conftest import X0
from tests.support.gpu import REL_TOL, cpu_and_gpu, relative_gap, sizes

pytestmark = pytest.mark.usefixtures("cuda_device")
NOISE = NoiseModel(0.4, 0.3)


def _agree(cpu, gpu) -> float:
    """The paths' and the statistics' agreement; returns the paths' relative gap."""
    gap = relative_gap(cpu.mc.paths, gpu.mc.paths)
    assert gap <= REL_TOL, gap
    assert cpu.mc.paths.shape[0] >= 2  # several paths compared, each at every save time
    for a, b in ((cpu.mc.mean, gpu.mc.mean), (cpu.mc.mean_state, gpu.mc.mean_state)):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(gpu.mc.hi, cpu.mc.hi, rtol=1e-9)
    np.testing.assert_allclose(gpu.mc.lo, cpu.mc.lo, rtol=1e-9)
    # every path starts at X0: a band of width 0 on both (Chan's merge on the device too)
    assert np.array_equal(gpu.mc.hi[0], gpu.mc.mean[0]) and np.array_equal(
        gpu.mc.lo[0], gpu.mc.mean[0]
    )
    assert np.array_equal(cpu.mc.hi[0], cpu.mc.mean[0])
    assert gpu.stats.engine["engine"] == "gpu"
    return gap


@pytest.mark.parametrize("layout", ["fused", "sparse"])
def test_g1_paths_are_the_cpu_kernels(g1, layout):
    paths, t_end, block = sizes((5, 0.02, 2), (256, 1.0, 100))
    if layout == "sparse":  # a thread per (row, path): slower on the simulator
        paths, t_end = sizes((3, 0.01), (64, 1.0))
    cpu, gpu = cpu_and_gpu(
        g1, THETA, layout=layout, gain="1/(1+t)", noise=NOISE, initial=X0, T=t_end, dt=1e-3,
        paths=paths, seed=4, block_size=block, store_paths=paths, save_every=t_end / 2,
    )  # fmt: skip
    _agree(cpu, gpu)
    assert cpu.mc.count == paths and not np.array_equal(gpu.mc.paths[0], gpu.mc.paths[1])


@pytest.mark.filterwarnings("ignore:Assumption 2 fails")  # the paper's G3
def test_switching_set_paths_are_the_cpu_kernels(switching_set):
    paths, t_end = sizes((3, 0.05), (128, 2.0))
    # dt 2e-3 and dwell 0.02: a switch every 10 steps, modes of different edge counts
    cpu, gpu = cpu_and_gpu(
        switching_set, THETA, gain="1/(1+t)", noise=NOISE, T=t_end, dt=2e-3, paths=paths,
        seed=1, block_size=2, store_paths=paths, save_every=t_end / 2,
    )  # fmt: skip
    assert len(set(cpu.grid.mode.tolist())) >= 2
    _agree(cpu, gpu)


def test_schedule_table_gain_paths_are_the_cpu_kernels(g1):
    paths, t_end = sizes((3, 0.02), (128, 1.0))
    gain = schedule_from_document(
        {"t": [0.0, 0.01, 0.5, 2.0], "c": [1.5, 0.4, 0.9, 0.5], "tail": "1/(1+t)"}
    )
    cpu, gpu = cpu_and_gpu(
        g1, THETA, gain=gain, noise=NOISE, initial=X0, T=t_end, dt=1e-3, paths=paths, seed=2,
        store_paths=paths, save_every=t_end / 2,
    )  # fmt: skip
    _agree(cpu, gpu)


def _spec(g1, *, paths, t_end, dt, gain, block_size, seed=0, save_every=None):
    """A MonteCarloSpec of G1 built by hand (no step-size guard: divergence on purpose)."""
    spec = SimulationSpec.build(THETA, noise=NOISE, initial=X0, T=t_end, dt=dt)
    pm = prepare_modes(g1, spec, lambda t: np.ones_like(t))
    saves = np.arange(0, t_end + 1e-12, save_every or t_end)
    grid = build_grid(t_end, dt, saves, pm.segments)
    return MonteCarloSpec(
        modes=FixedModes(tuple(pm.systems)), grid=grid, gain=gain, theta=pm.theta, x_init=pm.x_init,
        n_agents=pm.n, dim=pm.d, paths=paths, seed=seed, block_size=block_size,
        store_paths=paths,
    )  # fmt: skip


def test_chunks_of_blocks_merge_as_one_run(g1, cuda_device, monkeypatch):
    from ntc_design.simulate import gpu_run

    spec = _spec(g1, paths=5, t_end=0.01, dt=1e-3, gain=lambda t: 1 / (1 + t), block_size=2)
    whole = GpuEngine().run_mc(spec)
    monkeypatch.setattr(gpu_run, "CHUNK_BYTES", 1)  # one block per chunk
    chunked = GpuEngine().run_mc(spec)
    assert chunked.blocks == whole.blocks == [0, 1, 2]
    np.testing.assert_array_equal(chunked.stored, whole.stored)
    np.testing.assert_allclose(chunked.sq, whole.sq, rtol=1e-14)
    assert chunked.stored_index == list(range(5)) and chunked.count == 5


def test_a_divergence_is_reported_at_the_cpus_time_path_and_agent(g1):
    # c = 10⁶ on steps of 0.1: explicit Euler grows by ~10⁶ a step, past 1e150 in ~25
    spec = _spec(
        g1, paths=3, t_end=3.0, dt=0.1, gain=lambda t: np.full_like(t, 1e6), block_size=1,
        save_every=0.1,
    )  # fmt: skip
    cpu = montecarlo.run(spec, workers=1)
    gpu = GpuEngine().run_mc(spec)
    assert cpu.failure is not None and gpu.failure == cpu.failure
    assert gpu.valid_saves == cpu.valid_saves > 1
    v = cpu.valid_saves
    np.testing.assert_allclose(gpu.sq[:v], cpu.sq[:v], rtol=1e-9)


def _numpy_delayed(spec, delay: int) -> np.ndarray:
    """The digital recursion with delay D in NumPy (the CPU's normals, drawn by
    rng.normals in each path's stream order): every path's state after the last step."""
    s = spec.mode_systems()[0]
    grid, bp = spec.grid, spec.block_paths
    c = spec.gain(grid.t[:-1])
    h = np.diff(grid.t)
    out = []
    for b in range(spec.n_blocks):
        p = min(bp, spec.paths - b * bp)
        st = path_states(spec.seed, b, p)
        ring = [np.tile(spec.x_init, (p, 1)) for _ in range(delay + 1)]  # x_k, …, x_{k−D}
        for k in range(grid.n_steps):
            xi = normals(st, 2 * s.n_edges)
            y = ring[-1].copy()
            numpy_step(y, xi, c[k] * h[k], c[k] * np.sqrt(h[k]), s)
            ring = [ring[0] + (y - ring[-1]), *ring[:-1]]
        out.append(ring[0])
    return np.concatenate(out)


@pytest.mark.parametrize("delay", [0, 2])
def test_delayed_recursion_against_numpy(g1, delay):
    spec = _spec(g1, paths=3, t_end=0.01, dt=1e-3, gain=lambda t: 1 / (1 + t), block_size=2)
    object.__setattr__(spec, "delay", delay)  # what the digital recursion's spec carries
    gpu = GpuEngine().run_mc(spec)
    want = _numpy_delayed(spec, delay)
    assert relative_gap(want, gpu.stored[:, -1]) <= 1e-11
    if delay:  # the delay changes the paths
        assert relative_gap(_numpy_delayed(spec, 0), gpu.stored[:, -1]) > 1e-6


@pytest.mark.parametrize("delay", [0, 2])
def test_delayed_recursion_against_the_cpu_kernel(g1, delay):
    from ntc_design.simulate import kernels

    spec = _spec(g1, paths=3, t_end=0.01, dt=1e-3, gain=lambda t: 1 / (1 + t), block_size=2)
    object.__setattr__(spec, "delay", delay)
    gpu = GpuEngine().run_mc(spec)
    s, grid, bp = spec.mode_systems()[0], spec.grid, spec.block_paths
    c = spec.gain(grid.t[:-1])
    h = np.diff(grid.t)
    for b in range(spec.n_blocks):  # the CPU's blocks, each from its own seeds
        p0, p = b * bp, min(bp, spec.paths - b * bp)
        x = np.tile(spec.x_init, (p, delay + 1))  # the CPU kernel's ring: x_j in slot j mod (D+1)
        args = (
            x, path_states(spec.seed, b, p), 2 * s.n_edges, 0,
            grid.n_steps, c * h, c * np.sqrt(h), *kernel_arrays(s), True, p,
        )  # fmt: skip
        kernels.em_steps_rng(*args, delay=delay, k_base=0)
        slot = (grid.n_steps % (delay + 1)) * s.nd
        assert relative_gap(x[:, slot : slot + s.nd], gpu.stored[p0 : p0 + p, -1]) <= REL_TOL


@pytest.mark.filterwarnings("ignore:Assumption 2 fails")
def test_mode_arrays_list_each_agents_edges_in_ascending_order(switching_set):
    spec = SimulationSpec.build(THETA, noise=NOISE, T=0.1)
    pm = prepare_modes(switching_set, spec, lambda t: np.ones_like(t))
    ma = ModeArrays.of_systems(pm.systems)
    for m, s in enumerate(pm.systems):
        assert ma.e_cnt[m] == s.n_edges
        for i in range(pm.n):
            ids = ma.eids[ma.eptr[m, i] : ma.eptr[m, i + 1]]
            assert ids.tolist() == np.flatnonzero(s.dst == i).tolist()
        indptr = kernel_arrays(s)[0]
        np.testing.assert_array_equal(ma.iptr[m] - ma.iptr[m, 0], indptr)
    assert ma.e_max == max(s.n_edges for s in pm.systems) and ma.d3


def test_schedule_stops_at_the_cpus_checks_and_saves():
    grid = build_grid(1.0, 0.01, [0.0, 0.25, 1.0])
    sched = Schedule.of(grid, StepGains.of(grid, 1 / (1 + grid.t[:-1])), 40)
    assert sched.stops.tolist() == [25, 40, 80, 100]
    assert sched.saves == {0: 0, 25: 1, 100: 2}
    np.testing.assert_allclose(sched.ch, np.diff(grid.t) / (1 + grid.t[:-1]))
    # the CPU's batch: 64 steps, fewer when a batch of normals would pass 16 MiB
    assert check_batch(500, 8) == 64 and check_batch(10_000, 100) == 1


def test_a_digital_run_on_the_gpu_equals_the_cpu_run(g1):
    """The sampled, delayed protocol end to end: the same paths and statistics."""
    kw = dict(
        T=0.5, paths=6, seed=3, initial=np.linspace(-3, 3, 21), method="mc", save_every=0.1,
        digital={"period": 0.05, "delay": 2}, store_paths=6,
    )  # fmt: skip
    cpu = simulate(g1, [1, 2, -1], **kw)
    gpu = simulate(g1, [1, 2, -1], device="gpu", **kw)
    assert relative_gap(cpu.mc.mean, gpu.mc.mean) <= 1e-12


def _numpy_held(x_init, s, grid, c, h, delay, seed, paths, bp) -> np.ndarray:
    """The sampled protocol in NumPy to T, the held input written out: whole steps, then
    x(T) = x_K + s·u_K with the normals step K draws (c_K·s and c_K·s/√h on them)."""
    out = []
    for b in range(-(-paths // bp)):
        p = min(bp, paths - b * bp)
        st = path_states(seed, b, p)
        ring = [np.tile(x_init, (p, 1)) for _ in range(delay + 1)]  # x_k, …, x_{k−D}
        for k in range(grid.n_steps):
            dt = grid.t[k + 1] - grid.t[k]
            root = np.sqrt(h) if k < grid.n_steps - 1 else dt / np.sqrt(h)
            xi = normals(st, 2 * s.n_edges)
            y = ring[-1].copy()
            numpy_step(y, xi, c[k] * dt, c[k] * root, s)
            ring = [ring[0] + (y - ring[-1]), *ring[:-1]]
        out.append(ring[0])
    return np.concatenate(out)


def test_a_digital_run_ending_between_samples_is_the_cpus_and_the_held_input(g1):
    """T = 0.27 with h = 0.05: five samples and a partial step of 0.02 on both kernels,
    the same paths, and both the held input written out in NumPy."""
    kw = dict(
        T=0.27, paths=4, seed=5, initial=X0, method="mc", save_every=0.09, noise=NOISE,
        digital={"period": 0.05, "delay": 1}, store_paths=4, gain="1/(1+t)",
    )  # fmt: skip
    cpu = simulate(g1, THETA, **kw)
    gpu = simulate(g1, THETA, device="gpu", **kw)
    assert cpu.grid.t[-1] == 0.27 and cpu.grid.n_steps == 6 and cpu.save_times[-1] == 0.27
    _agree(cpu, gpu)
    spec = SimulationSpec.build(THETA, noise=NOISE, initial=X0, T=0.27)
    pm = prepare_modes(g1, spec, lambda t: 1 / (1 + t))
    c = 1 / (1 + cpu.grid.t[:-1])
    want = _numpy_held(pm.x_init, pm.systems[0], cpu.grid, c, 0.05, 1, 5, 4, 2)
    assert relative_gap(want, cpu.mc.paths[:, -1]) <= 1e-11
    assert relative_gap(want, gpu.mc.paths[:, -1]) <= REL_TOL
