"""Tests of :mod:`ntc_design.simulate.implicit`."""

import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, implicit, simulate
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.implicit import ImplicitSolver, SolverCache, ch_key
from ntc_design.simulate.moments import PreparedModes, em_moments, exact_moments
from ntc_design.simulate.system import mode_system
from tests.support.kernel import stiff_network


def _reference(lap, ch, b):
    a = (sp.identity(lap.shape[0]) + ch * lap).tocsc()
    return np.column_stack([spsolve(a, b[:, k]) for k in range(b.shape[1])])


@pytest.mark.parametrize("ch", [1e-3, 1e-2, 3e-2])
def test_jacobi_matches_a_direct_solve_to_its_a_priori_bound(implicit_net, ch):
    _, s = implicit_net
    b = np.random.default_rng(np.random.SeedSequence(7)).normal(size=(s.nd, 3))
    sol = ImplicitSolver(s.lap_b, ch, 3, method="jacobi")
    exact = _reference(s.lap_b, ch, b)
    # q = ‖D⁻¹O‖_∞ recomputed densely from the blocks
    a = np.eye(s.nd) + ch * s.lap_b.toarray()
    dblk = np.zeros_like(a)
    for i in range(0, s.nd, 3):
        dblk[i : i + 3, i : i + 3] = a[i : i + 3, i : i + 3]
    q = np.max(np.abs(np.linalg.solve(dblk, a - dblk)).sum(axis=1))
    assert sol.q == pytest.approx(q, rel=1e-10) and 0 < q < 1
    assert sol.sweeps == math.ceil(math.log(implicit.IMPLICIT_RTOL) / math.log(q)) - 1
    got = sol.solve(b)
    err = np.max(np.abs(got - exact), axis=0) / np.max(np.abs(exact), axis=0)
    assert np.all(err <= 10 * implicit.IMPLICIT_RTOL)  # the bound, plus rounding
    assert np.allclose(sol.solve(b[:, 0]), got[:, 0], rtol=0, atol=1e-14 * np.abs(got).max())


def test_gmres_solves_where_jacobi_would_not_contract(implicit_net):
    _, s = implicit_net
    ch = 20.0  # c h ρ(L_B) in the thousands: q > 1
    b = np.random.default_rng(np.random.SeedSequence(8)).normal(size=(s.nd, 2))
    sol = ImplicitSolver(s.lap_b, ch, 3, method="gmres")
    assert sol.q > 1 and sol.method == "gmres"
    got = sol.solve(b)
    a = sp.identity(s.nd) + ch * s.lap_b
    res = np.linalg.norm(a @ got - b, axis=0) / np.linalg.norm(b, axis=0)
    assert np.all(res <= implicit.GMRES_RTOL * 1.01)
    np.testing.assert_allclose(got, _reference(s.lap_b, ch, b), rtol=1e-7, atol=1e-9)
    with pytest.raises(nd.InputError, match=r"block Jacobi needs ‖D⁻¹O‖_∞ < 1, got"):
        ImplicitSolver(s.lap_b, ch, 3, method="jacobi")
    with pytest.raises(nd.InputError, match="implicit solver: must be one of"):
        ImplicitSolver(s.lap_b, ch, 3, method="cg")


def test_gmres_that_cannot_converge_is_refused_in_one_line(monkeypatch, implicit_net):
    _, s = implicit_net
    monkeypatch.setattr(implicit, "GMRES_MAX_RESTARTS", 1)
    monkeypatch.setattr(implicit, "GMRES_RESTART", 2)
    sol = ImplicitSolver(s.lap_b, 50.0, 3, method="gmres")
    with pytest.raises(nd.InputError, match=r"GMRES did not solve .* use a smaller ds") as e:
        sol.solve(np.ones(s.nd))
    assert "\n" not in str(e.value)


def test_auto_picks_lu_small_jacobi_large(monkeypatch, implicit_net):
    _, s = implicit_net
    assert ImplicitSolver(s.lap_b, 0.01, 3).method == "lu"
    monkeypatch.setattr(implicit, "IMPLICIT_LU_MAX_ND", 10)
    assert ImplicitSolver(s.lap_b, 0.01, 3).method == "jacobi"
    assert ImplicitSolver(s.lap_b, 20.0, 3).method == "gmres"


def test_steps_differing_by_rounding_share_one_solver(implicit_net):
    _, s = implicit_net
    cache = SolverCache(s.lap_b, 3)
    ch = 0.1 / 3
    near = ch * (1 + 4e-16)
    assert near != ch and ch_key(near) == ch_key(ch)
    assert cache(ch) is cache(near) and cache(2 * ch) is not cache(ch)
    assert cache(ch).ch == ch_key(ch) and abs(ch_key(ch) / ch - 1) <= 5e-12


def test_monte_carlo_by_jacobi_equals_the_lu(monkeypatch):
    """The same implicit run with the LU and with block Jacobi: equal to the solver's
    accuracy, and bit-identical on one or two workers (the sweep count is fixed in
    advance, not by a residual over the block)."""
    top = nd.random_network(200, 3, seed=9)
    kw = dict(
        T=0.2, ds=0.01, stepping="intrinsic", scheme="implicit", paths=6, seed=3,
        method="mc", save_every=0.1, block_size=2, noise=NoiseModel(sigma=0.4, f=0.3),
    )  # fmt: skip
    lu = simulate(top, THETA, workers=1, **kw)
    monkeypatch.setattr(implicit, "IMPLICIT_LU_MAX_ND", 10)
    jac = simulate(top, THETA, workers=1, **kw)
    jac2 = simulate(top, THETA, workers=2, **kw)
    np.testing.assert_allclose(jac.mc.mean, lu.mc.mean, rtol=1e-9)
    assert np.array_equal(jac.mc.mean, jac2.mc.mean)


def test_solver_cache_keeps_the_most_recent_few(implicit_net):
    """A decaying gain under h_max gives a new c·h at every capped step: the cache keeps
    the CACHE_SOLVERS most recent, so memory does not grow with the horizon."""
    _, s = implicit_net
    cache = SolverCache(s.lap_b, 3)
    made = [cache(1e-3 * (k + 1)) for k in range(implicit.CACHE_SOLVERS + 2)]
    assert len(cache._by_ch) == implicit.CACHE_SOLVERS
    assert cache(made[-1].ch) is made[-1]  # recent: kept
    assert cache(made[0].ch) is not made[0]  # oldest: rebuilt
    assert cache(made[0].ch).ch == made[0].ch


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
        return em_moments(PreparedModes.of(systems, eps0), grid, gain, scheme="implicit")

    em = recursion(0.02)
    mc, half = res.mc.mean[1:], np.maximum(res.mc.hi - res.mc.mean, 1e-12)[1:]
    z = np.abs(mc - em.ms_error[1:]) / half * 1.96
    assert np.median(z) < 1.2 and np.max(z) < 6.0
    ex = exact_moments(PreparedModes.of(systems, eps0, [(0.0, t_end, 0)]), gain, saves)

    def gaps(m):
        mean = np.max(np.abs(m.mean[1:] - ex.mean[1:])) / np.max(np.abs(ex.mean[1:]))
        tot = np.max(np.abs(m.ms_error[1:].sum(1) / ex.ms_error[1:].sum(1) - 1))
        return mean, tot

    (m1, t1), (m2, _) = gaps(em), gaps(recursion(0.01))
    (_, t3), (_, t4) = gaps(recursion(4e-4)), gaps(recursion(2e-4))
    assert 1.7 < m1 / m2 < 2.3 and m1 < 0.2
    assert 1.7 < t3 / t4 < 2.3 and t4 < 0.05
    assert 0.05 < t1 < 0.5  # the stiff-mode damping at ds·ρ >> 1: visible, bounded
