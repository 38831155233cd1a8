"""Tests of :mod:`ntc_design.model.generate`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.generate import FAMILIES, random_network, write_topology
from ntc_design.protocol import assumption2
from tests.cli_helpers import run_cli


@pytest.mark.parametrize("family", FAMILIES)
def test_generator_keeps_its_promise(family):
    for seed in range(6):
        for n, d in ((2, 1), (9, 2), (60, 3), (250, 2)):
            top = random_network(n, d, seed, family)
            assert top.n == n and top.dim == d
            dec = assumption2(top)
            assert dec.holds, (family, seed, n, d, dec.violations[:2])
    a, b = random_network(200, 3, 7, family), random_network(200, 3, 7, family)
    assert a.weights.keys() == b.weights.keys()
    assert all(np.array_equal(a.weights[k], b.weights[k]) for k in a.weights)
    c = random_network(200, 3, 8, family)
    assert a.weights.keys() != c.weights.keys() or any(
        not np.array_equal(a.weights[k], c.weights[k]) for k in a.weights
    )


def test_generator_rejects_bad_parameters():
    for kw, msg in (
        (dict(n=1), "at least 2"),
        (dict(family="tree"), "unknown"),
        (dict(p_negative=1.5), "p_negative"),
        (dict(seed=-1), "seed"),
    ):
        args = dict(n=10, d=2, seed=0) | kw
        with pytest.raises(nd.InputError, match=msg):
            random_network(**args)


def test_npz_round_trip_and_cli(tmp_path, capsys, monkeypatch):
    top = random_network(120, 3, seed=2, family="small-world")
    for suffix in (".npz", ".json"):
        p = write_topology(top, tmp_path / f"net{suffix}")
        back = nd.load(p)
        assert back.labels == top.labels and back.weights.keys() == top.weights.keys()
        assert all(np.array_equal(back.weights[k], top.weights[k]) for k in top.weights)
    code, out, _ = run_cli(
        ["generate", "--n", 50, "--d", 2, "--seed", 3, "--out", tmp_path / "g.npz"],
        capsys,
        monkeypatch,
    )
    assert code == 0 and "50" in out
    assert assumption2(nd.load(tmp_path / "g.npz")).holds
