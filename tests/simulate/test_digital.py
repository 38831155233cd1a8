"""Tests of :mod:`ntc_design.simulate.digital`: the sampled, delayed recursion's grid, its
exact moments (against a dense augmented-state computation and the issue's independent
table), the delayed Monte Carlo kernel and the driver's digital runs."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.digital import digital_grid, digital_moments
from ntc_design.simulate.kernels import em_steps
from ntc_design.simulate.modes import Stepper
from ntc_design.simulate.moments import PreparedModes
from ntc_design.simulate.system import mode_system

X0_LIN = np.linspace(-3, 3, 21)  # the issue's x(0) on G1
NOISE = NoiseModel(sigma=0.4, f=0.3)


def _edge_matrices(s):
    """g_e (Nd) and G_e (Nd×Nd) of every edge, densely, from the edge arrays."""
    nd_, d = s.nd, s.dim
    out = []
    for e in range(s.n_edges):
        i, j = int(s.dst[e]), int(s.src[e])
        g = np.zeros(nd_)
        g[d * i : d * i + d] = s.g_edge[e]
        gm = np.zeros((nd_, nd_))
        k = s.abs_w[e] @ s.fmat
        gm[d * i : d * i + d, d * j : d * j + d] += k
        gm[d * i : d * i + d, d * i : d * i + d] -= k
        out.append((g, gm))
    return out


def dense_digital(systems, modes, h, delay, k_steps, eps0, gain, part=0.0):
    """Z_{k+1} = A_k Z_k A_kᵀ + h c² E₀(Σ g gᵀ + G Z_DD Gᵀ)E₀ᵀ on the augmented state,
    with A_k written out as a dense block companion matrix, K = ``k_steps`` whole steps
    then, with ``part`` s > 0, the held input for s (h → s in A_K, noise factor s²/h):
    (E‖e(T)‖², peak)."""
    nd_ = systems[0].nd
    w = (delay + 1) * nd_
    z = np.tile(eps0, delay + 1)
    zz = np.outer(z, z)
    edges = [_edge_matrices(s) for s in systems]
    laps = [s.lap_b.toarray() for s in systems]
    peak = np.trace(zz[:nd_, :nd_])
    for k in range(k_steps + (part > 0)):
        c = gain(k * h)
        dt, var = (h, h) if k < k_steps else (part, part * part / h)
        a = np.zeros((w, w))
        a[:nd_, :nd_] = np.eye(nd_)
        a[:nd_, delay * nd_ :] -= dt * c * laps[modes[k]]
        for b in range(delay):
            a[(b + 1) * nd_ : (b + 2) * nd_, b * nd_ : (b + 1) * nd_] = np.eye(nd_)
        sdd = zz[delay * nd_ :, delay * nd_ :]
        noise = sum(np.outer(g, g) + gm @ sdd @ gm.T for g, gm in edges[modes[k]])
        zz = a @ zz @ a.T
        zz[:nd_, :nd_] += var * c * c * noise
        peak = max(peak, np.trace(zz[:nd_, :nd_]))
    return np.trace(zz[:nd_, :nd_]), peak


@pytest.fixture(scope="module")
def g1_issue(g1):
    des = nd.design(g1, THETA, thresholds=False)
    return mode_system(des, NOISE), X0_LIN - np.tile(THETA, 7)


@pytest.mark.parametrize(
    ("h", "delay", "final", "peak"),
    [  # the issue's table (E‖e(10)‖², peak), computed independently of this toolkit
        (0.01, 0, 2.903, 119.7),
        (0.05, 1, 2.841, 273),
        (0.05, 2, 2.943, 1078),
        (0.1, 0, 2.793, 289),
        (0.1, 1, 3.342, 3397),
        (0.1, 2, 15.88, 21604),
        (0.2, 1, 143.8, 110182),
        (0.2, 2, 8514, 574084),
    ],
)
def test_exact_moments_reproduce_the_issue_table_on_g1(g1_issue, h, delay, final, peak):
    s, eps0 = g1_issue
    grid, _ = digital_grid(Digital(h, delay), 10.0, np.array([10.0]))
    got = digital_moments(PreparedModes.of([s], eps0), grid, lambda t: 1 / (1 + t), delay)
    assert float(got.moments.ms_error[-1].sum()) == pytest.approx(final, rel=6e-4)
    assert got.peak == pytest.approx(peak, rel=6e-4)


@pytest.mark.parametrize(("h", "delay"), [(0.1, 0), (0.1, 1), (0.2, 2), (0.05, 3)])
def test_exact_moments_match_the_dense_augmented_recursion(g1_issue, h, delay):
    s, eps0 = g1_issue
    gain = lambda t: 1 / (1 + t)  # noqa: E731
    grid, _ = digital_grid(Digital(h, delay), 2.0, np.array([1.0, 2.0]))
    got = digital_moments(PreparedModes.of([s], eps0), grid, gain, delay)
    want, peak = dense_digital([s], [0] * grid.n_steps, h, delay, grid.n_steps, eps0, gain)
    assert float(got.moments.ms_error[-1].sum()) == pytest.approx(want, rel=1e-12)
    assert got.peak == pytest.approx(peak, rel=1e-12)
    assert got.moments.t.tolist() == pytest.approx([0.0, 1.0, 2.0])


def _dense_at(s, h, delay, eps0, gain, times):
    """E‖e(t)‖² at each time by the augmented recursion written out densely: whole steps
    to the sample before t, then the held input for the rest (h → t − kh in A_k, noise
    factor (t − kh)²/h); an independent loop from the start for every time."""
    out = []
    for t in times:
        k_full = int(np.floor(t / h + 1e-9))
        part = t - k_full * h
        out.append(dense_digital([s], [0] * (k_full + 1), h, delay, k_full, eps0, gain, part)[0])
    return np.array(out)


@pytest.mark.parametrize(("h", "delay"), [(0.3, 0), (0.3, 1), (0.45, 2)])
def test_exact_moments_at_t_and_between_samples_follow_the_held_input(g1_issue, h, delay):
    """T = 2 is not a whole number of periods: the run ends at T by a partial step, and
    save times between samples are the held input there (the dense loop above)."""
    s, eps0 = g1_issue
    gain = lambda t: 1 / (1 + t)  # noqa: E731
    times = np.array([0.1, 0.7, 1.0, 1.95, 2.0])
    grid, _ = digital_grid(Digital(h, delay), 2.0, times, between=True)
    assert grid.t[-1] == 2.0 and grid.noise_last == pytest.approx((2.0 % h) ** 2 / h)
    got = digital_moments(PreparedModes.of([s], eps0), grid, gain, delay)
    assert got.moments.t.tolist() == pytest.approx([0.0, *times])
    want = _dense_at(s, h, delay, eps0, gain, times)
    np.testing.assert_allclose(got.moments.ms_error[1:].sum(axis=1), want, rtol=1e-11)
    # the peak over [0, T]: E‖e(kh + s)‖² is convex in s, so a dense look between the
    # samples finds nothing above the largest value at a sample or at T
    fine = np.linspace(0.0, 2.0, 161)[1:]
    dense = _dense_at(s, h, delay, eps0, gain, fine)
    assert got.peak >= dense.max() * (1 - 1e-11)
    ends = _dense_at(s, h, delay, eps0, gain, [*grid.t[1:]])
    assert got.peak == pytest.approx(max(ends.max(), float(eps0 @ eps0)), rel=1e-11)


@pytest.mark.parametrize("delay", [0, 1])
def test_the_error_at_t_is_continuous_in_the_period(g1_issue, delay):
    """Across h = T/(K + ½), where K = round(T/h) used to jump, and across h = T/K, where
    a whole sample is added: the values on both sides agree (no rounding artefact)."""
    s, eps0 = g1_issue
    gain = lambda t: 1 / (1 + t)  # noqa: E731

    def final(h):
        grid, _ = digital_grid(Digital(h, delay), 10.0, np.array([10.0]))
        m = digital_moments(PreparedModes.of([s], eps0), grid, gain, delay)
        return float(m.moments.ms_error[-1].sum()), m.peak

    for edge in (10.0 / 104.5, 10.0 / 104, 10.0 / 57.5, 10.0 / 57):
        lo, hi = final(edge * (1 - 1e-7)), final(edge * (1 + 1e-7))
        assert lo[0] == pytest.approx(hi[0], rel=1e-4)
        assert lo[1] == pytest.approx(hi[1], rel=1e-4)
    # and it moves: the two sides of a half-period are not the same run
    assert final(10.0 / 104.4)[0] != final(10.0 / 104.6)[0]


def test_switching_moments_use_the_mode_of_each_sample(switching_set):
    from ntc_design.protocol.digital import step_modes

    names = list(switching_set.modes)
    designs = {k: nd.design(switching_set.modes[k], THETA, thresholds=False) for k in names}
    systems = [mode_system(designs[k], NOISE) for k in names]
    h, delay = 0.013, 1
    dg = Digital(h, delay)
    grid, _ = digital_grid(
        dg, 1.0, np.array([1.0]), lambda t: step_modes(switching_set.schedule, t, names, h)
    )
    eps0 = X0_LIN - np.tile(THETA, 7)
    got = digital_moments(PreparedModes.of(systems, eps0), grid, lambda t: 2 / (1 + t), delay)
    modes = grid.mode.tolist()
    assert len(set(modes)) == 3  # every mode is sampled
    k_full, part = dg.steps(1.0)  # 76 whole steps and 0.012 of one
    assert k_full == 76 and part == pytest.approx(0.012) and grid.n_steps == 77
    want, peak = dense_digital(
        systems, modes, h, delay, k_full, eps0, lambda t: 2 / (1 + t), part=part
    )
    assert float(got.moments.ms_error[-1].sum()) == pytest.approx(want, rel=1e-12)
    assert got.peak == pytest.approx(peak, rel=1e-12)


@pytest.mark.parametrize("delay", [0, 1, 3])
def test_the_delayed_kernel_is_the_recursion_written_out(g1_issue, delay):
    """em_steps with a delay (a ring of D + 1 states) against a plain loop over a shift
    register (same normals)."""
    s, _ = g1_issue
    st = Stepper(s, False)
    lap, e_n = s.lap_b.toarray(), s.n_edges
    rng = np.random.default_rng(7)
    k_n, p, h = 40, 5, 0.1
    xi = rng.standard_normal((k_n, p, 2 * e_n))
    c = 1 / (1 + np.arange(k_n) * h)
    ch, cs = c * h, c * np.sqrt(h)
    x = np.tile(np.tile(X0_LIN, delay + 1), (p, 1))
    em_steps(x, xi, 0, k_n, ch, cs, *st.args, True, 4, delay)
    for q in range(p):
        reg = [X0_LIN.copy() for _ in range(delay + 1)]
        for k in range(k_n):
            xd = reg[delay]
            noise = np.zeros(21)
            for e in range(e_n):
                i, j = s.dst[e], s.src[e]
                diff = xd[3 * j : 3 * j + 3] - xd[3 * i : 3 * i + 3]
                noise[3 * i : 3 * i + 3] += (
                    s.g_edge[e] * xi[k, q, e] + s.k_blocks[e] @ diff * xi[k, q, e_n + e]
                )
            reg = [reg[0] + ch[k] * (s.u - lap @ xd) + cs[k] * noise] + reg[:-1]
        ring = x[q].reshape(delay + 1, 21)  # x_j in slot j mod (D + 1)
        got = np.array([ring[(k_n - i) % (delay + 1)] for i in range(delay + 1)])
        assert np.allclose(got, np.array(reg), rtol=1e-13, atol=1e-12)


@pytest.mark.parametrize("rng", ["xoshiro", "numpy"])
def test_monte_carlo_agrees_with_the_exact_digital_moments(g1, rng):
    """A mild transient (h = 0.02, D = 1): the exact curve inside the 99 % band at almost
    every save time and agent (with large transients the error's tails are heavy and the
    band from the sample variance is not reliable; see the guide)."""
    res = simulate(
        g1, THETA, T=2.0, paths=3000, seed=5, initial=X0_LIN, noise=NOISE, rng=rng,
        digital={"period": 0.02, "delay": 1}, save_every=0.5, method="both",
    )  # fmt: skip
    ex, mc = res.exact.ms_error, res.mc
    z = (mc.mean - ex) / np.maximum((mc.hi - mc.lo) / (2 * 1.96), 1e-300)
    assert np.mean(np.abs(z[1:]) < 2.58) >= 0.9
    assert np.sum(mc.mean[-1]) == pytest.approx(np.sum(ex[-1]), rel=0.1)
    assert res.digital.steps == 100 and res.digital.delay == 1
    assert res.grid.t[-1] == pytest.approx(2.0)


def test_monte_carlo_ends_with_the_partial_step_within_its_band(g1):
    """h = 0.45 and T = 2: four samples and a partial step of 0.2; the Monte Carlo at T
    (and at the samples) inside the exact curve's band."""
    res = simulate(
        g1, THETA, T=2.0, paths=3000, seed=7, initial=X0_LIN, noise=NOISE,
        digital={"period": 0.45, "delay": 1}, save_every=0.5, method="both",
    )  # fmt: skip
    assert res.save_times.tolist() == pytest.approx([0.0, 0.45, 0.9, 1.35, 2.0])
    assert res.digital.steps == 4 and res.digital.partial_step == pytest.approx(0.2)
    ex, mc = res.exact.ms_error.sum(axis=1), res.mc
    half = (mc.hi - mc.lo).sum(axis=1) / 2  # the agents' 95 % bands, summed: loose
    assert np.all(np.abs(mc.mean.sum(axis=1) - ex)[1:] <= 1.5 * half[1:])
    assert mc.mean[-1].sum() == pytest.approx(ex[-1], rel=0.05)


def test_the_continuous_error_is_taken_at_t_between_samples(g1):
    """Issue 47.7: at h = 0.0956 (K·h = 10.04 > T with the old rounding) the continuous
    design's error at T was 0.0; it is 2.9169 at T, as at h = 0.1."""
    res = simulate(
        g1, THETA, T=10.0, initial=X0_LIN, noise=NOISE, method="exact",
        digital={"period": 0.0956, "delay": 1},
    )  # fmt: skip
    dg = res.summary()["digital"]
    assert dg["continuous_final_ms_error"] == pytest.approx(2.9169, rel=1e-4)
    assert dg["steps"] == 104 and dg["partial_step"] == pytest.approx(0.0576, rel=1e-9)
    assert res.save_times[-1] == 10.0 and not res.notes
    rows = {r[0].text: r[1].text for r in res.table().rows}
    assert rows["sampling"] == (
        "period h = 0.0956, delay D = 1, K = 104 and a partial step of 0.0576"
    )


def test_a_digital_run_reports_the_peak_and_the_continuous_error(g1):
    res = simulate(
        g1, THETA, T=10.0, initial=X0_LIN, noise=NOISE, method="exact",
        digital={"period": 0.1, "delay": 1},
    )  # fmt: skip
    dg = res.summary()["digital"]
    assert dg["period"] == 0.1 and dg["delay"] == 1 and dg["steps"] == 100
    assert dg["ms_error_peak"] == pytest.approx(3397.38, rel=1e-5)
    assert dg["continuous_final_ms_error"] == pytest.approx(2.9169, rel=1e-4)
    assert float(res.exact.ms_error[-1].sum()) == pytest.approx(3.3421, rel=1e-4)
    rows = {r[0].text: r[1].text for r in res.table().rows}
    assert rows["sampling"] == "period h = 0.1, delay D = 1, K = 100"


def test_save_times_move_to_the_nearest_grid_point_and_the_run_ends_at_t():
    grid, notes = digital_grid(Digital(0.3), 1.0, np.array([0.0, 0.4, 0.5, 0.94, 0.96, 1.0]))
    assert grid.t.tolist() == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.0]) and grid.t[-1] == 1.0
    assert grid.n_steps == 4 and not notes
    assert grid.save_steps.tolist() == [0, 1, 2, 3, 4]  # 0.94 -> 0.9, 0.96 -> T
    # the partial step's noise acts s = 0.1 of the period 0.3: factor s²/h
    assert grid.noise_h() == pytest.approx([0.3, 0.3, 0.3, 0.01 / 0.3])
    kept, _ = digital_grid(Digital(0.3), 1.0, np.array([0.45, 0.6 + 1e-12, 0.95]), between=True)
    assert kept.save_times.tolist() == pytest.approx([0.0, 0.45, 0.6, 0.95, 1.0])
    assert kept.save_steps.tolist() == [0, 1, 2, 3, 4]
    whole, _ = digital_grid(Digital(0.25), 1.0, np.array([1.0]))
    assert whole.n_steps == 4 and whole.noise_last is None


@pytest.mark.hostile
def test_a_delay_too_large_for_memory_is_refused_before_any_allocation(g1):
    with pytest.raises(InputError, match=r"^digital\.delay: .*more than"):
        simulate(g1, THETA, T=1.0, method="exact", digital={"period": 0.1, "delay": 9000})


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"stepping": "intrinsic"}, "digital: the sampled protocol steps every period h"),
        ({"T": 0.05}, "digital.period: h = 0.1 is longer than the horizon T = 0.05"),
    ],
)
def test_digital_runs_refuse_what_does_not_apply(g1, options, message):
    with pytest.raises(InputError, match=message):
        simulate(g1, THETA, digital={"period": 0.1}, method="exact", **{"T": 1.0, **options})


def test_a_step_writes_one_state_whatever_the_delay(g1_issue):
    """The ring: a step of the delayed kernel writes x_{j+1} over x_{j−D}'s slot and leaves
    the other D states alone (a shift register would move all D + 1: work growing with D)."""
    s, _ = g1_issue
    st = Stepper(s, False)
    delay, p = 500, 3
    rng = np.random.default_rng(1)
    x = rng.normal(size=(p, 21 * (delay + 1)))
    before = x.copy()
    xi = rng.standard_normal((1, p, 2 * s.n_edges))
    em_steps(x, xi, 0, 1, np.array([0.01]), np.array([0.1]), *st.args, True, 4, delay, 7)
    changed = np.flatnonzero(np.any(x != before, axis=0))
    slot = (7 + 1) % (delay + 1)
    assert changed.min() >= 21 * slot and changed.max() < 21 * (slot + 1)


def test_exact_runs_report_save_times_between_samples_and_monte_carlo_the_samples(g1):
    """h = 0.3, T = 2, a save every 0.5: exact moments alone at 0.5, 1, 1.5 (between
    samples, the held input there) and T; with Monte Carlo the nearest samples."""
    kw = dict(T=2.0, initial=X0_LIN, noise=NOISE, digital={"period": 0.3}, save_every=0.5)
    exact = simulate(g1, THETA, method="exact", **kw)
    both = simulate(g1, THETA, method="both", paths=20, **kw)
    assert exact.save_times.tolist() == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert both.save_times.tolist() == pytest.approx([0.0, 0.6, 0.9, 1.5, 2.0])
    des = nd.design(g1, THETA, thresholds=False)
    s, eps0 = mode_system(des, NOISE), X0_LIN - np.tile(THETA, 7)
    want = _dense_at(s, 0.3, 0, eps0, lambda t: 1 / (1 + t), [0.5, 1.0, 1.5, 2.0])
    np.testing.assert_allclose(exact.exact.ms_error[1:].sum(axis=1), want, rtol=1e-11)
    assert both.exact.ms_error[-1].sum() == pytest.approx(want[-1], rel=1e-12)
