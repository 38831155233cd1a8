"""G1 with time-varying weights, and small time-varying documents."""

import pytest

import ntc_design as nd
from tests.conftest import ROOT


@pytest.fixture(scope="session")
def g1tv():
    return nd.load(ROOT / "examples" / "g1_tv.yaml")


def small(weights: dict, extra: dict | None = None, dim: int = 2) -> dict:
    """A 3-agent path with one antagonistic edge; ``weights`` overrides edge weights."""
    w = {
        "1->2": {"diag": [-1, -2]},
        "2->3": [[2, 0], [0, 1]],
        "3->1": {"identity": 1},
        "2->1": {"identity": 1},
        **weights,
    }
    edges = [{"from": int(k[0]), "to": int(k[-1]), "weight": v} for k, v in w.items()]
    return {"dim": dim, "agents": 3, "edges": edges, **(extra or {})}
