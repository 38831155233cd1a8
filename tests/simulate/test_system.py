"""Tests of :mod:`ntc_design.simulate.system`."""

import numpy as np
import pytest
import scipy.sparse as sp

import ntc_design as nd
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.protocol import design
from ntc_design.simulate import NoiseModel, implicit, simulate, system
from ntc_design.simulate import system as sysmod
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.system import (
    DENSE_EIG_MAX_ND,
    _eig_bounds,
    grounded_laplacian_sparse,
    mode_system,
)
from tests.cli_helpers import assert_input_error
from tests.conftest import random_topology
from tests.support.kernel import stiff_network
from tests.support.simulate import write_scenario


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
    monkeypatch.setattr(sysmod, "DENSE_EIG_MAX_ND", 100)  # its largest component: 147 rows
    s = mode_system(des, NoiseModel())
    floor, how = s.implicit_floor
    assert "ARPACK" in how and floor == s.min_real > 0


def test_a_floor_within_rounding_of_zero_is_not_trusted(monkeypatch, implicit_net):
    """The dominance floor must clear FLOOR_RTOL·max|μ_i|; below it the eigenvalues decide."""
    des, s0 = implicit_net
    floor, _ = s0.implicit_floor
    blocks = implicit.diagonal_blocks(s0.lap_b, 3)
    mu_max = np.max(np.abs(np.linalg.eigvalsh(0.5 * (blocks + blocks.transpose(0, 2, 1)))[:, 0]))
    monkeypatch.setattr(sysmod, "FLOOR_RTOL", 1.01 * floor / mu_max)
    monkeypatch.setattr(sysmod, "DENSE_EIG_MAX_ND", 100)  # its largest component: 147 rows
    s = mode_system(des, NoiseModel())
    got, how = s.implicit_floor
    assert "ARPACK" in how and got == s.min_real


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


def test_guard_arpack_matches_dense_eigenvalues(monkeypatch):
    top = random_network(300, 3, seed=4)  # Nd = 900; strongly connected parts of <= 72 rows
    lap = design(top, [1, 2, -1], thresholds=False).grounded_laplacian_sparse()
    assert lap.shape[0] > DENSE_EIG_MAX_ND
    monkeypatch.setattr(sysmod, "DENSE_EIG_MAX_ND", 50)  # ARPACK on the 72-row part
    spec = _eig_bounds(sp.csr_matrix(lap))
    rho, bound, min_re, method = spec.rho, spec.bound, spec.min_real, spec.method
    lam = np.linalg.eigvals(lap.toarray())
    assert "ARPACK" in method
    assert rho == np.float64(rho) and abs(rho - np.max(np.abs(lam))) <= 1e-6 * rho
    assert abs(min_re - np.min(lam.real)) <= 1e-2 * abs(np.min(lam.real))
    exact = np.min(2 * lam.real / np.abs(lam) ** 2)
    assert abs(bound - exact) <= 1e-2 * exact


def test_step_size_guard(g1):
    with pytest.raises(nd.InputError, match=r"dt: Euler–Maruyama is unstable.*use dt <"):
        simulate(g1, THETA, T=1.0, dt=0.3, paths=10, save_every=1.0)
    # G1's drift bound 2·Re λ/|λ|² is 0.137 (λ = 14.58), but in mean square h = 0.1 is
    # unstable (the second moment of the recursion grows 1.8× per step):
    # the multiplicative-noise limit of agent 5 (0.057) refuses it; h = 0.04 is close
    with pytest.raises(nd.InputError, match=r"mean-square limit .* of agent 5.*use dt < 0.057"):
        simulate(g1, THETA, T=0.5, dt=0.1, paths=10, method="mc", save_every=0.5)
    with pytest.warns(UserWarning, match="within a factor"):
        simulate(g1, THETA, T=0.5, dt=0.04, paths=10, method="mc", save_every=0.5)


def test_cli_divergence_exits_1_and_keeps_partial_results(tmp_path, capsys, monkeypatch):
    # (1+t)^3 grows: the drift becomes unstable late in the run; the guard catches it
    # (Monte Carlo only: with the exact moments too, their step estimate refuses it first)
    sc = write_scenario(tmp_path, gain="50*(1+t)^3", T=1.0, method="mc")
    assert_input_error(["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch, "unstable")
    assert not (tmp_path / "o").exists()


# -- issue 41, item 8: the step guard's eigenvalues linear in the edges ----------------------


def chain_csv(path, n: int, d: int = 1):
    """A directed chain 2 -> 3 -> … -> n with the pair 1 <-> 2 of G1 in front (agent 1
    informed through its antagonistic in-edge): strongly connected parts of 1 and 2 agents."""
    eye = ",".join("1.0" if i == j else "0.0" for i in range(d) for j in range(d))
    neg = ",".join("-1.0" if i == j else "0.0" for i in range(d) for j in range(d))
    cols = ",".join(f"a{i}{j}" for i in range(1, d + 1) for j in range(1, d + 1))
    rows = [f"from,to,{cols}", f"2,1,{eye}", f"1,2,{neg}"]
    rows += [f"{i},{i + 1},{eye}" for i in range(2, n)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def test_component_eigenvalues_are_every_eigenvalue(monkeypatch):
    """Block triangular by strongly connected components: the union of the diagonal
    blocks' eigenvalues is the spectrum (against numpy on the whole matrix)."""
    top = random_network(300, 3, seed=4)
    lap = sp.csr_matrix(design(top, [1, 2, -1], thresholds=False).grounded_laplacian_sparse())
    full = np.sort_complex(np.linalg.eigvals(lap.toarray()))
    small, rest = sysmod.component_eigenvalues(lap)
    assert rest is None and small.size == lap.shape[0]
    got = np.sort_complex(small)
    np.testing.assert_allclose(got.real, full.real, atol=1e-8 * np.abs(full).max())
    np.testing.assert_allclose(np.abs(got), np.abs(full), atol=1e-8 * np.abs(full).max())
    monkeypatch.setattr(sysmod, "DENSE_EIG_MAX_ND", 50)  # the 72-row part is left over
    small, rest = sysmod.component_eigenvalues(lap)
    assert rest is not None and rest.shape[0] == 72 and small.size == lap.shape[0] - 72
    lam_rest = np.linalg.eigvals(rest.toarray())
    both = np.sort_complex(np.concatenate([small, lam_rest]))
    np.testing.assert_allclose(both.real, full.real, atol=1e-8 * np.abs(full).max())


def test_a_directed_chain_takes_no_arpack_and_blocks_of_its_own_size(tmp_path, monkeypatch):
    """The work counted: a 3,000-agent chain (Nd = 9,000 > DENSE_EIG_MAX_ND) gives its exact
    spectrum without ARPACK (which needed thousands of restarts on such a Jordan-like
    matrix: 400 s did not finish at N = 10⁵). Its diagonal weights decouple the three
    coordinates: 8,994 components of one row (read off the diagonal) and three of two rows
    (the 1 <-> 2 pair), which are the only matrices handed to eigvals, in one batch."""
    import scipy.sparse.linalg as spla

    def no_arpack(*a, **k):
        raise AssertionError("ARPACK called on a chain")

    sizes: list[tuple[int, ...]] = []
    real_eigvals = np.linalg.eigvals

    def counted(a):
        sizes.append(np.shape(a))
        return real_eigvals(a)

    monkeypatch.setattr(spla, "eigs", no_arpack)
    monkeypatch.setattr(np.linalg, "eigvals", counted)
    top = nd.load(chain_csv(tmp_path / "chain.csv", 3000, 3))
    des = nd.design(top, THETA, thresholds=False)
    s = mode_system(des, NoiseModel())
    assert s.nd == 9000 and "strongly connected" in s.eig_method
    assert sizes == [(3, 2, 2)]
    dense = np.linalg.eigvals(s.lap_b.toarray()[:12, :12])  # the 1 <-> 2 pair and agent 3
    assert s.spectral_radius == pytest.approx(
        max(np.abs(dense).max(), np.abs(s.lap_b.diagonal()).max())
    )
    assert s.min_real == pytest.approx(min(dense.real.min(), s.lap_b.diagonal()[12:].min()))


def test_cli_simulates_a_chain_without_arpack(tmp_path, capsys, monkeypatch):
    """ntc simulate of a chain CSV end to end (2 paths × 10 steps), no ARPACK call."""
    import scipy.sparse.linalg as spla

    from tests.cli_helpers import run_cli

    monkeypatch.setattr(spla, "eigs", lambda *a, **k: pytest.fail("ARPACK called on a chain"))
    chain_csv(tmp_path / "chain.csv", 2000)
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        "topology: chain.csv\ntheta: [1]\nnoise: {sigma: 0.4, f: 0.3}\nT: 0.01\ndt: 0.001\n"
        "paths: 2\nsave_every: 0.005\nmethod: mc\nworkers: 1\n",
        encoding="utf-8",
    )
    code, _, err = run_cli(["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 0, err
    assert (tmp_path / "o" / "summary.json").is_file()
