"""Stiff random networks and G1's mode system for the Monte Carlo kernels."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.system import mode_system


def stiff_network(n: int, seed: int, d: int = 3) -> nd.Topology:
    """A ring of antagonistic edges plus 10% random edges, PD weights of log-normal
    scale: Assumption 2 holds (every agent has a PD antagonistic in-weight) and the
    Lemma 1 δ is large, so L_B is stiff."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    pairs = [(i, (i + 1) % n) for i in range(n)]
    seen = set(pairs)
    while len(pairs) < n + n // 10:
        a, b = (int(v) for v in rng.integers(0, n, 2))
        if a != b and (a, b) not in seen:
            seen.add((a, b))
            pairs.append((a, b))
    edges = []
    for a, b in pairs:
        q = rng.normal(size=(d, d))
        w = (q @ q.T / d + 0.2 * np.eye(d)) * np.exp(rng.normal())
        neg = b == (a + 1) % n or rng.random() < 0.5
        edges.append((a + 1, b + 1, -w if neg else w))
    return nd.Topology.from_edges(n, d, edges)


@pytest.fixture(scope="session")
def g1_system(g1):
    des = nd.design(g1, THETA, thresholds=False)
    return des, mode_system(des, NoiseModel())
