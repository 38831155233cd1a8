"""Tests of :mod:`ntc_design.simulate.gpu_timevarying`: A(t) given as expressions on the
GPU (numba-cuda's simulator unless NTC_GPU_TESTS=device), path for path the CPU's."""

import numpy as np
import pytest

from ntc_design.simulate.gpu_timevarying import batch_modes
from ntc_design.simulate.options import MonteCarlo
from ntc_design.simulate.scenario import load_scenario
from ntc_design.simulate.timevarying import TimeVaryingDesign, time_varying_system
from tests.conftest import EXAMPLES
from tests.support.gpu import REL_TOL, cpu_and_gpu, relative_gap, sizes

pytestmark = pytest.mark.usefixtures("cuda_device")


def _tv(paths, t_end):
    top, spec, _ = load_scenario(
        EXAMPLES / "scenarios" / "g1_tv.yaml",
        {"paths": paths, "T": t_end, "save_every": t_end / 2, "method": "mc"},
    )
    return top, spec


@pytest.mark.parametrize("layout", ["fused", "sparse"])
def test_expression_topology_paths_are_the_cpus(layout):
    paths, t_end = sizes((3, 0.02), (64, 1.0))
    if layout == "sparse":
        t_end = sizes((0.006,), (1.0,))[0]
    top, spec = _tv(paths, t_end)
    mc = {**spec.mc.__dict__, "store_paths": paths, "block_size": 2, "workers": 1}
    cpu, gpu = cpu_and_gpu(top, spec.replace(mc=MonteCarlo(**mc)), layout=layout)
    assert relative_gap(cpu.mc.paths, gpu.mc.paths) <= REL_TOL
    np.testing.assert_allclose(gpu.mc.mean, cpu.mc.mean, rtol=1e-12)
    assert cpu.mc.paths.shape == (paths, 3, 21)


def test_batch_modes_are_the_designs_matrices_at_each_time():
    top, spec = _tv(2, 0.1)
    sys_ = time_varying_system(TimeVaryingDesign(top, spec.theta, spec.margin), spec.noise)
    ts = np.array([0.0, 0.37, 1.5])
    ma = batch_modes(sys_, ts)
    st = sys_.structure
    lap = sys_.design.at(ts).lap_b(st)
    nd = st.n * st.d
    for k in range(ts.size):  # mode k: L_B(t_k) dense, in CSR over every entry
        dense = ma.val[ma.iptr[k, 0] : ma.iptr[k, -1]].reshape(nd, nd)
        np.testing.assert_array_equal(dense, lap[k])
    np.testing.assert_array_equal(ma.u, sys_.design.at(ts).input_vector())
    assert ma.e_cnt.tolist() == [sys_.n_edges] * 3
