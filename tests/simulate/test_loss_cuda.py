"""Tests of :mod:`ntc_design.simulate.loss_cuda` on numba-cuda's CUDA simulator (a real
GPU with NTC_GPU_TESTS=device): the GPU's lossy step equals the CPU kernel's, path for
path, from the same streams, for every policy and a delay."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss_kernels import POLICY_CODES, loss_steps
from ntc_design.simulate.loss_mc import LossMonteCarloSpec
from ntc_design.simulate.rng import path_states
from ntc_design.simulate.system import mode_system
from tests.support.gpu import REL_TOL, relative_gap, sizes

X0 = np.linspace(-3, 3, 21)


@pytest.mark.parametrize(("policy", "delay"), [("skip", 0), ("rescale", 1), ("hold", 1)])
def test_the_gpu_step_is_the_cpu_kernels(g1, cuda_device, policy, delay):
    from ntc_design.simulate.loss_cuda import gpu_loss_steps

    s = mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))
    p, k_n = sizes((3, 4), (500, 100))
    h = 0.1
    grid, _ = digital_grid(Digital(h, delay), h * k_n, np.array([h * k_n]))
    loss = np.linspace(0.1, 0.5, s.n_edges)
    spec = LossMonteCarloSpec(
        s, grid, lambda t: 1 / (1 + t), THETA, X0, 7, 3, p, 1, loss, policy, delay
    )
    c = 1 / (1 + np.arange(k_n) * h)
    ch, cs, rh = c * h, c * np.sqrt(h), np.full(k_n, 1 / np.sqrt(h))
    arrays = spec.kernel_arrays()
    code = POLICY_CODES[policy]
    m = 2 * s.n_edges
    cpu_x, gpu_x = np.tile(X0, (p, delay + 1)), np.tile(X0, (p, delay + 1))
    cpu_h, gpu_h = spec.initial_held(p), spec.initial_held(p)
    cpu_s, gpu_s = path_states(6, 0, p), path_states(6, 0, p)
    empty = np.zeros((1, 1, 1))
    loss_steps(cpu_x, cpu_h, cpu_s, empty, empty, m, 0, k_n, ch, cs, rh, *arrays, code, 2, delay, 0)  # fmt: skip
    gpu_loss_steps(gpu_x, gpu_h, gpu_s, m, 0, k_n, ch, cs, rh, arrays, code, delay, 0)
    assert relative_gap(cpu_x, gpu_x) <= REL_TOL
    assert relative_gap(cpu_h, gpu_h) <= REL_TOL
    assert cpu_s.tolist() == gpu_s.tolist()  # the same words consumed
