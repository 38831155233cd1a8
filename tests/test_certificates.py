"""Certificates: Lyapunov vs LMI vs eigenvalues, switching sets, exact re-check, tampering."""

import copy
import json
import shutil

import control
import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.certify import certify, hurwitz_certificate, switching_certificate, verify
from ntc_design.certify.dense import prove_hurwitz
from ntc_design.certify.format import digest
from ntc_design.certify.lyapunov import common_lyapunov, decay_rate_lmi, lyapunov_solve
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.rigorous.exact import Dyadic, exact_pd, verified_float_pd

from .cli_helpers import assert_input_error, run_cli
from .conftest import ROOT

CERTS = ROOT / "certificates"


@pytest.fixture(scope="module")
def paper_designs():
    return {
        g: nd.design(nd.load(ROOT / "examples" / f"{g}.yaml"), THETA) for g in ("g1", "g2", "g3")
    }


@pytest.mark.parametrize("g", ["g1", "g2", "g3"])
def test_hurwitz_both_ways_and_rate_below_eigen_bound(paper_designs, g):
    d = paper_designs[g]
    lap_b = d.grounded_laplacian()
    cert = hurwitz_certificate(d)
    ver = verify(cert)
    assert ver.valid and ver.method == "exact-rational", ver.failed
    eig = float(np.min(np.linalg.eigvals(lap_b).real))
    lmi = cert["results"]["lmi"]
    assert lmi["eig_bound"] == pytest.approx(eig, rel=1e-12)
    assert lmi["alpha"] <= eig + 1e-12  # never above the eigenvalue bound
    assert lmi["alpha"] >= eig - 1e-3
    # the Lyapunov P agrees with python-control (A X + X Aᵀ + Q = 0) and SciPy
    p = np.array(cert["matrices"]["P"]["lyapunov"])
    np.testing.assert_allclose(p, control.lyap(lap_b.T, -np.eye(21)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        p, sla.solve_continuous_lyapunov(lap_b.T, np.eye(21)), rtol=1e-9, atol=1e-12
    )
    assert np.linalg.eigvalsh(p)[0] > 0


def test_g1_rate_is_the_eigenvalue_bound(paper_designs):
    """At δ = 7.244 the slowest G1 mode is 0.1 + 0.1·δ = 0.8244 (agent 3's loop)."""
    r = decay_rate_lmi(paper_designs["g1"].grounded_laplacian())
    assert r.eig_bound == pytest.approx(0.1 + 0.1 * paper_designs["g1"].delta, rel=1e-9)
    assert r.eig_bound - 1e-3 <= r.alpha <= r.eig_bound


def test_switching_set_symmetric_parts_and_common_p(examples):
    sd = nd.design(nd.load(examples / "switching.yaml"), THETA)
    cert = switching_certificate(sd)
    assert verify(cert).valid
    lam = cert["results"]["symmetric_part_min_eig"]
    for k, d in sd.modes.items():
        lap_b = d.grounded_laplacian()
        assert lam[k] == pytest.approx(np.linalg.eigvalsh(lap_b + lap_b.T)[0], rel=1e-12)
        assert lam[k] > 0
    assert lam == pytest.approx(
        {"G1": 0.8080097556, "G2": 2.6952230315, "G3": 1.6166592570}, rel=1e-8
    )
    assert cert["results"]["common_lyapunov"]["structure"] == "identity"
    ids = [c["id"] for c in cert["claims"]]
    assert "P_common ≻ 0" in ids and sum("P_common·L_B" in i for i in ids) == 3


def test_common_lyapunov_block_diagonal_when_identity_fails():
    """Modes similar to symmetric-PD ones through T = blockdiag(t_i I): P = TᵀT is
    block-diagonal and certifies all modes, while P = I does not."""
    rng = np.random.default_rng(3)
    n, d = 4, 2
    tvec = np.repeat([1.0, 6.0, 0.3, 2.0], d)
    mats = {}
    for k in range(3):
        m = rng.normal(size=(n * d, n * d))
        s = m @ m.T + np.eye(n * d)
        k_skew = rng.normal(size=(n * d, n * d))
        base = s + 0.5 * (k_skew - k_skew.T)
        mats[f"M{k}"] = (tvec[:, None] * base) / tvec[None, :]
    res = common_lyapunov(mats, d)
    assert res.structure == "block-diagonal"
    assert res.attempts[0][0] == "identity" and "fails" in res.attempts[0][1]
    for m in mats.values():
        s = res.p @ m + m.T @ res.p
        assert np.linalg.eigvalsh(s)[0] > 0
    off = res.p.copy()
    for i in range(n):
        off[i * d : (i + 1) * d, i * d : (i + 1) * d] = 0.0
    assert not np.any(off)  # exactly block-diagonal


def test_certificate_files_verify(capsys, monkeypatch):
    for name in ("g1.json", "switching.json"):
        code, out, err = run_cli(["verify", CERTS / name], capsys, monkeypatch)
        assert code == 0, err
        assert "VALID (exact-rational)" in out


def _load(name):
    return json.loads((CERTS / name).read_text())


def _write(tmp_path, doc, name="c.json"):
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


@pytest.mark.hostile
@pytest.mark.parametrize(
    "path",
    [
        ("matrices", "P", "lyapunov", 0, 0),
        ("matrices", "P", "rate", 3, 4),
        ("matrices", "L_B", "G1", 1, 1),
        ("subject", "modes", "G1", "delta"),
        ("subject", "modes", "G1", "B", "2", 0, 0),
        ("claims", 4, "alpha"),
        ("results", "lmi", "alpha"),
    ],
)
def test_tampering_any_entry_fails(tmp_path, capsys, monkeypatch, path):
    doc = _load("g1.json")
    node = doc
    for key in path[:-1]:
        node = node[key]
    old = node[path[-1]]
    node[path[-1]] = (old * (1 + 1e-9) + 1e-12) if old else 1e-12
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1
    assert "INVALID" in err and "digest" in err


@pytest.mark.hostile
def test_tampered_then_redigested_fails_on_the_inequality(tmp_path, capsys, monkeypatch):
    doc = _load("g1.json")
    p = np.array(doc["matrices"]["P"]["lyapunov"])
    p[0, 0] = -p[0, 0]
    doc["matrices"]["P"]["lyapunov"] = p.tolist()
    doc["digest"] = digest(doc)
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1
    assert "P_lyapunov ≻ 0" in err and "digest" not in err
    # an L_B that no longer matches the topology is caught even with a fresh digest
    doc = _load("g1.json")
    doc["matrices"]["L_B"]["G1"][0][0] += 1e-6
    doc["digest"] = digest(doc)
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1 and "L_B(G1) matches its topology" in err
    # changing δ (and L_B consistently) keeps the maths honest: a δ where L_B + L_Bᵀ is
    # not positive definite fails the symmetric claim
    sd = nd.design(nd.load(ROOT / "examples" / "switching.yaml"), THETA, delta=0.5)
    cert = switching_certificate(sd, structures=("identity",))
    assert "P_common ≻ 0" not in [c["id"] for c in cert["claims"]]
    assert cert["results"]["symmetric_part_min_eig"]["G1"] < 0


@pytest.mark.hostile
@pytest.mark.parametrize(
    "mutate, needles",
    [
        (lambda d: "not json at all", ["not valid JSON"]),
        (lambda d: {k: v for k, v in d.items() if k != "claims"}, ["missing field 'claims'"]),
        (
            lambda d: d["matrices"]["P"].update(lyapunov=[[1.0, 0.0], [0.0, 1.0]]),
            ["matrices.P.lyapunov", "21x21"],
        ),
        (lambda d: d["matrices"]["P"]["lyapunov"][2].__setitem__(2, "x"), ["non-numeric"]),
        (lambda d: d.update(format="something"), ["format"]),
    ],
)
def test_malformed_certificates(tmp_path, capsys, monkeypatch, mutate, needles):
    doc = _load("g1.json")
    res = mutate(doc)
    p = tmp_path / "c.json"
    p.write_text(res if isinstance(res, str) else json.dumps(res if isinstance(res, dict) else doc))
    assert_input_error(["verify", p], capsys, monkeypatch, str(p), *needles)


def test_certificate_roundtrip_copy_still_valid(tmp_path, capsys, monkeypatch):
    shutil.copy(CERTS / "switching.json", tmp_path / "s.json")
    code, out, _ = run_cli(["verify", tmp_path / "s.json"], capsys, monkeypatch)
    assert code == 0 and out.count("ok ") >= 15


def test_regenerated_certificates_match_the_shipped_subjects(examples):
    """certificates/ was produced by `ntc certify ... --out`: same subject, same claims."""
    d = nd.design(nd.load(examples / "g1.yaml"), THETA)
    fresh = hurwitz_certificate(d)
    shipped = _load("g1.json")
    assert fresh["subject_digest"] == shipped["subject_digest"]
    assert [c["id"] for c in fresh["claims"]] == [c["id"] for c in shipped["claims"]]


# -------------------------------------------------------------- exact and float proofs


def test_exact_and_float_pd_agree_on_boundary_cases():
    eps = 2.0**-40
    a = np.array([[1.0, 1.0], [1.0, 1.0 + eps]])  # det = eps > 0: PD, barely
    assert exact_pd(Dyadic.of(a)).holds
    b = np.array([[1.0, 1.0], [1.0, 1.0]])  # singular
    assert not exact_pd(Dyadic.of(b)).holds
    assert not verified_float_pd(b, np.zeros((2, 2))).holds
    assert verified_float_pd(np.eye(50), np.zeros((50, 50))).holds
    # an error bound bigger than the smallest eigenvalue prevents a proof
    assert not verified_float_pd(np.eye(3) * 1e-6, np.full((3, 3), 1e-6)).holds


def _matrix_with_known_spectrum(seed, worst_real):
    """Permutation-similar to a block upper triangular matrix whose diagonal blocks are
    [a] or [[a, b], [-b, a]]: its eigenvalues are known exactly in floating point."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 9))
    t = np.triu(rng.normal(size=(n, n)), 1)
    reals = rng.uniform(0.1, 3.0, size=n)
    k = int(rng.integers(n))
    reals[k] = worst_real
    i = 0
    while i < n:
        if i + 1 < n and rng.random() < 0.35:  # a complex pair a ± ib
            a, b = min(reals[i], reals[i + 1]), float(rng.uniform(0.5, 2))
            t[i, i] = t[i + 1, i + 1] = a
            t[i, i + 1], t[i + 1, i] = b, -b
            reals[i] = reals[i + 1] = a
            i += 2
        else:
            t[i, i] = reals[i]
            i += 1
    perm = rng.permutation(n)
    return t[np.ix_(perm, perm)], float(np.min(reals))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([0.0, -1e-12, -0.3, -2.0]))
def test_no_hurwitz_certificate_for_unstable_matrices(seed, worst):
    """A matrix L_B with an eigenvalue of real part <= 0 (−L_B has one with real part >= 0)
    never gets a Hurwitz certificate, exact or floating."""
    m, lo = _matrix_with_known_spectrum(seed, worst)
    assert lo <= 0
    assert not prove_hurwitz(m, exact=True).holds
    assert not prove_hurwitz(m, exact=False).holds
    assert decay_rate_lmi(m).p is None


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_hurwitz_certificate_issued_for_stable_matrices(seed):
    m, lo = _matrix_with_known_spectrum(seed, 0.2)
    if np.linalg.cond(m) < 1e8:
        assert prove_hurwitz(m, exact=True).holds
        assert prove_hurwitz(m, exact=False).holds


def test_lyapunov_solver_matches_scipy_on_larger_matrices():
    rng = np.random.default_rng(0)
    m = np.eye(400) * 3 + rng.normal(size=(400, 400)) * 0.05
    p = lyapunov_solve(m)
    np.testing.assert_allclose(
        p, sla.solve_continuous_lyapunov(m.T, np.eye(400)), rtol=1e-9, atol=1e-12
    )
    assert prove_hurwitz(m).holds and prove_hurwitz(m).p_pd.method == "verified-float"


# -------------------------------------------------------------------- gain and verdicts


@pytest.mark.parametrize(
    "expr, integral, zero, square, ms, as_",
    [
        ("1/(1+t)", True, True, True, True, True),
        ("(1+t)^-2", False, True, True, False, False),
        ("(1+t)^(-1/3)", True, True, False, True, False),
    ],
)
def test_gain_table(capsys, monkeypatch, expr, integral, zero, square, ms, as_):
    code, out, err = run_cli(["gain", expr, "--json"], capsys, monkeypatch)
    assert code == (0 if ms else 1), err  # exit 1 when no theorem's conditions hold
    g = json.loads(out)
    assert g["continuous_nonnegative"]["value"] is True
    assert g["integral_diverges"]["value"] is integral
    assert g["tends_to_zero"]["value"] is zero
    assert g["square_integrable"]["value"] is square
    assert g["mean_square"] is ms and g["almost_sure"] is as_
    for k in ("integral_diverges", "tends_to_zero", "square_integrable"):
        assert g[k]["reason"]


@pytest.mark.parametrize(
    "expr, needles",
    [
        ("1/(1+", ["cannot parse"]),
        ("x/(1+t)", ["uses x", "only the variable t"]),
        ("cos(t)", ["negative"]),
        ("1 - t", ["negative"]),
    ],
)
def test_bad_gains(capsys, monkeypatch, expr, needles):
    assert_input_error(["gain", expr], capsys, monkeypatch, "gain", *needles)


def test_theorem_verdict_g1_and_switching(examples):
    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="1/(1+t)")
    assert [(t.theorem, t.guaranteed) for t in r.theorems] == [(1, True), (2, True)]
    assert r.proven
    r = certify(nd.load(examples / "switching.yaml"), THETA, gain="1/(1+t)")
    assert [(t.theorem, t.guaranteed) for t in r.theorems] == [(3, True), (4, True)]
    a2 = [p for p in r.theorems[0].premises if p.name.startswith("Assumption 2")][0]
    assert (
        "G3" in a2.detail
    )  # G3 breaks Assumption 2 as stated; the proof needs only L_B + L_Bᵀ ≻ 0
    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="(1+t)^(-1/3)")
    assert r.theorems[0].guaranteed is True and r.theorems[1].guaranteed is False
    assert [p.name for p in r.theorems[1].failing] == ["∫₀^∞ c² dt < ∞"]
    # the JSON form keeps the keys the README shows
    doc = r.to_dict()["theorems"][1]
    assert doc["guaranteed"] is False and doc["failing"][0]["premise"] == "∫₀^∞ c² dt < ∞"


def test_verdict_names_failing_symmetric_premise_and_by_how_much(examples):
    sw = nd.load(examples / "switching.yaml")
    r = certify(sw, THETA, gain="1/(1+t)", delta=0.5)
    th3 = r.theorems[0]
    assert th3.guaranteed is False and not r.proven and not r.verification.valid
    failing = {p.name: p.detail for p in th3.failing}
    assert "L_B(G1) + L_B(G1)ᵀ ≻ 0" in failing
    assert "δ_S = 3.11769" in failing["L_B(G1) + L_B(G1)ᵀ ≻ 0"]
    assert "fails by" in failing["L_B(G1) + L_B(G1)ᵀ ≻ 0"]


def test_switching_file_with_different_modes_is_bad_input(tmp_path, examples, capsys, monkeypatch):
    (tmp_path / "small.yaml").write_text("dim: 3\nagents: 2\nedges: []\n")
    p = tmp_path / "sw.yaml"
    p.write_text(
        f"modes: {{G1: {examples.resolve() / 'g1.yaml'}, S: small.yaml}}\nschedule: [{{mode: G1, duration: 1}}]\n"
    )
    assert_input_error(["certify", p, "--theta", "1,2,-1"], capsys, monkeypatch, "modes.S", "N=2")


def test_certify_out_is_written_only_on_success(tmp_path, examples, capsys, monkeypatch):
    out = tmp_path / "c.json"
    assert_input_error(
        ["certify", examples / "g1.yaml", "--theta", "0,0,0", "--out", out],
        capsys,
        monkeypatch,
        "theta",
    )
    assert not out.exists()
    code, _, err = run_cli(
        ["certify", examples / "g1.yaml", "--theta", "1,2,-1", "--out", out], capsys, monkeypatch
    )
    assert code == 0, err
    assert verify(json.loads(out.read_text())).valid
    doc = copy.deepcopy(json.loads(out.read_text()))
    assert verify(doc).method == "exact-rational"


def test_verify_uses_verified_float_above_the_exact_size(examples):
    """Four disjoint copies of G1 (Nd = 84 > 80): the certificate is re-checked with the
    rigorous floating-point test, and a forged P still fails."""
    g1 = nd.load(examples / "g1.yaml")
    edges = [
        (7 * c + g1.labels[j], 7 * c + g1.labels[i], a)
        for c in range(4)
        for (i, j), a in g1.weights.items()
    ]
    big = nd.Topology.from_edges(28, 3, edges, name="4xG1")
    cert = hurwitz_certificate(nd.design(big, THETA, thresholds=False), rate=False)
    ver = verify(cert)
    assert ver.valid and ver.method == "verified-float", ver.failed
    p = np.array(cert["matrices"]["P"]["lyapunov"])
    p[5, 5] = -1.0
    cert["matrices"]["P"]["lyapunov"] = p.tolist()
    cert["digest"] = digest(cert)
    bad = verify(cert)
    assert not bad.valid and {c.name for c in bad.failed} >= {"P_lyapunov ≻ 0"}


def test_verdicts_read_typed_claims_not_names(examples):
    """Renaming every check leaves the verdict unchanged: theorems.py keys on the claim's
    property, not on its text."""
    import dataclasses

    from ntc_design.certify.theorems import fixed_verdicts

    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="1/(1+t)")
    renamed = dataclasses.replace(
        r.verification,
        checks=tuple(
            dataclasses.replace(c, name=f"check {k}") for k, c in enumerate(r.verification.checks)
        ),
    )
    th = fixed_verdicts(r.design, renamed, r.gain)
    assert [t.guaranteed for t in th] == [True, True]
    # and a failing Hurwitz claim is seen whatever it is called
    broken = dataclasses.replace(
        renamed,
        checks=tuple(
            dataclasses.replace(c, ok=False)
            if c.claim is not None
            and c.claim.kind.value == "lyapunov"
            and c.claim.prop.value == "hurwitz"
            else c
            for c in renamed.checks
        ),
    )
    assert [t.guaranteed for t in fixed_verdicts(r.design, broken, r.gain)] == [False, False]


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 9), st.sampled_from([-1e-3, 0.0, 1e-9, 0.5]))
def test_exact_pd_agrees_with_eigenvalues(seed, n, shift):
    """FLINT's fraction-free LU (Sylvester) against LAPACK eigenvalues, on matrices whose
    smallest eigenvalue is clearly away from 0 or exactly 0 (a rank-deficient Gram matrix)."""
    rng = np.random.default_rng(seed)
    g = rng.integers(-4, 5, size=(n, max(n - 1, 1))).astype(float)
    m = g @ g.T  # singular (rank <= n-1) for n >= 2, exact in doubles
    m = m + shift * np.eye(n)
    lam = np.linalg.eigvalsh(m)[0]
    pd = exact_pd(Dyadic.of(m)).holds
    if abs(lam) > 1e-6 * max(1.0, np.abs(m).max()):
        assert pd == (lam > 0)
    elif shift <= 0:
        assert not pd  # singular or shifted down: never positive definite


@pytest.mark.parametrize(
    "file, theorems",
    [("switching.yaml", ("Theorem 3", "Theorem 4")), ("g3.yaml", ("Theorem 1", "Theorem 2"))],
)
def test_terminal_verdict_names_a_replaced_assumption_2(file, theorems, capsys, monkeypatch):
    """G3 fails Assumption 2; the certified −L_B Hurwitz (or L_B + L_Bᵀ ≻ 0) replaces it, and
    the terminal says so under each theorem, as --json does."""
    from .cli_helpers import run_cli

    args = ["certify", ROOT / "examples" / file, "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    for th in theorems:
        block = out.split(th)[1].split("Theorem")[0]
        assert "guaranteed" in block and "replaced: Assumption 2" in block
        assert "in its place:" in block
    code, out, _ = run_cli([*args, "--json"], capsys, monkeypatch)
    doc = json.loads(out)
    for th in doc["theorems"]:
        (rep,) = th["replaced"]
        assert rep["premise"].startswith("Assumption 2") and rep["holds"] is True
        assert rep["replaced_by"] and "fails" in rep["detail"]


@pytest.mark.parametrize("file", ["g1.yaml", "switching.yaml"])
def test_terminal_and_html_show_the_kinds_rows(file, tmp_path, capsys, monkeypatch):
    """One presentation model: the kind's rows, labels written once, in both faces."""
    from ntc_design.reports.report import certificate_tables

    from .cli_helpers import run_cli

    args = ["certify", ROOT / "examples" / file, "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    res = certify(nd.load(ROOT / "examples" / file), [1.0, 2.0, -1.0], gain="1/(1+t)")
    summary, _, _ = certificate_tables(res, tmp_path / "c.json", tmp_path)
    html = {(a, b) for a, b in summary.rows if isinstance(b, str)}
    assert res.rows
    for row in res.rows:
        assert f"{row.label}: {row.value}" in out
        assert (row.label, row.value) in html


def test_verify_account_is_typed_rows_and_one_line_per_check():
    import copy as _copy

    from ntc_design.certify import verify as _verify
    from ntc_design.certify.checks import verification_tables

    doc = json.loads((CERTS / "g1.json").read_text())
    ver = _verify(doc).to_dict()
    about, checks = verification_tables(ver)
    assert about.labels[0] == "kind" and about.labels.count("certifies") == 2
    assert len(checks.rows) == len(ver["checks"]) and all(
        r[0].verdict_word == "ok   " for r in checks.rows
    )
    forged = _copy.deepcopy(doc)
    forged["subject"]["modes"]["G1\nerror: forged"] = forged["subject"]["modes"].pop("G1")
    lines = [ln for t in verification_tables(_verify(forged).to_dict()) for ln in t.list_lines()]
    assert not any(ln.startswith("error:") for ln in lines)
    assert any(ln.startswith("FAILS") for ln in lines)
