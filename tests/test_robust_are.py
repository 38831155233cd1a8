"""ntc_design.certify.robust_are: between the robust LMI's size and RICCATI_MAX_ND the decay
and margin ends are proven by the Riccati search. Checked against an independent rebuild
of L_B(A') (tests/test_robust.py's helpers), sampled and at vertices of the set."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.dense import lap_b_float
from ntc_design.certify.robust import ROBUST_MAX_ND, _problem, robust
from ntc_design.certify.robust_are import RICCATI_MAX_ND, RiccatiSearch
from ntc_design.certify.robust_scale import robust_scale
from ntc_design.generate import random_network
from ntc_design.paper import THETA

from .test_robust import features, forged_valid, in_set, raise_alpha_to, realised, sample


@pytest.fixture(scope="module")
def mid_robust():
    top = random_network(14, 3, seed=4)  # Nd = 42: past the LMI, where dominance is loose
    des = nd.design(top, THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return des, robust(des, 0.05, starts=2), robust_scale(des, 0.05)


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
    p = _problem(des)
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


def test_the_table_names_the_method_of_each_proven_end(mid_robust):
    _, rep, sparse = mid_robust
    said = [r[-1].text for r in rep.table().rows]
    assert "Riccati search" in said[0] and "S-procedure, reduced" in said[1]
    assert "Riccati search at α = 0" in said[2]
    assert "block dominance" in [r[-1].text for r in sparse.table().rows][0]


def test_the_certificate_past_the_lmi_size_verifies_and_forgeries_do_not(mid_robust):
    import json

    from ntc_design.certify import verify
    from ntc_design.certify.kinds.robust import robust_certificate

    des, rep, _ = mid_robust
    doc = json.loads(json.dumps(robust_certificate(rep)))
    ver = verify(doc)
    assert ver.valid
    assert doc["certifies"] == ["robust_margin", "robust_decay", "robust_offset"]
    assert "Y" not in doc["matrices"]  # a witness the verifier rebuilds
    # ntc verify says the numbers each property states, beside the property
    said = {p["property"]: p.get("stated") for p in ver.about.to_dict()["properties"]}
    alpha, gamma = doc["results"]["decay"]["lower"], doc["results"]["offset"]["gamma"]
    assert said["robust_decay"] == f"α = {alpha:.6g} at ρ = 0.05"
    assert said["robust_margin"] == f"margin radius {doc['results']['margin']['lower']:.6g}"
    assert said["robust_offset"] == f"<= {gamma**0.5:.6g} at ρ = 0.05"
    assert doc["results"]["offset"]["upper"] == pytest.approx(rep.offset.upper, rel=1e-15)
    assert doc["results"]["decay"]["lower"] == rep.proofs["alpha"] <= rep.decay.lower
    assert "Riccati" in doc["solver"]["name"]

    def forged(edit):
        return forged_valid(doc, edit)

    raise_alpha = raise_alpha_to(rep.decay.upper * 1.01)

    def raise_margin(d):
        d["results"]["margin"]["lower"] = 0.99
        for c in d["claims"]:
            if c["property"] == "robust_margin" and "radius" in c:
                c["radius"] = 0.99

    def zero_tau(d):
        t = d["matrices"]["multipliers"]["robust_decay"]
        d["matrices"]["multipliers"]["robust_decay"] = [0.0] + t[1:]

    def bend_p(d):
        d["matrices"]["P"]["robust_decay"][0][1] *= 1.0 + 1e-6

    def lower_gamma(d):  # below what a realisation attains: it must not verify
        d["results"]["offset"]["gamma"] = 0.99 * rep.offset.lower**2
        d["results"]["offset"]["upper"] = d["results"]["offset"]["gamma"] ** 0.5

    def zero_lambda(d):
        d["matrices"]["multipliers"]["robust_offset"] = [0.0] * len(
            d["matrices"]["multipliers"]["robust_offset"]
        )

    def widen_radius_of_offset(d):  # the offset claim's radius is the subject's
        for c in d["claims"]:
            if c["property"] == "robust_offset":
                c["radius"] = 0.2

    edits = (raise_alpha, raise_margin, zero_tau, bend_p, lower_gamma, zero_lambda,
             widen_radius_of_offset)  # fmt: skip
    for edit in edits:
        assert not forged(edit), edit.__name__
