"""Tests of :mod:`ntc_design.model.topology`."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.io.files import parse_topology
from ntc_design.model import (
    Topology,
    signed_laplacian,
)
from ntc_design.numerics.linalg import Definiteness
from tests.conftest import random_topology
from tests.support.model import seeds


def test_g1_sets(examples):
    top = nd.load(examples / "g1.yaml")
    ix = top.index
    lab = lambda xs: sorted(top.labels[k] for k in xs)  # noqa: E731
    assert lab(top.antagonised) == [2, 3]
    assert lab(top.omega(ix(2))) == [1, 6]
    assert lab(top.gamma(ix(1))) == [2]
    assert lab(top.in_neighbours(ix(2))) == [1, 6]
    assert lab(top.out_neighbours(ix(2))) == [1, 5]
    assert top.classes[(ix(2), ix(1))] is Definiteness.NSD
    assert top.classes[(ix(3), ix(6))] is Definiteness.ND


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


@pytest.mark.hostile
def test_a_loss_on_a_missing_edge_is_refused():
    w = np.ones((1, 1, 1))
    assert Topology.from_arrays([1, 2], 1, [0], [1], w, loss=np.array([np.nan])).loss == {}
    with pytest.raises(InputError, match=r"loss on a missing edge"):
        Topology((1, 2), 1, {(0, 1): np.ones((1, 1))}, loss={(1, 0): 0.2})
    top = Topology.from_arrays([1, 2], 1, [0], [1], w, loss=np.array([0.3]))
    assert top.loss == {(0, 1): 0.3}
