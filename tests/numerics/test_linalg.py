"""Tests of :mod:`ntc_design.numerics.linalg`."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.errors import InputError
from ntc_design.model.generate import random_network
from ntc_design.numerics.linalg import (
    Definiteness,
    DenseRefused,
    SPDFamily,
    cholesky_fill,
    classify,
    numba_cache_dir,
    require_dense,
)
from tests.conftest import ROOT
from tests.support.model import seeds
from tests.support.switching_scale import THETA_SW, _count_numeric


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
    r = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr[-2000:]
    cached = list((tmp_path / "cache" / "ntc-design" / "numba").rglob("*.nbi"))
    assert any("_em_core" in p.name for p in cached), cached  # the kernel the run called


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


@pytest.mark.parametrize(
    "mat, cls",
    [
        (np.diag([1.0, 1.0, 0.0]), Definiteness.PSD),
        (np.diag([1.0, 1.0, 1e-12]), Definiteness.PSD),
        (np.diag([1.0, 1.0, 1e-9]), Definiteness.PD),
        (-np.diag([1.0, 1.0, 0.0]), Definiteness.NSD),
        (-np.eye(3), Definiteness.ND),
        (np.zeros((3, 3)), Definiteness.ZERO),
        (np.diag([1.0, -1e-3, 2.0]), Definiteness.INDEFINITE),
    ],
)
def test_classification_tolerance(mat, cls):
    assert classify(mat) is cls


@settings(max_examples=60, deadline=None)
@given(seeds, st.floats(1e-6, 1e6), st.integers(1, 4))
def test_classification_invariant_under_positive_scaling(seed, c, d):
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(d, d))
    kind = rng.integers(4)
    a = [m @ m.T, -(m @ m.T), m + m.T, np.diag(np.r_[rng.random(d - 1) + 0.1, 0.0])][kind]
    assert classify(c * a) is classify(a)


def test_memory_guard_refuses_dense_steps_in_one_line():
    with pytest.raises(DenseRefused, match=r"needs about .* GiB"):
        require_dense(200_000, "test step")
    require_dense(100, "small step")
    big = random_network(20_000, 3, seed=0)  # Nd = 60,000: a dense L would take 27 GiB
    with pytest.raises(nd.InputError, match="signed Laplacian L: a dense 60000×60000"):
        big.laplacian()
    des = nd.design(big, [1.0, 0.0, 0.0], thresholds=False)  # the sparse path works
    assert des.assumption_holds and des.identity_residual < 1e-12
    assert des.grounded_laplacian_sparse().shape == (60_000, 60_000)


def test_sparse_cholesky_decides_definiteness_at_the_boundary():
    rng = np.random.default_rng(3)
    g = rng.normal(size=(40, 40))
    a = g @ g.T
    lam = sla.eigvalsh(a)[0]
    fam = SPDFamily([__import__("scipy.sparse").sparse.csr_matrix(a)])
    for rel in (1e-6, 1e-3, 0.5):
        assert fam.factor([1.0], lam * (1 - rel))[0]
        assert not fam.factor([1.0], lam * (1 + rel))[0]


def _comparison(seed, n=400, scale=1.0):
    """A random comparison matrix M = D − N (N >= 0) on a strongly connected graph."""
    import scipy.sparse as sp

    rng = np.random.default_rng(seed)
    ring = np.arange(n)
    rows = np.concatenate([ring, rng.integers(0, n, 2 * n)])
    cols = np.concatenate([(ring + 1) % n, rng.integers(0, n, 2 * n)])
    keep = rows != cols
    off = sp.csr_matrix((rng.uniform(0.1, 1.0, keep.sum()), (rows[keep], cols[keep])), (n, n))
    dg = scale * np.asarray(off.sum(axis=1)).ravel() + 0.05
    return (sp.diags(dg) - off).tocsr()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_comparison_solve_by_jacobi_matches_the_lu(seed):
    """Issue 20: M v = 1 by Jacobi sweeps (linear in the edges) instead of a sparse LU
    (superlinear fill on random graphs); on an M-matrix the same v as the LU."""
    from scipy.sparse.linalg import splu

    from ntc_design.numerics import linalg as sc

    m = _comparison(seed)
    v = sc.comparison_solve(m)
    exact = splu(m.tocsc()).solve(np.ones(m.shape[0]))
    assert np.all(v > 0)
    np.testing.assert_allclose(v, exact, rtol=1e-10)
    assert np.all(m @ v > 0)


def test_comparison_solve_falls_back_to_the_lu_when_jacobi_diverges(monkeypatch):
    """Not an M-matrix (ρ(D⁻¹N) > 1): the sweeps diverge; small matrices get the LU's v
    (dominance then fails on it), large ones the last finite sweep, never a crash."""
    from scipy.sparse.linalg import splu

    from ntc_design.numerics import linalg as sc

    m = _comparison(3, n=200, scale=0.5)
    exact = splu(m.tocsc()).solve(np.ones(m.shape[0]))
    np.testing.assert_allclose(sc.comparison_solve(m), exact, rtol=1e-12)
    assert not np.all(exact > 0)  # no positive v with M v > 0: dominance must fail
    monkeypatch.setattr(sc, "COMPARISON_LU_MAX_AGENTS", 10)
    v = sc.comparison_solve(m)
    assert v.shape == (200,) and not (np.all(v > 0) and np.all(m @ v > 0))


def test_memory_guard_refuses_a_factor_that_will_not_fit(big_switching, big_cert, monkeypatch):
    import ntc_design.numerics.linalg as la

    monkeypatch.setattr(la, "SPARSE_FACTOR_MAX_BYTES", 1000.0)
    res = certify(big_switching, THETA_SW)
    assert not res.verification.valid and not res.proven
    assert res.certificate["proofs"] == {}
    assert "refused" in res.certificate["results"]["details"]["A"]
    with pytest.raises(InputError, match="refused"):
        verify(big_cert)


def _reference_fill(a, perm):
    """nnz and longest row of the Cholesky factor of a[perm, perm], from a dense numeric
    factorisation of an SPD matrix with that pattern (random values: no cancellation)."""
    rng = np.random.default_rng(0)
    pat = (abs(a) + abs(a.T)).toarray() != 0
    m = np.where(pat, rng.uniform(-1, 1, pat.shape), 0.0)
    m = 0.5 * (m + m.T)
    m += np.diag(np.abs(m).sum(axis=1) + 1.0)
    low = np.linalg.cholesky(m[np.ix_(perm, perm)])
    nz = np.abs(low) > 0
    return int(nz.sum()), int(nz.sum(axis=1).max())


@pytest.mark.parametrize("seed", range(4))
def test_cholesky_fill_is_the_exact_factor_structure(seed):
    from cvxopt import amd, matrix, spmatrix

    top = random_network(60, 2, seed=seed, family=["random", "grid", "scale-free", "ring"][seed])
    s = (top.laplacian_sparse() + top.laplacian_sparse().T).tocoo()
    n = s.shape[0]
    low = sp.tril(abs(s) + abs(s.T), k=-1, format="coo")
    eye = np.arange(n)
    pat = spmatrix(
        matrix(np.ones(low.nnz + n)),
        matrix(np.concatenate([low.row, eye]).astype(np.int64)),
        matrix(np.concatenate([low.col, eye]).astype(np.int64)),
        (n, n),
    )
    perm = np.array(amd.order(pat, uplo="L"), dtype=np.int64).ravel()
    fill = cholesky_fill(s)
    assert (fill.nnz, fill.row_max) == _reference_fill(s, perm)
    # and CHOLMOD's (supernodal, padded) factor is at least as long in its longest row
    spd = abs(s).tocsr()
    spd = spd + sp.diags(np.asarray(spd.sum(axis=1)).ravel() + 1.0)  # same pattern, SPD
    fam = SPDFamily([spd.tocsr()])
    ok, k = fam.factor([1.0], 0.0, row_counts=True)
    assert ok and k >= fill.row_max


def test_reuse_needs_the_bit_identical_matrix(monkeypatch):
    """A remembered success answers only for the same float values and shift: one ulp
    off, or another shift, is factorised (and a shift past λ_min fails)."""
    import scipy.sparse as sp

    import ntc_design.numerics.linalg as la

    a = sp.csr_matrix(np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]]))
    calls = _count_numeric(monkeypatch)
    assert SPDFamily([a]).factor([1.0], 0.5, reuse=True)[0]
    assert SPDFamily([a]).factor([1.0], 0.5, reuse=True)[0] and len(calls) == 1
    b = a.copy()
    b.data[0] = np.nextafter(b.data[0], 3.0)
    assert SPDFamily([b]).factor([1.0], 0.5, reuse=True)[0] and len(calls) == 2
    lam = 2 - np.sqrt(2)
    assert not SPDFamily([a]).factor([1.0], lam * (1 + 1e-9), reuse=True)[0]
    assert not SPDFamily([a]).factor([1.0], lam * (1 + 1e-9), reuse=True)[0]
    assert len(calls) == 4  # failures are never remembered
    fam = SPDFamily([a])
    assert fam.factor([1.0], 0.5, reuse=True)[0]
    with pytest.raises(ValueError, match="no successful factorisation"):
        fam.solve(np.ones(3))  # a reused answer keeps no factor
    assert len(la._PROVEN) <= la.PROVEN_KEEP


def _dies():
    os._exit(3)


def _fails(x):
    raise InputError(f"bad part {x}")


def test_fork_map_keeps_order_and_reports_failures_in_one_line():
    from ntc_design.numerics.linalg import fork_map

    assert fork_map([(pow, (2, k)) for k in range(5)], 2) == [1, 2, 4, 8, 16]
    assert fork_map([(pow, (3, 2))], 2) == [9]  # one call: in this process
    with pytest.raises(InputError, match="bad part 7"):
        fork_map([(pow, (2, 1)), (_fails, (7,))], 2)
    with pytest.raises(InputError, match=r"died \(out of memory\?\); nothing is proven") as e:
        fork_map([(pow, (2, 1)), (_dies, ())], 2)
    assert "\n" not in str(e.value)


def _fork_map_in_a_daemon(conn):
    from ntc_design.numerics.linalg import fork_map

    try:
        conn.send(("ok", fork_map([(pow, (2, k)) for k in range(4)], 2)))
    except BaseException as exc:  # noqa: BLE001 - reported to the test
        conn.send(("error", repr(exc)))


def test_fork_map_runs_in_place_inside_a_daemon_process():
    """A Dask worker is a daemon (a sweep certifies there): no children allowed, so the
    proofs run one after the other in it instead of failing."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    here, there = ctx.Pipe()
    p = ctx.Process(target=_fork_map_in_a_daemon, args=(there,), daemon=True)
    p.start()
    got = here.recv()
    p.join(30)
    assert got == ("ok", [1, 2, 4, 8])


def test_proof_workers_fit_the_memory(monkeypatch):
    from ntc_design.numerics import linalg

    monkeypatch.setattr(linalg, "available_memory", lambda: 3.5 * 2**30)
    assert linalg.proof_workers(16, bytes_each=2**30) == min(3, len(os.sched_getaffinity(0)))
    assert linalg.proof_workers(16, bytes_each=2**40) == 1  # one proof always runs
    assert linalg.proof_workers(16) == 1  # 3.5 GiB < one factor at the 4 GiB limit
