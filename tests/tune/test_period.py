"""Tests of :mod:`ntc_design.tune.period`: the longest safe period against an independent
scan of the exact sampled recursion (a dense augmented-state computation), the bounds and
the command line."""

import json

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.simulate.system import mode_system
from ntc_design.tune.period import longest_safe_period, period_curve
from tests.cli_helpers import assert_input_error, run_cli

X0 = np.linspace(-3, 3, 21)


@pytest.fixture(scope="module")
def spec():
    return SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3), initial=X0.tolist())


def _dense(g1, h, delay, t_end):
    """E‖e_K‖² and the peak, K = round(T/h), by the augmented recursion written densely."""
    des = nd.design(g1, THETA, thresholds=False)
    s = mode_system(des, NoiseModel(0.4, 0.3))
    lap, n = s.lap_b.toarray(), 21
    gs = []
    for e in range(s.n_edges):
        i, j = int(s.dst[e]), int(s.src[e])
        gm = np.zeros((n, n))
        gm[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += s.k_blocks[e]
        gm[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] -= s.k_blocks[e]
        g = np.zeros(n)
        g[3 * i : 3 * i + 3] = s.g_edge[e]
        gs.append((gm, g))
    w = (delay + 1) * n
    z = np.tile(X0 - np.tile(THETA, 7), delay + 1)
    zz = np.outer(z, z)
    peak = np.trace(zz[:n, :n])
    for k in range(round(t_end / h)):
        c = 1 / (1 + k * h)
        a = np.zeros((w, w))
        a[:n, :n] = np.eye(n)
        a[:n, delay * n :] -= h * c * lap
        for b in range(delay):
            a[(b + 1) * n : (b + 2) * n, b * n : (b + 1) * n] = np.eye(n)
        sdd = zz[delay * n :, delay * n :]
        zz = a @ zz @ a.T
        zz[:n, :n] += h * c * c * sum(np.outer(g, g) + gm @ sdd @ gm.T for gm, g in gs)
        peak = max(peak, np.trace(zz[:n, :n]))
    return np.trace(zz[:n, :n]), peak


def test_period_curve_matches_the_dense_recursion(g1, spec):
    got = period_curve(g1, spec, 2.0, 1, np.array([0.05, 0.2]))
    for (final, peak), h in zip(got, (0.05, 0.2), strict=True):
        want = _dense(g1, h, 1, 2.0)
        assert final == pytest.approx(want[0], rel=1e-10)
        assert peak == pytest.approx(want[1], rel=1e-10)


@pytest.mark.parametrize(("delay", "expected"), [(0, 0.1744), (1, 0.0958)])
def test_longest_safe_period_agrees_with_an_independent_scan(g1, spec, delay, expected):
    """G1, T = 10, tolerance 0.1: an independent scan in steps of 0.0005 (the dense
    recursion above, run once off-line) first fails at 0.1744 (D = 0) and 0.0958 (D = 1);
    here the boundary is checked directly just below and above the result."""
    r = longest_safe_period(g1, spec, 10.0, delay=delay, tolerance=0.1)
    assert expected * 0.99 <= r.period <= expected  # below the scan's first failure
    assert r.continuous_final == pytest.approx(2.9169, rel=1e-4)
    below, _ = _dense(g1, r.period * 0.99, delay, 10.0)
    above, _ = _dense(g1, expected, delay, 10.0)
    assert below <= 1.1 * r.continuous_final < above
    assert all(p.ok for p in r.curve if p.period <= r.period)
    assert r.to_dict()["period"] == r.period and len(r.to_dict()["curve"]) == len(r.curve)


def test_the_peak_bound_shortens_the_period(g1, spec):
    free = longest_safe_period(g1, spec, 10.0, delay=1, tolerance=0.1)
    capped = longest_safe_period(g1, spec, 10.0, delay=1, tolerance=0.1, max_peak=300.0)
    assert capped.period < free.period
    assert all(p.peak <= 300.0 for p in capped.curve if p.period <= capped.period)


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"tolerance": -0.1}, "--tolerance: must be >= 0"),
        ({"delay": -1}, "--delay: must be an integer >= 0"),
        ({"max_peak": 0.0}, "--max-peak: must be a positive number"),
    ],
)
def test_bad_options_name_the_flag(g1, spec, kw, message):
    with pytest.raises(InputError, match=message):
        longest_safe_period(g1, spec, 10.0, **kw)


def test_cli_period_auto_prints_and_writes_the_period(tmp_path, capsys, monkeypatch, examples):
    sc = examples / "scenarios" / "g1_deadline.yaml"
    out = tmp_path / "p"
    args = [
        "tune",
        sc,
        "--horizon",
        "10",
        "--period",
        "auto",
        "--delay",
        "1",
        "--json",
        "--out",
        out,
    ]
    code, text, err = run_cli(args, capsys, monkeypatch)
    assert code == 0, err
    doc = json.loads(text)
    assert doc["period"] == pytest.approx(0.0958, rel=0.01) and doc["delay"] == 1
    assert json.loads((out / "period.json").read_text())["period"] == doc["period"]


@pytest.mark.hostile
def test_cli_bad_period_text(capsys, monkeypatch, examples):
    sc = examples / "scenarios" / "g1_deadline.yaml"
    assert_input_error(
        ["tune", sc, "--horizon", "10", "--period", "soon"], capsys, monkeypatch,
        "--period: expected a number or auto",
    )  # fmt: skip
