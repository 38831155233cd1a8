"""Tests of :mod:`ntc_design.simulate.replay`: the toolkit's reference for the exported
agents against an independent scalar loop of the law (bit for bit) and against the
simulator's compiled kernel (to rounding, 1e-12 relative over 1000 steps)."""

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
