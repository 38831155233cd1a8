"""Issue 9 (switching half): big switching sets get a sparse certificate per mode
(``switching-scale``), cross-checked against dense eigenvalues and the dense switching
certificate; forgeries fail; the sparse-factor memory guard; ``.npz`` modes; the
vectorised topology hash against the reference formula."""

import copy
import json
import os
import stat

import numpy as np
import pytest
import scipy.sparse as sp

from ntc_design.certify import certify, verify
from ntc_design.certify.format import digest, document_hash, topology_hash
from ntc_design.certify.kinds.switching import switching_certificate
from ntc_design.certify.kinds.switching_scale import switching_scale_certificate
from ntc_design.certify.scale import component_matrix, lap_b_blocks, symmetric_part_bound
from ntc_design.design import design
from ntc_design.errors import InputError
from ntc_design.generate import random_network, write_topology
from ntc_design.linalg import SPDFamily, cholesky_fill
from ntc_design.loader import load
from ntc_design.model import SwitchingTopology, Topology

from .cli_helpers import assert_input_error, run_cli

THETA_SW = [1.0, -2.0, 0.5]


def _switching(n=30, d=3, seeds=(1, 2), families=("random", "small-world")):
    modes = {}
    for k, (s, f) in enumerate(zip(seeds, families, strict=True)):
        t = random_network(n, d, seed=s, family=f)
        # every mode over the same agents: relabel onto mode 0's labels
        modes["AB"[k]] = t
    labels = modes["A"].labels
    modes = {
        k: Topology.from_arrays(labels, d, t.edge_arrays.rows, t.edge_arrays.cols, t.edge_arrays.w)
        for k, t in modes.items()
    }
    return SwitchingTopology(modes, (("A", 0.1), ("B", 0.2)))


def _dense_sym_min(des):
    lap = des.grounded_laplacian()
    return float(np.linalg.eigvalsh(lap + lap.T)[0])


def _refresh(doc):
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.fixture(scope="module")
def big_switching():
    return _switching()


@pytest.fixture(scope="module")
def big_cert(big_switching):
    return switching_scale_certificate(design(big_switching, THETA_SW, thresholds=False))


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


@pytest.mark.filterwarnings("ignore::ntc_design.design.AssumptionWarning")
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
    "field, value, needle",
    [
        ("lower", -1.0, "lower"),
        ("lower", float("nan"), "lower"),
        ("lower", 1e300, "lower"),
        ("lower", True, "lower"),
        ("k", 3, "expected {lower}"),
    ],
)
def test_malformed_proof_fields_are_bad_input(big_cert, field, value, needle):
    doc = copy.deepcopy(big_cert)
    doc["proofs"]["A"][field] = value
    with pytest.raises(InputError, match=needle):
        verify(_refresh(doc))


def test_verify_checks_the_users_topology_and_theta(big_switching, big_cert):
    assert verify(big_cert, topology=big_switching, theta=THETA_SW).valid
    other = SwitchingTopology(dict(big_switching.modes), (("A", 0.1), ("B", 0.3)))
    ver = verify(big_cert, topology=other)
    assert [c.name for c in ver.failed] == ["about the given topology"]
    ver = verify(big_cert, theta=[1.0, 2.0, 0.5])
    assert [c.name for c in ver.failed] == ["θ is the one given"]
    ver = verify(big_cert, topology=big_switching.modes["A"])
    assert [c.name for c in ver.failed] == ["about the given topology"]


def test_hurwitz_scale_verify_checks_the_users_topology_and_theta():
    top = random_network(40, 3, seed=5)
    res = certify(top, THETA_SW)
    assert res.certificate["kind"] == "hurwitz-scale" and res.verification.valid
    assert verify(res.certificate, topology=top, theta=THETA_SW).valid
    other = random_network(40, 3, seed=6)
    assert [c.name for c in verify(res.certificate, topology=other).failed] == [
        "about the given topology"
    ]
    assert [c.name for c in verify(res.certificate, theta=[1, 1, 1]).failed] == [
        "θ is the one given"
    ]
    assert verify(res.certificate).about.modes[0].topology_hash == topology_hash(top)


def test_memory_guard_refuses_a_factor_that_will_not_fit(big_switching, big_cert, monkeypatch):
    import ntc_design.linalg as la

    monkeypatch.setattr(la, "SPARSE_FACTOR_MAX_BYTES", 1000.0)
    res = certify(big_switching, THETA_SW)
    assert not res.verification.valid and not res.proven
    assert res.certificate["proofs"] == {}
    assert "refused" in res.certificate["results"]["details"]["A"]
    with pytest.raises(InputError, match="refused"):
        verify(big_cert)


def _reference_fill(a, perm):
    """nnz and longest row of the Cholesky factor of a[perm, perm], from a dense numeric
    factorisation of an SPD matrix with that pattern (random values: no cancellation)."""
    rng = np.random.default_rng(0)
    pat = (abs(a) + abs(a.T)).toarray() != 0
    m = np.where(pat, rng.uniform(-1, 1, pat.shape), 0.0)
    m = 0.5 * (m + m.T)
    m += np.diag(np.abs(m).sum(axis=1) + 1.0)
    low = np.linalg.cholesky(m[np.ix_(perm, perm)])
    nz = np.abs(low) > 0
    return int(nz.sum()), int(nz.sum(axis=1).max())


@pytest.mark.parametrize("seed", range(4))
def test_cholesky_fill_is_the_exact_factor_structure(seed):
    from cvxopt import amd, matrix, spmatrix

    top = random_network(60, 2, seed=seed, family=["random", "grid", "scale-free", "ring"][seed])
    s = (top.laplacian_sparse() + top.laplacian_sparse().T).tocoo()
    n = s.shape[0]
    low = sp.tril(abs(s) + abs(s.T), k=-1, format="coo")
    eye = np.arange(n)
    pat = spmatrix(
        matrix(np.ones(low.nnz + n)),
        matrix(np.concatenate([low.row, eye]).astype(np.int64)),
        matrix(np.concatenate([low.col, eye]).astype(np.int64)),
        (n, n),
    )
    perm = np.array(amd.order(pat, uplo="L"), dtype=np.int64).ravel()
    fill = cholesky_fill(s)
    assert (fill.nnz, fill.row_max) == _reference_fill(s, perm)
    # and CHOLMOD's (supernodal, padded) factor is at least as long in its longest row
    spd = abs(s).tocsr()
    spd = spd + sp.diags(np.asarray(spd.sum(axis=1)).ravel() + 1.0)  # same pattern, SPD
    fam = SPDFamily([spd.tocsr()])
    ok, k = fam.factor([1.0], 0.0, row_counts=True)
    assert ok and k >= fill.row_max


def test_npz_modes_in_a_switching_file(tmp_path, big_switching, capsys, monkeypatch):
    for k, t in big_switching.modes.items():
        write_topology(t, tmp_path / f"{k}.npz")
    f = tmp_path / "big_switching.yaml"
    f.write_text(
        "modes: {A: A.npz, B: B.npz}\nschedule: [{mode: A, duration: 0.1}, {mode: B, duration: 0.2}]\n"
    )
    got = load(f)
    for k, t in big_switching.modes.items():
        assert topology_hash(got.modes[k]) == topology_hash(t)
    out = tmp_path / "c.json"
    code, text, err = run_cli(
        ["certify", f, "--theta", "1,-2,0.5", "--out", out, "--gain", "1/(1+t)"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    assert (
        "proven lower bound ℓ: λ_min > ℓ" in text and "Theorem 3 (mean square): guaranteed" in text
    )
    mode = stat.S_IMODE(os.stat(out).st_mode)
    umask = os.umask(0)
    os.umask(umask)
    assert mode == 0o666 & ~umask  # a file to share, not a private temporary file
    code, text, err = run_cli(
        ["verify", out, "--topology", f, "--theta", "1,-2,0.5"], capsys, monkeypatch
    )
    assert code == 0, err
    assert "kind: switching-scale" in text and "VALID" in text
    doc = json.loads(out.read_text())
    doc["proofs"]["A"]["lower"] *= 1.5
    out.write_text(json.dumps(_refresh(doc)))
    code, _, err = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 1 and "L_B(A) + L_B(A)ᵀ ≻ 0" in err
    (tmp_path / "B.npz").write_bytes(b"not a zip")
    assert_input_error(["check", f], capsys, monkeypatch, "big_switching.yaml", "modes.B", "B.npz")


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


def test_delta_s_is_skipped_with_a_reason_when_the_bisection_would_not_fit(monkeypatch):
    import ntc_design.linalg as la

    top = random_network(80, 3, seed=2)
    full = design(top, THETA_SW, thresholds=True).thresholds
    assert full.symmetric is not None and full.symmetric > 0
    monkeypatch.setattr(
        la,
        "SPARSE_FACTOR_MAX_FLOPS",
        10 * la.cholesky_fill((top.laplacian_sparse() + top.laplacian_sparse().T).tocsr()).flops,
    )
    th = design(top, THETA_SW, thresholds=True).thresholds
    assert th.symmetric is None
    assert any(n.startswith("δ_S not computed: the bisection needs about 50") for n in th.notes)
    assert th.hurwitz == full.hurwitz  # the per-component δ_H does not factorise


def test_rate_estimate_skips_a_component_that_fills_in(monkeypatch):
    import ntc_design.certify.scale as sc

    top = random_network(700, 3, seed=1, extra=2.0)
    res = certify(top, THETA_SW)
    assert res.certificate["kind"] == "hurwitz-scale" and res.verification.valid
    big = res.certificate["results"]["largest_component_agents"]
    assert big * 3 > sc.RATE_DENSE_MAX_ND  # the big component goes to ARPACK ...
    assert "ARPACK" in res.certificate["results"]["rate_estimate"]["method"]
    monkeypatch.setattr(sc, "RATE_ARPACK_MAX_FLOPS", 1.0)  # ... unless it fills in
    res2 = certify(top, THETA_SW)
    assert res2.verification.valid
    assert "filling in too much" in res2.certificate["results"]["rate_estimate"]["method"]


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
            "recomputed",
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


def test_an_unscheduled_mode_is_neither_proven_nor_reported(big_switching):
    once = SwitchingTopology(dict(big_switching.modes), (("A", 0.5),))
    res = certify(once, THETA_SW)
    c = res.certificate
    assert res.verification.valid
    assert set(c["proofs"]) == {"A"} and set(c["results"]["symmetric_part_min_eig"]) == {"A"}


def test_a_topology_mismatch_names_the_mode(big_switching, big_cert):
    other = SwitchingTopology(
        {"A": big_switching.modes["A"], "B": big_switching.modes["A"]}, (("A", 0.1), ("B", 0.2))
    )
    (bad,) = verify(big_cert, topology=other).failed
    assert "(mode B differs)" in bad.detail
    moved = SwitchingTopology(dict(big_switching.modes), (("A", 0.1), ("B", 0.25)))
    (bad,) = verify(big_cert, topology=moved).failed
    assert "(the schedule differs)" in bad.detail


def test_a_missing_npz_mode_says_so(tmp_path, capsys, monkeypatch):
    f = tmp_path / "big_switching.yaml"
    f.write_text("modes: {A: nope.npz}\nschedule: [{mode: A, duration: 1}]\n")
    assert_input_error(["check", f], capsys, monkeypatch, "modes.A", "nope.npz: no such file")


def test_overflow_or_nan_never_proves_anything():
    """Review findings: an overflowing shift made CHOLMOD take NaN pivots as positive."""
    fam = SPDFamily([sp.csr_matrix(np.array([[np.nan, 1, 1], [1, 1, 1], [1, 1, -1.0]]))])
    assert fam.factor([1.0], 0.0) == (False, 0)
    # antagonistic −[[1,1],[1,1]] both ways and δ = 1e308: L_B x = 0 for x = (1,−1,1,−1)
    w = -np.ones((2, 2, 2))
    top = Topology.from_arrays(["a", "b"], 2, np.array([0, 1]), np.array([1, 0]), w)
    lap, err = component_matrix(lap_b_blocks(top, 1e308), np.arange(2))
    p = symmetric_part_bound(lap, err)
    assert not p.holds and "overflows" in p.detail
    # cooperative 1e308 and 1.7e308: the model refuses such weights; the bound itself
    # still proves nothing from entries whose sums overflow
    w2 = np.array([[[1e308]], [[1.7e308]]])
    with pytest.raises(InputError, match="outside"):
        Topology.from_arrays(["a", "b"], 1, np.array([0, 1]), np.array([1, 0]), w2)
    lap2 = sp.csr_matrix(np.array([[1e308, -1e308], [-1.7e308, 1.7e308]]))
    err2 = sp.csr_matrix(np.zeros((2, 2)))
    assert not symmetric_part_bound(lap2, err2, 2.0**250).holds


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


def test_tiny_weights_are_bad_input_not_a_proof(big_cert):
    from ntc_design.certify.arrays import pack

    doc = copy.deepcopy(big_cert)
    t = doc["subject"]["modes"]["A"]["topology"]
    from ntc_design.certify.arrays import unpack

    w = unpack(t["weights"], "w", "f8", (t["edges"], 3, 3))
    w[0] = np.eye(3) * 2.0**-1074  # a subnormal weight
    t["weights"] = pack(w, "f8")
    with pytest.raises(InputError, match="weights"):
        verify(_refresh(doc))


def test_the_block_memory_guard(monkeypatch):
    import ntc_design.certify.scale as sc

    top = random_network(50, 3, seed=1)
    monkeypatch.setattr(sc, "DENSE_MAX_BYTES", 4 * 8.0 * 50 * 9 - 1)
    with pytest.raises(InputError, match="diagonal blocks: N = 50 agents of d = 3"):
        lap_b_blocks(top, 1.0)


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


@pytest.mark.parametrize("value", ["abc", [1], None, 10**400])
def test_malformed_unscheduled_proof_is_invalid_not_a_crash(big_cert, value):
    doc = copy.deepcopy(big_cert)
    doc["proofs"]["Z"] = {"lower": value}
    doc["results"]["symmetric_part_min_eig"]["Z"] = 1.0
    ver = verify(_refresh(doc))
    assert [c.name for c in ver.failed] == [
        "reported results (each number recomputed, bounded or informational)"
    ]


def test_a_bound_below_the_number_range_is_issued_as_zero():
    """Second review: ℓ < 2^-250 made an honest certificate unreadable; it is issued as 0."""
    s = 2.0**-240
    i2, t2 = np.eye(2) * s, np.diag([1.0, 2.0**-9]) * s
    a = Topology.from_edges(4, 2, [(1, 2, -i2), (2, 1, -i2), (3, 4, -t2), (4, 3, -t2)])
    b = Topology.from_edges(4, 2, [(1, 2, -i2), (2, 1, -i2), (3, 4, -i2), (4, 3, -i2)])
    big_switching = SwitchingTopology({"A": a, "B": b}, (("A", 1.0), ("B", 1.0)))
    c = switching_scale_certificate(design(big_switching, [1.0, -2.0], thresholds=False))
    assert c["proofs"]["A"]["lower"] == 0.0 and c["results"]["symmetric_part_min_eig"]["A"] > 0
    assert verify(json.loads(json.dumps(c))).valid


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


def _count_numeric(monkeypatch):
    """A spy on CHOLMOD's numeric factorisation: the list of calls grows by one each."""
    from cvxopt import cholmod

    calls = []
    real = cholmod.numeric

    def spy(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(cholmod, "numeric", spy)
    return calls


def test_factorisations_per_mode(big_switching, monkeypatch):
    """Issue 20: the issuer factorises twice per mode (the ℓ = 0 proof, which is also the
    eigensolver's inverse, then ℓ), ``certify`` re-verifies without factorising the same
    matrices again, and a fresh verify factorises once per mode."""
    import ntc_design.linalg as la

    la._PROVEN.clear()
    calls = _count_numeric(monkeypatch)
    res = certify(big_switching, THETA_SW)
    assert res.certificate["kind"] == "switching-scale" and res.verification.valid
    assert all(lo > 0 for lo in res.certificate["results"]["symmetric_part_lower_bound"].values())
    assert len(calls) == 4
    la._PROVEN.clear()
    assert verify(json.loads(json.dumps(res.certificate))).valid
    assert len(calls) == 6


def test_reuse_needs_the_bit_identical_matrix(monkeypatch):
    """A remembered success answers only for the same float values and shift: one ulp
    off, or another shift, is factorised (and a shift past λ_min fails)."""
    import scipy.sparse as sp

    import ntc_design.linalg as la

    a = sp.csr_matrix(np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]]))
    calls = _count_numeric(monkeypatch)
    assert SPDFamily([a]).factor([1.0], 0.5, reuse=True)[0]
    assert SPDFamily([a]).factor([1.0], 0.5, reuse=True)[0] and len(calls) == 1
    b = a.copy()
    b.data[0] = np.nextafter(b.data[0], 3.0)
    assert SPDFamily([b]).factor([1.0], 0.5, reuse=True)[0] and len(calls) == 2
    lam = 2 - np.sqrt(2)
    assert not SPDFamily([a]).factor([1.0], lam * (1 + 1e-9), reuse=True)[0]
    assert not SPDFamily([a]).factor([1.0], lam * (1 + 1e-9), reuse=True)[0]
    assert len(calls) == 4  # failures are never remembered
    fam = SPDFamily([a])
    assert fam.factor([1.0], 0.5, reuse=True)[0]
    with pytest.raises(ValueError, match="no successful factorisation"):
        fam.solve(np.ones(3))  # a reused answer keeps no factor
    assert len(la._PROVEN) <= la.PROVEN_KEEP


def test_a_mode_above_the_rate_proof_size_keeps_one_factorisation(big_switching, monkeypatch):
    """Issue 20: above RATE_PROOF_MAX_FLOPS the second factorisation (ℓ > 0) is not made:
    ℓ = 0 is proven by the factor that serves the estimate, the estimate is still the
    dense eigenvalue, and the certificate verifies."""
    from ntc_design import linalg
    from ntc_design.certify import switching_scale as ss

    calls = []
    real = linalg.SPDFamily.factor

    def counting(self, *a, **k):
        calls.append(1)
        return real(self, *a, **k)

    monkeypatch.setattr(linalg.SPDFamily, "factor", counting)
    des = design(big_switching, THETA_SW, thresholds=False)
    full = switching_scale_certificate(des)
    n_full = len(calls)
    monkeypatch.setattr(ss, "RATE_PROOF_MAX_FLOPS", 0.0)
    calls.clear()
    one = switching_scale_certificate(des)
    assert n_full == 4 and len(calls) == 2  # two modes: two factorisations each, then one
    for k, d in des.modes.items():
        assert full["proofs"][k]["lower"] > 0 and one["proofs"][k]["lower"] == 0.0
        assert one["results"]["symmetric_part_min_eig"][k] == pytest.approx(
            _dense_sym_min(d), rel=1e-9
        )
        assert "ℓ > 0 not attempted" in one["results"]["details"][k]
    assert verify(one).valid


def test_big_modes_are_proven_in_parallel_with_the_same_certificate(big_switching, monkeypatch):
    """Modes above PARALLEL_MIN_ND are proven in forked processes (certify and verify):
    the same proofs and numbers as in one process, and certify's own re-verification
    still reuses the children's factorisations (none repeated in the parent)."""
    from ntc_design import linalg
    from ntc_design.certify import switching_scale as ss

    des = design(big_switching, THETA_SW, thresholds=False)
    serial = switching_scale_certificate(des)
    big_nd = ss.PARALLEL_MIN_ND
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", 0)
    monkeypatch.setattr(linalg, "proof_workers", lambda n: 2)
    monkeypatch.setattr(ss, "proof_workers", lambda n: 2)
    linalg._PROVEN.clear()
    par = switching_scale_certificate(des)
    assert par["proofs"] == serial["proofs"]
    assert par["results"]["symmetric_part_min_eig"] == serial["results"]["symmetric_part_min_eig"]
    assert len(linalg._PROVEN) == 4  # the children's successes, known to the parent
    calls = []
    real = linalg.SPDFamily.factor

    def counting(self, *a, **k):
        ok = real(self, *a, **k)
        calls.append(self._symbolic is not None)  # a numeric factorisation happened here
        return ok

    monkeypatch.setattr(linalg.SPDFamily, "factor", counting)
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", big_nd)  # verify in this process
    ver = verify(par)  # in the parent: every mode's matrix was proven by a child
    assert ver.valid and calls and not any(calls)
    # verify's own parallel path, from scratch: the same checks as in one process
    from ntc_design.certify.kinds import switching_scale as kind

    monkeypatch.setattr(linalg.SPDFamily, "factor", real)
    linalg._PROVEN.clear()
    one = verify(par)
    monkeypatch.setattr(ss, "PARALLEL_MIN_ND", 0)
    used = []
    monkeypatch.setattr(kind, "fork_map", lambda c, w: used.append(w) or linalg.fork_map(c, w))
    linalg._PROVEN.clear()
    two = verify(par)
    assert used == [2]
    assert one.valid and two.valid
    assert [(c.name, c.ok, c.detail) for c in one.checks] == [
        (c.name, c.ok, c.detail) for c in two.checks
    ]
    assert len(linalg._PROVEN) == 2  # the children's proofs reached the parent


def _dies():
    os._exit(3)


def _fails(x):
    raise InputError(f"bad part {x}")


def test_fork_map_keeps_order_and_reports_failures_in_one_line():
    from ntc_design.linalg import fork_map

    assert fork_map([(pow, (2, k)) for k in range(5)], 2) == [1, 2, 4, 8, 16]
    assert fork_map([(pow, (3, 2))], 2) == [9]  # one call: in this process
    with pytest.raises(InputError, match="bad part 7"):
        fork_map([(pow, (2, 1)), (_fails, (7,))], 2)
    with pytest.raises(InputError, match=r"died \(out of memory\?\); nothing is proven") as e:
        fork_map([(pow, (2, 1)), (_dies, ())], 2)
    assert "\n" not in str(e.value)


def _fork_map_in_a_daemon(conn):
    from ntc_design.linalg import fork_map

    try:
        conn.send(("ok", fork_map([(pow, (2, k)) for k in range(4)], 2)))
    except BaseException as exc:  # noqa: BLE001 - reported to the test
        conn.send(("error", repr(exc)))


def test_fork_map_runs_in_place_inside_a_daemon_process():
    """A Dask worker is a daemon (a sweep certifies there): no children allowed, so the
    proofs run one after the other in it instead of failing."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    here, there = ctx.Pipe()
    p = ctx.Process(target=_fork_map_in_a_daemon, args=(there,), daemon=True)
    p.start()
    got = here.recv()
    p.join(30)
    assert got == ("ok", [1, 2, 4, 8])


def test_proof_workers_fit_the_memory(monkeypatch):
    from ntc_design import linalg

    monkeypatch.setattr(linalg, "available_memory", lambda: 3.5 * 2**30)
    assert linalg.proof_workers(16, bytes_each=2**30) == min(3, len(os.sched_getaffinity(0)))
    assert linalg.proof_workers(16, bytes_each=2**40) == 1  # one proof always runs
    assert linalg.proof_workers(16) == 1  # 3.5 GiB < one factor at the 4 GiB limit
