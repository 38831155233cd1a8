"""Lyapunov equations and LMIs for −L_B (the certificates layer's numerical side).

Conventions (python-control's ``lyap(A, Q)`` solves ``A X + X Aᵀ + Q = 0``; SciPy's
``solve_continuous_lyapunov(A, Q)`` solves ``A X + X Aᴴ = Q``). Here everything is
written for the consensus error dynamics ``ε̇ = −L_B ε``: −L_B is Hurwitz iff there is
``P ≻ 0`` with ``P L_B + L_Bᵀ P ≻ 0``; with right-hand side I this is the Lyapunov
equation (14) of Niu & Wu, ``−P L_B − L_Bᵀ P = −I``, with the sign moved.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sparse
from scipy.linalg.lapack import dtrsyl

LEAF = 96


def _split(t: np.ndarray, k: int) -> int:
    """A split index that does not cut a 2×2 block of the quasi-triangular t."""
    return k + 1 if k < t.shape[0] and t[k, k - 1] != 0.0 else k


def _sylv_upper(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Solve ``A X + X B = C`` for upper quasi-triangular A, B, recursively (level-3
    BLAS for the couplings, LAPACK ``dtrsyl`` at the leaves)."""
    m, n = c.shape
    if m <= LEAF and n <= LEAF:
        x, scale, info = dtrsyl(a, b, c)
        if info < 0:
            raise RuntimeError(f"dtrsyl failed (info={info})")
        return x / scale
    if m >= n:
        k = _split(a, m // 2)
        a11, a12, a22 = a[:k, :k], a[:k, k:], a[k:, k:]
        x2 = _sylv_upper(a22, b, c[k:])
        x1 = _sylv_upper(a11, b, c[:k] - a12 @ x2)
        return np.vstack([x1, x2])
    k = _split(b, n // 2)
    b11, b12, b22 = b[:k, :k], b[:k, k:], b[k:, k:]
    x1 = _sylv_upper(a, b11, c[:, :k])
    x2 = _sylv_upper(a, b22, c[:, k:] - x1 @ b12)
    return np.hstack([x1, x2])


def lyapunov_solve(lap_b: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
    """Solve ``P L_B + L_Bᵀ P = Q`` (Q = I by default; Niu & Wu, eq. (14)) for P.

    Real Schur form ``L_B = Z T Zᵀ`` turns it into ``Tᵀ Y + Y T = Zᵀ Q Z`` with
    ``P = Z Y Zᵀ``; reversing the row order (J) makes ``J Tᵀ J`` upper quasi-triangular,
    so a recursive blocked Bartels–Stewart solve applies. Equivalent to python-control's
    ``lyap(L_Bᵀ, -Q)`` and SciPy's ``solve_continuous_lyapunov(L_Bᵀ, Q)``, but level-3.

    Parameters
    ----------
    lap_b : numpy.ndarray
        The Nd×Nd matrix L_B (eq. (8)).
    q : numpy.ndarray, optional
        The right-hand side, symmetric; the identity when omitted.

    Returns
    -------
    numpy.ndarray
        The symmetric solution P (unique when −L_B is Hurwitz).

    Raises
    ------
    RuntimeError
        LAPACK's ``dtrsyl`` reports an illegal argument (non-finite input).
    """
    n = lap_b.shape[0]
    q = np.eye(n) if q is None else q
    t, z = sla.schur(lap_b, output="real")
    c = z.T @ q @ z
    a = t.T[::-1, ::-1].copy()  # J Tᵀ J: upper quasi-triangular
    x = _sylv_upper(a, t, c[::-1].copy())  # X = J Y
    y = x[::-1]
    p = z @ y @ z.T
    return 0.5 * (p + p.T)


@dataclass(frozen=True)
class LyapunovResult:
    """The Lyapunov-equation P with its relative residual, smallest eigenvalue and the
    seconds taken."""

    p: np.ndarray
    residual: float  # ‖P L_B + L_Bᵀ P − Q‖_F / ‖Q‖_F
    p_min_eig: float
    seconds: float


def hurwitz_by_lyapunov(lap_b: np.ndarray) -> LyapunovResult:
    """(a) of the certificate: P from the Lyapunov equation with Q = I (eq. (14)).

    Parameters
    ----------
    lap_b : numpy.ndarray
        The Nd×Nd matrix L_B (eq. (8)).

    Returns
    -------
    LyapunovResult
        P, the residual ``‖P L_B + L_Bᵀ P − I‖_F / √(Nd)``, λ_min(P) and the time taken;
        −L_B is Hurwitz when λ_min(P) > 0 and the residual is small (proven exactly by
        :func:`ntc_design.certify.dense.prove_hurwitz`).
    """
    t0 = time.perf_counter()
    p = lyapunov_solve(lap_b)
    r = p @ lap_b + lap_b.T @ p - np.eye(lap_b.shape[0])
    res = float(np.linalg.norm(r) / np.sqrt(lap_b.shape[0]))
    lam = float(sla.eigvalsh(p, subset_by_index=[0, 0])[0])
    return LyapunovResult(p, res, lam, time.perf_counter() - t0)


@dataclass(frozen=True)
class RateResult:
    """The decay rate α of the LMI bisection, the eigenvalue bound it is compared with,
    the P that proves α, the solver status, the bisection steps and the seconds taken."""

    alpha: float  # certified decay rate (verified in floating point), or 0
    eig_bound: float  # −max Re λ(−L_B)
    p: np.ndarray | None
    status: str
    iterations: int
    seconds: float


def _cvx():
    import cvxpy as cp  # imported lazily: heavy, and only the LMI paths need it

    return cp


def _solve(prob) -> str:
    cp = _cvx()
    try:
        # chordal decomposition: the LMIs have the network's sparsity pattern
        prob.solve(solver=cp.CLARABEL, chordal_decomposition_enable=True)
    except cp.error.SolverError as exc:
        return f"solver error: {exc}"
    return str(prob.status)


def verified_margin(mats: Sequence[np.ndarray], p: np.ndarray, alpha: float) -> float:
    """Smallest eigenvalue (relative) of P and of every P L + Lᵀ P − 2αP, in floats."""
    worst = np.linalg.eigvalsh(p)[0] / np.linalg.norm(p, 2)
    for lap in mats:
        m = p @ lap + lap.T @ p - 2 * alpha * p
        worst = min(worst, np.linalg.eigvalsh(0.5 * (m + m.T))[0] / np.linalg.norm(m, 2))
    return float(worst)


#: The shifted Lyapunov equation is solved at α = (1 − η)·(eigenvalue bound) for the
#: first η that P verifies at (floating point, a strict margin): the nearer the bound, the
#: worse conditioned P (‖P‖ grows like 1/(bound − α)).
RATE_BACKOFFS = (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.1, 0.5)


def decay_rate_lyapunov(lap_b: np.ndarray, eig_bound: float | None = None) -> RateResult:
    """(b) of the certificate without an SDP solver: for α below the eigenvalue bound
    α* = min Re λ(L_B), L_B − αI is positive stable, so the Lyapunov equation
    ``P (L_B − αI) + (L_B − αI)ᵀ P = I`` has a solution P ≻ 0, and then
    ``P L_B + L_Bᵀ P − 2αP = I ≻ 0``: the LMI's inequality, with α within
    :data:`RATE_BACKOFFS` (relative) of the best any P can prove (α*). One Bartels–Stewart
    solve per attempt, where the LMI bisection takes ~14 SDPs; the verifier re-proves P
    exactly either way.

    Parameters
    ----------
    lap_b : numpy.ndarray
        The Nd×Nd matrix L_B (eq. (8)).
    eig_bound : float, optional
        The eigenvalue bound, when the caller has it already.

    Returns
    -------
    RateResult
        α (0 when none verifies or −L_B is not Hurwitz), its P, the status and the
        attempts made (in ``iterations``).
    """
    t0 = time.perf_counter()
    n = lap_b.shape[0]
    bound = float(np.min(np.linalg.eigvals(lap_b).real)) if eig_bound is None else eig_bound
    if not bound > 0:  # NaN included
        return RateResult(0.0, bound, None, "not Hurwitz: eigenvalue bound <= 0", 0, 0.0)
    for k, eta in enumerate(RATE_BACKOFFS, start=1):
        alpha = (1.0 - eta) * bound
        p = lyapunov_solve(lap_b - alpha * np.eye(n))
        p = 0.5 * (p + p.T)
        if np.all(np.isfinite(p)) and verified_margin([lap_b], p, alpha) > 1e-9:
            status = f"optimal: α = (1 − {eta:g})·bound by the shifted Lyapunov equation"
            return RateResult(alpha, bound, p, status, k, time.perf_counter() - t0)
    return RateResult(
        0.0, bound, None, "no α > 0 verified", len(RATE_BACKOFFS), time.perf_counter() - t0
    )


def decay_rate_lmi(
    lap_b: np.ndarray, tol: float = 1e-4, max_iter: int = 40, eig_bound: float | None = None
) -> RateResult:
    """(b) of the certificate: the largest α with ``P ⪰ I`` and
    ``P L_B + L_Bᵀ P − 2αP ⪰ 0`` (so ``‖ε(t)‖ <= κ e^{−αt}‖ε(0)‖`` for ε̇ = −L_B ε),
    by bisection on α with one Clarabel SDP per step. Each accepted α is checked on the
    returned P in floating point (a strict margin), so α never exceeds what P proves;
    the result is compared with the eigenvalue bound ``−max Re λ(−L_B)``.

    Parameters
    ----------
    lap_b : numpy.ndarray
        The Nd×Nd matrix L_B (eq. (8)).
    tol : float, optional
        Bisection stops when the bracket is below ``tol`` times the eigenvalue bound.
    max_iter : int, optional
        At most this many SDP solves.
    eig_bound : float, optional
        The eigenvalue bound, when the caller has it already.

    Returns
    -------
    RateResult
        α (0 when none is verified or −L_B is not Hurwitz) with its P and the solver
        status.
    """
    cp = _cvx()
    t0 = time.perf_counter()
    n = lap_b.shape[0]
    bound = float(np.min(np.linalg.eigvals(lap_b).real)) if eig_bound is None else eig_bound
    if bound <= 0:
        return RateResult(0.0, bound, None, "not Hurwitz: eigenvalue bound <= 0", 0, 0.0)
    p_var = cp.Variable((n, n), symmetric=True)
    a_par = cp.Parameter(nonneg=True)
    lmi = p_var @ lap_b + lap_b.T @ p_var - 2 * a_par * p_var
    prob = cp.Problem(cp.Minimize(0), [p_var >> np.eye(n), 0.5 * (lmi + lmi.T) >> 0])
    lo, hi, best, it = 0.0, bound, None, 0
    while hi - lo > tol * bound and it < max_iter:
        it += 1
        mid = 0.5 * (lo + hi)
        a_par.value = mid
        status = _solve(prob)
        if status in ("optimal", "optimal_inaccurate") and p_var.value is not None:
            p = 0.5 * (p_var.value + p_var.value.T)
            if verified_margin([lap_b], p, mid) > 1e-9:
                lo, best = mid, p
                continue
        hi = mid
    status = "optimal" if best is not None else "no α > 0 verified"
    return RateResult(lo, bound, best, status, it, time.perf_counter() - t0)


@dataclass(frozen=True)
class CommonLyapunov:
    """A common Lyapunov matrix for a set of modes: ``P ≻ 0`` with
    ``P L_B(k) + L_B(k)ᵀ P ≻ 0`` for every mode k."""

    p: np.ndarray | None
    structure: str | None  # "identity", "block-diagonal", "dense" or None
    attempts: tuple[tuple[str, str, float], ...]  # (structure, status, seconds)
    margin: float | None  # verified min eigenvalue, relative
    notes: tuple[str, ...] = field(default=())


def _block_basis(n: int, block: int) -> list[tuple[int, int, int]]:
    """(block index, r, c) with r <= c: one scalar variable per entry of each symmetric
    d×d diagonal block of P."""
    return [(b, r, c) for b in range(n // block) for r in range(block) for c in range(r, block)]


def _block_lmi_columns(lap: np.ndarray, block: int, basis) -> sparse.csc_matrix:
    """Columns vec(E_m L + Lᵀ E_m) for the block basis E_m (symmetric, so vec order is
    irrelevant); sparse: E_m L only touches the rows of its block."""
    n = lap.shape[0]
    rows, cols, vals = [], [], []
    for m, (b, r, c) in enumerate(basis):
        e = np.zeros((block, block))
        e[r, c] = e[c, r] = 1.0
        sl = slice(b * block, (b + 1) * block)
        f = np.zeros((n, n))
        f[sl, :] = e @ lap[sl, :]
        f[:, sl] += lap[sl, :].T @ e
        nz = np.flatnonzero(f)
        rows.append(nz)
        cols.append(np.full(nz.size, m))
        vals.append(f.ravel()[nz])
    return sparse.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(n * n, len(basis)),
    )


def _block_diagonal_problem(lst: Sequence[np.ndarray], block: int):
    """Vectorised LMI for a per-agent block-diagonal P: P = Σ x_m E_m, so each mode's
    P L + Lᵀ P is one sparse matrix times x (cheap to compile; its sparsity pattern is
    the network's, which Clarabel's chordal decomposition exploits)."""
    cp = _cvx()
    n = lst[0].shape[0]
    basis = _block_basis(n, block)
    x = cp.Variable(len(basis))
    cons = []
    for b in range(n // block):
        idx = [m for m, (bb, _, _) in enumerate(basis) if bb == b]
        sel = np.zeros((block * block, len(basis)))
        for m in idx:
            _, r, c = basis[m]
            sel[r + c * block, m] = sel[c + r * block, m] = 1.0
        pb = cp.reshape(sparse.csc_matrix(sel) @ x, (block, block), order="F")
        cons.append(pb >> np.eye(block))
    for lap in lst:
        f = _block_lmi_columns(lap, block, basis)
        lmi = cp.reshape(f @ x, (n, n), order="F")
        cons.append(0.5 * (lmi + lmi.T) >> 1e-6 * np.eye(n))

    def value() -> np.ndarray | None:
        if x.value is None:
            return None
        p = np.zeros((n, n))
        for m, (b, r, c) in enumerate(basis):
            p[b * block + r, b * block + c] = p[b * block + c, b * block + r] = x.value[m]
        return p

    return cp.Problem(cp.Minimize(0), cons), value


def _dense_problem(lst: Sequence[np.ndarray]):
    """The naive LMI: one dense symmetric P (n(n+1)/2 variables)."""
    cp = _cvx()
    n = lst[0].shape[0]
    p_var = cp.Variable((n, n), symmetric=True)
    cons = [p_var >> np.eye(n)]
    for lap in lst:
        lmi = p_var @ lap + lap.T @ p_var
        cons.append(0.5 * (lmi + lmi.T) >> 1e-6 * np.eye(n))
    return cp.Problem(
        cp.Minimize(0), cons
    ), lambda: None if p_var.value is None else np.asarray(p_var.value)


def common_lyapunov(
    mats: Mapping[str, np.ndarray],
    block: int,
    structures: Sequence[str] = ("identity", "block-diagonal", "dense"),
) -> CommonLyapunov:
    """Search for a common Lyapunov matrix, cheapest structure first:
    P = I (holds iff every L_B + L_Bᵀ ≻ 0), then per-agent block-diagonal P (an SDP with
    N·d(d+1)/2 variables, vectorised and sparse), then a dense P (the naive LMI).
    Solver results are accepted only after a floating-point check with a strict margin;
    an infeasible or inaccurate result is reported with its status, never as a P.

    Parameters
    ----------
    mats : Mapping of str to numpy.ndarray
        Each mode's L_B (eq. (8)), all of one size Nd×Nd.
    block : int
        The block size d of the block-diagonal structure.
    structures : sequence of str, optional
        Which of ``"identity"``, ``"block-diagonal"``, ``"dense"`` to try, in order.

    Returns
    -------
    CommonLyapunov
        The first verified P with its structure and margin, and every attempt's status
        (P None when none is verified).

    Raises
    ------
    ValueError
        An unknown structure name.
    """
    lst = list(mats.values())
    n = lst[0].shape[0]
    attempts: list[tuple[str, str, float]] = []
    for s in structures:
        t0 = time.perf_counter()
        if s == "identity":
            p = np.eye(n)
            m = verified_margin(lst, p, 0.0)
            ok = m > 1e-9
            attempts.append(
                (s, "verified" if ok else f"fails (margin {m:.3g})", time.perf_counter() - t0)
            )
            if ok:
                return CommonLyapunov(p, s, tuple(attempts), m)
            continue
        if s == "block-diagonal":
            prob, value = _block_diagonal_problem(lst, block)
        elif s == "dense":
            prob, value = _dense_problem(lst)
        else:
            raise ValueError(f"unknown structure {s!r}")
        status = _solve(prob)
        pv = value() if status in ("optimal", "optimal_inaccurate") else None
        if pv is not None:
            p = 0.5 * (pv + pv.T)
            m = verified_margin(lst, p, 0.0)
            if m > 1e-9:
                attempts.append((s, f"{status}, verified", time.perf_counter() - t0))
                return CommonLyapunov(p, s, tuple(attempts), m)
            status = f"{status} but the float check fails (margin {m:.3g})"
        attempts.append((s, status, time.perf_counter() - t0))
    return CommonLyapunov(None, None, tuple(attempts), None)


__all__ = [
    "CommonLyapunov",
    "LyapunovResult",
    "RateResult",
    "common_lyapunov",
    "decay_rate_lmi",
    "hurwitz_by_lyapunov",
    "lyapunov_solve",
]
