"""Tests of :mod:`ntc_design.simulate.loss_kernels`: the stream order of the arrivals
(against a written-out xoshiro256** and :func:`.kernels.fill_normals`), and the compiled
lossy step against a plain loop fed the same draws, for every policy and delay."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.kernels import fill_normals
from ntc_design.simulate.loss_kernels import POLICY_CODES, TO_UNIT, draw_arrivals, loss_steps
from ntc_design.simulate.loss_mc import LossMonteCarloSpec
from ntc_design.simulate.rng import path_states
from ntc_design.simulate.system import mode_system

X0_LIN = np.linspace(-3, 3, 21)
M64 = (1 << 64) - 1


def xoshiro_words(state, count):
    """xoshiro256** written out with Python integers."""
    s = [int(v) for v in state]
    out = []
    for _ in range(count):
        rot = lambda x, k: ((x << k) | (x >> (64 - k))) & M64  # noqa: E731
        out.append((rot((s[1] * 5) & M64, 7) * 9) & M64)
        t = (s[1] << 17) & M64
        s[2] ^= s[0]
        s[3] ^= s[1]
        s[1] ^= s[2]
        s[0] ^= s[3]
        s[2] ^= t
        s[3] = rot(s[3], 45)
    return out


def test_the_uniforms_are_the_streams_next_words():
    states = path_states(9, 0, 3)
    want = [[(w >> 11) * TO_UNIT for w in xoshiro_words(states[q], 10)] for q in range(3)]
    uni = np.empty((2, 3, 5))
    draw_arrivals(states.copy(), np.empty((2, 3, 0)), uni)
    got = uni.transpose(1, 0, 2).reshape(3, 10)
    assert got.tolist() == want


def test_the_arrivals_follow_each_steps_normals():
    states = path_states(4, 1, 70)
    normals, uni = np.empty((3, 70, 6)), np.empty((3, 70, 4))
    draw_arrivals(states.copy(), normals, uni)
    ref = states.copy()
    for k in range(3):
        z = np.empty((1, 70, 6))
        fill_normals(ref, z)
        u = np.empty((1, 70, 4))
        draw_arrivals(ref, np.empty((1, 70, 0)), u)
        assert normals[k].tolist() == z[0].tolist()
        assert uni[k].tolist() == u[0].tolist()


@pytest.fixture(scope="module")
def g1_spec(g1):
    des = nd.design(g1, THETA, thresholds=False)
    return mode_system(des, NoiseModel(0.4, 0.3)), des


def written_out(s, des, top, x0, xi, uni, h, delay, loss, policy):
    """Each path by a plain loop over a shift register of D + 1 states."""
    k_n, p, _ = xi.shape
    d, n, ne = 3, 7, s.n_edges
    q = 1.0 - loss
    ground = np.zeros((n, d, d))
    for i, b in des.B.items():
        ground[i] = des.delta * np.asarray(b)
    u = des.input_vector()
    out = np.empty((p, n * d))
    for path in range(p):
        reg = [x0.copy() for _ in range(delay + 1)]
        held = []
        for i, j in top.edges:
            held.append(
                top.weight(i, j) @ x0[j * d : j * d + d]
                - top.abs_weight(i, j) @ x0[i * d : i * d + d]
            )
        for k in range(k_n):
            c = 1 / (1 + k * h)
            xd = reg[delay]
            dx = c * h * u.copy()
            for i in range(n):
                dx[i * d : i * d + d] -= c * h * ground[i] @ xd[i * d : i * d + d]
            for e, (i, j) in enumerate(top.edges):
                a, ab = top.weight(i, j), top.abs_weight(i, j)
                meas = a @ xd[j * d : j * d + d] - ab @ xd[i * d : i * d + d]
                g = 0.4 * ab @ np.ones(d)
                diff = xd[j * d : j * d + d] - xd[i * d : i * d + d]
                nz = g * xi[k, path, e] + 0.3 * ab @ diff * xi[k, path, ne + e]
                arrived = uni[k, path, e] < q[e]
                if policy == "hold":
                    if arrived:
                        held[e] = meas + nz / np.sqrt(h)
                    dx[i * d : i * d + d] += c * h * held[e]
                elif arrived:
                    term = c * h * meas + c * np.sqrt(h) * nz
                    dx[i * d : i * d + d] += term / q[e] if policy == "rescale" else term
            reg = [reg[0] + dx, *reg[:-1]]
        out[path] = reg[0]
    return out


@pytest.mark.parametrize("policy", ["skip", "rescale", "hold"])
@pytest.mark.parametrize("delay", [0, 2])
def test_the_kernel_is_the_recursion_written_out(g1, g1_spec, policy, delay):
    s, des = g1_spec
    h, k_n, p = 0.1, 12, 5
    grid, _ = digital_grid(Digital(h, delay), h * k_n, np.array([h * k_n]))
    loss = np.linspace(0.05, 0.6, s.n_edges)
    spec = LossMonteCarloSpec(
        s, grid, lambda t: 1 / (1 + t), THETA, X0_LIN, 7, 3, p, 1, loss, policy, delay
    )
    rng = np.random.default_rng(5)
    xi = rng.standard_normal((k_n, p, 2 * s.n_edges))
    uni = rng.random((k_n, p, s.n_edges))
    c = 1 / (1 + np.arange(k_n) * h)
    ch, cs, rh = c * h, c * np.sqrt(h), np.full(k_n, 1 / np.sqrt(h))
    x = np.tile(X0_LIN, (p, delay + 1))
    held = spec.initial_held(p)
    empty = np.zeros((0, 4), np.uint64)
    code = POLICY_CODES[policy]
    # two calls (steps 0..4, then 5..11) continue the ring and the held values
    loss_steps(x, held, empty, xi, uni, 2 * s.n_edges, 0, 5, ch, cs, rh, *spec.kernel_arrays(), code, 2, delay, 0)  # fmt: skip
    loss_steps(x, held, empty, xi, uni, 2 * s.n_edges, 5, k_n, ch, cs, rh, *spec.kernel_arrays(), code, 2, delay, 0)  # fmt: skip
    slot = (k_n % (delay + 1)) * 21
    want = written_out(s, des, g1, X0_LIN, xi, uni, h, delay, loss, policy)
    assert x[:, slot : slot + 21] == pytest.approx(want, rel=1e-11, abs=1e-11)


@pytest.mark.parametrize("policy", ["skip", "hold"])
def test_drawing_in_the_kernel_equals_the_drawn_arrays(g1_spec, policy):
    s, _ = g1_spec
    h, k_n, p = 0.1, 9, 7
    grid, _ = digital_grid(Digital(h, 1), h * k_n, np.array([h * k_n]))
    spec = LossMonteCarloSpec(
        s, grid, lambda t: 1 / (1 + t), THETA, X0_LIN, 7, 3, p, 1, np.full(s.n_edges, 0.3),
        policy, 1,
    )  # fmt: skip
    c = 1 / (1 + np.arange(k_n) * h)
    ch, cs, rh = c * h, c * np.sqrt(h), np.full(k_n, 1 / np.sqrt(h))
    states = path_states(2, 0, p)
    xi, uni = np.empty((k_n, p, 2 * s.n_edges)), np.empty((k_n, p, s.n_edges))
    draw_arrivals(states.copy(), xi, uni)
    code = POLICY_CODES[policy]
    args = (2 * s.n_edges, 0, k_n, ch, cs, rh, *spec.kernel_arrays(), code, 4, 1, 0)
    a, b = np.tile(X0_LIN, (p, 2)), np.tile(X0_LIN, (p, 2))
    loss_steps(a, spec.initial_held(p), states.copy(), xi[:0], uni[:0], *args)
    loss_steps(b, spec.initial_held(p), np.zeros((0, 4), np.uint64), xi, uni, *args)
    assert a.tolist() == b.tolist()
