"""Tests of :mod:`ntc_design.interop`."""

import control
import networkx as nx
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ntc_design import InputError, Topology, design, load
from ntc_design.interop import (
    design_statespace,
    save_topology,
    topology_from_networkx,
    topology_to_networkx,
)
from ntc_design.model import paper
from tests.conftest import random_topology


def _same(a: Topology, b: Topology) -> None:
    assert [str(x) for x in a.labels] == [str(x) for x in b.labels]
    assert a.dim == b.dim and a.name == b.name
    assert set(a.weights) == set(b.weights)
    for k, w in a.weights.items():
        assert np.array_equal(w, b.weights[k]), k  # bit-exact


@given(st.integers(0, 10_000), st.integers(1, 3))
def test_networkx_round_trip_is_exact(seed, d):
    top = random_topology(seed, n=5, d=d)
    g = topology_to_networkx(top)
    assert isinstance(g, nx.DiGraph) and g.number_of_edges() == len(top.weights)
    for (i, j), a in top.weights.items():  # edge j -> i carries A_ij
        assert np.array_equal(g.edges[top.labels[j], top.labels[i]]["weight"], a)
    back = topology_from_networkx(g)
    _same(top, back)
    assert np.array_equal(back.laplacian(), top.laplacian())


def test_networkx_scalar_weights_for_d1_and_errors():
    g = nx.DiGraph(name="ring")
    g.add_edge("a", "b", w=2.0)
    g.add_edge("b", "c", w=-0.5)
    g.add_edge("c", "a", w=1.0)
    top = topology_from_networkx(g, weight="w")
    assert top.dim == 1 and top.name == "ring" and top.labels == ("a", "b", "c")
    assert top.weight(top.index("b"), top.index("a"))[0, 0] == 2.0
    assert top.sign(top.index("c"), top.index("b")) == -1
    _same(top, topology_from_networkx(topology_to_networkx(top, "w"), weight="w"))
    with pytest.raises(InputError, match="expected a networkx.DiGraph"):
        topology_from_networkx(nx.Graph([(1, 2)]))
    bad = nx.DiGraph()
    bad.add_edge(1, 2)
    with pytest.raises(InputError, match=r"edge 1->2: no 'weight' attribute"):
        topology_from_networkx(bad)
    bad.add_edge(1, 2, weight=[[1.0, 2.0], [0.0, 1.0]])
    with pytest.raises(InputError, match="not symmetric"):
        topology_from_networkx(bad)
    bad.add_edge(2, 1, weight=np.eye(3))
    with pytest.raises(InputError, match=r"edge 2->1: 'weight' has shape \(3, 3\)"):
        topology_from_networkx(bad)


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_save_load_round_trip(tmp_path, examples, suffix):
    for top in (load(examples / "g1.yaml"), random_topology(7, n=6, d=2)):
        path = save_topology(top, tmp_path / f"t{suffix}")
        _same(top, load(path))
    with pytest.raises(InputError, match="does not exist"):
        save_topology(top, tmp_path / "no" / "t.yaml")


def test_statespace_dc_gain_is_one_kron_identity():
    for top in (paper.g1(), paper.g2(), random_topology(3, n=5, d=2, p_neg=0.5)):
        des = design(top, np.arange(1, top.dim + 1, dtype=float), 0.1)
        sys = design_statespace(des)
        assert isinstance(sys, control.StateSpace)
        assert (sys.nstates, sys.ninputs, sys.noutputs) == (top.nd, top.dim, top.nd)
        assert np.allclose(sys.B @ des.theta, des.input_vector(), rtol=1e-13, atol=1e-13)
        if np.max(np.linalg.eigvals(sys.A).real) < 0:  # −L_B Hurwitz: the DC gain exists
            dc = control.dcgain(sys)
            assert np.allclose(dc, np.kron(np.ones((top.n, 1)), np.eye(top.dim)), atol=1e-9)
    # the step response of the G1 protocol settles at 1⊗θ componentwise
    des = design(paper.g1(), paper.THETA, 0.1)
    resp = control.step_response(design_statespace(des), T=np.linspace(0, 40, 400))
    final = resp.outputs[:, :, -1]  # (outputs, inputs): response to a unit step in θ_k
    assert np.allclose(final, np.kron(np.ones((7, 1)), np.eye(3)), atol=1e-6)
