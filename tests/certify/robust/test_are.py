"""Tests of :mod:`ntc_design.certify.robust.are`."""

import numpy as np
import pytest

from ntc_design.certify.dense import lap_b_float
from ntc_design.certify.robust import ROBUST_MAX_ND
from ntc_design.certify.robust.are import RICCATI_MAX_ND, RiccatiSearch
from ntc_design.certify.robust.problem import dense_problem
from tests.support.robust import features, in_set, realised, sample


def test_the_riccati_ends_are_sound_and_within_the_targets(mid_robust):
    des, rep, sparse = mid_robust
    assert ROBUST_MAX_ND < des.topology.nd <= RICCATI_MAX_ND
    assert rep.proofs["method"] == "riccati" and rep.proofs["offset"] is not None
    # tighter than block dominance, and within 2× of what a realisation attains
    assert rep.decay.lower > 1.2 * sparse.decay.lower
    assert rep.decay.upper / rep.decay.lower < 1.5
    assert rep.margin.lower > 4 * sparse.margin.lower
    assert (rep.margin.upper or 1.0) / rep.margin.lower < 2.0
    # the reduced S-procedure: 5× tighter than the comparison bound, within 1.5× (target)
    assert rep.offset.upper < 0.2 * sparse.offset.upper
    assert rep.offset.upper / rep.offset.lower < 1.5
    assert "eliminated" in rep.offset.method
    assert "Riccati" in rep.decay.method and "Riccati" in rep.margin.method
    rng = np.random.default_rng(np.random.SeedSequence(42))
    for k in range(40):
        a, o = features(des, sample(des, 0.05, rng, "vertex" if k % 2 else "random"))
        assert a >= rep.decay.lower and o <= rep.offset.upper
    for k in range(20):
        a, _ = features(des, sample(des, rep.margin.lower, rng, "vertex" if k % 2 else "random"))
        assert a > 0
    doc = rep.to_dict()
    for key, col in (("decay", 0), ("offset", 1)):
        w = realised(des, doc[key]["realization"])
        assert in_set(des, w, 0.05)
        figure = rep.decay.upper if key == "decay" else rep.offset.lower
        assert features(des, w)[col] == pytest.approx(figure, rel=1e-6)


def test_a_proof_is_refused_when_any_premise_fails(mid_robust):
    des, rep, _ = mid_robust
    p = dense_problem(des)
    search = RiccatiSearch(*lap_b_float(des.topology, des.B, des.delta), p.edges, p.d)
    rad = np.full(search.m, 0.05)
    got = search(0.5 * rep.decay.lower, rad)
    assert got is not None
    pm, tau = got
    assert search.proven(pm, tau, 0.5 * rep.decay.lower, rad)
    assert not search.proven(pm, np.where(np.arange(tau.size) == 0, 0.0, tau), 0.1, rad)
    assert not search.proven(-pm, tau, 0.5 * rep.decay.lower, rad)  # P must be ≻ 0
    bent = pm.copy()
    bent[0, 1] += 1e-9 * abs(bent[0, 1]) + 1e-300
    assert not search.proven(bent, tau, 0.5 * rep.decay.lower, rad)  # P exactly symmetric
    assert not search.proven(pm, tau, rep.nominal_decay * 1.01, rad)  # above the nominal
    assert not search.proven(pm, tau, 0.5 * rep.decay.lower, -rad)  # a negative radius
    assert search(rep.nominal_decay * 1.01, rad) is None
    assert search(rep.decay.upper * 1.001, rad) is None  # a realisation decays slower
