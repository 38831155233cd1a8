"""Tests of :mod:`ntc_design.simulate.replay`: the toolkit's reference for the exported
agents against an independent scalar loop of the law (bit for bit) and against the
simulator's compiled kernel (to rounding, 1e-12 relative over 1000 steps); on lossy links
(skip, rescale) against a written-out recursion and the lossy Monte Carlo kernel, and flags
other than 0 or 1 refused."""

import math
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.gain.schedule import ScheduleGain, join_tail
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.noise import NoiseModel
from ntc_design.simulate.prepare import make_gain
from ntc_design.simulate.replay import kernel_normals, kernel_replay, replay
from ntc_design.simulate.system import mode_system
from tests.conftest import X0

NOISE = NoiseModel(0.4, 0.3)


@pytest.fixture(scope="module")
def g1_design(g1, theta):
    return nd.design(g1, theta, thresholds=False)


@pytest.fixture(scope="module")
def sw_design(switching_set, theta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return nd.design(switching_set, theta, thresholds=False)


def _schedule():
    t = np.linspace(0.0, 4.0, 41)
    c = 1.5 / (1.0 + t) ** 0.8
    return ScheduleGain(t, c, "linear", join_tail(4.0, float(c[-1])))


def scalar_law(law, x_init, normals, steps):
    """THE AGENT LAW written out as plain loops over floats (the module docstring of
    ntc_design.protocol.agents), independently of the vectorised replay."""
    n, d = law.n, law.dim
    h, lag = law.digital.period, law.digital.delay
    sqrth = math.sqrt(h)
    f = law.noise_f.tolist()
    x = [list(map(float, x_init[i * d : (i + 1) * d])) for i in range(n)]
    ring = [x] * (lag + 1)
    z = iter(np.asarray(normals, dtype=float).tolist())
    modes = law.step_modes(steps)
    for k in range(steps):
        ml = law.modes[int(modes[k])]
        c = law.gain.value(float(k) * h)
        hc = h * c
        zs = [next(z) for _ in range(2 * ml.n_edges)]
        now, xd = ring[k % (lag + 1)], ring[(k + 1) % (lag + 1)]
        nxt = []
        for i in range(n):
            ms = []
            for e in ml.in_edges(i):
                j = int(ml.src[e])
                diff = [xd[j][b] - xd[i][b] for b in range(d)]
                m = []
                for a in range(d):
                    fd = f[a][0] * diff[0]
                    for b in range(1, d):
                        fd += f[a][b] * diff[b]
                    m.append(
                        float(ml.sign[e]) * xd[j][a]
                        - xd[i][a]
                        + (float(ml.sigma[e]) * zs[2 * e] + fd * zs[2 * e + 1]) / sqrth
                    )
                ms.append((e, m))
            out = []
            for a in range(d):
                acc = float(ml.u[i][a])
                if i in ml.informed:
                    for b in range(d):
                        acc -= float(ml.bd[i][a][b]) * xd[i][b]
                for e, m in ms:
                    for b in range(d):
                        acc += float(ml.weight[e][a][b]) * m[b]
                out.append(now[i][a] + hc * acc)
            nxt.append(out)
        ring[(k + 1) % (lag + 1)] = nxt
    return np.array(ring[steps % (lag + 1)]).ravel()


def _normals(law, steps, seed=0, paths=None):
    count = int(law.normals_per_step(steps).sum())
    shape = count if paths is None else (paths, count)
    return np.random.default_rng(seed).standard_normal(shape)


@pytest.mark.parametrize("delay", [0, 2])
@pytest.mark.parametrize("gain", ["1/(1+t)", "schedule"])
def test_replay_is_the_scalar_law_bit_for_bit(g1_design, delay, gain):
    g = _schedule() if gain == "schedule" else gain
    law = agent_law(g1_design, Digital(0.05, delay), g, 0.4, 0.3)
    z = _normals(law, 150, seed=delay)
    assert (replay(law, X0, z, 150) == scalar_law(law, X0, z, 150)).all()


def test_replay_is_the_scalar_law_on_a_switching_schedule(sw_design):
    law = agent_law(sw_design, Digital(0.013, 1), "1/(1+t)", 0.4, 0.3)
    z = _normals(law, 120, seed=3)
    assert set(law.step_modes(120).tolist()) == {0, 1, 2}
    assert (replay(law, X0, z, 120) == scalar_law(law, X0, z, 120)).all()


@pytest.mark.parametrize("delay", [0, 2])
def test_replay_agrees_with_the_compiled_kernel_over_1000_steps(g1_design, delay):
    law = agent_law(g1_design, Digital(0.01, delay), "1/(1+t)", 0.4, 0.3)
    z = _normals(law, 1000, seed=11)
    got = replay(law, X0, z, 1000)
    want = kernel_replay(law, [mode_system(g1_design, NOISE, "G1")], make_gain("1/(1+t)")[0],
                         X0, z, 1000)  # fmt: skip
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))
    assert np.max(np.abs(got - want)) > 0  # two different operation orders, not one code


def test_replay_agrees_with_the_kernel_on_a_switching_schedule_and_a_table(sw_design):
    g = _schedule()
    law = agent_law(sw_design, Digital(0.013, 2), g, 0.4, 0.3)
    systems = [mode_system(sw_design.modes[m], NOISE, m) for m in law.mode_names]
    z = _normals(law, 1000, seed=2, paths=3)
    x0 = np.tile(X0, (3, 1))
    got = replay(law, x0, z, 1000)
    want = kernel_replay(law, systems, g, x0, z, 1000)
    assert got.shape == want.shape == (3, 21)
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))


def test_kernel_normals_are_the_sorted_layout(g1_design):
    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3)
    z = np.arange(2 * 8 * 2, dtype=float)  # two steps of eight edges
    xi = kernel_normals(law, z, 2)
    ml = law.modes[0]
    for e in range(8):
        assert xi[1, 0, ml.sorted_index[e]] == z[16 + 2 * e]
        assert xi[1, 0, 8 + ml.sorted_index[e]] == z[16 + 2 * e + 1]


def test_paths_are_independent_and_recorded(g1_design):
    law = agent_law(g1_design, Digital(0.1, 1), "1/(1+t)", 0.4, 0.3)
    z = _normals(law, 40, paths=4)
    x0 = np.random.default_rng(1).normal(size=(4, 21))
    together = replay(law, x0, z, 40)
    for p in range(4):
        assert (together[p] == replay(law, x0[p], z[p], 40)).all()
    rec = replay(law, x0, z, 40, record=True)
    assert rec.shape == (41, 4, 21)
    assert (rec[0] == x0).all() and (rec[-1] == together).all()
    assert (replay(law, X0, z[0, :0], 0) == X0).all()  # K = 0: x(0)


@pytest.mark.hostile
def test_refusals(g1_design):
    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3)
    with pytest.raises(InputError, match=r"normals: 3 steps need 48 normals per path"):
        replay(law, X0, np.zeros(47), 3)
    with pytest.raises(InputError, match=r"initial: expected N·d = 21 numbers"):
        replay(law, X0[:20], np.zeros(48), 3)
    with pytest.raises(InputError, match=r"steps: expected an integer K >= 0"):
        replay(law, X0, np.zeros(0), -1)
    with pytest.raises(InputError, match=r"normals: expected 1 row"):
        replay(law, X0, np.zeros((2, 48)), 3)
    bad = agent_law(g1_design, Digital(0.1), "1/(t-t)", 0.4, 0.3)
    with pytest.raises(InputError, match=r"gain: c\(t\) = inf is not finite at t = 0.0"):
        replay(bad, X0, np.zeros(48), 3)
    with pytest.raises(InputError, match=r"systems: 2 given for 1 modes"):
        kernel_replay(law, [None, None], make_gain("1")[0], X0, np.zeros(48), 3)


def _lossy_loop(law, x0, z, chi, steps):
    """The lossy law written out edge by edge with dense products (a different order):
    x_{k+1} = x_k + h c_k (u − δB x_{k−D} + Σ_{arrived} W_e m_e(x_{k−D})), the initial
    state held before the start (simulate/loss.py's recursion)."""
    ml = law.modes[0]
    n, d = law.n, law.dim
    h, lag = law.digital.period, law.digital.delay
    x = np.asarray(x0, dtype=float).reshape(n, d).copy()
    past = [x] * (lag + 1)  # x_{k−D} … x_k
    zz = z.reshape(steps, ml.n_edges, 2)
    cc = chi.reshape(steps, ml.n_edges)
    for k in range(steps):
        c = 1.0 / (1.0 + k * h)
        x, now = past[0], past[-1]
        drift = ml.u - np.einsum("iab,ib->ia", ml.bd, x)
        for e in range(ml.n_edges):
            if not cc[k, e]:
                continue
            i, j = int(ml.dst[e]), int(ml.src[e])
            noise = ml.sigma[e] * zz[k, e, 0] + law.noise_f @ (x[j] - x[i]) * zz[k, e, 1]
            m = ml.sign[e] * x[j] - x[i] + noise / math.sqrt(h)
            scale = 1.0 / ml.keep[e] if law.policy == "rescale" else 1.0
            drift[i] += scale * (ml.weight[e] @ m)
        past = [*past[1:], now + h * c * drift]
    return past[-1].ravel()


@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_lossy_law_is_the_written_out_recursion(g1_design, policy, delay):
    from ntc_design.protocol.agents import lossy_law

    law = agent_law(g1_design, Digital(0.05, delay), "1/(1+t)", 0.4, 0.3)
    e = law.modes[0].n_edges
    losses = {
        (int(i), int(j)): 0.1 + 0.05 * (k % 3)
        for k, (i, j) in enumerate(zip(law.modes[0].dst, law.modes[0].src, strict=True))
    }
    lossy = lossy_law(law, losses, policy)
    steps = 300
    z = np.random.default_rng(5).standard_normal(2 * e * steps)
    chi = (np.random.default_rng(6).random(e * steps) < 0.8).astype(int)
    assert 0 < chi.sum() < chi.size
    got = replay(lossy, X0, z, steps, arrivals=chi)
    want = _lossy_loop(lossy, X0, z, chi, steps)
    assert np.allclose(got, want, rtol=1e-12, atol=1e-12 * np.max(np.abs(want)))
    assert np.max(np.abs(got - replay(law, X0, z, steps))) > 1e-3  # the losses matter
    # every message arriving at p = 0: the lossless law, bit for bit
    none = lossy_law(law, {}, policy)
    assert np.array_equal(
        replay(none, X0, z, steps, arrivals=np.ones(e * steps)), replay(law, X0, z, steps)
    )


@pytest.mark.hostile
@pytest.mark.parametrize(
    "flags, needle",
    [
        ("half", "arrivals: an arrival flag is not 0 or 1"),
        ("two", "arrivals: an arrival flag is not 0 or 1"),
        ("nan", "arrivals: an arrival flag is not 0 or 1"),
        ("short", "flags per path"),
        ("none", "give E flags per step"),
    ],
)
def test_arrival_flags_other_than_0_or_1_are_refused(g1_design, flags, needle):
    from ntc_design.protocol.agents import lossy_law

    law = lossy_law(agent_law(g1_design, Digital(0.05), "1/(1+t)", 0.4, 0.3), {}, "skip")
    e, steps = law.modes[0].n_edges, 4
    chi = np.ones(e * steps)
    arr = {
        "half": np.where(np.arange(chi.size) == 3, 0.5, chi),
        "two": chi * 2,
        "nan": chi * np.nan,
        "short": chi[:-1],
        "none": None,
    }[flags]
    with pytest.raises(InputError, match=needle):
        replay(law, X0, np.zeros(2 * e * steps), steps, arrivals=arr)
    with pytest.raises(InputError, match="lossless; it reads no arrival flags"):
        replay(
            agent_law(g1_design, Digital(0.05), "1/(1+t)", 0.4, 0.3),
            X0,
            np.zeros(2 * e * steps),
            steps,
            arrivals=chi,
        )


@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_lossy_law_is_the_monte_carlo_kernels_step(g1_design, policy):
    # the compiled lossy kernel (its own arithmetic order) fed the same normals and
    # arrivals: the law agrees to rounding, so both drop (skip) or rescale the same terms
    from ntc_design.protocol.agents import lossy_law
    from ntc_design.simulate.digital import digital_grid
    from ntc_design.simulate.loss_kernels import POLICY_CODES, loss_steps
    from ntc_design.simulate.loss_mc import LossMonteCarloSpec

    h, steps, paths = 0.05, 200, 3
    law0 = agent_law(g1_design, Digital(h), "1/(1+t)", 0.4, 0.3)
    ml = law0.modes[0]
    e = ml.n_edges
    p_file = np.linspace(0.05, 0.4, e)
    law = lossy_law(
        law0, {(int(i), int(j)): float(p) for i, j, p in zip(ml.dst, ml.src, p_file, strict=True)},
        policy,
    )  # fmt: skip
    p_sorted = np.empty(e)
    p_sorted[ml.sorted_index] = p_file
    rng = np.random.default_rng(11)
    z = rng.standard_normal((paths, 2 * e * steps))
    chi = (rng.random((paths, e * steps)) < 0.7).astype(np.int64)
    want = replay(law, np.tile(X0, (paths, 1)), z, steps, arrivals=chi)
    s = mode_system(g1_design, NOISE)
    grid, _ = digital_grid(Digital(h), h * steps, np.array([h * steps]))
    spec = LossMonteCarloSpec(
        s, grid, lambda t: 1 / (1 + t), g1_design.theta, X0, 7, 3, paths, 1, p_sorted, policy, 0
    )
    xi = kernel_normals(law, z, steps)
    uni = np.empty((steps, paths, e))
    flags = chi.reshape(paths, steps, e).transpose(1, 0, 2)
    uni[:, :, ml.sorted_index] = np.where(flags == 1, 0.0, 1.0 - 1e-12)  # below 1 − p_e or not
    c = 1 / (1 + np.arange(steps) * h)
    ch, cs, rh = c * h, c * np.sqrt(h), np.full(steps, 1 / np.sqrt(h))
    x = np.tile(X0, (paths, 1))
    empty = np.zeros((0, 4), np.uint64)
    loss_steps(x, spec.initial_held(paths), empty, xi, uni, 2 * e, 0, steps, ch, cs, rh,
               *spec.kernel_arrays(), POLICY_CODES[policy], 2, 0, 0)  # fmt: skip
    scale = np.max(np.abs(want))
    assert np.allclose(x, want, rtol=1e-11, atol=1e-11 * scale)
    assert np.max(np.abs(want - replay(law0, np.tile(X0, (paths, 1)), z, steps))) > 1e-3


@pytest.mark.hostile
def test_the_lossless_kernel_replay_refuses_a_lossy_law(g1_design):
    from ntc_design.protocol.agents import lossy_law

    law = lossy_law(agent_law(g1_design, Digital(0.05), "1/(1+t)", 0.4, 0.3), {}, "skip")
    with pytest.raises(InputError, match="^law: kernel_replay runs the lossless kernel"):
        kernel_replay(law, [mode_system(g1_design, NOISE)], make_gain("1/(1+t)"), X0, [], 0)
