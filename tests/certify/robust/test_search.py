"""Tests of :mod:`ntc_design.certify.robust.search`."""

import json
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.certify.kinds.robust import robust_certificate
from ntc_design.certify.robust import robust
from ntc_design.model.generate import random_network, write_topology
from ntc_design.model.paper import THETA
from tests.conftest import ROOT
from tests.support.robust import features, in_set, independent_lap_b, realised, sample


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


def test_a_random_network_within_twice(tmp_path):

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


# -- how a statement names its set: one radius, or the per-edge radii ---------------------


# -- weights singular only by rounding, and ρ = 0 -----------------------------------------


#: At ρ = 0 the brackets are the nominal figures, to these tolerances (robust()'s
#: docstring): the decay's proven end within 0.005/2³ (FRACTIONS[0] and three bisection
#: steps) relative; the offset's within 1e−4·‖1⊗θ‖ (the offset SDP's strict margin).
DECAY_RTOL_AT_ZERO = 0.005 / 2**3
OFFSET_TOL_AT_ZERO = 1e-4


@pytest.mark.parametrize("n, d, theta", [(6, 2, [1.0, -1.0]), (5, 3, [1.0, 2.0, -1.0])])
@pytest.mark.parametrize("seed", range(16))
def test_at_radius_zero_the_brackets_are_the_nominal_figures(n, d, theta, seed):
    # ntc generate --agents 6 --dim 2 --seed 11 once gave no bracket end at any radius (a weight
    # v vᵀ whose kernel rounding had lost: VᵀWV not positive definite)
    from ntc_design.certify import certify

    top = random_network(n, d, seed=seed)
    assert certify(top, theta).verification.valid  # the nominal case is proven
    des = nd.design(top, theta, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.0, starts=0, margin=False)
    lap = independent_lap_b(des, dict(top.weights))
    nominal = float(np.min(np.linalg.eigvals(lap).real))
    target = np.tile(des.theta, n)
    offset = float(np.linalg.norm(np.linalg.solve(lap, des.input_vector()) - target))
    assert rep.decay.upper == pytest.approx(nominal, rel=1e-9)
    assert rep.decay.lower is not None
    assert nominal * (1 - DECAY_RTOL_AT_ZERO) * (1 - 1e-12) <= rep.decay.lower <= nominal
    assert rep.offset.upper is not None
    assert offset <= rep.offset.upper <= offset + OFFSET_TOL_AT_ZERO * np.linalg.norm(target)
    assert rep.offset.lower == pytest.approx(offset, abs=1e-12 * np.linalg.norm(target))


def test_a_weight_singular_by_rounding_is_certified_soundly_at_every_radius():
    # seed 11's weight 6→3 is v vᵀ rounded (determinant −6.5e−20 exactly): brackets at
    # ρ = 0.05 now, each proven end respected by sampled realisations of the set
    from ntc_design.certify.robust import uncertain_edges

    top = random_network(6, 2, seed=11)
    ed = uncertain_edges(top)
    assert sum(not np.array_equal(ed.channel_w[e], ed.w[e]) for e in range(ed.m)) == 1
    des = nd.design(top, [1.0, -1.0], thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.05, starts=1)
    assert rep.decay.lower is not None and rep.offset.upper is not None
    assert rep.margin.lower is not None and rep.margin.lower > 0.05
    doc = json.loads(json.dumps(robust_certificate(rep)))
    assert verify(doc).valid
    rng = np.random.default_rng(np.random.SeedSequence(11))
    for kind in ("vertex", "ball"):
        for _ in range(100):
            a, o = features(des, sample(des, 0.05, rng, kind))
            assert a >= rep.decay.lower and o <= rep.offset.upper


# -- issue 41, item 8: the work estimated before it starts ---------------------------------


def test_the_dense_estimate_counts_what_robust_solves(g1):
    """G1: P has 21·22/2 = 231 unknowns and 8 multipliers τ_e; the offset SDP's Y is
    21 × (21 + 21 + 1) (21 channel columns: the weights' ranks 3, 2, 1 and five 3s) with
    8 λ_e and γ."""
    from ntc_design.certify.robust import search as rb

    des = nd.design(g1, THETA, thresholds=False)
    seconds, what = rb.robust_seconds(des)
    assert "8 decay LMIs of 239 unknowns and an offset SDP of 912" in what
    assert seconds == pytest.approx(
        rb.BASE_SECONDS + 8 * rb.DECAY_SECONDS * 239**2 + rb.OFFSET_SECONDS * 912**2
    )
    assert rb.robust_seconds(des, margin=False)[1].startswith("about 4 decay LMIs")


@pytest.mark.hostile
def test_a_long_robust_run_says_how_long_before_any_solve(tmp_path, capsys, monkeypatch):
    """N·d = 39 (13 agents, d = 3): about 2 min of SDPs; the estimate is printed before
    the first one (the test stops there: no solve is made)."""
    from ntc_design.certify.robust import lmi as robust_lmi
    from tests.cli_helpers import run_cli

    def stop(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(robust_lmi, "solve_sdp", stop)
    f = tmp_path / "n13.npz"
    write_topology(random_network(13, 3, seed=0), f)
    code, out, err = run_cli(["robust", f, "--theta", "1,2,-1"], capsys, monkeypatch)
    assert code == 130, err
    line = next(ln for ln in err.splitlines() if ln.startswith("warning: robust: roughly"))
    assert "N·d = 39" in line and "794 unknowns" in line and "min" in line


@pytest.mark.hostile
def test_a_robust_run_over_the_limit_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from ntc_design.certify.robust import scale as robust_scale
    from ntc_design.certify.robust import search as rb
    from tests.cli_helpers import assert_input_error

    def never(*a, **k):
        raise AssertionError("the sparse bounds ran")

    monkeypatch.setattr(robust_scale, "robust_scale", never)
    monkeypatch.setattr(rb, "SPARSE_SECONDS", 1.0)  # 1 s a weight entry: hours at N = 300
    f = tmp_path / "n300.npz"
    write_topology(random_network(300, 3, seed=0), f)
    line = assert_input_error(
        ["robust", f, "--theta", "1,2,-1"], capsys, monkeypatch, "robust: roughly", "limit"
    )
    assert "sparse bounds over" in line
