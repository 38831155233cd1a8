"""The drift-implicit step's solve (I + c h L_B) y = b at any size (issue 20): block
Jacobi with an a-priori sweep count, GMRES, the LU, and the guard's dominance floor,
against direct solves and dense eigenvalues."""

import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import ntc_design as nd
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.simulate import NoiseModel, implicit, simulate
from ntc_design.simulate import system as sysmod
from ntc_design.simulate.implicit import ImplicitSolver, SolverCache, ch_key
from ntc_design.simulate.system import mode_system


@pytest.fixture(scope="module")
def implicit_net():
    top = nd.random_network(400, 3, seed=5)
    des = nd.design(top, THETA, thresholds=False)
    return des, mode_system(des, NoiseModel(sigma=0.4, f=0.3))


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


def test_guard_floor_by_dominance_is_below_every_real_part(implicit_net):
    """Re λ >= min_i (M v)_i / v_i, against every eigenvalue, without ARPACK."""
    _, s = implicit_net
    assert s.nd > sysmod.DENSE_EIG_MAX_ND
    floor, how = s.implicit_floor
    lam = np.linalg.eigvals(s.lap_b.toarray())
    assert "dominance" in how and 0 < floor <= lam.real.min()
    assert "spectrum" not in s.__dict__  # the eigenvalues were not needed


def test_guard_falls_back_to_eigenvalues_when_dominance_fails(monkeypatch, implicit_net):
    des, _ = implicit_net
    monkeypatch.setattr(sysmod, "_dominance_floor", lambda s: -np.inf)
    s = mode_system(des, NoiseModel())
    floor, how = s.implicit_floor
    assert "ARPACK" in how and floor == s.min_real > 0


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


def test_a_floor_within_rounding_of_zero_is_not_trusted(monkeypatch, implicit_net):
    """The dominance floor must clear FLOOR_RTOL·max|μ_i|; below it the eigenvalues decide."""
    des, s0 = implicit_net
    floor, _ = s0.implicit_floor
    blocks = implicit.diagonal_blocks(s0.lap_b, 3)
    mu_max = np.max(np.abs(np.linalg.eigvalsh(0.5 * (blocks + blocks.transpose(0, 2, 1)))[:, 0]))
    monkeypatch.setattr(sysmod, "FLOOR_RTOL", 1.01 * floor / mu_max)
    s = mode_system(des, NoiseModel())
    got, how = s.implicit_floor
    assert "ARPACK" in how and got == s.min_real
