"""Tests of :mod:`ntc_design.simulate.gpu`: the device check (one line naming what is
missing), what the GPU refuses, and ``simulate(..., device="gpu")`` end to end on
numba-cuda's simulator."""

import importlib.util
import json
import os
import subprocess
import sys

import pytest

from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate import gpu as gpu_mod
from ntc_design.simulate.gpu import GpuEngine, check_supported
from ntc_design.simulate.montecarlo import PathBlocks
from tests.conftest import ROOT, X0
from tests.support.gpu import REL_TOL, relative_gap


def test_without_numba_cuda_the_message_names_the_gpu_extra(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "numba_cuda" else real(name)
    )
    with pytest.raises(InputError, match=r"^device: gpu needs numba-cuda.*gpu extra"):
        gpu_mod.load_cuda()
    ok, why = gpu_mod.gpu_available()
    assert not ok and "\n" not in why and "ntc-design[gpu]" in why


def test_without_a_gpu_the_check_says_what_is_missing_in_one_line():
    # a fresh process without the simulator: numba.cuda meets the machine as it is
    env = {k: v for k, v in os.environ.items() if "CUDASIM" not in k and "NTC_CUDA" not in k}
    code = (
        "import json; from ntc_design.simulate.gpu import gpu_available; "
        "print(json.dumps(gpu_available()))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True, check=True
    )
    ok, why = json.loads(out.stdout.strip().splitlines()[-1])
    if ok:
        pytest.skip(f"this machine has a GPU: {why}")
    assert why.startswith("device: gpu") and "\n" not in why
    assert any(w in why for w in ("numba-cuda", "driver", "GPU", "NVVM")), why


@pytest.mark.parametrize(
    "attrs, field",
    [
        ({"rng": "numpy"}, "rng: numpy stays on the CPU"),
        ({"scheme": "implicit"}, "scheme: implicit runs on the CPU only"),
        ({"mode_systems": lambda self: (type("S", (), {"f": abs})(),)}, "noise.f: a callable f"),
    ],
)
def test_what_the_gpu_does_not_run_is_refused_naming_the_field(attrs, field):
    spec = type("Spec", (PathBlocks,), {"rng": "xoshiro", "scheme": "explicit", **attrs})()
    with pytest.raises(InputError, match=f"^{field}"):
        check_supported(spec)


def test_engine_layout_is_checked():
    with pytest.raises(InputError, match="^layout: expected one of auto, fused, sparse"):
        GpuEngine(layout="dense")


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_simulate_on_the_device_option(g1, cuda_device):
    opts = dict(
        noise=NoiseModel(0.4, 0.3), initial=X0, T=0.01, dt=1e-3, paths=3, seed=5,
        save_every=0.005, method="mc", workers=1, store_paths=3,
    )  # fmt: skip
    cpu = simulate(g1, THETA, **opts)
    gpu = simulate(g1, THETA, device="gpu", **opts)
    assert gpu.stats.engine == GpuEngine().describe()
    assert gpu.parameters["device"] == "gpu" and cpu.parameters["device"] == "cpu"
    assert relative_gap(cpu.mc.paths, gpu.mc.paths) <= REL_TOL
    with pytest.raises(InputError, match="^device: gpu .*does not combine with a scheduler"):
        simulate(g1, THETA, device="gpu", engine=object(), **opts)
    # exact moments only: no paths, so no device needed
    ex = simulate(g1, THETA, device="gpu", **{**opts, "method": "exact"})
    assert ex.mc is None and ex.exact is not None
