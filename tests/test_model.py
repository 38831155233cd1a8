"""Model: classification, Laplacian, neighbour sets, paths, files; hypothesis properties."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.files import parse_topology
from ntc_design.linalg import Definiteness, classify
from ntc_design.model import (
    Topology,
    in_degree_dominated,
    positive_negative_reachable,
    signed_laplacian,
)

from .conftest import random_topology

seeds = st.integers(min_value=0, max_value=2**32 - 1)


@pytest.mark.parametrize(
    "mat, cls",
    [
        (np.diag([1.0, 1.0, 0.0]), Definiteness.PSD),
        (np.diag([1.0, 1.0, 1e-12]), Definiteness.PSD),
        (np.diag([1.0, 1.0, 1e-9]), Definiteness.PD),
        (-np.diag([1.0, 1.0, 0.0]), Definiteness.NSD),
        (-np.eye(3), Definiteness.ND),
        (np.zeros((3, 3)), Definiteness.ZERO),
        (np.diag([1.0, -1e-3, 2.0]), Definiteness.INDEFINITE),
    ],
)
def test_classification_tolerance(mat, cls):
    assert classify(mat) is cls


def test_g1_sets(examples):
    top = nd.load(examples / "g1.yaml")
    ix = top.index
    lab = lambda xs: sorted(top.labels[k] for k in xs)  # noqa: E731
    assert lab(top.antagonised) == [2, 3]
    assert lab(top.omega(ix(2))) == [1, 6]
    assert lab(top.gamma(ix(1))) == [2]
    assert lab(top.in_neighbours(ix(2))) == [1, 6]
    assert lab(top.out_neighbours(ix(2))) == [1, 5]
    assert [in_degree_dominated(top, i) for i in range(7)] == [
        True,
        False,
        False,
        True,
        True,
        True,
        True,
    ]
    assert top.classes[(ix(2), ix(1))] is Definiteness.NSD
    assert top.classes[(ix(3), ix(6))] is Definiteness.ND
    paths = positive_negative_reachable(top, [ix(2), ix(3)])
    assert [top.labels[k] for k in paths[ix(7)]] == [2, 5, 6, 7]
    # the NSD edge 1 -> 2 cannot be used by a positive-negative path
    assert ix(2) not in positive_negative_reachable(top, [ix(1)])


def test_laplacian_g1_blocks(examples):
    top = nd.load(examples / "g1.yaml")
    lap = top.laplacian()
    d = 3
    blk = lambda i, j: lap[(i - 1) * d : i * d, (j - 1) * d : j * d]  # noqa: E731
    a12 = np.diag([1.0, 1, 2])
    np.testing.assert_array_equal(blk(1, 2), -a12)
    np.testing.assert_array_equal(blk(1, 1), a12)
    np.testing.assert_array_equal(blk(2, 1), np.diag([1.0, 1, 0]))  # -A21
    np.testing.assert_array_equal(blk(2, 2), np.eye(3))  # |A21| + |A26|
    np.testing.assert_array_equal(blk(4, 4), a12)


@settings(max_examples=40, deadline=None)
@given(seeds, st.integers(2, 6), st.integers(1, 3))
def test_laplacian_block_rows(seed, n, d):
    """Block rows: L_ij = -A_ij, L_ii = Σ|A_ik|; so (L(1⊗v))_i = 2 Σ_{Ω_i}|A_ij| v."""
    top = random_topology(seed, n=n, d=d)
    lap = signed_laplacian(top)
    v = np.random.default_rng(seed).normal(size=d)
    lv = lap @ np.tile(v, n)
    for i in range(n):
        want_diag = sum((top.abs_weight(i, j) for j in range(n) if j != i), np.zeros((d, d)))
        np.testing.assert_allclose(lap[i * d : (i + 1) * d, i * d : (i + 1) * d], want_diag)
        for j in range(n):
            if j != i:
                np.testing.assert_array_equal(
                    lap[i * d : (i + 1) * d, j * d : (j + 1) * d], -top.weight(i, j)
                )
        expect = 2 * sum((top.abs_weight(i, j) for j in top.omega(i)), np.zeros((d, d))) @ v
        np.testing.assert_allclose(
            lv[i * d : (i + 1) * d], expect, atol=1e-10 * (1 + np.abs(lap).max())
        )


@settings(max_examples=40, deadline=None)
@given(
    seeds,
    st.lists(st.floats(-10, 10), min_size=2, max_size=2).filter(lambda t: max(map(abs, t)) > 1e-3),
    st.floats(1e-3, 1e3),
)
def test_identity_residual_any_theta_any_delta(seed, theta, delta):
    """-L_B(1⊗θ) + k1(Δ⊗I)Bθ = 0 for every θ and every δ > 0 (Lemma 1 identity)."""
    top = random_topology(seed, n=5, d=2)
    des = nd.design(top, theta, delta=delta, thresholds=False)
    assert des.identity_residual < 1e-12
    r = -des.grounded_laplacian() @ np.tile(des.theta, top.n) + des.input_vector()
    assert np.max(np.abs(r)) <= 1e-11 * (1 + np.abs(des.grounded_laplacian()).max()) * np.max(
        np.abs(theta)
    )


@settings(max_examples=60, deadline=None)
@given(seeds, st.floats(1e-6, 1e6), st.integers(1, 4))
def test_classification_invariant_under_positive_scaling(seed, c, d):
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(d, d))
    kind = rng.integers(4)
    a = [m @ m.T, -(m @ m.T), m + m.T, np.diag(np.r_[rng.random(d - 1) + 0.1, 0.0])][kind]
    assert classify(c * a) is classify(a)


@settings(max_examples=30, deadline=None)
@given(seeds, st.integers(2, 6), st.integers(1, 3))
def test_json_round_trip(seed, n, d):
    top = random_topology(seed, n=n, d=d)
    doc = json.loads(json.dumps(top.to_dict()))
    back = Topology.from_data(parse_topology(doc, "roundtrip.json"))
    assert back.labels == top.labels and back.dim == top.dim
    assert set(back.weights) == set(top.weights)
    for k, a in top.weights.items():
        np.testing.assert_array_equal(back.weights[k], a)
    assert back.classes == top.classes
    np.testing.assert_array_equal(back.laplacian(), top.laplacian())


def test_labels_from_list_and_json_file(tmp_path):
    doc = {
        "dim": 1,
        "agents": ["a", "b", "c"],
        "edges": [
            {"from": "a", "to": "b", "weight": [[-2]]},
            {"from": "b", "to": "c", "weight": 1},
        ],
    }
    p = tmp_path / "t.json"
    p.write_text(json.dumps(doc))
    top = nd.load(p)
    assert top.labels == ("a", "b", "c")
    des = nd.design(top, [3.0]).to_dict()
    assert des["informed"] == ["b"] and des["V1"] == ["b"]
    assert des["assumption_holds"] is False  # agent a can be reached by no path
    assert [v["agent"] for v in des["violations"]] == ["a"]


def test_time_varying_topology_designed_at_any_t():
    rot = lambda t: np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])  # noqa: E731
    w = lambda t: rot(t) @ np.diag([2.0 + np.sin(t), 1.0]) @ rot(t).T  # noqa: E731
    tv = nd.TimeVaryingTopology(
        (1, 2, 3),
        2,
        {(1, 2): lambda t: -w(t), (2, 3): w, (3, 1): lambda t: (1 + t) * np.eye(2)},
    )
    for t in (0.0, 0.7, 3.0):
        des = nd.design(tv.at(t), [1.0, 1.0])
        assert des.identity_residual < 1e-12
        assert [des.topology.labels[i] for i in des.informed] == [2]
        np.testing.assert_allclose(des.B[1], w(t), atol=1e-12)
    bad = nd.TimeVaryingTopology((1, 2), 2, {(1, 2): lambda t: np.diag([1.0, -t])})
    nd.design(bad.at(0.0), [1.0, 0.0])
    with pytest.raises(nd.InputError, match=r"edge 1->2 at t=1: weight is indefinite"):
        bad.at(1.0)


def test_assumption2_violation_reasons():
    # agent 2 is not in-degree-dominated (it sends more than it hears) and has no
    # antagonistic in-edge: it can be in neither V1 nor V2
    top = Topology.from_edges(3, 1, [(1, 2, [[1.0]]), (2, 3, [[5.0]]), (2, 1, [[-1.0]])])
    dec = nd.assumption2(top)
    assert not dec.holds
    reasons = {top.labels[v.agent]: v.reason for v in dec.violations}
    assert "not in-degree-dominated and has no antagonistic in-edge" in reasons[2]


def test_check_tables_are_typed_rows_every_face_renders(g1, g3):
    from ntc_design.design import structure_report, structure_tables

    edges, agents, a2 = structure_tables(structure_report(g1), "G1")
    assert len(edges.rows) == len(g1.classes) == 8 and edges.columns == ("edge", "class")
    assert [r[0].plain() for r in agents.rows] == [str(x) for x in g1.labels]
    c2 = agents.rows[list(g1.labels).index(2)][-1].plain()
    assert c2 == "7.1440"  # C_2, the paper's C for G1
    assert a2.layout == "list" and a2.rows[0][1].verdict_word == "holds"
    assert a2.list_lines()[0] == "Assumption 2: holds (V1 = {2, 3}, V2 = {1, 4, 5, 6, 7})"
    assert "<table" in edges.html() and "PD" in edges.text()  # the HTML and terminal faces
    *_, bad = structure_tables(structure_report(g3), "G3", most=1)
    assert bad.rows[0][1].verdict_word == "fails" and len(bad.rows) == 2
    assert bad.notes == ("1 more (--json lists them all)",)
