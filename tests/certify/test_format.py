"""Tests of :mod:`ntc_design.certify.format`."""

import json

import numpy as np
import pytest

from ntc_design.certify.format import document_hash, topology_hash
from ntc_design.model import Topology
from ntc_design.model.generate import random_network, write_topology
from ntc_design.model.load import load


def _reference_hash(top):
    edges = [
        [
            top.labels[j],
            top.labels[i],
            [[(float(x) + 0.0).hex() for x in row] for row in np.asarray(a).tolist()],
        ]
        for (i, j), a in sorted(top.weights.items())
        if np.any(a)
    ]
    return document_hash({"labels": list(top.labels), "dim": top.dim, "edges": edges})


@pytest.mark.parametrize("seed", range(5))
def test_topology_hash_is_the_canonical_json_hash(seed, tmp_path):
    top = random_network(30, 1 + seed % 3, seed=seed)
    assert topology_hash(top) == _reference_hash(top)
    # labels that JSON escapes, −0.0 and an all-zero weight (not hashed)
    labels = ["α", 'q"uote', "back\\slash", "x"]
    w = np.array([[[-0.0]], [[2.5]], [[0.0]]])
    t = Topology.from_arrays(labels, 1, np.array([1, 2, 3]), np.array([0, 1, 0]), w)
    assert topology_hash(t) == _reference_hash(t)
    path = tmp_path / "t.yaml"
    write_topology(top, path)
    assert topology_hash(load(path)) == topology_hash(top)


def test_structured_labels_hash_like_the_reference():
    w = np.array([[[1.0]], [[-2.0]]])
    labels = [[1, "a"], {"k": 2, "b": [1]}, "c"]
    t = Topology(labels, 1, {(1, 0): w[0], (2, 1): w[1]})
    assert topology_hash(t) == _reference_hash(t)


def test_topology_hash_in_chunks_is_the_same(monkeypatch):
    import ntc_design.certify.format as cc

    top = random_network(60, 2, seed=9)
    want = _reference_hash(top)
    for chunk in (1, 7, 10_000):
        monkeypatch.setattr(cc, "HASH_CHUNK", chunk)
        assert topology_hash(top) == want


def test_vectorised_topology_hash_text_is_float_hex_exactly():
    """Issue 20: the edge text is built from fixed-width byte fields (no float.hex per
    entry); it must be byte for byte the reference text, subnormals and zeros included."""
    from ntc_design.certify import format as cc

    rng = np.random.default_rng(4)
    k, d = 500, 3
    w = rng.standard_normal((k, d, d)) * 10.0 ** rng.integers(-320, 300, (k, d, d))
    w.ravel()[:6] = [0.0, 5e-324, -(2.0**-1022), 1.0, -1.7976931348623157e308, 1e-310]
    labels = ["a", 'q"', 7, "ü"] + [f"n{i}" for i in range(20)]
    lab = cc.label_json(labels)
    padded = np.array(lab, dtype="S").view(np.uint8).reshape(len(lab), -1)
    cols, rows = rng.integers(0, len(lab), k), rng.integers(0, len(lab), k)
    want = cc._edges_text(lab, cols, rows, w)
    assert cc._edges_text_fast(padded, cols, rows, w).decode() == want
    assert lab[:3] == [json.dumps("a"), json.dumps('q"'), "7"] and lab[3] == json.dumps("ü")
