"""A tiny sweep (topology, scenario, grid) written once, its undisturbed run as the
reference, and results without the columns that differ between runs."""

import pandas as pd
import pytest

from ntc_design.sweep import run_sweep

TOPOLOGY = """name: tiny
dim: 1
agents: 3
edges:
  - {from: 1, to: 2, weight: [[1]]}
  - {from: 2, to: 3, weight: [[-1]]}
  - {from: 3, to: 1, weight: [[2]]}
"""


SCENARIO = """topology: tiny.yaml
theta: [1]
margin: 0.5
noise: {sigma: 0.3, f: 0.2}
initial: {uniform: [-1, 1], seed: 1}
T: 1
dt: 0.01
paths: 200
block_size: 50
"""


SWEEP = """base: sc.yaml
grid:
  noise.sigma: [0.1, 0.3]
  seed: [0, 1, 2, 3]
"""


# columns that legitimately differ between runs: who ran a point and how long it took
VOLATILE = ["wall_seconds", "worker"]


@pytest.fixture(scope="session")
def sweep_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("sweep")
    (d / "tiny.yaml").write_text(TOPOLOGY)
    (d / "sc.yaml").write_text(SCENARIO)
    (d / "sw.yaml").write_text(SWEEP)
    return d


@pytest.fixture(scope="session")
def sweep_reference(sweep_files):
    """The sweep run here, undisturbed, with no cluster."""
    out = sweep_files / "ref"
    res = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (res.points, res.computed, res.failed) == (8, 8, 0)
    return out


def _stable(path) -> pd.DataFrame:
    return pd.read_csv(path).drop(columns=VOLATILE)
