"""Tests of :mod:`ntc_design.model.graph`."""

from itertools import pairwise

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import shortest_path

from ntc_design.model import Topology
from ntc_design.model.graph import (
    antagonistic_in_weight,
    in_degree_dominated,
    in_degree_dominated_all,
    in_out_difference,
    positive_negative_reachable,
)
from ntc_design.numerics.linalg import DEF_RTOL
from tests.conftest import random_topology

SEEDS = range(6)


def _sign(w: np.ndarray) -> int:
    """sgn(A) from dense eigenvalues (independent of the package's classifier): the random
    and hand-made weights here are far from the definiteness tolerance."""
    lam = np.linalg.eigvalsh(w)
    scale = np.abs(lam).max()
    if scale == 0.0:
        return 0
    return 1 if lam[0] >= -1e-9 * scale else -1


def _definite(w: np.ndarray) -> bool:
    lam = np.linalg.eigvalsh(w)
    scale = np.abs(lam).max()
    return scale > 0 and (lam[0] > 1e-9 * scale or lam[-1] < -1e-9 * scale)


def _dense_sums(top: Topology):
    """Σ|A_ij| over in-edges, over out-edges and over negative in-edges, from the raw weights."""
    d = top.dim
    inn = np.zeros((top.n, d, d))
    out = np.zeros((top.n, d, d))
    ant = np.zeros((top.n, d, d))
    for (i, j), w in top.weights.items():
        s = _sign(w)
        inn[i] += s * w
        out[j] += s * w
        if s < 0:
            ant[i] += -w
    return inn, out, ant


# -- antagonistic in-weight and in/out difference ---------------------------------------


def test_g1_antagonistic_in_weights_by_hand(g1):
    # agent 2 hears 1 (A21 = -diag(1,1,0)) and 6 (A26 = -diag(0,0,1)): |A21| + |A26| = I
    np.testing.assert_array_equal(antagonistic_in_weight(g1, g1.index(2)), np.eye(3))
    # agent 3 hears only 6, A36 = -0.1·diag(1,1,2)
    np.testing.assert_allclose(
        antagonistic_in_weight(g1, g1.index(3)), np.diag([0.1, 0.1, 0.2]), rtol=1e-15
    )
    # agent 1 only has the cooperative in-edge from 2
    np.testing.assert_array_equal(antagonistic_in_weight(g1, g1.index(1)), np.zeros((3, 3)))


def test_antagonistic_in_weight_is_a_writable_copy(g1):
    i = g1.index(2)
    a = antagonistic_in_weight(g1, i)
    a[:] = 99.0  # a caller's scratch use must not change the topology's cached sums
    np.testing.assert_array_equal(antagonistic_in_weight(g1, i), np.eye(3))


@pytest.mark.parametrize("seed", SEEDS)
def test_sums_match_the_dense_definition(seed):
    top = random_topology(seed, n=5, d=2)
    inn, out, ant = _dense_sums(top)
    for i in range(top.n):
        got = antagonistic_in_weight(top, i)
        np.testing.assert_allclose(got, ant[i], atol=1e-12)
        # |A| is positive semidefinite, so the sum is too
        assert np.linalg.eigvalsh(got)[0] >= -1e-12 * max(1.0, np.abs(got).max())
        np.testing.assert_allclose(in_out_difference(top, i), inn[i] - out[i], atol=1e-12)


def test_g1_in_out_difference_by_hand(g1):
    # agent 1: in |A12| = diag(1,1,2); out |A21| = diag(1,1,0)
    np.testing.assert_array_equal(in_out_difference(g1, g1.index(1)), np.diag([0.0, 0.0, 2.0]))
    # agent 7 has only the in-edge from 6: its difference is A76 itself
    np.testing.assert_array_equal(in_out_difference(g1, g1.index(7)), np.diag([3.1, 3.1, 3.2]))


def test_in_out_differences_sum_to_zero(g1, g2, g3):
    # every edge enters one agent's in-sum and another's out-sum: the total cancels
    for top in (g1, g2, g3, random_topology(11, n=6, d=3)):
        total = sum(in_out_difference(top, i) for i in range(top.n))
        np.testing.assert_allclose(total, 0.0, atol=1e-12)


# -- in-degree dominance ---------------------------------------------------------------


def _chain(a: float, b: float) -> Topology:
    """1 -> 2 with weight a, 2 -> 3 with weight b (d = 1): agent 2's in − out is a − b."""
    return Topology.from_edges(3, 1, [(1, 2, [[a]]), (2, 3, [[b]])])


def test_in_degree_dominance_of_a_chain():
    top = _chain(2.0, 1.0)
    # agent 1 only sends (in − out = −2 < 0), 2 receives more than it sends, 3 only receives
    assert [in_degree_dominated(top, i) for i in range(3)] == [False, True, True]
    assert in_degree_dominated_all(top).tolist() == [False, True, True]
    top = _chain(1.0, 2.0)
    assert [in_degree_dominated(top, i) for i in range(3)] == [False, False, True]


def test_an_isolated_agent_is_dominated():
    top = Topology.from_edges(3, 2, [(1, 2, np.eye(2))])
    assert in_degree_dominated(top, 2) is True
    all_ = in_degree_dominated_all(top)
    assert all_.dtype == bool and all_.tolist() == [False, True, True]


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_dominance_tolerance_is_relative_to_the_sums(scale):
    # in − out = −ε·scale: within DEF_RTOL·scale it counts as zero, ten times over it does not
    inside = _chain(scale, scale * (1 + DEF_RTOL / 10))
    outside = _chain(scale, scale * (1 + 10 * DEF_RTOL))
    assert in_degree_dominated(inside, 1) is True
    assert in_degree_dominated(outside, 1) is False
    assert bool(in_degree_dominated_all(inside)[1]) is True
    assert bool(in_degree_dominated_all(outside)[1]) is False


def test_dominance_needs_every_direction():
    # d = 2: in = diag(3, 1), out = diag(1, 2): one direction gains, the other loses
    top = Topology.from_edges(
        3, 2, [(1, 2, np.diag([3.0, 1.0])), (2, 3, np.diag([1.0, 2.0]))], name="mixed"
    )
    assert in_degree_dominated(top, 1) is False
    lam = np.linalg.eigvalsh(in_out_difference(top, 1))
    assert lam[0] < 0 < lam[-1]


@pytest.mark.parametrize("seed", SEEDS)
def test_batched_dominance_agrees_with_the_definition(seed):
    top = random_topology(seed, n=6, d=3, p_edge=0.4)
    inn, out, _ = _dense_sums(top)
    batched = in_degree_dominated_all(top)
    assert batched.shape == (top.n,)
    for i in range(top.n):
        assert bool(batched[i]) == in_degree_dominated(top, i)
        scale = max(np.linalg.norm(inn[i], 2), np.linalg.norm(out[i], 2))
        lam = np.linalg.eigvalsh(inn[i] - out[i])[0]
        if scale == 0.0:
            assert batched[i]
        elif abs(lam) > 1e-6 * scale:  # clear cases only: the tolerance decides the rest
            assert bool(batched[i]) == (lam > 0)


# -- positive-negative reachability ----------------------------------------------------


def test_paths_follow_definite_edges_only():
    # 1 -> 2 PD, 2 -> 3 ND, 3 -> 4 PSD (not usable), 2 -> 5 zero weight (not an edge)
    top = Topology.from_edges(
        5,
        2,
        [
            (1, 2, np.eye(2)),
            (2, 3, -np.diag([1.0, 2.0])),
            (3, 4, np.diag([1.0, 0.0])),
            (2, 5, np.zeros((2, 2))),
        ],
    )
    paths = positive_negative_reachable(top, [0])
    assert paths == {0: [0], 1: [0, 1], 2: [0, 1, 2]}
    # from 4 nothing leaves: only the trivial path
    assert positive_negative_reachable(top, [3]) == {3: [3]}


def test_no_sources_reach_nothing(g1):
    assert positive_negative_reachable(g1, []) == {}


def test_duplicate_sources_and_ties():
    # a diamond 1 -> {2, 3} -> 4: the path to 4 goes through the lower index, 2
    e = np.eye(1)
    top = Topology.from_edges(4, 1, [(1, 2, e), (1, 3, e), (2, 4, e), (3, 4, -e)])
    paths = positive_negative_reachable(top, iter([0, 0]))  # any iterable, repeats ignored
    assert paths == {0: [0], 1: [0, 1], 2: [0, 2], 3: [0, 1, 3]}
    # two sources: each keeps its trivial path, the other is not routed through
    both = positive_negative_reachable(top, [2, 0])
    assert both[2] == [2] and both[0] == [0] and both[3] == [2, 3]


@pytest.mark.parametrize("seed", SEEDS)
def test_paths_are_shortest_and_valid(seed):
    top = random_topology(seed, n=7, d=2, p_edge=0.35)
    n = top.n
    adj = np.zeros((n, n))
    for (i, j), w in top.weights.items():
        if _definite(w):
            adj[j, i] = 1.0  # edge j -> i
    dist = shortest_path(csr_matrix(adj), unweighted=True, indices=[0, 1])
    best = dist.min(axis=0)
    paths = positive_negative_reachable(top, [0, 1])
    assert set(paths) == {v for v in range(n) if np.isfinite(best[v])}
    for v, p in paths.items():
        assert p[0] in (0, 1) and p[-1] == v
        assert len(p) - 1 == best[v]
        for a, b in pairwise(p):
            assert adj[a, b] == 1.0, (a, b)


def test_g1_reachability_from_the_antagonised_agents(g1):
    # V1 = {2, 3} in the paper reaches every agent through PD/ND edges (Assumption 2)
    ix = g1.index
    paths = positive_negative_reachable(g1, [ix(2), ix(3)])
    assert set(paths) == set(range(7))
    assert [g1.labels[k] for k in paths[ix(4)]] == [3, 4]
    assert [g1.labels[k] for k in paths[ix(1)]] == [2, 1]
    assert [g1.labels[k] for k in paths[ix(7)]] == [2, 5, 6, 7]
    # the NSD edge 1 -> 2 cannot be used by a positive-negative path
    assert ix(2) not in positive_negative_reachable(g1, [ix(1)])


def test_g1_in_degree_dominance_by_agent(g1):
    # agents 2 and 3 (the antagonised ones) are not dominated by their in-degree in G1
    assert [in_degree_dominated(g1, i) for i in range(7)] == [
        True, False, False, True, True, True, True,
    ]  # fmt: skip
