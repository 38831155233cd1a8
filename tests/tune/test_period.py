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


@pytest.fixture(scope="module")
def g1_safe(g1, spec):
    """G1's longest safe period at T = 10, tolerance 0.1, per delay, each searched once
    for the tests that read it."""
    got: dict[int, object] = {}

    def safe(delay: int):
        if delay not in got:
            got[delay] = longest_safe_period(g1, spec, 10.0, delay=delay, tolerance=0.1)
        return got[delay]

    return safe


@pytest.fixture(scope="module")
def g1_dense(g1):
    """G1's L_B, the edges' G_e stacked (E, Nd, Nd) and Σ g_e g_eᵀ, written densely."""
    des = nd.design(g1, THETA, thresholds=False)
    s = mode_system(des, NoiseModel(0.4, 0.3))
    n = 21
    gms = np.zeros((s.n_edges, n, n))
    q = np.zeros((n, n))
    for e in range(s.n_edges):
        i, j = int(s.dst[e]), int(s.src[e])
        gms[e, 3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += s.k_blocks[e]
        gms[e, 3 * i : 3 * i + 3, 3 * i : 3 * i + 3] -= s.k_blocks[e]
        g = np.zeros(n)
        g[3 * i : 3 * i + 3] = s.g_edge[e]
        q += np.outer(g, g)
    return s.lap_b.toarray(), gms, q


def _dense(g1_dense, h, delay, t_end):
    """E‖e(T)‖² and the peak by the augmented recursion written densely: K = ⌊T/h⌋ whole
    steps (T/h within 1e-9 of a whole number counts as one), then the held input for
    s = T − K·h (h → s in the step's matrix, noise factor s²/h)."""
    lap, gms, q = g1_dense
    n = lap.shape[0]
    whole = abs(round(t_end / h) * h - t_end) <= 1e-9 * t_end
    k_full = round(t_end / h) if whole else int(np.floor(t_end / h))
    part = 0.0 if whole else t_end - k_full * h
    w = (delay + 1) * n
    z = np.tile(X0 - np.tile(THETA, 7), delay + 1)
    zz = np.outer(z, z)
    peak = np.trace(zz[:n, :n])
    for k in range(k_full + (part > 0)):
        c = 1 / (1 + k * h)
        dt, var = (h, h) if k < k_full else (part, part * part / h)
        a = np.zeros((w, w))
        a[:n, :n] = np.eye(n)
        a[:n, delay * n :] -= dt * c * lap
        for b in range(delay):
            a[(b + 1) * n : (b + 2) * n, b * n : (b + 1) * n] = np.eye(n)
        sdd = zz[delay * n :, delay * n :]
        zz = a @ zz @ a.T
        zz[:n, :n] += var * c * c * (q + np.matmul(gms @ sdd, gms.transpose(0, 2, 1)).sum(0))
        peak = max(peak, np.trace(zz[:n, :n]))
    return np.trace(zz[:n, :n]), peak


def test_period_curve_matches_the_dense_recursion(g1, spec, g1_dense):
    hs = (0.05, 0.2, 0.07, 0.3)  # whole numbers of periods in T = 2, then partial steps
    got = period_curve(g1, spec, 2.0, 1, np.array(hs))
    for (final, peak), h in zip(got, hs, strict=True):
        want = _dense(g1_dense, h, 1, 2.0)
        assert final == pytest.approx(want[0], rel=1e-10)
        assert peak == pytest.approx(want[1], rel=1e-10)


@pytest.mark.parametrize(("delay", "expected"), [(0, 0.17441), (1, 0.09600)])
def test_longest_safe_period_agrees_with_an_independent_scan(g1_safe, g1_dense, delay, expected):
    """G1, T = 10, tolerance 0.1. Off-line, an independent scan in steps of 2.5e-5 (the
    dense recursion) first fails at 0.17445 (D = 0, everything from 0.11 passes) and at
    0.0961 (D = 1, from 0.09; windows 0.0961–0.09625 and from 0.0967 fail). Here the
    claim is checked on a grid the search does not use: every T/(K + j/10) for the four
    samples below the answer passes, and a period within 0.2 % above it fails."""
    r = g1_safe(delay)
    assert r.period == pytest.approx(expected, rel=1e-4)
    assert r.continuous_final == pytest.approx(2.9169, rel=1e-4)
    bound = 1.1 * r.continuous_final
    k0 = int(10.0 / r.period)
    own = [10.0 / (k + j / 10) for k in range(k0, k0 + 4) for j in range(10)]
    finals = [_dense(g1_dense, h, delay, 10.0)[0] for h in own if h <= r.period]
    assert len(finals) >= 30 and max(finals) <= bound
    above = [_dense(g1_dense, r.period * (1 + i * 4e-4), delay, 10.0)[0] for i in range(1, 6)]
    assert max(above) > bound  # the answer is tight to a fifth of a percent
    assert all(p.ok for p in r.curve if p.period <= r.period)
    ev = r.to_dict()["verification"]
    assert ev["periods"] == r.evidence.periods >= 100 and ev["complete"]
    assert ev["dense_samples"][0] == k0 and ev["worst"]["final_ms_error"] <= bound
    assert r.to_dict()["period"] == r.period and len(r.to_dict()["curve"]) == len(r.curve)


@pytest.mark.slow
def test_a_failing_window_below_the_bisection_shortens_the_answer(g1, spec, g1_dense):
    """D = 2: the geometric scan and the bisection stop at 0.06156, but 0.06135–0.06137
    (just past T/163) fails; the verification finds it and answers below it."""
    r = longest_safe_period(g1, spec, 10.0, delay=2, tolerance=0.1)
    assert r.period == pytest.approx(0.061327, rel=1e-4)
    assert any("failing period below" in n for n in r.notes)
    assert _dense(g1_dense, 0.06136, 2, 10.0)[0] > 1.1 * r.continuous_final
    assert _dense(g1_dense, r.period, 2, 10.0)[0] <= 1.1 * r.continuous_final


def test_the_peak_bound_shortens_the_period(g1, spec, g1_safe):
    free = g1_safe(1)
    capped = longest_safe_period(g1, spec, 10.0, delay=1, tolerance=0.1, max_peak=300.0)
    assert capped.period < free.period
    assert all(p.peak <= 300.0 for p in capped.curve if p.period <= capped.period)


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"tolerance": -0.1}, "tolerance: must be >= 0"),
        ({"delay": -1}, "delay: must be an integer >= 0"),
        ({"max_peak": 0.0}, "max_peak: must be a positive number"),
    ],
)
def test_bad_options_name_the_parameter(g1, spec, kw, message):
    # the Python caller's names; ntc tune names the flags (tests/cli/test_runs.py)
    with pytest.raises(InputError, match=f"^{message}") as err:
        longest_safe_period(g1, spec, 10.0, **kw)
    assert err.value.field == next(iter(kw))


def test_a_diverging_continuous_design_has_no_period(
    g1, spec, tmp_path, capsys, monkeypatch, examples
):
    """c = 50/(1 + t): the continuous design's own E‖e‖² explodes (past 1e8 times its
    start); no period is judged against it: one line, exit 1, nothing written."""
    r = longest_safe_period(g1, spec.replace(gain="50/(1+t)"), 10.0)
    assert r.period is None and r.diverged is not None and r.evidence is None
    assert "diverges" in r.diverged and r.to_dict()["diverged"] == r.diverged
    sc = tmp_path / "div.yaml"
    sc.write_text(
        f"topology: {examples / 'g1.yaml'}\n"
        "theta: [1, 2, -1]\ngain: '5'\nnoise: {sigma: 0.4, f: 0.3}\n"
        f"initial: {X0.tolist()}\nT: 10\n",
        encoding="utf-8",
    )
    out = tmp_path / "p"
    code, text, err = run_cli(["tune", sc, "--period", "auto", "--out", out], capsys, monkeypatch)
    assert code == 1 and text == "" and not out.exists()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "the continuous design diverges" in lines[0]
    code, text, err = run_cli(["tune", sc, "--period", "auto", "--json"], capsys, monkeypatch)
    doc = json.loads(text)
    assert code == 1 and doc["period"] is None and doc["diverged"] in err


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
    assert doc["period"] == pytest.approx(0.0960, rel=1e-3) and doc["delay"] == 1
    assert doc["verification"]["periods"] >= 100 and doc["diverged"] is None
    assert json.loads((out / "period.json").read_text())["period"] == doc["period"]


@pytest.mark.hostile
def test_cli_bad_period_text(capsys, monkeypatch, examples):
    sc = examples / "scenarios" / "g1_deadline.yaml"
    assert_input_error(
        ["tune", sc, "--horizon", "10", "--period", "soon"], capsys, monkeypatch,
        "--period: expected a number or auto",
    )  # fmt: skip
