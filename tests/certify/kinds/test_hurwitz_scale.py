"""Tests of :mod:`ntc_design.certify.kinds.hurwitz_scale`."""

import copy
import json

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.certify.format import digest
from ntc_design.model import Topology
from ntc_design.model.generate import random_network, write_topology
from ntc_design.protocol import AssumptionWarning, design
from tests.cli_helpers import assert_input_error, run_cli
from tests.support.scale import _methods
from tests.support.switching_scale import THETA_SW, _refresh


@pytest.mark.slow
def test_dominance_certificate_and_verify_round_trip(tmp_path):

    from ntc_design.certify import scale_certificate, verify, write_certificate
    from ntc_design.certify.arrays import pack, unpack
    from ntc_design.certify.format import digest

    top = random_network(300, 3, seed=2, family="scale-free")
    des = nd.design(top, [1.0, -1.0, 2.0], thresholds=False)
    cert = scale_certificate(des)
    assert _methods(cert)["dominance"] == cert["results"]["components"]
    p = tmp_path / "c.json"
    write_certificate(cert, p)
    ver = verify(json.loads(p.read_text()))
    assert ver.valid, ver.failed
    n = top.n

    def forged(field, change):
        bad = json.loads(p.read_text())
        arr = unpack(bad["components"][field], field, "i8" if field == "label" else "f8", (n,))
        arr = arr.copy()
        change(arr)
        bad["components"][field] = pack(arr, "i8" if field == "label" else "f8")
        bad["digest"] = digest(bad)
        return verify(bad)

    comp = unpack(cert["components"]["label"], "label", "i8", (n,))
    big = int(np.argmax(np.bincount(comp)))
    agent = int(np.flatnonzero(comp == big)[0])
    assert np.sum(comp == big) > 1

    def shrink_v(a):
        a[agent] *= 1e-6

    def inflate_mu(a):
        a[0] *= 1.5

    assert not forged("v", shrink_v).valid  # M v > 0 fails
    assert not forged("mu", inflate_mu).valid  # μ_0 above λ_min is not proven
    ea = top.edge_arrays
    j, i = int(ea.cols[0]), int(ea.rows[0])

    def backward(a):
        a[i], a[j] = min(a[i], a[j]), max(a[i], a[j]) + 1

    ver = forged("label", backward)
    assert not ver.valid and any("goes backward" in c.detail for c in ver.failed)
    # a tampered file without a new digest is caught by the digest
    bad = json.loads(p.read_text())
    bad["subject"]["modes"][top.name]["delta"] *= 1.01
    assert not verify(bad).valid


def test_unreached_agent_is_never_certified(tmp_path, capsys, monkeypatch):
    from ntc_design.certify import certify, scale_certificate, verify

    base = random_network(59, 3, seed=1)
    lone = Topology(base.labels + (60,), 3, dict(base.weights), name="lonely")
    with pytest.warns(AssumptionWarning):
        des = nd.design(lone, [1.0, 0.0, 0.0], thresholds=False)
    cert = scale_certificate(des)
    assert _methods(cert)["none"] >= 1
    ver = verify(cert)
    assert not ver.valid
    assert "60" in ver.failed[-1].detail
    small = Topology.from_edges(3, 1, [(1, 2, [[1.0]]), (2, 1, [[-1.0]])])
    with pytest.warns(AssumptionWarning):
        assert not certify(small, [1.0]).verification.valid  # the dense path agrees
    p = tmp_path / "lonely.npz"
    write_topology(lone, p)
    code, _, err = run_cli(["certify", p, "--theta", "1,0,0"], capsys, monkeypatch)
    assert code == 1 and "not proven" in err


@pytest.mark.hostile
def test_malformed_scale_certificate_is_one_line(tmp_path, capsys, monkeypatch):

    from ntc_design.certify import scale_certificate, write_certificate
    from ntc_design.certify.format import digest

    des = nd.design(random_network(40, 2, seed=6), [1.0, 1.0], thresholds=False)
    good = scale_certificate(des)
    name = des.topology.name

    def topo(doc):
        return doc["subject"]["modes"][name]["topology"]

    cases = [
        (lambda d: topo(d)["weights"].update(base64="%%%"), "invalid base64"),
        (lambda d: topo(d)["from"].update(shape=[3]), "expected dtype i8 and shape"),
        (lambda d: d["components"].pop("v"), "missing field 'v'"),
        (lambda d: d["components"]["method"].__setitem__(0, "magic"), "unknown method"),
        (lambda d: topo(d).update(dim=0), "dim"),
    ]
    for k, (change, needle) in enumerate(cases):
        doc = json.loads(json.dumps(good))
        change(doc)
        doc["digest"] = digest(doc)
        p = tmp_path / f"bad{k}.json"
        write_certificate(doc, p)
        assert_input_error(["verify", p], capsys, monkeypatch, str(p), needle)


@pytest.mark.parametrize(
    "forge, needle",
    [
        (lambda r: r.update(eig_bound=-5.0), "eig_bound differs"),
        (
            lambda r: (r.update(eig_bound=-5.0), r["rate_estimate"].update(value=-5.0)),
            "not positive",
        ),
        (
            lambda r: r["rate_lower_bound"].update(value=r["rate_lower_bound"]["value"] * 2),
            "rate_lower_bound.value: reported lower bound",  # above the re-derived one
        ),
        (lambda r: r.update(components=r["components"] + 1), "components: reported"),
    ],
)
def test_forged_hurwitz_scale_results_fail(forge, needle):
    top = random_network(40, 3, seed=5)
    big_cert = certify(top, THETA_SW).certificate
    doc = copy.deepcopy(big_cert)
    forge(doc["results"])
    ver = verify(_refresh(doc))
    assert len(ver.failed) == 1 and ver.failed[0].name.startswith("reported results")
    assert needle in ver.failed[0].detail


@pytest.mark.parametrize("factor", [0.5, 0.0, -1.0])
def test_a_looser_rate_lower_bound_still_verifies(factor):
    # a lower bound below the re-derived one is still true: an older, more cautious
    # issuer's certificate keeps verifying
    doc = copy.deepcopy(certify(random_network(40, 3, seed=5), THETA_SW).certificate)
    doc["results"]["rate_lower_bound"]["value"] *= factor
    ver = verify(_refresh(doc))
    assert ver.valid, [(c.name, c.detail) for c in ver.failed]


def test_rate_lower_bound_only_when_every_component_is_dominance():
    """Second review: a bound over the dominance components only is not a bound on the
    decay rate when a 'symmetric' component decays slower."""
    from ntc_design.certify import scale_certificate

    i2, s2 = np.eye(2), np.diag([1.0, 1e-3])
    top = Topology.from_edges(4, 2, [(1, 2, -i2), (2, 1, -i2), (3, 4, -s2), (4, 3, -s2)])
    des = design(top, [1.0, -2.0], thresholds=False)
    c = scale_certificate(des)
    assert c["results"]["methods"]["symmetric"] == 1
    assert c["results"]["rate_lower_bound"]["value"] is None
    assert verify(c).valid
    doc = copy.deepcopy(c)
    doc["results"]["rate_lower_bound"]["value"] = 0.09
    (bad,) = verify(_refresh(doc)).failed
    assert "not every component is a dominance one" in bad.detail
    # all-dominance network: the bound is there, below the estimate, and checked
    c2 = certify(random_network(40, 3, seed=5), THETA_SW).certificate
    lo, est = c2["results"]["rate_lower_bound"]["value"], c2["results"]["eig_bound"]
    assert lo is not None and 0 < lo <= est
    doc = copy.deepcopy(c2)
    doc["results"]["eig_bound"] = doc["results"]["rate_estimate"]["value"] = lo / 10
    (bad,) = verify(_refresh(doc)).failed
    assert "rate_estimate.value: reported" in bad.detail  # redone: the network is small


@pytest.mark.parametrize(
    "forge",
    [
        lambda d: d.update(certifies=["hurwitz", "decay_rate"]),
        lambda d: d["claims"].append({"id": "made up", "kind": "components", "mode": "x"}),
        lambda d: d.update(subject_digest="sha256:0"),
        lambda d: d["results"]["rate_lower_bound"].update(value=10**400),
    ],
)
def test_hurwitz_scale_checks_what_it_certifies_and_claims(forge):
    big_cert = certify(random_network(40, 3, seed=5), THETA_SW).certificate
    doc = copy.deepcopy(big_cert)
    forge(doc)
    doc["digest"] = digest(doc)
    if "subject_digest" in doc and doc["subject_digest"] != "sha256:0":
        _refresh(doc)
    assert not verify(doc).valid


def test_the_components_row_names_the_methods_in_words():
    from ntc_design.certify.kinds.hurwitz_scale import HurwitzScaleKind

    res = certify(random_network(40, 3, seed=5), THETA_SW).certificate["results"]
    (comp, *_) = HurwitzScaleKind().rows(res)
    m = res["methods"]
    assert comp.label == "components"
    assert comp.value == (
        f"{res['components']} (largest {res['largest_component_agents']} agents), by "
        f"dominance {m['dominance']}, symmetric {m['symmetric']}, lyapunov {m['lyapunov']}, "
        f"none {m['none']}"
    )
