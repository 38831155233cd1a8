import os
from pathlib import Path

# One BLAS/LAPACK thread per test process, the CLI subprocesses included (they inherit the
# environment): two pytest-xdist workers already fill a 2-core machine, and OpenBLAS's
# spinning threads on a busy core made a 21×21 LU solve 1,000× slower (the Crank–Nicolson
# moments test: 104 s against 2 s on a loaded machine). Results do not depend on it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402 - after the thread settings, which numpy reads on import
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from ntc_design import SwitchingTopology, Topology  # noqa: E402
from ntc_design.model import paper  # noqa: E402

# numpy may have been loaded before this file (a plugin): the limit applied to it as well
threadpool_limits(limits=1, user_api="blas")

# Every size check assumes the same memory on every machine (an 8 GB laptop's share), so a
# refusal's wording and order never depend on what the machine has free.
os.environ["NTC_AVAILABLE_MEMORY"] = "6G"
# under coverage, the CLI subprocesses write their data beside the suite's, not into the
# temporary folders the tests check for stray files
os.environ.setdefault("COVERAGE_FILE", str(Path(__file__).resolve().parent.parent / ".coverage"))

# The GPU kernels' tests run on numba-cuda's CUDA simulator (tests/support/gpu.py) unless
# NTC_GPU_TESTS=device (benchmarks/gpu_check.sh, on a GPU): chosen here, before any test
# imports numba.cuda (importing a module to read its docstrings does), which fixes the mode
if os.environ.get("NTC_GPU_TESTS", "") != "device":
    os.environ.setdefault("NTC_CUDA_SIMULATOR", "1")
    os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")

# Property tests draw the same examples on every run: results are identical on re-run.
settings.register_profile("ntc", derandomize=True, print_blob=True)
settings.load_profile("ntc")

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

#: (all, fast lane) as this process collected them, before ``-m`` deselects any, when it
#: collected the whole suite (no path given): the README's counts test reads them rather
#: than collecting the suite again in a second pytest (about 15 s of CPU in every slow lane)
WHOLE_SUITE_COUNTS = pytest.StashKey[tuple[int, int]]()


@pytest.hookimpl(tryfirst=True)  # before the -m deselection
def pytest_collection_modifyitems(config, items):
    if not config.args or config.args == config.getini("testpaths"):
        fast = sum(1 for it in items if it.get_closest_marker("slow") is None)
        config.stash[WHOLE_SUITE_COUNTS] = (len(items), fast)


# the initial state of the G1 simulations (21 = 7 agents × d 3), one seed for every test
X0 = np.random.default_rng(np.random.SeedSequence(1)).uniform(-3, 3, size=21)


def random_topology(
    seed: int, n: int = 5, d: int = 2, p_edge: float = 0.5, p_neg: float = 0.4, p_semi: float = 0.3
) -> Topology:
    """A random signed matrix-weighted digraph: PD/PSD/ND/NSD weights, explicit seed."""
    rng = np.random.default_rng(seed)
    edges = []
    for i in range(n):
        for j in range(n):
            if i == j or rng.random() > p_edge:
                continue
            m = rng.normal(size=(d, d))
            w = m @ m.T + 0.1 * np.eye(d)
            if d > 1 and rng.random() < p_semi:  # drop a direction: semidefinite
                v = np.linalg.eigh(w)[1][:, 0]
                w = w - (v @ w @ v) * np.outer(v, v)
                w = 0.5 * (w + w.T)
            sgn = -1.0 if rng.random() < p_neg else 1.0
            edges.append((j + 1, i + 1, sgn * w))
    return Topology.from_edges(n, d, edges)


@pytest.fixture(scope="session")
def examples() -> Path:
    return EXAMPLES


# -- the paper's networks and θ, shared by every module (built once per session) ----------


@pytest.fixture(scope="session")
def theta() -> np.ndarray:
    """The paper's θ = (1, 2, −1)."""
    return np.array(paper.THETA, dtype=float)


@pytest.fixture(scope="session")
def g1() -> Topology:
    """G1 of the paper (Fig. 1), the same as examples/g1.yaml."""
    return paper.g1()


@pytest.fixture(scope="session")
def g2() -> Topology:
    """G2 of the paper."""
    return paper.g2()


@pytest.fixture(scope="session")
def g3() -> Topology:
    """G3 of the paper (it breaks Assumption 2 as stated)."""
    return paper.g3()


@pytest.fixture(scope="session")
def switching_set() -> SwitchingTopology:
    """The paper's switching set G1, G2, G3 with its schedule."""
    return paper.switching()


# fixtures shared by several test files, defined once beside their helpers
pytest_plugins = [
    "tests.support.certificates",
    "tests.support.distributed",
    "tests.support.gpu",
    "tests.support.implicit",
    "tests.support.kernel",
    "tests.support.reports",
    "tests.support.robust",
    "tests.support.robust_are",
    "tests.support.switching_scale",
    "tests.support.time_varying",
    "tests.support.tune",
    "tests.support.tune_schedule",
]
