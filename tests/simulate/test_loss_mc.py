"""Tests of :mod:`ntc_design.simulate.loss_mc`: the Monte Carlo on lossy links agrees with
the exact moments within its band for every policy, with either generator, and does not
depend on the workers."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.result import SimulationDiverged

X0_LIN = np.linspace(-3, 3, 21)


def _run(top, policy, **kw):
    opts = {
        "gain": "1/(1+t)",
        "noise": NoiseModel(0.4, 0.3),
        "T": 1.0,
        "paths": 4000,
        "seed": 4,
        "save_every": 0.5,
        "method": "both",
        "initial": X0_LIN.tolist(),
        # 10 % to T = 1: later and at 30 % the error is heavy-tailed (a few paths carry
        # the mean; 40,000 paths approach the exact value, 2,000 fall short of it)
        "digital": Digital(0.1, kw.pop("delay", 1), kw.pop("loss", 0.1), policy),
    }
    opts.update(kw)
    return simulate(top, THETA, **opts)


@pytest.mark.parametrize("policy", ["skip", "rescale", "hold"])
def test_monte_carlo_agrees_with_the_exact_moments_within_its_band(g1, policy):
    res = _run(g1, policy)
    mc, exact = res.mc, res.exact
    assert mc is not None and exact is not None
    half = 0.5 * (mc.hi[-1] - mc.lo[-1])  # the 95 % band (1.96 σ) per agent
    assert np.all(np.abs(mc.mean[-1] - exact.ms_error[-1]) <= 2.5 * half)
    total_sd = np.sqrt(np.sum((half / 1.96) ** 2))  # a bound ignoring correlation is looser
    assert abs(mc.mean[-1].sum() - exact.ms_error[-1].sum()) <= 4 * 7 * total_sd


def test_the_numpy_generator_runs_the_same_recursion(g1):
    res = _run(g1, "rescale", rng="numpy")
    half = 0.5 * (res.mc.hi[-1] - res.mc.lo[-1])
    assert np.all(np.abs(res.mc.mean[-1] - res.exact.ms_error[-1]) <= 2.5 * half)


def test_the_paths_do_not_depend_on_the_workers(g1):
    one = _run(g1, "skip", paths=64, workers=1, method="mc")
    two = _run(g1, "skip", paths=64, workers=2, method="mc")
    assert one.mc.mean.tolist() == two.mc.mean.tolist()


@pytest.mark.hostile
def test_lossy_links_refuse_what_they_do_not_model(g1, switching_set):
    with pytest.raises(InputError, match=r"^digital\.loss: lossy links are modelled on one"):
        _run(switching_set, "skip", T=1.0)


@pytest.mark.parametrize(("policy", "delay"), [("hold", 1), ("skip", 0)])
def test_the_gpu_runs_the_same_paths(g1, cuda_device, policy, delay):
    from tests.support.gpu import REL_TOL, relative_gap, sizes

    # paths 5: blocks of 3 and 2 paths side by side on the device, each from its streams
    paths, t_end = sizes((5, 0.3), (3001, 10.0))
    opts = {"paths": paths, "T": t_end, "save_every": 0.1, "method": "mc", "workers": 1}
    cpu = _run(g1, policy, delay=delay, **opts)
    gpu = _run(g1, policy, delay=delay, device="gpu", **opts)
    assert relative_gap(cpu.mc.mean, gpu.mc.mean) <= REL_TOL
    assert relative_gap(cpu.mc.mean_state, gpu.mc.mean_state) <= REL_TOL
    assert relative_gap(cpu.mc.paths, gpu.mc.paths) <= REL_TOL  # the stored paths
    assert cpu.mc.count == gpu.mc.count == paths
    with pytest.raises(InputError, match=r"^rng: numpy stays on the CPU"):
        _run(g1, "skip", device="gpu", rng="numpy", **opts)


def test_a_divergence_on_the_gpu_is_reported_at_the_cpus_time_path_and_agent(g1, cuda_device):
    from tests.support.gpu import REL_TOL, relative_gap

    opts = {"paths": 6, "T": 12.0, "save_every": 0.5, "method": "mc", "workers": 1}
    with pytest.raises(SimulationDiverged) as on_cpu:
        _run(g1, "rescale", gain="1000", **opts)
    with pytest.raises(SimulationDiverged) as on_gpu:
        _run(g1, "rescale", gain="1000", device="gpu", **opts)
    cpu, gpu = on_cpu.value.result, on_gpu.value.result
    assert cpu.failure is not None and 0 < cpu.failure.t < 12.0
    assert gpu.failure == cpu.failure
    assert str(on_gpu.value) == str(on_cpu.value)
    assert relative_gap(cpu.mc.mean, gpu.mc.mean) <= REL_TOL  # the saves before it


def test_a_gpu_chunk_takes_the_blocks_that_fit_its_memory(g1):
    from dataclasses import replace

    import ntc_design as nd
    from ntc_design.simulate.digital import digital_grid
    from ntc_design.simulate.loss_mc import GPU_CHUNK_BYTES, LossMonteCarloSpec
    from ntc_design.simulate.system import mode_system

    s = mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))
    grid, _ = digital_grid(Digital(0.1, 1), 1.0, np.array([1.0]))
    loss = np.full(s.n_edges, 0.1)
    base = LossMonteCarloSpec(
        s, grid, lambda t: 1 / (1 + t), THETA, X0_LIN, 7, 3, 400_000, 1, loss, "skip", 1
    )
    assert base.chunk_blocks == 1  # the CPU: a block per task
    gpu = replace(base, device="gpu")
    ne = s.n_edges
    per_path = 8 * (42 + ne * 3 + 3 * ne + 21 + 4)  # rings, held, draws, increments, stream
    n = gpu.chunk_blocks
    assert n > 1
    assert n * gpu.block_paths * per_path <= GPU_CHUNK_BYTES
    assert (n + 1) * gpu.block_paths * per_path > GPU_CHUNK_BYTES
