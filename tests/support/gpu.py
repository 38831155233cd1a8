"""The GPU tests' device: numba-cuda's simulator (NTC_CUDA_SIMULATOR=1, the default) or,
with NTC_GPU_TESTS=device (benchmarks/gpu_check.sh on a machine with a GPU), the real
one; sizes small on the simulator (every thread runs in Python) and larger on a GPU."""

import importlib.util
import os

import numpy as np
import pytest

from ntc_design.simulate import SimulationSpec, simulate
from ntc_design.simulate.gpu import SIMULATOR_ENV, GpuEngine

REAL = os.environ.get("NTC_GPU_TESTS", "") == "device"
REL_TOL = 1e-9  # a path on the GPU equals the CPU's to rounding (fused multiply-adds)


@pytest.fixture
def cuda_device(monkeypatch):
    """``numba.cuda`` (the simulator unless NTC_GPU_TESTS=device), or skip saying why."""
    if importlib.util.find_spec("numba_cuda") is None:
        pytest.skip("numba-cuda is not installed (the test extra brings it)")
    from ntc_design.errors import InputError
    from ntc_design.simulate.gpu import load_cuda

    if not REAL:  # tests/conftest.py set it for the whole session; a file run alone too
        monkeypatch.setenv(SIMULATOR_ENV, "1")
    try:
        return load_cuda()
    except InputError as exc:
        pytest.skip(str(exc))


def sizes(sim: tuple, real: tuple) -> tuple:
    """The simulator's sizes, or the real device's."""
    return real if REAL else sim


def relative_gap(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| / max(|a|, 1e-12) (0 for two empty arrays)."""
    assert a.shape == b.shape, (a.shape, b.shape)
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-12)))


def cpu_and_gpu(topology, theta, layout="auto", **options):
    """The same run on the CPU (one worker) and on the GPU: (cpu, gpu) results; ``theta``
    with flat options, or a whole SimulationSpec."""
    opts = {} if isinstance(theta, SimulationSpec) else {"method": "mc", "workers": 1, **options}
    cpu = simulate(topology, theta, **opts)
    gpu = simulate(topology, theta, engine=GpuEngine(layout=layout), **opts)
    return cpu, gpu


__all__ = ["REAL", "REL_TOL", "cpu_and_gpu", "cuda_device", "relative_gap", "sizes"]
