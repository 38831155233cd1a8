"""Robust certification (issue 31): the brackets on G1 and a random network against an
independent rebuild of L_B(A'), the realisations, the certificate kind and its forgeries,
and the command's bad input."""

import copy
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.certify.format import finish
from ntc_design.certify.kinds.robust import robust_certificate
from ntc_design.certify.robust import robust
from ntc_design.paper import THETA  # the paper's θ, defined once

from .cli_helpers import assert_input_error
from .conftest import ROOT


def independent_lap_b(des, weights: dict) -> np.ndarray:
    """L_B(A') from scratch: L_ii = Σ_j |A'_ij| (|A| by eigen-decomposition), L_ij = −A'_ij,
    plus δ·blockdiag(B_i) (the nominal protocol)."""
    top = des.topology
    n, d = top.n, top.dim
    lap = np.zeros((n * d, n * d))
    for (i, j), a in weights.items():
        lam, q = np.linalg.eigh(a)
        absa = (q * np.abs(lam)) @ q.T
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += absa
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
    for i, b in des.B.items():
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += des.delta * b
    return lap


def sample(des, radius, rng, kind):
    """A random realisation: per weight |A'| = F(I + E)F with E symmetric, ‖E‖ <= ρ."""
    out = {}
    for key, a in des.topology.weights.items():
        lam, q = np.linalg.eigh(a)
        s = 1.0 if lam[-1] > 0 else -1.0 if lam[0] < 0 else 0.0
        absa = s * a
        lw, qw = np.linalg.eigh(absa)
        f = (qw * np.sqrt(np.clip(lw, 0, None))) @ qw.T
        d = a.shape[0]
        if kind == "vertex":
            e = radius * np.diag(rng.choice([-1.0, 1.0], size=d))
            r = np.linalg.qr(rng.normal(size=(d, d)))[0]
            e = r @ e @ r.T
        else:
            x = rng.normal(size=(d, d))
            lam_e, qe = np.linalg.eigh(x + x.T)
            e = (qe * np.clip(lam_e, -radius, radius)) @ qe.T
        out[key] = s * (f @ (np.eye(d) + e) @ f)
        out[key] = 0.5 * (out[key] + out[key].T)
    return out


def features(des, weights):
    lap = independent_lap_b(des, weights)
    alpha = float(np.min(np.linalg.eigvals(lap).real))
    x = np.linalg.solve(lap, des.input_vector())
    return alpha, float(np.linalg.norm(x - np.tile(des.theta, des.topology.n)))


@pytest.fixture(scope="module")
def g1_robust():
    des = nd.design(nd.load(ROOT / "examples" / "g1.yaml"), THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.05)
    return des, rep


def test_g1_brackets_meet_the_targets_and_the_independent_figures(g1_robust):
    des, rep = g1_robust
    d, o, m = rep.decay, rep.offset, rep.margin
    assert 0 < d.lower <= d.upper and d.upper / d.lower <= 1.5
    assert 0 < o.lower <= o.upper and o.upper / o.lower <= 1.5
    assert 0 < m.lower <= m.upper <= 1.0 and m.upper / m.lower <= 2.0
    # the independent search at ρ = 0.05: worst decay 0.819, worst offset 0.077
    assert d.upper == pytest.approx(0.819, abs=2e-3) and o.lower >= 0.077
    assert rep.nominal_decay == pytest.approx(0.8244, abs=1e-4)


def test_no_sampled_realisation_beats_a_certified_end(g1_robust):
    des, rep = g1_robust
    rng = np.random.default_rng(np.random.SeedSequence(31))
    worst_a, worst_o = np.inf, 0.0
    for k in range(300):
        w = sample(des, 0.05, rng, "vertex" if k % 2 else "random")
        a, o = features(des, w)
        worst_a, worst_o = min(worst_a, a), max(worst_o, o)
    assert worst_a >= rep.decay.lower and worst_o <= rep.offset.upper
    # and the searched realisations are at least as bad as what sampling finds
    assert rep.decay.upper <= worst_a + 1e-9 and rep.offset.lower >= worst_o - 1e-9
    # within the margin radius every sample is Hurwitz
    for _ in range(100):
        a, _ = features(des, sample(des, rep.margin.lower, rng, "vertex"))
        assert a > 0


def realised(des, edges):
    top = des.topology
    w = dict(top.weights)
    for e in edges:
        w[(top.index(e["to"]), top.index(e["from"]))] = np.asarray(e["weight"], dtype=float)
    return w


def in_set(des, w, radius):
    for key, a in des.topology.weights.items():
        lam = np.linalg.eigvalsh(a)
        s = 1.0 if lam[-1] > 0 else -1.0
        lo = np.linalg.eigvalsh(s * w[key] - (1 - radius) * s * a)[0]
        hi = np.linalg.eigvalsh((1 + radius) * s * a - s * w[key])[0]
        if min(lo, hi) < -1e-9 * np.max(np.abs(a)):
            return False
    return True


def test_realisations_lie_in_the_set_and_attain_their_figures(g1_robust):
    des, rep = g1_robust
    doc = rep.to_dict()
    wd = realised(des, doc["decay"]["realization"])
    wo = realised(des, doc["offset"]["realization"])
    assert in_set(des, wd, 0.05) and in_set(des, wo, 0.05)
    assert features(des, wd)[0] == pytest.approx(doc["decay"]["upper"], rel=1e-9)
    assert features(des, wo)[1] == pytest.approx(doc["offset"]["lower"], rel=1e-9)
    dm = realised(des, doc["margin"]["destabilizing"])
    lap = independent_lap_b(des, dm)
    assert np.min(np.linalg.eigvals(lap).real) <= 1e-12  # not Hurwitz
    assert set(doc) >= {"radius", "decay", "offset", "margin"}


def test_only_antagonistic_weights_move_the_consensus_point(g1_robust):
    des, _ = g1_robust
    rng = np.random.default_rng(np.random.SeedSequence(5))
    w = sample(des, 0.3, rng, "random")
    coop = {
        k: (w[k] if np.linalg.eigvalsh(a)[-1] > 0 else a) for k, a in des.topology.weights.items()
    }
    assert features(des, coop)[1] < 1e-9  # cooperative changes alone keep x* = 1⊗θ


def forged_valid(doc: dict, edit) -> bool:
    """Whether ``doc`` still verifies after ``edit`` (its digests recomputed)."""
    bad = copy.deepcopy(doc)
    edit(bad)
    for k in ("digest", "subject_digest", "versions"):
        bad.pop(k, None)
    return verify(finish(bad)).valid


def raise_alpha_to(value: float):
    """An edit stating decay rate ``value``, in the results and in the claims."""

    def raise_alpha(d):
        d["results"]["decay"]["lower"] = value
        for c in d["claims"]:
            if c["property"] == "robust_decay" and "alpha" in c:
                c["alpha"] = d["results"]["decay"]["lower"]

    return raise_alpha


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


def test_a_random_network_within_twice(tmp_path):
    from ntc_design.generate import random_network

    top = random_network(6, 2, seed=3)
    des = nd.design(top, [1.0, -1.0], thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.05, starts=3)
    assert rep.decay.upper / rep.decay.lower <= 2.0
    assert rep.offset.lower > 0 and rep.offset.upper / rep.offset.lower <= 2.0
    rng = np.random.default_rng(np.random.SeedSequence(9))
    for _ in range(100):
        a, o = features(des, sample(des, 0.05, rng, "vertex"))
        assert a >= rep.decay.lower and o <= rep.offset.upper


@pytest.mark.hostile
@pytest.mark.parametrize(
    "radius, needle",
    [("1.5", "below 1"), ("-0.1", ">= 0"), ("nan", "finite"), ("1", "below 1")],
)
def test_a_bad_radius_is_one_line_exit_2(radius, needle, capsys, monkeypatch):
    g1_robust = ROOT / "examples" / "g1.yaml"
    args = ["robust", g1_robust, "--theta", "1,2,-1", "--radius", radius]
    assert_input_error(args, capsys, monkeypatch, needle, "--radius")


# -- per-edge uncertainty in topology files ---------------------------------------------


@pytest.mark.slow  # the full suite runs it; the fast lane stays under 3 min
def test_per_edge_radii_from_a_file_are_certified_and_respected(tmp_path):
    text = (ROOT / "examples" / "g1.yaml").read_text()
    text = text.replace(
        "weight: {diag: [-1, -1, 0]}}", "weight: {diag: [-1, -1, 0]}, uncertainty: 0.2}"
    )
    text = text.replace("name: G1\n", "name: G1\nuncertainty: 0.02\n")
    p = tmp_path / "g1u.yaml"
    p.write_text(text)
    top = nd.load(p)
    assert top.uncertainty[(1, 0)] == 0.2 and top.uncertainty[(0, 1)] == 0.02
    des = nd.design(top, THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.3, starts=2)  # --radius is only the default: the file sets all
    assert max(rep.radii) == 0.2 and min(rep.radii) == 0.02 and rep.radius == 0.2
    doc = json.loads(json.dumps(robust_certificate(rep)))
    assert isinstance(doc["subject"]["radius"], list)
    assert verify(doc).valid
    rng = np.random.default_rng(np.random.SeedSequence(2))
    for _ in range(100):
        w = {}
        for key, a in des.topology.weights.items():
            one = sample_one(a, top.uncertainty[key], rng)
            w[key] = one
        a_, o_ = features(des, w)
        assert a_ >= rep.decay.lower and o_ <= rep.offset.upper
    wd = realised(des, rep.to_dict()["decay"]["realization"])
    assert in_set_per_edge(des, wd, top.uncertainty)


def sample_one(a, radius, rng):
    lam = np.linalg.eigvalsh(a)
    s = 1.0 if lam[-1] > 0 else -1.0
    lw, qw = np.linalg.eigh(s * a)
    f = (qw * np.sqrt(np.clip(lw, 0, None))) @ qw.T
    d = a.shape[0]
    r = np.linalg.qr(rng.normal(size=(d, d)))[0]
    e = r @ np.diag(radius * rng.choice([-1.0, 1.0], size=d)) @ r.T
    out = s * (f @ (np.eye(d) + e) @ f)
    return 0.5 * (out + out.T)


def in_set_per_edge(des, w, radii):
    return all(in_set_edge(a, w[k], radii[k]) for k, a in des.topology.weights.items())


def in_set_edge(a, b, radius):
    s = 1.0 if np.linalg.eigvalsh(a)[-1] > 0 else -1.0
    tol = 1e-9 * np.max(np.abs(a))
    return (
        np.linalg.eigvalsh(s * b - (1 - radius) * s * a)[0] >= -tol
        and np.linalg.eigvalsh((1 + radius) * s * a - s * b)[0] >= -tol
    )


def test_csv_and_mat_carry_the_radii(tmp_path):
    from scipy.io import savemat

    (tmp_path / "t.csv").write_text("from,to,a11,uncertainty\n2,1,-1,0.02\n3,2,2,\n")
    assert nd.load(tmp_path / "t.csv").uncertainty == {(1, 0): 0.02}
    a = np.zeros((3, 3))
    a[0, 1], a[1, 2] = -1.0, 2.0
    u = np.zeros((3, 3))
    u[0, 1] = 0.03
    savemat(tmp_path / "m.mat", {"A": a, "dim": 1, "uncertainty": u})
    assert nd.load(tmp_path / "m.mat").uncertainty == {(0, 1): 0.03}


@pytest.mark.hostile
@pytest.mark.parametrize(
    "name, content, needle",
    [
        ("zero.yaml", "dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[0]], uncertainty: 0.1}\n", "edge 2->1: uncertainty on a zero weight"),
        ("big.yaml", "dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], uncertainty: 1.5}\n", "edge 2->1: uncertainty: the radius must be"),
        ("text.yaml", "dim: 1\nagents: [1, 2]\nuncertainty: lots\nedges:\n  - {from: 2, to: 1, weight: [[1]]}\n", "uncertainty: expected a number"),
        ("neg.csv", "from,to,a11,uncertainty\n2,1,-1,-0.1\n", "row 2: uncertainty"),
        ("nan.csv", "from,to,a11,uncertainty\n2,1,-1,nan\n", "row 2: uncertainty"),
    ],
)  # fmt: skip
def test_a_bad_uncertainty_is_one_line_exit_2(tmp_path, name, content, needle, capsys, monkeypatch):
    p = tmp_path / name
    p.write_text(content)
    assert_input_error(["check", p], capsys, monkeypatch, needle, str(p))


@pytest.mark.hostile
def test_mat_uncertainty_on_a_missing_edge_is_refused(tmp_path):
    from scipy.io import savemat

    a = np.zeros((3, 3))
    a[0, 1] = -1.0
    u = np.zeros((3, 3))
    u[2, 0] = 0.1
    savemat(tmp_path / "m.mat", {"A": a, "dim": 1, "uncertainty": u})
    with pytest.raises(nd.InputError, match=r"uncertainty\(3, 1\): uncertainty on a missing edge"):
        nd.load(tmp_path / "m.mat")


# -- above the dense size: sparse dominance bounds ------------------------------------------


@pytest.fixture(scope="module")
def mid_network():
    from ntc_design.generate import random_network

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


@pytest.mark.hostile
def test_out_above_the_dense_size_is_refused_before_work(tmp_path, capsys, monkeypatch):
    from ntc_design.generate import random_network

    p = tmp_path / "big.yaml"
    import yaml

    p.write_text(yaml.safe_dump(random_network(70, 3, seed=1).to_dict()))  # Nd = 210
    from ntc_design.certify.robust_are import RICCATI_MAX_ND

    args = ["robust", p, "--theta", "1,2,-1", "--out", tmp_path / "c.json"]
    needle = f"--out: a robust certificate is issued up to Nd = {RICCATI_MAX_ND}"
    assert_input_error(args, capsys, monkeypatch, needle)
    assert not (tmp_path / "c.json").exists()


# -- simulating weight realisations (scenario key robust:) ---------------------------------


def _scenario(tmp_path, robust_block: str, paths: int = 60) -> Path:
    p = tmp_path / "sc.yaml"
    p.write_text(
        f"topology: {ROOT / 'examples' / 'g1.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "noise: {sigma: 0.4, f: 0.3}\ninitial: {uniform: [-3, 3], seed: 1}\n"
        f"T: 2\ndt: 0.002\npaths: {paths}\nworkers: 1\n{robust_block}\n"
    )
    return p


@pytest.mark.slow  # the full suite runs it; the fast lane stays under 3 min
def test_the_study_draws_in_the_set_and_respects_the_brackets(tmp_path):
    from ntc_design.simulate.scenario import load_scenario
    from ntc_design.sweep.robust import draw_realisation, robust_study, within_brackets

    sc = _scenario(tmp_path, "robust: {realizations: 4, radius: 0.1, seed: 3}")
    top, spec, _ = load_scenario(sc)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        st = robust_study(top, spec)
    assert len(st.rows) == 4 and within_brackets(st) == {"decay": True, "offset": True}
    des = nd.design(top, THETA, thresholds=False)
    for r in st.rows:
        real = draw_realisation(top, np.full(8, 0.1), 3, r["realization"])
        assert in_set(des, dict(real.weights), 0.1)
        a, o = features(des, dict(real.weights))  # the independent rebuild
        assert r["decay_rate"] == pytest.approx(a, rel=1e-9)
        assert r["offset"] == pytest.approx(o, rel=1e-9)
    # the draws depend on (seed, index) only: the same realisation 2 on its own
    again = draw_realisation(top, np.full(8, 0.1), 3, 2)
    assert all(
        np.array_equal(again.weights[k], draw_realisation(top, np.full(8, 0.1), 3, 2).weights[k])
        for k in again.weights
    )
    assert st.csv().count("\n") == 5 and st.csv().startswith("realization,decay_rate,offset")


@pytest.mark.slow  # the full suite runs it; the fast lane stays under 3 min
def test_simulate_writes_robust_csv_and_the_report_shows_it(tmp_path):
    sc = _scenario(tmp_path, "robust: {realizations: 2, radius: 0.05, seed: 1}")
    out = tmp_path / "run"
    r = subprocess.run(
        [sys.executable, "-m", "ntc_design", "simulate", str(sc), "--out", str(out)],
        cwd=ROOT, capture_output=True, text=True,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "both proven bounds hold" in r.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["robust"]["realizations"] == 2 and (out / "robust.csv").is_file()
    r = subprocess.run(
        [sys.executable, "-m", "ntc_design", "report", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    html = (out / "report.html").read_text()
    assert "Weights within ρ" in html and "both proven bounds hold" in html
    assert 'id="run-fig-robust"' in html and (out / "figures" / "run_robust.png").is_file()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "block, needle",
    [
        ("robust: {realizations: 0}", "robust.realizations"),
        ("robust: {radius: 1.5}", "robust.radius"),
        ("robust: {realisations: 3}", "robust.realisations: unknown field"),
        ("robust: 7", "robust: expected"),
    ],
)
def test_a_bad_robust_block_is_one_line_exit_2(tmp_path, block, needle, capsys, monkeypatch):
    sc = _scenario(tmp_path, block)
    args = ["simulate", sc, "--out", tmp_path / "o"]
    assert_input_error(args, capsys, monkeypatch, needle, str(sc))
    assert not (tmp_path / "o").exists()


def test_the_readme_states_the_g1_brackets(g1_robust):
    import re

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    m = re.search(
        r"they are \[([\d.]+), ([\d.]+)\], \[([\d.]+), ([\d.]+)\] and \[([\d.]+), ([\d.]+)\]",
        readme,
    )
    assert m, "the README's G1 brackets"
    _, rep = g1_robust
    got = (
        rep.decay.lower,
        rep.decay.upper,
        rep.offset.lower,
        rep.offset.upper,
        rep.margin.lower,
        rep.margin.upper,
    )
    assert list(m.groups()) == [f"{x:.3g}" for x in got]
