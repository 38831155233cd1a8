"""Issue 9 (model/design half): sparse L and L_B, batched classification and Lemma 1
coefficients, Assumption 2 by BFS against the reference scan, labels in public results,
the generator's promise, the .npz edge list, the memory guard."""

import json
import math
import warnings

import numpy as np
import pytest
import scipy.linalg as sla

import ntc_design as nd
from ntc_design.design import (
    AssumptionWarning,
    assumption2,
    design,
    lemma1_coefficient,
)
from ntc_design.design.assumption import lemma1_coefficients
from ntc_design.generate import FAMILIES, random_network, write_topology
from ntc_design.linalg import DEF_CODES, DenseRefused, SPDFamily, classify, require_dense
from ntc_design.model import (
    Topology,
    antagonistic_in_weight,
    in_degree_dominated,
    positive_negative_reachable,
)

from .cli_helpers import assert_input_error, run_cli
from .conftest import random_topology


def _reference_assumption2(top):
    """The dense-era algorithm: V1 grown level by level, BFS from scratch each time."""
    n = top.n
    idd = [in_degree_dominated(top, i) for i in range(n)]
    cands = {
        i: lemma1_coefficient(top, i)
        for i in range(n)
        if classify(antagonistic_in_weight(top, i)).value == "PD"
    }
    if any(not idd[i] and i not in cands for i in range(n)):
        return False, None
    floor = max((cands[i] for i in range(n) if not idd[i]), default=-math.inf)
    for level in sorted({c for c in cands.values() if c >= floor}):
        v1 = [i for i in sorted(cands) if cands[i] <= level]
        paths = positive_negative_reachable(top, v1)
        if all(i in paths for i in range(n)):
            return True, (tuple(v1), paths)
    return False, None


@pytest.mark.parametrize("seed", range(12))
def test_sparse_laplacian_equals_dense_and_design_matches_reference(seed):
    top = random_topology(seed, n=6, d=2, p_edge=0.45)
    lap = top.laplacian()
    np.testing.assert_array_equal(top.laplacian_sparse().toarray(), lap)
    for (i, j), c in top.classes.items():  # batched classification = one by one
        assert c is classify(top.weights[(i, j)])
    cand, c = lemma1_coefficients(top)
    for i in range(top.n):
        assert cand[i] == (classify(antagonistic_in_weight(top, i)).value == "PD")
        if cand[i]:
            assert c[i] == pytest.approx(lemma1_coefficient(top, i), rel=1e-9, abs=1e-12)
    dec = assumption2(top)
    ok, ref = _reference_assumption2(top)
    assert dec.holds == ok
    if ok:
        assert dec.v1 == ref[0]
        for i in dec.v2:
            assert dec.paths[i] == tuple(ref[1][i])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumptionWarning)
        des = design(top, [1.0, -1.0], thresholds=False)
    lb = des.grounded_laplacian()
    np.testing.assert_allclose(des.grounded_laplacian_sparse().toarray(), lb, rtol=0, atol=0)


def test_failing_assumption_warns_and_violators_are_in_neither_set():
    # agent 2 sends more than it hears and has no antagonistic in-edge (issue 8)
    top = Topology.from_edges(
        ["a", "b", "c"], 1, [("a", "b", [[1.0]]), ("b", "c", [[5.0]]), ("b", "a", [[-1.0]])]
    )
    with pytest.warns(AssumptionWarning, match="Assumption 2 fails"):
        des = nd.design(top, [1.0])
    assert not des.assumption_holds
    assert des.violating_agents == ("b",)
    assert "b" not in des.v1_agents and "b" not in des.v2_agents
    doc = des.to_dict()
    assert "b" not in doc["V2"] and "b" not in doc["V1"]


def test_public_results_use_labels(tmp_path):
    top = random_network(30, 2, seed=4, family="ring")
    relab = Topology(tuple(f"x{k}" for k in range(top.n)), top.dim, dict(top.weights))
    des = nd.design(relab, [1.0, 2.0])
    assert des.informed_agents == tuple(relab.labels[i] for i in des.informed)
    assert all(isinstance(a, str) and a.startswith("x") for a in des.informed_agents)
    assert set(des.v1_agents) | set(des.v2_agents) == set(relab.labels)
    assert set(des.B_by_agent) == set(des.informed_agents)
    doc = des.to_dict()
    assert doc["informed"] == list(des.informed_agents)
    assert doc["V1"] == list(des.v1_agents)


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


@pytest.mark.hostile
def test_bad_npz_gives_one_line(tmp_path, capsys, monkeypatch):
    top = random_network(10, 2, seed=1)
    ea = top.edge_arrays
    good = {
        "format": np.array("ntc-design/edge-list"),
        "dim": np.array(2),
        "labels": np.arange(1, 11),
        "from": ea.cols,
        "to": ea.rows,
        "weights": ea.w,
    }
    cases = [
        ({"to": ea.rows + 100}, "to[0]"),
        ({"weights": ea.w[:, :1]}, "weights"),
        ({"from": ea.cols.astype(float)}, "from"),
        ({"extra": np.zeros(2)}, "unknown array"),
        ({"labels": np.array([1] * 10)}, "unique"),
        ({"format": np.array("x")}, "format"),
    ]
    for k, (change, needle) in enumerate(cases):
        p = tmp_path / f"bad{k}.npz"
        np.savez(p, **(good | change))
        assert_input_error(["check", p], capsys, monkeypatch, str(p), needle)
    dup = tmp_path / "dup.npz"
    np.savez(
        dup,
        **(
            good
            | {
                "from": np.r_[ea.cols, ea.cols[:1]],
                "to": np.r_[ea.rows, ea.rows[:1]],
                "weights": np.r_[ea.w, ea.w[:1]],
            }
        ),
    )
    assert_input_error(["check", dup], capsys, monkeypatch, "duplicated edge")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"PK\x03\x04 not really")
    assert_input_error(["check", junk], capsys, monkeypatch, "not a readable")
    asym = tmp_path / "asym.npz"
    w = ea.w.copy()
    w[3, 0, 1] += 1.0
    np.savez(asym, **(good | {"weights": w}))
    assert_input_error(["check", asym], capsys, monkeypatch, "not symmetric")


def test_memory_guard_refuses_dense_steps_in_one_line():
    with pytest.raises(DenseRefused, match=r"needs about .* GiB"):
        require_dense(200_000, "test step")
    require_dense(100, "small step")
    big = random_network(20_000, 3, seed=0)  # Nd = 60,000: a dense L would take 27 GiB
    with pytest.raises(nd.InputError, match="signed Laplacian L: a dense 60000×60000"):
        big.laplacian()
    des = nd.design(big, [1.0, 0.0, 0.0], thresholds=False)  # the sparse path works
    assert des.assumption_holds and des.identity_residual < 1e-12
    assert des.grounded_laplacian_sparse().shape == (60_000, 60_000)


def test_sparse_cholesky_decides_definiteness_at_the_boundary():
    rng = np.random.default_rng(3)
    g = rng.normal(size=(40, 40))
    a = g @ g.T
    lam = sla.eigvalsh(a)[0]
    fam = SPDFamily([__import__("scipy.sparse").sparse.csr_matrix(a)])
    for rel in (1e-6, 1e-3, 0.5):
        assert fam.factor([1.0], lam * (1 - rel))[0]
        assert not fam.factor([1.0], lam * (1 + rel))[0]


def test_sparse_critical_couplings_agree_with_dense():
    """δ_S (sparse bisection) and δ_H (per component) against the dense method."""
    from ntc_design.thresholds import critical_couplings, critical_couplings_sparse

    for seed in range(4):
        top = random_network(25, 2, seed, "ring" if seed % 2 else "random")
        des = nd.design(top, [1.0, 1.0], thresholds=False)
        dense = critical_couplings(des.topology.laplacian(), des.coupling_matrix())
        sp_ = critical_couplings_sparse(
            top.laplacian_sparse(), des.coupling_matrix_sparse(), top.dim
        )
        assert sp_.symmetric == pytest.approx(dense.symmetric, rel=2e-4, abs=1e-9)
        if sp_.hurwitz is not None:
            assert sp_.hurwitz == pytest.approx(dense.hurwitz, rel=1e-6, abs=1e-9)
        assert DEF_CODES  # the batched codes table is exported


# ----------------------------------------------------------- scalable certificates


def _two_agent_cycle(delta):
    """Two agents hearing each other through ND, strongly anisotropic weights: the
    comparison matrix is an M-matrix only for δ > 99, L_B + L_Bᵀ ≻ 0 only for δ > ~4.05,
    yet −L_B is Hurwitz for every δ > 0 (each coordinate is a 2×2 block with positive
    trace and determinant)."""
    top = Topology.from_edges(
        2, 2, [(2, 1, -np.diag([1.0, 0.01])), (1, 2, -np.diag([0.01, 1.0]))], name="cycle"
    )
    return nd.design(top, [1.0, 2.0], delta=delta, thresholds=False)


def _methods(cert):
    return cert["results"]["methods"]


def test_component_decomposition_is_block_triangular():
    from ntc_design.thresholds import strong_components

    top = random_network(400, 2, seed=5)
    des = nd.design(top, [1.0, 1.0], thresholds=False)
    lb = des.grounded_laplacian_sparse()
    ncomp, comp = strong_components(lb, 2)
    ea = top.edge_arrays
    assert np.all(comp[ea.cols] <= comp[ea.rows])  # every edge goes forward
    # the eigenvalues of L_B are those of its component blocks
    dense = lb.toarray()
    ev = np.sort_complex(np.linalg.eigvals(dense))
    parts = []
    for c in range(ncomp):
        ix = (np.flatnonzero(comp == c)[:, None] * 2 + np.arange(2)).ravel()
        parts.append(np.linalg.eigvals(dense[np.ix_(ix, ix)]))
    np.testing.assert_allclose(
        np.sort_complex(np.concatenate(parts)), ev, atol=1e-8 * abs(ev).max()
    )
    assert ncomp > 1 and np.bincount(comp).max() > 1


@pytest.mark.slow
def test_dominance_certificate_and_verify_round_trip(tmp_path):
    import json

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


def test_dominance_fails_and_the_fallbacks_decide():
    from ntc_design.certify import scale_certificate, verify

    low = scale_certificate(_two_agent_cycle(1.0))  # neither dominance nor symmetric part
    assert _methods(low) == {"dominance": 0, "symmetric": 0, "lyapunov": 1, "none": 0}
    assert verify(low).valid
    mid = scale_certificate(_two_agent_cycle(10.0))  # symmetric part ≻ 0, no dominance
    assert _methods(mid)["symmetric"] == 1 and _methods(mid)["dominance"] == 0
    assert verify(mid).valid
    high = scale_certificate(_two_agent_cycle(120.0))  # dominance
    assert _methods(high)["dominance"] == 1
    assert verify(high).valid


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


def test_certify_cli_at_scale_and_the_lmi_guard(tmp_path, capsys, monkeypatch):
    from ntc_design.certify import hurwitz_certificate

    p = tmp_path / "n200.npz"
    write_topology(random_network(200, 2, seed=3), p)  # the N = 200, d = 2 abort
    cert = tmp_path / "c.json"
    code, out, _ = run_cli(["certify", p, "--theta", "1,2", "--out", cert], capsys, monkeypatch)
    assert code == 0 and "skipped: decay-rate LMI" in out.replace("\n", " ")
    code, out, _ = run_cli(["verify", cert], capsys, monkeypatch)
    assert code == 0 and "VALID" in out
    des = nd.design(nd.load(p), [1.0, 2.0], thresholds=False)
    with pytest.raises(DenseRefused, match="decay-rate LMI: a dense 400×400 P needs about"):
        hurwitz_certificate(des, rate_method="lmi")  # the default needs no SDP: no guard


def test_symmetric_part_bound_just_above_and_below_definiteness():
    """prove_symmetric_part on L = diag-shifted matrices around λ_min(L + Lᵀ) = 0."""
    import scipy.sparse as sp

    from ntc_design.certify.scale import prove_symmetric_part

    rng = np.random.default_rng(11)
    n = 60
    g = sp.random(n, n, density=0.1, random_state=rng).toarray()
    s = g + g.T
    lam = np.linalg.eigvalsh(s)[0]
    for rel, expect in ((1e-6, True), (-1e-6, False)):
        shift = -lam / 2 + rel * abs(lam)
        lap = sp.csr_matrix(g + shift * np.eye(n))
        ok, _ = prove_symmetric_part(lap, sp.csr_matrix((n, n)))
        assert ok is expect
    # an error bound larger than the margin refuses the proof
    lap = sp.csr_matrix(g + (-lam / 2 + 1e-6 * abs(lam)) * np.eye(n))
    ok, _ = prove_symmetric_part(lap, sp.csr_matrix(np.full((n, n), 1e-3)))
    assert not ok


@pytest.mark.hostile
def test_malformed_scale_certificate_is_one_line(tmp_path, capsys, monkeypatch):
    import json

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


@pytest.mark.hostile
def test_unreached_agents_are_refused_in_bulk_not_one_by_one(tmp_path, capsys, monkeypatch):
    """20,000 agents, one edge: every other agent is a one-agent block L_ii = 0. No
    fallback can prove such a block, so none is tried (the work stays linear in N: it
    took a sparse factorisation and a pass over all agents per agent before), and the
    verdict names the first violations only."""
    import warnings

    import yaml

    from ntc_design.certify import scale as scale_mod

    from .cli_helpers import run_cli

    calls = []
    real = scale_mod.prove_symmetric_part
    monkeypatch.setattr(scale_mod, "prove_symmetric_part", lambda *a: calls.append(1) or real(*a))
    f = tmp_path / "one_edge.yaml"
    f.write_text(
        yaml.safe_dump(
            {"dim": 1, "agents": 20000, "edges": [{"from": 1, "to": 2, "weight": [[-1.0]]}]}
        )
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code, out, err = run_cli(["certify", f, "--theta", "1", "--json"], capsys, monkeypatch)
    assert code == 1 and calls == []
    doc = json.loads(out)
    res = doc["certificate"]["results"]
    assert res["methods"]["none"] == 19999 and res["methods"]["dominance"] == 1
    assert any("19999 one-agent component(s)" in s for s in res["skipped"])
    (a2,) = [p for p in doc["theorems"][0]["premises"] if p["premise"].startswith("Assumption 2")]
    detail = a2["detail"]
    assert "… 19994 more agents" in detail and len(detail) < 2000
    assert a2["holds"] is False and a2["replaced_by"] is None


def _comparison(seed, n=400, scale=1.0):
    """A random comparison matrix M = D − N (N >= 0) on a strongly connected graph."""
    import scipy.sparse as sp

    rng = np.random.default_rng(seed)
    ring = np.arange(n)
    rows = np.concatenate([ring, rng.integers(0, n, 2 * n)])
    cols = np.concatenate([(ring + 1) % n, rng.integers(0, n, 2 * n)])
    keep = rows != cols
    off = sp.csr_matrix((rng.uniform(0.1, 1.0, keep.sum()), (rows[keep], cols[keep])), (n, n))
    dg = scale * np.asarray(off.sum(axis=1)).ravel() + 0.05
    return (sp.diags(dg) - off).tocsr()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_comparison_solve_by_jacobi_matches_the_lu(seed):
    """Issue 20: M v = 1 by Jacobi sweeps (linear in the edges) instead of a sparse LU
    (superlinear fill on random graphs); on an M-matrix the same v as the LU."""
    from scipy.sparse.linalg import splu

    from ntc_design import linalg as sc

    m = _comparison(seed)
    v = sc.comparison_solve(m)
    exact = splu(m.tocsc()).solve(np.ones(m.shape[0]))
    assert np.all(v > 0)
    np.testing.assert_allclose(v, exact, rtol=1e-10)
    assert np.all(m @ v > 0)


def test_comparison_solve_falls_back_to_the_lu_when_jacobi_diverges(monkeypatch):
    """Not an M-matrix (ρ(D⁻¹N) > 1): the sweeps diverge; small matrices get the LU's v
    (dominance then fails on it), large ones the last finite sweep, never a crash."""
    from scipy.sparse.linalg import splu

    from ntc_design import linalg as sc

    m = _comparison(3, n=200, scale=0.5)
    exact = splu(m.tocsc()).solve(np.ones(m.shape[0]))
    np.testing.assert_allclose(sc.comparison_solve(m), exact, rtol=1e-12)
    assert not np.all(exact > 0)  # no positive v with M v > 0: dominance must fail
    monkeypatch.setattr(sc, "COMPARISON_LU_MAX_AGENTS", 10)
    v = sc.comparison_solve(m)
    assert v.shape == (200,) and not (np.all(v > 0) and np.all(m @ v > 0))
