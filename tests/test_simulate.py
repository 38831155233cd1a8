"""Simulator: Monte Carlo vs exact moments, switching, counterexample gains,
reproducibility, step-size guard, failures and bad input."""

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import ntc_design as nd
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.simulate import NoiseModel, SimulationDiverged, simulate
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.moments import em_moments
from ntc_design.simulate.montecarlo import MonteCarloSpec, run
from ntc_design.simulate.system import mode_system

from .cli_helpers import assert_input_error, run_cli
from .conftest import ROOT, X0


@pytest.fixture(scope="module")
def sw():
    return nd.load(ROOT / "examples" / "switching.yaml")


def em_exact(res, gain=lambda t: 1 / (1 + t)):
    """Exact moments of the Euler–Maruyama recursion on the run's own grid."""
    systems = [mode_system(res.designs[k], NoiseModel()) for k in res.designs]
    return em_moments(systems, res.grid, gain, X0 - np.tile(THETA, 7), 7, 3).ms_error


def assert_mc_matches_exact(res, max_outside=0.15, max_z=6.0, exact=None):
    """The exact curve lies in the MC 95% band at most save times. Save times share their
    paths (errors are correlated in time) and ‖x_i − θ‖² is heavy-tailed under
    multiplicative noise (the band under-covers now and then), so the test bounds the
    fraction outside, the median standardized error (a bias of one standard error would
    push it above 1) and the worst case."""
    mc, ex = res.mc, (res.exact.ms_error if exact is None else exact)
    half = np.maximum(mc.hi - mc.mean, 1e-12)
    z = np.abs(mc.mean[1:] - ex[1:]) / half[1:] * 1.96
    outside = np.mean((ex[1:] < mc.lo[1:]) | (ex[1:] > mc.hi[1:]))
    assert outside <= max_outside, f"{outside:.0%} of (time, agent) pairs outside the 95% band"
    assert np.median(z) < 1.2, f"median |MC − exact| = {np.median(z):.2f} standard errors"
    assert np.max(z) < max_z, f"max |MC − exact| = {np.max(z):.2f} standard errors"


def test_g1_monte_carlo_agrees_with_exact(g1):
    """MC against the exact moments of its own Euler–Maruyama recursion (no
    discretisation gap: a sharp test), and the recursion against the continuous moments
    (the O(dt) bias of Euler–Maruyama, visible for agent 3 at dt = 1e-3)."""
    res = simulate(g1, THETA, T=2.0, dt=1e-3, paths=2000, seed=3, initial=X0, save_every=0.1)
    assert res.mc.count == 2000
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em)
    np.testing.assert_allclose(res.mc.mean[0], res.exact.ms_error[0], rtol=1e-9)
    gap = np.abs(em[1:] - res.exact.ms_error[1:]) / res.exact.ms_error[1:]
    assert 1e-5 < np.max(gap) < 0.02  # O(dt) bias: present, and small
    fine = simulate(g1, THETA, T=2.0, dt=2.5e-4, paths=2000, seed=3, initial=X0, save_every=0.1)
    assert_mc_matches_exact(fine)


def test_exact_curves_decrease_toward_zero(g1):
    res = simulate(
        g1, THETA, T=1000.0, initial=X0, method="exact", save_times=[1, 10, 100, 500, 1000]
    )
    tot = res.exact.ms_error.sum(axis=1)
    assert np.all(np.diff(tot[1:]) < 0)
    assert tot[-1] < 0.02 * tot[2] and tot[-1] < 0.05
    # E‖ε‖² ~ const·c(t) for c = 1/(1+t): the product settles
    ratio = tot[-2:] * (1 + np.array([500.0, 1000.0]))
    assert ratio[1] == pytest.approx(ratio[0], rel=0.1)


def test_exact_moments_match_dop853(g1):
    """Independent integration of the vectorised moment ODE with SciPy's DOP853."""
    des = nd.design(g1, THETA, thresholds=False)
    sysm = mode_system(des, NoiseModel(0.4, 0.3))
    nd_ = 21
    eye = np.eye(nd_)
    lop = -(np.kron(des.grounded_laplacian(), eye) + np.kron(eye, des.grounded_laplacian()))
    nop = np.zeros((nd_ * nd_, nd_ * nd_))
    for i, j, k in sysm.h_blocks:
        h = np.zeros((nd_, nd_))
        h[i * 3 : (i + 1) * 3, j * 3 : (j + 1) * 3] += k
        h[i * 3 : (i + 1) * 3, i * 3 : (i + 1) * 3] -= k
        nop += np.kron(h, h)
    q = (sysm.g @ sysm.g.T).toarray().ravel()
    eps0 = X0 - np.tile(THETA, 7)

    def rhs(t, v):
        c = 1 / (1 + t)
        return c * (lop @ v) + c * c * (nop @ v + q)

    sol = solve_ivp(
        rhs,
        (0, 20),
        np.outer(eps0, eps0).ravel(),
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        t_eval=[1, 5, 20],
    )
    ref = np.array(
        [
            [np.trace(s.reshape(21, 21)[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]) for i in range(7)]
            for s in sol.y.T
        ]
    )
    res = simulate(g1, THETA, T=20.0, initial=X0, method="exact", save_times=[1, 5, 20])
    np.testing.assert_allclose(res.exact.ms_error[1:], ref, rtol=1e-6)


def test_switching_agreement_and_switch_times(sw):
    res = simulate(sw, THETA, T=1.0, dt=1e-3, paths=2000, seed=5, initial=X0, save_every=0.05)
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em)
    assert np.max(np.abs(em[1:] / res.exact.ms_error[1:] - 1)) < 0.02
    segs = sw.segments(1.0)
    names = list(sw.modes)
    grid = build_grid(1.0, 1e-3, [0, 1.0], [(a, b, names.index(m)) for a, b, m in segs])
    for a, _, m in segs:
        k = int(np.argmin(np.abs(grid.t - a)))
        assert grid.t[k] == a  # every switching instant is a grid point, exactly
        assert names[grid.mode[k]] == m
    starts = grid.t[:-1]
    assert [names[m] for m in grid.mode[::7]] == [sw.mode_at(t) for t in starts[::7]]


def test_vanishing_gain_stays_away(g1):
    """c = (1+t)^-2: ∫c = 1, so the exact error freezes at a positive level."""
    res = simulate(
        g1, THETA, gain="(1+t)^-2", T=100.0, initial=X0, method="exact", save_times=[10, 50, 100]
    )
    tot = res.exact.ms_error.sum(axis=1)
    assert tot[-1] > 1.0
    assert tot[-1] == pytest.approx(tot[-2], rel=0.05)


def test_energy_gain_paths_keep_fluctuating(g1):
    """c = (1+t)^(-1/3): the stored paths still move late in the run; with 1/(1+t) they
    settle. Same seed, same paths, only the gain differs."""
    kw = dict(
        T=30.0, dt=2e-3, paths=20, seed=7, initial=X0, save_every=0.5, method="mc", store_paths=10
    )
    wild = simulate(g1, THETA, gain="(1+t)^(-1/3)", **kw).summary()["sample_paths"]
    calm = simulate(g1, THETA, gain="1/(1+t)", **kw).summary()["sample_paths"]
    assert wild["stored"] == 10
    assert wild["late_fluctuation_mean"] > 2.5 * calm["late_fluctuation_mean"]
    assert wild["late_fluctuation_mean"] > 0.5


def _spec(g1, paths=1100, block=250):
    des = nd.design(g1, THETA, thresholds=False)
    sysm = mode_system(des, NoiseModel())
    grid = build_grid(0.3, 1e-3, np.arange(0, 0.31, 0.1))
    gain = lambda t: 1.0 / (1.0 + t)  # noqa: E731
    return MonteCarloSpec(
        systems=(sysm,), grid=grid, gain=gain, theta=des.theta, x_init=X0, n_agents=7, dim=3,
        paths=paths, seed=11, block_size=block, store_paths=5,
    )  # fmt: skip


def test_same_seed_identical_across_workers_and_chunks(g1):
    spec = _spec(g1)
    a = run(spec, workers=1, blocks_per_chunk=5)
    b = run(spec, workers=2, blocks_per_chunk=1)
    c = run(spec, workers=2, blocks_per_chunk=2)
    for other in (b, c):
        assert np.array_equal(a.sq, other.sq) and np.array_equal(a.sq2, other.sq2)
        assert np.array_equal(a.state, other.state) and np.array_equal(a.stored, other.stored)
    d = run(_spec(g1), workers=1)
    assert np.array_equal(a.sq, d.sq)
    e = run(MonteCarloSpec(**{**spec.__dict__, "seed": 12}), workers=1)
    assert not np.array_equal(a.sq, e.sq)


def test_intrinsic_stepping_matches_exact_with_fewer_steps(g1):
    kw = dict(T=50.0, paths=2000, seed=9, initial=X0, save_every=2.5)
    res = simulate(g1, THETA, stepping="intrinsic", ds=1e-3, **kw)
    assert res.stats.steps < 50_000 / 8  # uniform dt = 1e-3 would take 50 000 steps
    em = em_exact(res)
    assert_mc_matches_exact(res, exact=em, max_outside=0.2)
    # the intrinsic-time Euler–Maruyama bias against the continuous moments stays O(ds)
    assert np.max(np.abs(em[1:] / res.exact.ms_error[1:] - 1)) < 0.02


def test_step_size_guard(g1):
    with pytest.raises(nd.InputError, match=r"dt: Euler–Maruyama is unstable.*use dt <"):
        simulate(g1, THETA, T=1.0, dt=0.3, paths=10, save_every=1.0)
    # G1's drift bound 2·Re λ/|λ|² is 0.137 (λ = 14.58), but in mean square h = 0.1 is
    # unstable (the second moment of the recursion grows 1.8× per step, test_kernel.py):
    # the multiplicative-noise limit of agent 5 (0.057) refuses it; h = 0.04 is close
    with pytest.raises(nd.InputError, match=r"mean-square limit .* of agent 5.*use dt < 0.057"):
        simulate(g1, THETA, T=0.5, dt=0.1, paths=10, method="mc", save_every=0.5)
    with pytest.warns(UserWarning, match="within a factor"):
        simulate(g1, THETA, T=0.5, dt=0.04, paths=10, method="mc", save_every=0.5)


def test_divergence_names_time_and_agent_and_keeps_results(g1):
    blow = lambda x: 50.0 * x * np.abs(x) ** 3  # noqa: E731 - violates Assumption 1 on purpose
    with pytest.raises(SimulationDiverged, match=r"diverged .* by t = .* at agent \d") as exc:
        simulate(
            g1,
            THETA,
            T=5.0,
            dt=1e-3,
            paths=50,
            initial=X0,
            noise=NoiseModel(0.4, blow),
            save_every=0.01,
            workers=1,
        )
    res = exc.value.result
    assert 0 < res.save_times.size < 501
    assert np.all(np.isfinite(res.mc.mean))
    assert res.failure.t > 0


def test_noise_callable_shape_is_checked(g1):
    with pytest.raises(nd.InputError, match=r"noise.f: returned shape"):
        simulate(g1, THETA, T=0.1, paths=4, noise=NoiseModel(0.4, lambda x: x[..., :1]))


def test_nonlinear_f_runs_mc_only(g1):
    res = simulate(
        g1,
        THETA,
        T=0.2,
        paths=50,
        initial=X0,
        noise=NoiseModel(0.4, lambda x: 0.3 * np.tanh(x)),
        save_every=0.1,
        workers=1,
    )
    assert res.exact is None and any("not linear" in n for n in res.notes)


def test_time_varying_topology_simulates(g1):
    w = lambda t: np.diag([2.0 + np.sin(t), 1.0, 1.5])  # noqa: E731
    tv = nd.TimeVaryingTopology(
        (1, 2, 3), 3, {(1, 2): lambda t: -w(t), (2, 3): w, (3, 1): lambda t: np.eye(3)}
    )
    res = simulate(tv, THETA, T=1.0, paths=400, seed=1, save_every=0.25, resample=0.1, workers=1)
    assert len(res.designs) == 10 and res.exact is not None
    assert_mc_matches_exact(res, max_outside=0.25)


# --------------------------------------------------------------------------- CLI


def write_scenario(tmp_path, **over):
    doc = {
        "topology": str(ROOT / "examples" / "g1.yaml"),
        "theta": THETA,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3},
        "initial": {"uniform": [-3, 3], "seed": 1},
        "T": 0.2,
        "dt": 0.001,
        "paths": 40,
        "seed": 0,
        "save_every": 0.05,
        "method": "both",
        "workers": 1,
    }
    doc.update(over)
    p = tmp_path / "sc.yaml"
    p.write_text(json.dumps({k: v for k, v in doc.items() if v is not None}))
    return p


def test_cli_simulate_writes_outputs(tmp_path, capsys, monkeypatch):
    sc = write_scenario(tmp_path)
    out = tmp_path / "out"
    code, _, err = run_cli(["simulate", sc, "--out", out], capsys, monkeypatch)
    assert code == 0, err
    header = (out / "ms_error.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "mc_1", "mc_1_lo", "mc_1_hi", "exact_1"] and header[-1] == "exact_7"
    rows = (out / "ms_error.csv").read_text().splitlines()[1:]
    assert len(rows) == 5 and float(rows[-1].split(",")[0]) == pytest.approx(0.2)
    summ = json.loads((out / "summary.json").read_text())
    assert summ["parameters"]["seed"] == 0 and summ["designs"]["G1"]["delta"] == pytest.approx(
        7.244, abs=1e-3
    )
    z = np.load(out / "paths.npz")
    assert z["paths"].shape == (10, 5, 21)


def test_cli_divergence_exits_1_and_keeps_partial_results(tmp_path, capsys, monkeypatch):
    # (1+t)^3 grows: the drift becomes unstable late in the run; the guard catches it
    # (Monte Carlo only: with the exact moments too, their step estimate refuses it first)
    sc = write_scenario(tmp_path, gain="50*(1+t)^3", T=1.0, method="mc")
    assert_input_error(["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch, "unstable")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "over, needles",
    [
        ({"dt": 0}, ["dt", "positive"]),
        ({"dt": -0.1}, ["dt", "positive"]),
        ({"T": 0}, ["T", "positive"]),
        ({"paths": 0}, ["paths", "positive integer"]),
        ({"topology": "nope.yaml"}, ["topology", "no such file"]),
        ({"initial": [[1, 2, 3]] * 6}, ["initial", "expected 7 states"]),
        ({"gain": "0.1 - t"}, ["gain", "negative"]),
        ({"gain": "1/(1+"}, ["gain", "cannot parse"]),
        ({"method": "magic"}, ["method"]),
        ({"colour": 1}, ["colour", "unknown field"]),
    ],
)
def test_bad_scenarios(tmp_path, capsys, monkeypatch, over, needles):
    sc = write_scenario(tmp_path, **over)
    out = tmp_path / "never"
    assert_input_error(["simulate", sc, "--out", out], capsys, monkeypatch, *needles)
    assert not out.exists()
