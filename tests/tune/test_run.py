"""Tests of :mod:`ntc_design.tune.run`."""

import json
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.gain.conditions import analyse_gain
from ntc_design.simulate import SimulationSpec
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune import (
    BASELINE,
    ExactObjective,
    PowerGain,
    PowerOptions,
    tune,
)
from tests.cli_helpers import assert_input_error
from tests.support.moments_math import _moment_rhs
from tests.support.tune import T_PAIR


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
    res = tune(top, spec, T_PAIR, PowerOptions(bounds={"gamma": (1.0, 1.0)}, landscape=False))
    assert res.tuned.gamma == 1.0
    assert res.ms_error_T["tuned"] == pytest.approx(closed(res.tuned.a, res.tuned.b), rel=1e-8)
    assert res.ms_error_T["tuned"] <= best * (1 + 1e-4)
    assert res.ms_error_T["baseline"] == pytest.approx(closed(1.0, 1.0), rel=1e-8)
    assert res.ms_error_T["baseline"] > best * 1.05  # the baseline is measurably worse


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


@pytest.mark.slow  # ~9 s: a switching set's tuning with δ and its certificate
def test_switching_set_tuned_with_delta_is_certified(examples):
    top, spec, _ = load_scenario(examples / "scenarios" / "switching.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = tune(
            top, spec, 2.0, PowerOptions(tune_delta=True, max_evaluations=40, landscape=False)
        )
        lo = 1.05 * max(nd.design(m, spec.theta).thresholds.symmetric for m in top.modes.values())
        # the reported value is the exact moments of the design at that δ
        again = ExactObjective(top, spec.replace(delta=res.delta), 2.0).curve(res.tuned).final
    ms = res.ms_error_T
    assert ms["tuned"] <= ms["baseline"]
    assert res.delta is not None and res.delta >= lo * (1 - 1e-3)
    assert res.certified and res.certificate.verification.valid
    assert ms["tuned"] == pytest.approx(again, rel=1e-9)


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
        (["--horizon", "1", "--evaluations", "3"], "--evaluations:"),
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
        tune(g1, spec, 1.0, PowerOptions(bounds=bounds))


# -- issue 41, item 8: a tuning run estimated before it starts ----------------------------


def _no_evaluation(monkeypatch):
    """Every objective evaluation stops the run (the estimate must come first)."""
    from ntc_design.tune import objective

    def stop(*a, **k):
        raise KeyboardInterrupt

    for cls in objective.OBJECTIVES.values():
        monkeypatch.setattr(cls, "_curve", stop)


@pytest.mark.hostile
def test_monte_carlo_tuning_at_a_long_horizon_is_refused_before_any_run(
    examples, capsys, monkeypatch
):
    """g1_tv at T = 10⁴ by Monte Carlo: 10⁷ steps × 1000 paths a candidate, 180 of them
    (about a day): one line naming --horizon, nothing evaluated."""
    _no_evaluation(monkeypatch)
    sc = examples / "scenarios" / "g1_tv.yaml"
    line = assert_input_error(
        ["tune", sc, "--horizon", "1e4", "--method", "mc"], capsys, monkeypatch, "--horizon"
    )
    assert "180 evaluations of Monte Carlo" in line and "more than the limit of 60 min" in line


@pytest.mark.hostile
def test_a_long_tuning_run_says_how_long_before_the_first_evaluation(examples, capsys, monkeypatch):
    """g1_tv at T = 10⁴ by its exact moments: minutes; the estimate is printed, then the
    first evaluation (stopped here)."""
    from tests.cli_helpers import run_cli

    _no_evaluation(monkeypatch)
    sc = examples / "scenarios" / "g1_tv.yaml"
    code, _, err = run_cli(["tune", sc, "--horizon", "1e4"], capsys, monkeypatch)
    assert code == 130, err
    line = next(ln for ln in err.splitlines() if ln.startswith("warning: --horizon:"))
    assert "tuning for T = 10000 takes roughly" in line
    assert "277 evaluations of exact moments (A(t))" in line


def test_the_estimate_is_the_mean_candidate_of_the_grid(examples):
    """tune_seconds: the coarse grid's 60 candidates priced by their closed-form step
    counts (a candidate above the step cap scores +∞ unintegrated, so costs nothing)."""
    from ntc_design.tune.objective import MAX_STEPS, objective_for
    from ntc_design.tune.run import _dimensions, tune_seconds

    top, spec, _ = load_scenario(examples / "scenarios" / "g1_tv.yaml")
    obj = objective_for(top, spec, 1e4)
    dims = _dimensions("both", None, None)
    total, n, per = tune_seconds(obj, dims, 160, landscape=True)
    assert n == 160 + 13 * 9
    grid = [
        PowerGain(a, b, g) for a in dims[0].grid() for b in dims[1].grid() for g in dims[2].grid()
    ]
    costs = [obj.seconds(g) for g in grid]
    assert len(costs) == 60 and per == pytest.approx(np.mean(costs))
    assert total == pytest.approx(n * per + 2 * obj.seconds(BASELINE, accurate=True))
    stiff = [g for g in grid if obj._steps(g) > MAX_STEPS]
    assert stiff and all(obj.seconds(g) == 0 for g in stiff)
