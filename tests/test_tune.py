"""Tuning the gain for a deadline (ntc tune, ntc_design.tune): the objective against closed
forms and an independent integration of the moment equations, the optimum against a known
one, the tuned gain's theorems and certificate, the written scenario against Monte Carlo,
and hostile input."""

import json
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import minimize

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.gain import analyse_gain, gain_function
from ntc_design.simulate import NoiseModel, SimulationSpec, simulate
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune import (
    BASELINE,
    Dimension,
    ExactObjective,
    MonteCarloObjective,
    PowerGain,
    objective_for,
    search,
    tune,
)

from .cli_helpers import assert_input_error, run_cli
from .test_moments_math import _moment_rhs

# -- the family ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "a, b, gamma", [(1.0, 1.0, 1.0), (2.345, 0.2, 0.7123), (0.05, 10.0, 0.51), (7.0, 0.3, 0.05)]
)
def test_power_gain_text_is_read_back_as_the_same_function(a, b, gamma):
    g = PowerGain(a, b, gamma).rounded()
    t = np.array([0.0, 0.5, 3.0, 100.0])
    np.testing.assert_allclose(gain_function(g.text)(t), g(t), rtol=1e-12)


@pytest.mark.parametrize("gamma", [0.3, 0.5, 0.8, 1.0])
def test_power_gain_integrals_against_quadrature(gamma):
    g = PowerGain(1.7, 0.4, gamma)
    i1, i2 = g.integrals(7.0)
    assert i1 == pytest.approx(quad(lambda t: g(t), 0, 7.0)[0], rel=1e-9)
    assert i2 == pytest.approx(quad(lambda t: g(t) ** 2, 0, 7.0)[0], rel=1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_power_gain_refuses_non_positive_parameters(bad):
    with pytest.raises(nd.InputError, match="a: expected a finite number > 0"):
        PowerGain(bad, 1.0, 1.0)


# -- the search ---------------------------------------------------------------------------


def test_search_finds_an_interior_minimum_and_respects_its_budget():
    calls = []

    def f(p):
        calls.append(p)
        return (p["x"] - 0.3) ** 2 + (math.log(p["y"]) - 1.0) ** 2 + 1e-3

    tr = search(f, [Dimension("x", 0, 1), Dimension("y", 0.1, 10, log=True)], max_evaluations=90)
    (x, y), v = tr.best
    assert x == pytest.approx(0.3, abs=2e-3) and y == pytest.approx(math.e, rel=5e-3)
    assert v == pytest.approx(1e-3, abs=1e-5)
    assert len(calls) == len(tr.values) <= 90


def test_search_skips_infinite_candidates():
    tr = search(
        lambda p: math.inf if p["x"] > 0.5 else (p["x"] - 0.4) ** 2 + 1, [Dimension("x", 0, 1)]
    )
    assert tr.best[0][0] == pytest.approx(0.4, abs=2e-3)


# -- a known optimum: two agents, d = 1, additive noise, γ = 1 ------------------------------
# Both edges antagonistic with weight −w: L_B = w[[1+δ, 1], [1, 1+δ]], eigenvalues w(2+δ)
# and wδ with eigenvectors (1, ±1)/√2, additive noise w·σ on each agent, f = 0. In the
# eigenbasis S_k' = −2λ_k c S_k + c² w²σ², which for c = a/(b + t) integrates to
# S_k(T) = S_k(0) (b/(b+T))^(2λa) + a²w²σ²/(2λa − 1)·[(b+T)^(−1) − b^(2λa−1)(b+T)^(−2λa)].

PAIR = """name: pair_network
dim: 1
agents: 2
edges:
  - {from: 2, to: 1, weight: [[-1.0]]}
  - {from: 1, to: 2, weight: [[-1.0]]}
"""
W, SIG, T_PAIR = 1.0, 1.0, 5.0
X0_PAIR = np.array([3.0, -1.0])


@pytest.fixture(scope="module")
def pair_network(tmp_path_factory):
    p = tmp_path_factory.mktemp("pair") / "pair.yaml"
    p.write_text(PAIR, encoding="utf-8")
    top = nd.load(p)
    spec = SimulationSpec.build([1.0], noise=NoiseModel(SIG, 0.0), initial=X0_PAIR)
    delta = nd.design(top, [1.0]).delta
    lam = np.array([W * (2 + delta), W * delta])
    v = np.array([[1, 1], [1, -1]]) / np.sqrt(2)
    s0 = (v.T @ (X0_PAIR - 1.0)) ** 2

    def closed(a, b):
        k = 2 * lam * a
        q = (W * SIG) ** 2
        tail = (b + T_PAIR) ** -1 - b ** (k - 1) * (b + T_PAIR) ** -k
        return float(np.sum(s0 * (b / (b + T_PAIR)) ** k + a * a * q / (k - 1) * tail))

    return top, spec, closed


@pytest.mark.parametrize("a, b", [(1.0, 1.0), (0.3, 2.0), (2.0, 0.5), (6.0, 7.0)])
def test_exact_objective_equals_the_closed_form(pair_network, a, b):
    top, spec, closed = pair_network
    obj = ExactObjective(top, spec, T_PAIR)
    assert obj.curve(PowerGain(a, b, 1.0)).final == pytest.approx(closed(a, b), rel=1e-8)
    # the search's coarser RK4 is still accurate to 1e-5
    assert obj.value(PowerGain(a, b, 1.0)) == pytest.approx(closed(a, b), rel=1e-5)


def test_tuned_gain_reaches_the_known_optimum(pair_network):
    top, spec, closed = pair_network
    ref = minimize(
        lambda p: closed(math.exp(p[0]), math.exp(p[1])),
        [0.0, 0.0],
        method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-13, "maxfev": 4000},
    )
    best = ref.fun
    assert 0.05 < math.exp(ref.x[0]) < 20 and 0.1 < math.exp(ref.x[1]) < 10  # interior
    res = tune(top, spec, T_PAIR, bounds={"gamma": (1.0, 1.0)}, landscape=False)
    assert res.tuned.gamma == 1.0
    assert res.ms_error_T["tuned"] == pytest.approx(closed(res.tuned.a, res.tuned.b), rel=1e-8)
    assert res.ms_error_T["tuned"] <= best * (1 + 1e-4)
    assert res.ms_error_T["baseline"] == pytest.approx(closed(1.0, 1.0), rel=1e-8)
    assert res.ms_error_T["baseline"] > best * 1.05  # the baseline is measurably worse


# -- G1, the switching set, A(t) ----------------------------------------------------------


@pytest.fixture(scope="module")
def g1_tuned(tmp_path_factory, examples):
    """`ntc tune` of the paper's G1 scenario at T = 10, with --out, as a user runs it."""
    out = tmp_path_factory.mktemp("tune") / "g1"
    args = [str(examples / "scenarios" / "g1_fixed.yaml"), "--horizon", "10", "--eps", "2"]
    proc = subprocess.run(
        [sys.executable, "-m", "ntc_design", "tune", *args, "--out", str(out), "--json"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    return proc, out


def _independent_final(top, theta, des, gain, x_init, t_end):
    """E Σ‖x_i(T) − θ‖² from the moment equations built from the SDE (test_moments_math)
    and integrated by SciPy's DOP853."""
    eps0 = x_init - np.tile(theta, top.n)
    y0 = np.concatenate([eps0, np.outer(eps0, eps0).ravel()])
    sol = solve_ivp(
        _moment_rhs(top, des.grounded_laplacian(), gain),
        (0.0, t_end),
        y0,
        t_eval=[t_end],
        rtol=1e-9,
        atol=1e-12,
        method="DOP853",
    )
    assert sol.success
    nd_ = top.n * top.dim
    return float(np.trace(sol.y[nd_:, -1].reshape(nd_, nd_)))


@pytest.mark.slow
def test_g1_tuned_gain_beats_the_baseline_and_matches_an_independent_integration(
    g1_tuned, examples
):
    proc, out = g1_tuned
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    ms = doc["ms_error_T"]
    assert ms["tuned"] < 0.95 * ms["baseline"]
    top, spec, _ = load_scenario(examples / "scenarios" / "g1_fixed.yaml")
    x_init, _ = spec.initial_state(top.n, top.dim)
    des = nd.design(top, spec.theta, spec.margin)
    tuned = PowerGain(doc["a"], doc["b"], doc["gamma"])
    assert tuned.text == doc["gain"]
    for key, g in (("tuned", tuned), ("baseline", BASELINE)):
        ref = _independent_final(top, spec.theta, des, g, x_init, 10.0)
        assert ms[key] == pytest.approx(ref, rel=1e-2)
    # the time to ε is where the tuned curve crosses it, and earlier than the baseline's
    te = doc["time_to_eps"]
    assert 0 < te["tuned"] < te["baseline"] <= 10
    assert _independent_final(top, spec.theta, des, tuned, x_init, te["tuned"]) == pytest.approx(
        2.0, rel=2e-2
    )


@pytest.mark.slow
def test_g1_tuned_gain_satisfies_the_theorems_and_its_certificate_verifies(g1_tuned):
    proc, out = g1_tuned
    doc = json.loads(proc.stdout)
    assert doc["required_holds"] is True and doc["certificate_valid"] is True
    g = analyse_gain(doc["gain"])
    assert g.mean_square is True and g.almost_sure is True
    cert = json.loads((out / "certificate.json").read_text(encoding="utf-8"))
    assert verify(cert).valid
    assert 0.51 <= doc["gamma"] <= 1.0


@pytest.mark.slow
def test_g1_written_scenario_agrees_with_monte_carlo(g1_tuned):
    proc, out = g1_tuned
    doc = json.loads(proc.stdout)
    top, spec, _ = load_scenario(out / "tuned.yaml", {"paths": 400, "method": "mc"})
    assert spec.gain == doc["gain"] and spec.T == 10.0
    run = simulate(top, spec=spec)
    lo, hi = run.mc.lo[-1].sum(), run.mc.hi[-1].sum()  # the per-agent 95 % bands added
    assert lo <= doc["ms_error_T"]["tuned"] <= hi
    report = (out / "tune.html").read_text(encoding="utf-8")
    assert doc["gain"] in report and "figures/tune_landscape.png" in report
    assert (out / "figures" / "tune_curves.pdf").stat().st_size > 1000


@pytest.mark.slow  # ~9 s: a switching set's tuning with δ and its certificate
def test_switching_set_tuned_with_delta_is_certified(examples):
    top, spec, _ = load_scenario(examples / "scenarios" / "switching.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = tune(top, spec, 2.0, tune_delta=True, max_evaluations=40, landscape=False)
        lo = 1.05 * max(nd.design(m, spec.theta).thresholds.symmetric for m in top.modes.values())
        # the reported value is the exact moments of the design at that δ
        again = ExactObjective(top, spec.replace(delta=res.delta), 2.0).curve(res.tuned).final
    ms = res.ms_error_T
    assert ms["tuned"] <= ms["baseline"]
    assert res.delta is not None and res.delta >= lo * (1 - 1e-3)
    assert res.certified and res.certificate.verification.valid
    assert ms["tuned"] == pytest.approx(again, rel=1e-9)


def test_nonlinear_noise_is_tuned_by_monte_carlo_with_common_random_numbers(g1, theta):
    spec = SimulationSpec.build(
        theta,
        noise=NoiseModel(0.4, lambda x: 0.3 * np.sin(x)),
        initial=np.linspace(-3, 3, g1.n * g1.dim),
        paths=64,
        dt=0.01,
        seed=3,
        workers=1,
    )
    obj = objective_for(g1, spec, 1.0)
    assert isinstance(obj, MonteCarloObjective) and obj.statistical
    g = PowerGain(1.3, 0.8, 0.9)
    assert obj.value(g) == obj.value(g)  # the same draws for every evaluation
    res = tune(g1, spec, 1.0, max_evaluations=12, landscape=False, certificate=False)
    assert res.statistical and "statistical" in res.method
    c = res.curves["tuned"]
    assert c.lo[-1] <= c.final <= c.hi[-1] and c.hi[-1] > c.lo[-1]
    assert res.ms_error_T["tuned"] <= res.ms_error_T["baseline"]


def test_exact_is_refused_for_a_nonlinear_f(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, np.sin))
    with pytest.raises(nd.InputError, match="exact moments are not available here"):
        objective_for(g1, spec, 1.0, method="exact")


def test_a_stiff_or_unstable_candidate_scores_infinity_without_being_integrated(g1, theta):
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.3), initial=np.ones(21))
    obj = ExactObjective(g1, spec, 10.0)
    assert obj.value(PowerGain(20.0, 0.1, 1.0)) == math.inf  # c(0) = 200: about 4e5 RK4 steps
    assert "too stiff" in next(iter(obj.skipped.values()))
    # c(0) = 4.5: integrable, but the multiplicative noise makes E‖ε‖² grow without bound
    assert obj.value(PowerGain(4.472, 1.0, 0.51)) == math.inf


# -- hostile input --------------------------------------------------------------------------


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--horizon", "0"], "horizon"),
        (["--horizon", "nan"], "horizon"),
        (["--horizon", "1", "--require", "sure"], "require"),
        (["--horizon", "1", "--eps", "-1"], "eps"),
        (["--horizon", "1", "--method", "fast"], "method"),
        (["--horizon", "1", "--family", "exp"], "--family"),
        (["--horizon", "1", "--evaluations", "3"], "max_evaluations"),
    ],
)
def test_cli_bad_options_give_one_line(extra, needle, examples, capsys, monkeypatch):
    assert_input_error(
        ["tune", examples / "scenarios" / "g1_fixed.yaml", *extra], capsys, monkeypatch, needle
    )


@pytest.mark.hostile
def test_cli_tune_delta_on_expressions_of_t_gives_one_line(examples, capsys, monkeypatch):
    assert_input_error(
        ["tune", examples / "scenarios" / "g1_tv.yaml", "--horizon", "1", "--tune-delta"],
        capsys,
        monkeypatch,
        "--tune-delta",
        "functions of t",
    )


@pytest.mark.hostile
def test_cli_out_that_is_a_file_is_refused_before_the_run(examples, tmp_path, capsys, monkeypatch):
    f = tmp_path / "taken"
    f.write_text("mine", encoding="utf-8")
    assert_input_error(
        ["tune", examples / "scenarios" / "g1_fixed.yaml", "--horizon", "1", "--out", f],
        capsys,
        monkeypatch,
        "--out",
    )
    assert f.read_text(encoding="utf-8") == "mine"


@pytest.mark.hostile
@pytest.mark.parametrize(
    "bounds, needle",
    [
        ({"gamma": (0.3, 1.0)}, "gamma range"),
        ({"a": (0.0, 1.0)}, "a must be > 0"),
        ({"c": (1.0, 2.0)}, "unknown parameter"),
        ({"b": (3.0, 1.0)}, "b range"),
    ],
)
def test_bad_bounds_are_refused(g1, theta, bounds, needle):
    spec = SimulationSpec.build(theta)
    with pytest.raises(nd.InputError, match=needle):
        tune(g1, spec, 1.0, bounds=bounds)


def test_cli_prints_the_table_and_exits_zero(examples, capsys, monkeypatch, tmp_path):
    code, out, err = run_cli(
        [
            "tune",
            examples / "scenarios" / "g1_fixed.yaml",
            "--horizon",
            "2",
            "--evaluations",
            "30",
            "--out",
            tmp_path / "t",
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    for label in ("gain c(t)", "E Σ‖x_i(T) − θ‖², T = 2.0000", "certificate of the tuned design"):
        assert label in out
    said = " ".join(out.split("written to", 1)[1].split())  # the line, unwrapped
    files = sorted(p.name for p in (tmp_path / "t").iterdir() if p.is_file())
    assert files and all(f in said for f in files), (files, said)  # every file is named


@pytest.mark.slow  # ~14 s: exact moments of a time-varying topology at every evaluation
def test_a_topology_given_as_expressions_of_t_is_tuned_by_its_exact_moments(examples):
    top, spec, _ = load_scenario(examples / "scenarios" / "g1_tv.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = tune(top, spec, 1.0, max_evaluations=10, landscape=False, certificate=False)
        again = simulate(top, spec=spec.replace(T=1.0, gain=res.tuned.text, method="exact"))
    assert res.method == "exact moments (A(t))" and not res.statistical
    assert res.ms_error_T["tuned"] <= res.ms_error_T["baseline"]
    assert res.ms_error_T["tuned"] == pytest.approx(again.exact.ms_error[-1].sum(), rel=1e-9)
