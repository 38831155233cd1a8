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
        ["generate", "--agents", 50, "--dim", 2, "--seed", 3, "--out", tmp_path / "g.npz"],
        capsys,
        monkeypatch,
    )
    assert code == 0 and "50" in out
    assert assumption2(nd.load(tmp_path / "g.npz")).holds


@pytest.mark.parametrize("n, m", [(2, 1), (3, 2), (50, 1), (400, 3)])
def test_preferential_attachment_is_the_sequential_process(n, m):
    # the same uniforms replayed one edge at a time: each target is a uniform entry of the
    # list of every earlier edge's two ends (degree-proportional), appended as it goes
    from ntc_design.model.generate import preferential_attachment

    u, v = preferential_attachment(n, m, np.random.default_rng(7))
    m0 = min(m, n - 1)
    ends = [x for i in range(m0) for x in (i + 1, i)]
    draws = np.random.default_rng(7).random(max(0, n - m0 - 1) * m)
    want_u, want_v = list(range(1, m0 + 1)), list(range(m0))
    k = 0
    for t in range(m0 + 1, n):
        count = len(ends)
        for _ in range(m):
            target = ends[int(draws[k] * count)]
            k += 1
            want_u.append(t)
            want_v.append(target)
            ends += [t, target]
    assert u.tolist() == want_u and v.tolist() == want_v
    assert np.all(v < u)  # every edge joins a later agent to an earlier one: connected


@pytest.mark.parametrize("family", ["small-world", "scale-free"])
def test_generated_families_are_connected_and_satisfy_assumption_2(family):
    top = random_network(300, 2, seed=4, family=family)
    assert assumption2(top).holds
    import scipy.sparse as sp
    from scipy.sparse import csgraph

    ea = top.edge_arrays
    g = sp.coo_matrix((np.ones(ea.rows.size), (ea.rows, ea.cols)), shape=(top.n, top.n))
    assert csgraph.connected_components(g, directed=False)[0] == 1
