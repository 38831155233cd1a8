"""Interop with networkx, python-control, pandas and topology files."""

import control
import networkx as nx
import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ntc_design import InputError, Topology, design, load, paper
from ntc_design.certify import certify
from ntc_design.interop import (
    design_statespace,
    save_topology,
    topology_from_networkx,
    topology_to_networkx,
)
from ntc_design.simulate import NoiseModel, simulate

from .conftest import random_topology


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


def test_control_lyap_cross_checks_the_certificate():
    res = certify(paper.g1(), paper.THETA, 0.1)
    mats = res.certificate["matrices"]
    lap_b = np.array(mats["L_B"]["G1"])
    p = np.array(mats["P"]["lyapunov"])
    # control.lyap solves A X + X Aᵀ + Q = 0: with A = −L_Bᵀ, Q = I it is P L_B + L_Bᵀ P = I
    x = control.lyap(-lap_b.T, np.eye(lap_b.shape[0]))
    assert np.allclose(x, p, rtol=1e-9, atol=1e-12)
    assert np.linalg.eigvalsh(0.5 * (x + x.T))[0] > 0


def test_tidy_dataframe_and_long_csv(tmp_path):
    from ntc_design.simulate.scenario import write_outputs

    res = simulate(
        paper.g1(),
        paper.THETA,
        noise=NoiseModel(0.4, 0.3),
        T=0.5,
        paths=40,
        seed=3,
        save_every=0.1,
        workers=1,
    )
    df = res.to_pandas()
    assert list(df.columns) == ["t", "agent", "mc", "lo", "hi", "exact"]
    assert len(df) == res.save_times.size * 7
    assert not df.isna().any().any()
    row = df[(df.agent == "4") & np.isclose(df.t, 0.3)].iloc[0]
    k = int(np.argmin(np.abs(res.save_times - 0.3)))
    assert row.mc == res.mc.mean[k, 3] and row.exact == res.exact.ms_error[k, 3]
    assert (df.lo <= df.mc).all() and (df.mc <= df.hi).all()
    # pivoting back gives the wide matrix
    wide = df.pivot(index="t", columns="agent", values="exact")[[str(a) for a in res.labels]]
    assert np.array_equal(wide.to_numpy(), res.exact.ms_error)
    write_outputs(res, tmp_path)
    back = pd.read_csv(tmp_path / "ms_error_long.csv", dtype={"agent": str})
    pd.testing.assert_frame_equal(back, df, check_exact=True)
    exact_only = simulate(paper.g1(), paper.THETA, T=0.2, method="exact", save_every=0.1)
    assert exact_only.to_pandas()["mc"].isna().all()
