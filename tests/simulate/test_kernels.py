"""Tests of :mod:`ntc_design.simulate.kernels`."""

import math

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.kernels import (
    TO_UNIT,
    draw_lanes,
    em_steps,
    kernel_arrays,
    numpy_step,
    ziggurat_slow,
)
from ntc_design.simulate.rng import NormalSource, path_states
from ntc_design.simulate.system import mode_system
from ntc_design.simulate.ziggurat import LAYERS, ZIG_R, ZIG_X
from tests.support.kernel import stiff_network


@pytest.mark.parametrize("d", [1, 2, 3, 4])
def test_the_block_and_general_loops_equal_the_dense_step(d):
    # d = 3 takes the 3×3-block loops, other d the general ones; both against dense algebra
    top = stiff_network(12, seed=d, d=d)
    s = mode_system(nd.design(top, np.arange(1.0, d + 1), thresholds=False), NoiseModel())
    rng = np.random.default_rng(d)
    p, k_n = 19, 15
    x0 = rng.normal(size=(p, s.nd))
    xi = rng.normal(size=(k_n, p, 2 * s.n_edges))
    ch = 1e-4 * (1 + rng.random(k_n))
    ref = x0.copy()
    for k in range(k_n):
        ref = dense_step(ref, xi[k], ch[k], np.sqrt(ch[k]), s)
    args = kernel_arrays(s)
    assert (args[3].size > 1) == (d == 3)  # the block form only for d = 3
    for tile in (1, 7, p):
        x = x0.copy()
        em_steps(x, xi, 0, k_n, ch, np.sqrt(ch), *args, True, tile)
        np.testing.assert_allclose(x, ref, rtol=1e-12, atol=1e-12)


def dense_step(x, xi_k, ch, cs, s, f=None):
    """The earlier dense kernel: x + ch (u − L_B x) + cs (G ξ1 + W (F D x ⊙ ξ2))."""
    ne, d = s.n_edges, s.dim
    diff = (x @ s.dmat.toarray().T).reshape(x.shape[0], ne, d)
    if f is not None:
        diff = f(diff)
    z = (diff * xi_k[:, ne : 2 * ne, None]).reshape(x.shape[0], ne * d)
    noise = xi_k[:, :ne] @ s.g.toarray().T + z @ s.wmat.toarray().T
    return x + ch * (s.u - x @ s.lap_b.toarray().T) + cs * noise


@pytest.mark.parametrize(
    "noise",
    [
        NoiseModel(),
        NoiseModel(0.2, np.array([[0.3, 0.1, 0.0], [0.1, 0.2, 0.0], [0.0, 0.0, 0.1]])),
        NoiseModel(0.4, 0.3, {(2, 1): 0.05}),
    ],
)
def test_compiled_and_sparse_steps_equal_the_dense_kernel(g1, noise):
    des = nd.design(g1, THETA, thresholds=False)
    s = mode_system(des, noise)
    rng = np.random.default_rng(4)
    p, k_n = 37, 25
    x0 = rng.normal(size=(p, 21))
    xi = rng.normal(size=(k_n, p, 2 * s.n_edges))
    ch = 1e-3 * (1 + rng.random(k_n))
    cs = np.sqrt(ch)
    ref = x0.copy()
    for k in range(k_n):
        ref = dense_step(ref, xi[k], ch[k], cs[k], s)
    args = kernel_arrays(s)
    for tile in (1, 8, p):  # the tile of paths changes nothing
        x = x0.copy()
        em_steps(x, xi, 0, k_n, ch, cs, *args, True, tile)
        np.testing.assert_allclose(x, ref, rtol=1e-12, atol=1e-12)
    x = x0.copy()
    for k in range(k_n):
        numpy_step(x, xi[k], ch[k], cs[k], s)
    np.testing.assert_allclose(x, ref, rtol=1e-12, atol=1e-12)


def test_sparse_step_applies_a_callable_f(g1):
    des = nd.design(g1, THETA, thresholds=False)
    f = lambda v: 0.3 * np.tanh(v)  # noqa: E731
    s = mode_system(des, NoiseModel(0.4, f))
    rng = np.random.default_rng(5)
    x = rng.normal(size=(9, 21))
    xi = rng.normal(size=(9, 2 * s.n_edges))
    ref = dense_step(x, xi, 1e-3, 0.03, s, f)
    numpy_step(x, xi, 1e-3, 0.03, s)
    np.testing.assert_allclose(x, ref, rtol=1e-12, atol=1e-12)


def test_fused_kernel_draws_the_array_kernels_numbers(g1, theta):
    from ntc_design.simulate.kernels import em_steps, em_steps_rng
    from ntc_design.simulate.modes import Stepper
    from ntc_design.simulate.noise import NoiseModel
    from ntc_design.simulate.system import mode_system

    s = mode_system(nd.design(g1, theta), NoiseModel(0.4, 0.3), "G1")
    st = Stepper(s, False)
    p, k = 37, 20
    ch, cs = np.full(k, 1e-3), np.full(k, math.sqrt(1e-3))
    x0 = np.random.default_rng(0).uniform(-3, 3, (p, s.nd))
    xa, xb = x0.copy(), x0.copy()
    states = path_states(11, 0, p)
    xi = np.empty((k, p, 2 * s.n_edges))
    NormalSource("xoshiro", 11, 0, p).fill(xi)
    em_steps(xa, xi, 0, k, ch, cs, *st.args, True, 8)
    em_steps_rng(xb, states, 2 * s.n_edges, 0, k, ch, cs, *st.args, True, 16)
    np.testing.assert_array_equal(xa, xb)  # tile widths 8 and 16: the same bits


_CACHE_PROBE = """
import json, sys
import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel
from ntc_design.simulate import kernels
from ntc_design.simulate.system import mode_system
s = mode_system(nd.design(nd.load("examples/g1.yaml"), THETA, thresholds=False), NoiseModel())
args = kernels.kernel_arrays(s)
before = [kernels.kernel_cached(f, s.nd, args) for f in (True, False)]
loaded = len(kernels._em_core.overloads)
if sys.argv[1] == "warm":
    kernels.warm_kernel(True, s.nd, args)
print(json.dumps([before, loaded, kernels.kernel_cached(True, s.nd, args)]))
"""


def _probe(cache, what):
    import json
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    r = subprocess.run(
        [sys.executable, "-c", _CACHE_PROBE, what],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout.splitlines()[-1])


def test_a_cold_cache_is_seen_from_numbas_index_without_compiling(tmp_path):
    # an empty cache folder: neither specialisation is there, and asking compiled nothing
    assert _probe(tmp_path, "ask") == [[False, False], 0, False]
    assert list(tmp_path.rglob("*.nb*")) == []


@pytest.mark.slow  # compiles the fused kernel into an empty cache (~3 s of CPU)
def test_a_compiled_kernel_is_found_in_the_index_by_the_next_process(tmp_path):
    assert _probe(tmp_path, "warm") == [[False, False], 0, True]
    # a new process: the fused kernel is in the index (nothing loaded yet), the array one not
    assert _probe(tmp_path, "ask") == [[True, False], 0, True]


def _xoshiro(s):
    """One xoshiro256** step written out with Python integers: (word, new state)."""
    m64 = (1 << 64) - 1
    rot = lambda x, k: ((x << k) | (x >> (64 - k))) & m64  # noqa: E731
    word = (rot((s[1] * 5) & m64, 7) * 9) & m64
    t = (s[1] << 17) & m64
    s2, s3 = s[2] ^ s[0], s[3] ^ s[1]
    s1 = s[1] ^ s2
    s0 = s[0] ^ s3
    return word, [s0, s1, s2 ^ t, rot(s3, 45)]


def test_draw_lanes_draws_each_lanes_stream_in_order_scaled():
    """The shared lane draw against one stream at a time written out: the ziggurat's fast
    test in Python, its rare tail or wedge by :func:`ziggurat_slow` from the same state;
    rows past ``m`` are left alone and every lane's state ends where its stream is."""
    states = path_states(3, 0, 5)
    st = np.ascontiguousarray(states.T)
    zt, wl, m, c2 = np.full((210, 5), 7.0), np.empty(5, dtype=np.uint64), 200, 2.5
    draw_lanes(st[0], st[1], st[2], st[3], zt, wl, c2, m)
    assert (zt[m:] == 7.0).all()
    slow = 0
    for q in range(5):
        s, want = [int(v) for v in states[q]], []
        while len(want) < m:
            w, s = _xoshiro(s)
            i, u = w & (LAYERS - 1), 2.0 * ((w >> 11) * TO_UNIT) - 1.0
            if abs(u) < ZIG_R[i]:
                want.append(c2 * (u * ZIG_X[i]))
                continue
            slow += 1
            z, *s = ziggurat_slow(np.int64(i), u, *(np.uint64(v) for v in s))
            s = [int(v) for v in s]
            want.append(c2 * z)
        assert zt[:m, q].tolist() == want
        assert [int(v) for v in st[:, q]] == s
    assert slow > 0  # the tail or wedge ran
