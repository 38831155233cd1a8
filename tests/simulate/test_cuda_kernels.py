"""Tests of :mod:`ntc_design.simulate.cuda_kernels` (on numba-cuda's simulator unless
NTC_GPU_TESTS=device): the streams word for word against the CPU's, the check and the
statistics against NumPy."""

import os
import subprocess
import sys

import numpy as np
import pytest

from ntc_design.simulate.rng import ZIG_R, ZIG_X, normals, path_states
from tests.conftest import ROOT
from tests.support.gpu import sizes

pytestmark = [
    pytest.mark.usefixtures("cuda_device"),
    # the simulator runs xoshiro's uint64 arithmetic in NumPy, which warns when it wraps
    pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning"),
]


def test_device_normals_are_the_cpu_streams_word_for_word(cuda_device):
    from ntc_design.simulate import cuda_kernels as ck

    cu = cuda_device
    count, p = sizes((1500, 2), (20000, 64))
    st = path_states(11, 0, p)
    want = normals(st.copy(), count)  # (p, count), fill_normals on the CPU
    cpu_states = st.copy()
    normals(cpu_states, count)
    z = cu.device_array((count, p))
    dst = cu.to_device(np.ascontiguousarray(st.T))
    ck.draw_kernel()[1, p](dst, z, count, 1.0, cu.to_device(ZIG_X), cu.to_device(ZIG_R))
    got = z.copy_to_host().T
    # the fast test fails for 0.43 % of words: the wedges (and rarely the tail) were drawn,
    # and each consumed the same extra words (the streams end in the same state)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
    assert np.array_equal(dst.copy_to_host().T, cpu_states)
    assert abs(float(got.mean())) < 0.1 and 0.9 < float(got.std()) < 1.1


def test_check_kernel_finds_the_first_path_then_row(cuda_device):
    from ntc_design.simulate import cuda_kernels as ck

    cu = cuda_device
    nd, p = 6, 4
    x = np.zeros((2 * nd, p))  # two slots: only rows nd … 2nd − 1 are checked
    x[nd + 5, 1] = np.nan
    x[nd + 0, 2] = 2e150
    x[3, 0] = np.inf  # in the other slot
    bad = cu.to_device(np.array([ck.NO_FAILURE], np.int64))
    ck.check_kernel()[1, nd * p](cu.to_device(x), nd, nd, bad)
    assert int(bad.copy_to_host()[0]) == 1 * nd + 5
    bad = cu.to_device(np.array([ck.NO_FAILURE], np.int64))
    ck.check_kernel()[1, nd * p](cu.to_device(np.zeros((nd, p))), 0, nd, bad)
    assert int(bad.copy_to_host()[0]) == ck.NO_FAILURE


def test_statistics_are_numpy_sums_over_the_paths(cuda_device):
    from ntc_design.simulate import cuda_kernels as ck

    cu = cuda_device
    n, d, p, ppt, n_store = 3, 2, 7, 3, 2
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2 * n * d, p))  # slot 1 holds the state
    theta = np.array([0.5, -1.0])
    groups = -(-p // ppt)
    part = cu.device_array((groups, 3 * n + n * d))
    acc = cu.to_device(np.zeros((2, 3 * n + n * d)))
    stored = cu.to_device(np.zeros((2, n_store, n * d)))
    xd = cu.to_device(x)
    ck.stats_kernel()[(1, groups), n](
        xd, n * d, cu.to_device(theta), n, d, ppt, part, stored, n_store, 1
    )
    ck.sum_kernel()[1, part.shape[1]](part, groups, acc, 1, n, ppt, p)
    got = acc.copy_to_host()
    e = (x[n * d :].T - np.tile(theta, n)).reshape(p, n, d)
    e2 = (e * e).sum(axis=2)
    np.testing.assert_allclose(got[1, :n], e2.sum(axis=0), rtol=1e-13)
    # the squared deviations from the mean of all p paths (groups of 3, 3 and 1 merged)
    dev = e2 - e2.mean(axis=0)
    np.testing.assert_allclose(got[1, n : 2 * n], (dev * dev).sum(axis=0), rtol=1e-12)
    np.testing.assert_allclose(got[1, 2 * n : 3 * n], e2.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(got[1, 3 * n :], x[n * d :].sum(axis=1), rtol=1e-13)
    assert not got[0].any()  # another save slot: untouched
    np.testing.assert_array_equal(stored.copy_to_host()[1], x[n * d :, :n_store].T)


# every kernel through numba-cuda's real compiler to PTX for sm_90 (H100/H200): the typing
# and code generation the simulator does not exercise; no device needed, only NVVM/NVRTC
_PTX = """
import numba.cuda.dispatcher as dp
from numba import cuda, types as T
from ntc_design.simulate import cuda_kernels as ck

class Hopper:
    compute_capability = (9, 0)

dp.get_current_device = lambda: Hopper()  # device functions ask for a device's cc
f8, i8, u8 = T.float64, T.int64, T.uint64
a1, a2, a3 = (lambda t: t[::1]), (lambda t: t[:, ::1]), (lambda t: t[:, :, ::1])
modes = (a2(i8), a1(i8), a1(f8), a2(i8), a1(i8), a3(f8), a2(f8), a1(i8), a1(i8))
kernels = [(ck.draw_kernel(), (a2(u8), a2(f8), i8, f8, a1(f8), a1(f8))),
           (ck.check_kernel(), (a2(f8), i8, i8, a1(i8))),
           (ck.stats_kernel(), (a2(f8), i8, a1(f8), i8, i8, i8, a2(f8), a3(f8), i8, i8)),
           (ck.sum_kernel(), (a2(f8), i8, a2(f8), i8, i8, i8, i8))]
for d3 in (True, False):
    kernels.append((ck.fused_kernel(21, 3, 16, d3), (a2(f8), a2(u8), i8, i8, a1(f8), a1(f8),
        a1(i8), *modes, a1(i8), a1(i8), a3(f8), a2(f8), i8, a1(f8), a1(f8))))
    kernels.append((ck.step_kernel(d3), (a2(f8), a2(f8), i8, i8, i8, f8, i8, i8, *modes,
        a2(i8), a1(i8), a1(i8), a3(f8), a2(f8), i8)))
for k, sig in kernels:
    ptx, _ = cuda.compile_ptx(k.py_func, sig, cc=(9, 0))
    assert ".entry" in ptx
print(len(kernels))
"""


@pytest.mark.slow
def test_every_kernel_compiles_to_ptx_for_hopper():
    env = {k: v for k, v in os.environ.items() if "CUDASIM" not in k and "NTC_CUDA" not in k}
    r = subprocess.run(
        [sys.executable, "-c", _PTX], env=env, cwd=ROOT, capture_output=True, text=True
    )
    if r.returncode and ("libnvrtc" in r.stderr or "NVVM" in r.stderr or "libnvvm" in r.stderr):
        pytest.skip("no NVVM/NVRTC here (numba-cuda[cu12] brings them)")
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.split() == ["8"]
