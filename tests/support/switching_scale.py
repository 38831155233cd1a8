"""A big switching set (30 agents per mode), its certificate, and a spy counting the
numeric work of verification."""

import numpy as np
import pytest

from ntc_design.certify.format import digest, document_hash
from ntc_design.certify.kinds.switching_scale import switching_scale_certificate
from ntc_design.model import SwitchingTopology, Topology
from ntc_design.model.generate import random_network
from ntc_design.protocol import design

THETA_SW = [1.0, -2.0, 0.5]


def _switching(n=30, d=3, seeds=(1, 2), families=("random", "small-world")):
    modes = {}
    for k, (s, f) in enumerate(zip(seeds, families, strict=True)):
        t = random_network(n, d, seed=s, family=f)
        # every mode over the same agents: relabel onto mode 0's labels
        modes["AB"[k]] = t
    labels = modes["A"].labels
    modes = {
        k: Topology.from_arrays(labels, d, t.edge_arrays.rows, t.edge_arrays.cols, t.edge_arrays.w)
        for k, t in modes.items()
    }
    return SwitchingTopology(modes, (("A", 0.1), ("B", 0.2)))


def _dense_sym_min(des):
    lap = des.grounded_laplacian()
    return float(np.linalg.eigvalsh(lap + lap.T)[0])


def _refresh(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="session")
def big_switching():
    return _switching()


@pytest.fixture(scope="session")
def big_cert(big_switching):
    return switching_scale_certificate(design(big_switching, THETA_SW, thresholds=False))


def _count_numeric(monkeypatch):
    """A spy on CHOLMOD's numeric factorisation: the list of calls grows by one each."""
    from cvxopt import cholmod

    calls = []
    real = cholmod.numeric

    def spy(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(cholmod, "numeric", spy)
    return calls
