"""Tests of :mod:`ntc_design.certify.robust.scale`."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.kinds.robust import robust_certificate
from ntc_design.certify.robust import robust
from ntc_design.certify.robust import scale as rs
from ntc_design.certify.robust.are import RICCATI_MAX_ND
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from tests.support.robust import features, in_set, realised, sample

# -- above the dense size: sparse dominance bounds ------------------------------------------


@pytest.fixture(scope="module")
def mid_network():
    from ntc_design.model.generate import random_network

    top = random_network(70, 3, seed=4)  # Nd = 210: the sparse path alone
    des = nd.design(top, THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.1)
    return des, rep


def test_the_sparse_brackets_are_sound_against_dense_eigenvalues(mid_network):
    des, rep = mid_network
    assert des.topology.nd > 80 and rep.proofs == {}
    with pytest.raises(nd.InputError, match="a certificate is issued up to Nd"):
        robust_certificate(rep)  # nothing stored to re-check: refused, not a KeyError
    assert rep.decay.lower is not None and 0 < rep.decay.lower <= rep.decay.upper
    assert 0 < rep.offset.lower <= rep.offset.upper  # comparison bound: sound, not tight
    rng = np.random.default_rng(np.random.SeedSequence(11))
    for k in range(30):
        a, o = features(des, sample(des, 0.1, rng, "vertex" if k % 2 else "random"))
        assert a >= rep.decay.lower and o <= rep.offset.upper
    wo = realised(des, rep.to_dict()["offset"]["realization"])
    assert in_set(des, wo, 0.1)
    assert features(des, wo)[1] == pytest.approx(rep.offset.lower, rel=1e-9)
    # the attained end: every weight scaled by 1 ∓ ρ, recomputed with dense eigenvalues
    w = realised(des, rep.to_dict()["decay"]["realization"])
    assert in_set(des, w, 0.1)
    assert features(des, w)[0] == pytest.approx(rep.decay.upper, rel=1e-6)
    assert 0 < rep.margin.lower <= 1.0
    for _ in range(20):
        a, _ = features(des, sample(des, rep.margin.lower, rng, "vertex"))
        assert a > 0


def _design(seed: int):
    # N = 110, d = 2: Nd = 220, past the dense Riccati size; a 24-agent component that
    # dominance does not prove even at ρ = 0 (seed 1), or above ρ ≈ 0.5 (seed 0)
    return nd.design(random_network(110, 2, seed=seed), [1.0, -1.0], thresholds=False)


def test_a_component_block_is_the_dense_block_within_its_bound():
    des = _design(0)
    lap = des.grounded_laplacian()
    _, comp = rs._components(des.topology)
    d = des.topology.dim
    sizes = np.bincount(comp)
    for c in np.argsort(sizes)[-3:]:  # the three largest components
        search, m = rs.component_riccati(des, comp, int(c))
        agents = np.flatnonzero(comp == c)
        idx = (agents[:, None] * d + np.arange(d)).reshape(-1)
        block = lap[np.ix_(idx, idx)]
        assert np.all(np.abs(block - search.lap) <= search.lap_err)
        assert float(np.max(search.lap_err)) < 1e-12 * float(np.max(np.abs(block)))
        # every uncertain edge into the component: its own, and those from outside (s = 0)
        ea = des.topology.edge_arrays
        assert m == int(np.sum(np.isin(ea.rows, agents) & (ea.sign != 0)))
        outside = ~np.isin(ea.cols, agents) & np.isin(ea.rows, agents) & (ea.sign != 0)
        assert int(np.sum(search.s == 0)) == int(np.sum(outside))


@pytest.mark.parametrize("seed", [0, 1])
def test_the_components_dominance_misses_are_proven_and_sound(seed, monkeypatch):
    des = _design(seed)
    assert des.topology.nd > RICCATI_MAX_ND
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = rs.robust_scale(des, 0.05)
        monkeypatch.setattr(rs, "COMPONENT_RICCATI_MAX_ND", 0)
        alone = rs.robust_scale(des, 0.05)
    assert "Riccati" in rep.margin.method and "Riccati" not in alone.margin.method
    if seed == 1:
        assert alone.margin.lower is None  # dominance proves no radius at all
    else:
        assert alone.margin.lower < 0.5 * rep.margin.lower  # more than 2× below
    assert rep.margin.lower >= 0.5  # within 2× of ρ = 1 (the target)
    rng = np.random.default_rng(np.random.SeedSequence(seed + 3))
    for k in range(16):
        w = sample(des, rep.margin.lower, rng, "vertex" if k % 2 else "random")
        assert features(des, w)[0] > 0  # Hurwitz, rebuilt independently


def test_dominance_failures_name_only_the_failing_components():
    des = _design(0)
    _, comp = rs._components(des.topology)
    sign = des.topology.edge_arrays.sign
    assert rs.dominance_failures(des, np.zeros(sign.size), comp, None) == set()
    failing = rs.dominance_failures(des, np.where(sign != 0, 0.9, 0.0), comp, None)
    assert failing and all(np.count_nonzero(comp == c) > 1 for c in failing)
