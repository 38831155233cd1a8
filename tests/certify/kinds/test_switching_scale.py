"""Tests of :mod:`ntc_design.certify.kinds.switching_scale`."""

import copy

import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.kinds.switching import switching_certificate
from ntc_design.errors import InputError
from ntc_design.model import SwitchingTopology, Topology
from ntc_design.model.generate import random_network
from ntc_design.protocol import design
from tests.support.switching_scale import THETA_SW, _dense_sym_min, _refresh


def test_proven_bound_brackets_the_dense_eigenvalue(big_switching, big_cert):
    des = design(big_switching, THETA_SW, thresholds=False)
    for k, d in des.modes.items():
        lam = _dense_sym_min(d)
        lo = big_cert["proofs"][k]["lower"]
        est = big_cert["results"]["symmetric_part_min_eig"][k]
        assert lam > 0
        assert est == pytest.approx(lam, rel=1e-9)
        assert 0 < lo < lam  # a lower bound ...
        assert lo > lam * (1 - 2e-3)  # ... and a tight one
    ver = verify(big_cert)
    assert ver.valid, [c for c in ver.failed]
    assert ver.about.kind == "switching-scale"
    assert ver.about.scheduled == ("A", "B")


def test_certify_uses_the_sparse_kind_above_the_dense_size_and_agrees_with_dense(big_switching):
    res = certify(big_switching, THETA_SW, gain="1/(1+t)")
    assert res.certificate["kind"] == "switching-scale"
    assert res.verification.valid and res.proven
    assert [t.guaranteed for t in res.theorems] == [True, True]
    # the dense switching certificate on the same designs: same verdict, same λ_min
    dense = switching_certificate(res.design)
    dver = verify(dense)
    assert dver.valid
    for k, lam in dense["results"]["symmetric_part_min_eig"].items():
        assert res.certificate["results"]["symmetric_part_min_eig"][k] == pytest.approx(
            lam, rel=1e-9
        )


def test_a_failing_mode_is_never_certified(big_switching):
    des = design(big_switching, THETA_SW, thresholds=True)
    ds = des.modes["B"].thresholds.symmetric
    assert ds is not None and ds > 0
    # δ below δ_S in every mode: L_B + L_Bᵀ is indefinite in at least mode B
    res = certify(big_switching, THETA_SW, delta=0.5 * ds, gain="1/(1+t)")
    assert res.certificate["kind"] == "switching-scale"
    assert not res.verification.valid and not res.proven
    assert "B" not in res.certificate["proofs"]
    lam = res.certificate["results"]["symmetric_part_min_eig"]["B"]
    assert lam < 0
    prem = [p for p in res.theorems[0].premises if p.name.startswith("L_B(B)")][0]
    assert prem.holds is False and prem.detail.startswith(f"fails by {-lam:.6g}")


@pytest.mark.filterwarnings("ignore::ntc_design.protocol.AssumptionWarning")
def test_an_agent_nothing_reaches_is_never_certified():
    a = random_network(25, 3, seed=4)
    ea = a.edge_arrays
    keep = ea.rows != 7  # agent 7 loses every in-edge: its row of L_B is 0
    b = Topology.from_arrays(a.labels, 3, ea.rows[keep], ea.cols[keep], ea.w[keep])
    big_switching = SwitchingTopology({"A": a, "B": b}, (("A", 1.0), ("B", 1.0)))
    res = certify(big_switching, THETA_SW)
    assert res.certificate["kind"] == "switching-scale"
    assert not res.verification.valid and not res.proven
    assert "B" not in res.certificate["proofs"] and "A" in res.certificate["proofs"]


@pytest.mark.parametrize(
    "forge, needle",
    [
        (lambda d: d["proofs"]["A"].update(lower=d["proofs"]["A"]["lower"] * 1.01), "L_B(A)"),
        (lambda d: d["proofs"].pop("B"), "L_B(B)"),
        (lambda d: d["claims"].pop(), "listed claims"),
        (lambda d: d.update(certifies=["symmetric_part", "common_lyapunov"]), "certifies"),
        (lambda d: d["subject"]["schedule"].pop(), "switching hash"),
        (
            lambda d: d["subject"]["modes"]["B"].update(theta=[1.0, 2.0, 3.0]),
            "θ ≠ 0, one for every mode",
        ),
        (lambda d: d["subject"]["modes"]["A"].update(informed=[]), "informed"),
    ],
)
def test_forgeries_fail_after_the_digest_is_recomputed(big_cert, forge, needle):
    doc = copy.deepcopy(big_cert)
    forge(doc)
    ver = verify(_refresh(doc))
    assert not ver.valid
    assert any(needle in c.name for c in ver.failed), [c.name for c in ver.failed]
    assert all(c.ok for c in ver.checks if c.name == "digest")


@pytest.mark.parametrize(
    "forge",
    [
        lambda d: d["results"]["symmetric_part_min_eig"].update(A=0.5),  # below its bound
        lambda d: d["results"]["symmetric_part_lower_bound"].update(A=0.99),
        lambda d: d["results"]["common_lyapunov"].update(structure=None),
        lambda d: d["proofs"].update(C={"lower": 0.0}),  # a mode the schedule never uses
    ],
)
def test_forged_switching_results_fail(big_cert, forge):
    doc = copy.deepcopy(big_cert)
    forge(doc)
    ver = verify(_refresh(doc))
    assert [c.name for c in ver.failed] == [
        "reported results (each number recomputed, bounded or informational)"
    ]


def test_an_unscheduled_mode_is_neither_proven_nor_reported(big_switching):
    once = SwitchingTopology(dict(big_switching.modes), (("A", 0.5),))
    res = certify(once, THETA_SW)
    c = res.certificate
    assert res.verification.valid
    assert set(c["proofs"]) == {"A"} and set(c["results"]["symmetric_part_min_eig"]) == {"A"}


@pytest.mark.parametrize(
    "path, value, needle",
    [
        (("subject", "modes", "A", "delta"), 10**400, "delta"),
        (("subject", "modes", "A", "delta"), 1e300, "delta"),
        (("proofs", "A", "lower"), 10**400, "lower"),
    ],
)
def test_out_of_range_numbers_are_bad_input(big_cert, path, value, needle):
    doc = copy.deepcopy(big_cert)
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(InputError, match=needle):
        verify(_refresh(doc))


@pytest.mark.parametrize("value", ["abc", [1], None, 10**400])
def test_malformed_unscheduled_proof_is_invalid_not_a_crash(big_cert, value):
    doc = copy.deepcopy(big_cert)
    doc["proofs"]["Z"] = {"lower": value}
    doc["results"]["symmetric_part_min_eig"]["Z"] = 1.0
    ver = verify(_refresh(doc))
    assert [c.name for c in ver.failed] == [
        "reported results (each number recomputed, bounded or informational)"
    ]
