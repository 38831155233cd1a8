"""The edge-list Monte Carlo kernel, the drift-implicit scheme, the step-size guard at
every size and the sparse moment equations."""

import os
import subprocess
import sys

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.linalg import numba_cache_dir
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.simulate import NoiseModel, kernels, moments, montecarlo, simulate, system
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.kernels import em_steps, kernel_arrays, numpy_step, tile_width
from ntc_design.simulate.moments import em_moments, exact_moments
from ntc_design.simulate.montecarlo import MonteCarloSpec, run, run_chunk
from ntc_design.simulate.system import grounded_laplacian_sparse, mode_system

from .conftest import X0, random_topology


def stiff_network(n: int, seed: int, d: int = 3) -> nd.Topology:
    """A ring of antagonistic edges plus 10% random edges, PD weights of log-normal
    scale: Assumption 2 holds (every agent has a PD antagonistic in-weight) and the
    Lemma 1 δ is large, so L_B is stiff."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    pairs = [(i, (i + 1) % n) for i in range(n)]
    seen = set(pairs)
    while len(pairs) < n + n // 10:
        a, b = (int(v) for v in rng.integers(0, n, 2))
        if a != b and (a, b) not in seen:
            seen.add((a, b))
            pairs.append((a, b))
    edges = []
    for a, b in pairs:
        q = rng.normal(size=(d, d))
        w = (q @ q.T / d + 0.2 * np.eye(d)) * np.exp(rng.normal())
        neg = b == (a + 1) % n or rng.random() < 0.5
        edges.append((a + 1, b + 1, -w if neg else w))
    return nd.Topology.from_edges(n, d, edges)


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


@pytest.fixture(scope="module")
def g1_system(g1):
    des = nd.design(g1, THETA, thresholds=False)
    return des, mode_system(des, NoiseModel())


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


def _kernel_spec(system_, paths, block=500, scheme="explicit", t_end=0.3, grid=None):
    grid = grid or build_grid(t_end, 1e-3, np.arange(0, t_end + 1e-9, 0.1))
    gain = lambda t: 1.0 / (1.0 + t)  # noqa: E731
    return MonteCarloSpec(
        systems=(system_,), grid=grid, gain=gain, theta=np.array(THETA, float), x_init=X0,
        n_agents=7, dim=3, paths=paths, seed=11, block_size=block, store_paths=5, scheme=scheme,
    )  # fmt: skip


def test_few_paths_still_make_two_blocks(g1_system):
    _, s = g1_system
    for paths, blocks in ((1, 1), (2, 2), (30, 2), (200, 2), (1000, 2), (1001, 3), (2000, 4)):
        assert _kernel_spec(s, paths).n_blocks == blocks
    spec = _kernel_spec(s, 30)
    a, b = run(spec, workers=1), run(spec, workers=2)
    assert a.count == 30 and np.array_equal(a.sq, b.sq) and np.array_equal(a.stored, b.stored)


def test_batch_and_tile_sizes_do_not_change_results(g1_system, monkeypatch):
    _, s = g1_system
    spec = _kernel_spec(s, 40)
    ref = run_chunk(spec, [0, 1])
    monkeypatch.setattr(montecarlo, "XI_BYTES", 8 * 20 * 16 * 3)  # 3 steps per batch
    monkeypatch.setattr(kernels, "TILE_MIN", 3)  # tiles of 3 paths (and a last one of 2)
    monkeypatch.setattr(kernels, "TILE_MAX", 3)
    assert tile_width(20, 21) == 3
    other = run_chunk(spec, [0, 1])
    for q, r in zip(ref, other, strict=True):
        assert np.array_equal(q.sq, r.sq) and np.array_equal(q.state, r.state)


def test_sparse_assembly_equals_the_dense_grounded_laplacian(g1, monkeypatch):
    monkeypatch.setattr(system, "DENSE_LB_MAX_ND", 0)  # force the edge-list assembly
    for top in (g1, random_topology(3, n=9, d=2), stiff_network(15, 1)):
        des = nd.design(top, THETA[: top.dim], thresholds=False)
        dense = des.grounded_laplacian()
        sparse = grounded_laplacian_sparse(des)
        np.testing.assert_allclose(
            sparse.toarray(), dense, rtol=0, atol=1e-13 * np.abs(dense).max()
        )


def test_arpack_bounds_match_all_eigenvalues(monkeypatch):
    top = stiff_network(80, 2)
    des = nd.design(top, THETA, thresholds=False)
    dense = mode_system(des, NoiseModel())
    assert dense.eig_method == "all eigenvalues"
    monkeypatch.setattr(system, "DENSE_EIG_MAX_ND", 10)
    arp = mode_system(des, NoiseModel())
    assert arp.eig_method.startswith("ARPACK")
    assert arp.spectral_radius == pytest.approx(dense.spectral_radius, rel=1e-6)
    assert arp.stability_bound == pytest.approx(dense.stability_bound, rel=1e-6)
    assert arp.min_real == pytest.approx(dense.min_real, rel=1e-6)


def test_mean_square_limit_matches_the_exact_second_moment_recursion(g1_system):
    """The guard's estimate of the largest mean-square-stable step at c = 1 against the
    spectral radius of S -> A S Aᵀ + h Σ_e G_e S G_eᵀ (A = I − h L_B) on G1."""
    _, s = g1_system
    grid = build_grid(0.2, 0.2, [0, 0.2])
    with pytest.raises(nd.InputError, match=r"mean-square limit") as exc:
        system.check_step_size([s], grid, np.ones(1))
    h_guard = float(str(exc.value).split("use dt < ")[1].split(",")[0])
    lap, n = s.lap_b.toarray(), 21
    nmat = np.zeros((n * n, n * n))
    for i, j, k in s.h_blocks:
        h = np.zeros((n, n))
        h[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += k
        h[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] -= k
        nmat += np.kron(h, h)

    def radius(tau):
        a = np.eye(n) - tau * lap
        return np.max(np.abs(np.linalg.eigvals(np.kron(a, a) + tau * nmat)))

    assert radius(0.97 * h_guard) < 1.0 < radius(1.03 * h_guard)
    assert h_guard < 0.9 * s.stability_bound  # the noise, not the drift, sets it


def test_stiff_network_is_refused_up_front_and_runs_implicitly():
    """N = 1000 with a large δ: dt = 1e-4 is far above 2/ρ(L_B); the guard refuses it
    before running, naming the largest stable step and the implicit scheme, which then
    runs at a step 10× larger still."""
    top = stiff_network(1000, 0)
    des = nd.design(top, THETA, thresholds=False)
    assert des.assumption_holds and des.delta > 100
    with pytest.raises(nd.InputError, match=r"unstable.*use dt < .*scheme: implicit") as exc:
        simulate(top, THETA, T=0.01, dt=1e-4, paths=4, method="mc", save_every=0.01)
    msg = str(exc.value)
    h_ok = float(msg.split("use dt < ")[1].split(",")[0])
    rho = float(msg.split("ρ(L_B) = ")[1].split(",")[0])
    assert "ARPACK" in msg
    s = mode_system(des, NoiseModel())
    assert rho == pytest.approx(s.spectral_radius, rel=1e-3)  # printed to 4 digits
    assert 0.8 * 2 / rho < h_ok <= 1.0001 * s.stability_bound  # about 2/ρ, no more
    res = simulate(
        top, THETA, T=0.05, ds=1e-3, stepping="intrinsic", scheme="implicit", paths=4,
        method="mc", save_every=0.05, workers=1, initial=np.tile([1.0, 0.0, 0.0], 1000),
    )  # fmt: skip
    assert res.stats.steps >= 40 and np.all(np.isfinite(res.mc.mean))
    assert res.mc.mean[-1].sum() < 0.7 * res.mc.mean[0].sum()


def test_implicit_needs_intrinsic_stepping(g1):
    with pytest.raises(nd.InputError, match=r"scheme: implicit needs stepping: intrinsic"):
        simulate(g1, THETA, T=0.1, paths=4, scheme="implicit")
    with pytest.raises(nd.InputError, match=r"scheme: must be explicit or implicit"):
        simulate(g1, THETA, T=0.1, paths=4, scheme="magic")


def test_implicit_monte_carlo_matches_its_exact_recursion():
    """Stiff network (ρ(L_B) ≈ 1.2e3): the explicit step limit is 1.7e-3; the implicit
    scheme at ds = 0.02 (ds·ρ ≈ 24) matches the exact moments of its own recursion
    (sharp). Against the continuous moments its bias is first order: in the mean even at
    ds·ρ >> 1, in the mean-square error once ds·ρ < 1 (at ds·ρ >> 1 it damps the
    variance of the stiff modes)."""
    top = stiff_network(12, 2)
    x0 = np.random.default_rng(3).uniform(-2, 2, size=36)
    t_end, saves = 0.5, np.arange(0, 0.51, 0.05)
    kw = dict(T=t_end, initial=x0, save_times=saves, stepping="intrinsic", gain="1")
    with pytest.raises(nd.InputError, match="unstable"):
        simulate(top, THETA, ds=0.02, paths=4, method="mc", **kw)
    res = simulate(top, THETA, ds=0.02, scheme="implicit", paths=3000, seed=2, method="mc", **kw)
    systems = [mode_system(res.designs[k], NoiseModel()) for k in res.designs]
    eps0 = x0 - np.tile(THETA, 12)
    gain = lambda t: np.ones_like(np.asarray(t, dtype=float))  # noqa: E731

    def recursion(ds):
        grid = build_grid(t_end, ds, saves, gain=gain, intrinsic_ds=ds, h_max=1.0)
        return em_moments(systems, grid, gain, eps0, 12, 3, scheme="implicit")

    em = recursion(0.02)
    mc, half = res.mc.mean[1:], np.maximum(res.mc.hi - res.mc.mean, 1e-12)[1:]
    z = np.abs(mc - em.ms_error[1:]) / half * 1.96
    assert np.median(z) < 1.2 and np.max(z) < 6.0
    ex = exact_moments(systems, [(0.0, t_end, 0)], gain, eps0, saves, 12, 3)

    def gaps(m):
        mean = np.max(np.abs(m.mean[1:] - ex.mean[1:])) / np.max(np.abs(ex.mean[1:]))
        tot = np.max(np.abs(m.ms_error[1:].sum(1) / ex.ms_error[1:].sum(1) - 1))
        return mean, tot

    (m1, t1), (m2, _) = gaps(em), gaps(recursion(0.01))
    (_, t3), (_, t4) = gaps(recursion(4e-4)), gaps(recursion(2e-4))
    assert 1.7 < m1 / m2 < 2.3 and m1 < 0.2
    assert 1.7 < t3 / t4 < 2.3 and t4 < 0.05
    assert 0.05 < t1 < 0.5  # the stiff-mode damping at ds·ρ >> 1: visible, bounded


def test_implicit_recursion_moments_match_a_dense_reference(g1_system):
    """em_moments(implicit) against R (S + h(GGᵀ + Σ G_e S G_eᵀ)) Rᵀ written densely."""
    des, s = g1_system
    grid = build_grid(0.5, 0.05, [0, 0.25, 0.5])
    eps0 = X0 - np.tile(THETA, 7)
    got = em_moments([s], grid, lambda t: 1 / (1 + t), eps0, 7, 3, scheme="implicit")
    lap, g = s.lap_b.toarray(), s.g.toarray()
    m, sm = eps0.copy(), np.outer(eps0, eps0)
    for k in range(grid.n_steps):
        c, h = 1 / (1 + grid.t[k]), grid.h[k]
        r = np.linalg.inv(np.eye(21) + c * h * lap)
        noise = g @ g.T
        for i, j, kk in s.h_blocks:
            gm = np.zeros((21, 21))
            gm[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += kk
            gm[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] -= kk
            noise += gm @ sm @ gm.T
        sm = r @ (sm + c * c * h * noise) @ r.T
        m = r @ m
    np.testing.assert_allclose(got.second, sm, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got.mean[-1], m, rtol=1e-10, atol=1e-12)


def test_sparse_moments_equal_dense_moments(g1, monkeypatch):
    """Moments on the edge-assembled sparse L_B equal those on the design's dense L_B."""
    des = nd.design(g1, THETA, thresholds=False)
    segs = [(0.0, 2.0, 0)]
    eps0 = X0 - np.tile(THETA, 7)
    gain = lambda t: 1 / (1 + t)  # noqa: E731
    a = exact_moments([mode_system(des, NoiseModel())], segs, gain, eps0, [0, 1, 2], 7, 3)
    monkeypatch.setattr(system, "DENSE_LB_MAX_ND", 0)
    b = exact_moments([mode_system(des, NoiseModel())], segs, gain, eps0, [0, 1, 2], 7, 3)
    np.testing.assert_allclose(a.ms_error, b.ms_error, rtol=1e-12)
    np.testing.assert_allclose(a.second, b.second, rtol=1e-10, atol=1e-14)


def test_moments_above_the_limit_are_refused_before_running(g1, monkeypatch):
    monkeypatch.setattr(moments, "MOMENTS_MAX_ND", 20)
    with pytest.raises(nd.InputError, match=r"exact moments at Nd = 21 need about .* GB"):
        simulate(g1, THETA, T=0.1, paths=4, method="both")


@pytest.mark.slow  # a fresh interpreter compiles the kernels into an empty cache (~6 s)
def test_numba_caches_in_the_users_cache_folder_not_beside_the_sources(tmp_path):
    # a cache beside installed sources outlives `pip uninstall` and turns the left-over
    # folder into a namespace package that shadows a later editable install
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    code = (
        "import ntc_design as nd; from ntc_design.simulate import simulate; "
        "simulate(nd.load('examples/g1.yaml'), [1, 2, -1], T=0.01, paths=2, method='mc', workers=1)"
    )
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    r = subprocess.run(
        [sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr[-2000:]
    cached = list((tmp_path / "cache" / "ntc-design" / "numba").rglob("*.nbi"))
    assert any("em_steps" in p.name for p in cached), cached


def test_numba_cache_folder_that_cannot_be_created_is_not_used(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder", encoding="utf-8")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    assert numba_cache_dir() is None
    assert "NUMBA_CACHE_DIR" not in os.environ
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "ok"))
    assert numba_cache_dir() == str(tmp_path / "ok" / "ntc-design" / "numba")
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "ok" / "ntc-design" / "numba")
