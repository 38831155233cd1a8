"""Tests of :mod:`ntc_design.certify.kinds.robust`."""

import copy
import json

import numpy as np
import pytest

from ntc_design.certify import verify
from ntc_design.certify.format import finish
from ntc_design.certify.kinds.robust import robust_certificate
from tests.support.robust import forged_valid, raise_alpha_to


def test_the_certificate_verifies_and_forgeries_do_not(g1_robust):
    _, rep = g1_robust
    doc = json.loads(json.dumps(robust_certificate(rep)))
    ver = verify(doc)
    assert ver.valid and ver.about.kind == "robust"

    def forged(edit):
        return forged_valid(doc, edit)

    raise_alpha = raise_alpha_to(rep.decay.upper * 1.01)

    def raise_radius(d):
        d["subject"]["radius"] = 0.5
        d["results"]["radius"] = 0.5
        for c in d["claims"]:
            if c.get("radius") == rep.radius:
                c["radius"] = 0.5

    def shrink_gamma(d):
        d["results"]["offset"]["gamma"] *= 0.5
        d["results"]["offset"]["upper"] = d["results"]["offset"]["gamma"] ** 0.5

    def zero_tau(d):
        d["matrices"]["multipliers"]["robust_decay"] = [0.0] * len(
            d["matrices"]["multipliers"]["robust_decay"]
        )

    def outside(d):
        e = d["realizations"]["decay"]["edges"][0]
        e["weight"] = (2.0 * np.asarray(e["weight"])).tolist()

    for edit in (raise_alpha, raise_radius, shrink_gamma, zero_tau, outside):
        assert not forged(edit), edit.__name__


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


# -- the brackets' other ends: checked in their sound direction ---------------------------

_ENDS = {  # the end, and which side of the value re-derived from its realisation it is on
    ("decay", "upper"): "upper",
    ("offset", "lower"): "lower",
    ("offset", "upper"): "upper",
    ("margin", "upper"): "upper",
}


def _set_end(path, value):
    def edit(d):
        d["results"][path[0]][path[1]] = value

    return edit


@pytest.mark.parametrize("path", list(_ENDS), ids=".".join)
def test_a_looser_end_still_verifies(tri_robust, path):
    # a bracket end a little wider than today's re-derivation is still true (three agents:
    # each verify a few hundredths of G1's; G1's forgeries are the first test's)
    _, _, rep = tri_robust
    doc = json.loads(json.dumps(robust_certificate(rep)))
    got = doc["results"][path[0]][path[1]]
    looser = got * 1.01 if _ENDS[path] == "upper" else got * 0.99
    assert forged_valid(doc, _set_end(path, looser))


@pytest.mark.hostile
@pytest.mark.parametrize("path", list(_ENDS), ids=".".join)
def test_an_end_forged_in_the_unsound_direction_is_rejected(tri_robust, path):
    _, _, rep = tri_robust
    doc = json.loads(json.dumps(robust_certificate(rep)))
    got = doc["results"][path[0]][path[1]]
    tighter = got * 0.99 if _ENDS[path] == "upper" else got * 1.01
    bad = copy.deepcopy(doc)
    _set_end(path, tighter)(bad)
    for k in ("digest", "subject_digest", "versions"):
        bad.pop(k, None)
    ver = verify(finish(bad))
    audit = [c for c in ver.failed if c.name.startswith("reported results")]
    needle = f"{'.'.join(path)}: reported {_ENDS[path]} bound {tighter!r}"
    assert audit and needle in audit[0].detail, [(c.name, c.detail) for c in ver.failed]


def test_per_edge_radii_are_stated_as_the_per_edge_set(tri_robust):
    # what ntc verify prints beside each property, and in the claims' checks
    from tests.support.robust import TRI_SET

    _, _, rep = tri_robust
    doc = json.loads(json.dumps(robust_certificate(rep)))
    ver = verify(doc)
    assert ver.valid
    said = {p["property"]: p.get("stated") for p in ver.about.to_dict()["properties"]}
    alpha, gamma = doc["results"]["decay"]["lower"], doc["results"]["offset"]["gamma"]
    margin = doc["results"]["margin"]["lower"]
    assert said == {
        "robust_margin": f"margin radius {margin:.6g}, one ρ on every edge",
        "robust_decay": f"α = {alpha:.6g} for {TRI_SET}",
        "robust_offset": f"<= {gamma**0.5:.6g} for {TRI_SET}",
    }
    details = {c.claim.prop.value: c.detail for c in ver.checks if c.claim is not None}
    assert details["robust_decay"].endswith(f"(α = {alpha!r}, {TRI_SET})")
    assert details["robust_offset"].endswith(f"({TRI_SET})")
    assert details["robust_margin"].endswith(f"(α = 0.0, ρ = {margin!r})")  # one ρ: true
    assert "ρ = 0.5" not in " ".join([*said.values(), *details.values()])


def test_the_verification_names_the_proof_it_used(tri_robust):
    """Not the kind's 'exact-rational, or verified-float past the LMI size': the method
    of the proofs that ran (Nd = 3 here: every claim exactly; past the size, the test
    above)."""
    doc = json.loads(json.dumps(robust_certificate(tri_robust[2])))
    ver = verify(doc)
    assert ver.valid and ver.method == "exact-rational"
    assert all(c.detail.startswith("exact-rational") for c in ver.checks if c.claim is not None)
