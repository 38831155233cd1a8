"""Small linear-algebra helpers shared by every layer, with the project's tolerances.

Tolerances (documented once, used everywhere):

* ``SYM_RTOL = 1e-12``: a weight ``A`` is symmetric when
  ``max|A - Aᵀ| <= SYM_RTOL * max|A|``. The matrix is used as given; it is never
  symmetrised for the user.
* ``DEF_RTOL = 1e-10``: an eigenvalue ``λ`` of a symmetric ``A`` counts as zero when
  ``|λ| <= DEF_RTOL * ‖A‖₂``. So ``diag(1, 1, 0)`` is PSD (not PD), and ``diag(1, 1, 1e-12)``
  is PSD too, while ``diag(1, 1, 1e-9)`` is PD.
"""

from __future__ import annotations

import functools
import hashlib
import os
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ..errors import InputError
from .memory import available_memory

#: Every nonzero weight, and every number entering a proof, has a magnitude in
#: [2^-MAGNITUDE_EXP, 2^MAGNITUDE_EXP] (about [5.5e-76, 1.8e75]): sums over 10^7 edges of
#: products of three such numbers neither overflow nor underflow a double, and exact
#: dyadic entries stay a few hundred bits long.
MAGNITUDE_EXP = 250


def out_of_range(a: np.ndarray | float) -> bool:
    """Whether some nonzero entry lies outside ``[2^-MAGNITUDE_EXP, 2^MAGNITUDE_EXP]``.

    Parameters
    ----------
    a : ndarray or float
        The numbers.

    Returns
    -------
    bool
    """
    x = np.abs(np.asarray(a, dtype=float))
    nz = x[x != 0]
    return bool(nz.size) and (
        float(nz.min()) < 2.0**-MAGNITUDE_EXP or float(nz.max()) > 2.0**MAGNITUDE_EXP
    )


RANGE_TEXT = (
    f"a nonzero |entry| outside [2^-{MAGNITUDE_EXP}, 2^{MAGNITUDE_EXP}] (cannot be bounded)"
)


SYM_RTOL = 1e-12
DEF_RTOL = 1e-10


class DenseRefused(InputError):
    """A dense step refused by its memory estimate (see :func:`require_dense`)."""


class Definiteness(StrEnum):
    """Class of a symmetric weight (paper, Sec. 2.1: sgn and |·|)."""

    PD = "PD"
    PSD = "PSD"
    ND = "ND"
    NSD = "NSD"
    ZERO = "zero"
    INDEFINITE = "indefinite"

    @property
    def sign(self) -> int:
        """sgn(A): +1 for PD/PSD, -1 for ND/NSD, 0 for the zero matrix."""
        return {"PD": 1, "PSD": 1, "ND": -1, "NSD": -1, "zero": 0}.get(self.value, 0)

    @property
    def definite(self) -> bool:
        """True for PD or ND: the edges a positive-negative path may use."""
        return self in (Definiteness.PD, Definiteness.ND)


def sym_eigvalsh(a: np.ndarray) -> np.ndarray:
    """Eigenvalues of the symmetric part of ``a``.

    Parameters
    ----------
    a : numpy.ndarray
        A square matrix.

    Returns
    -------
    numpy.ndarray
        The eigenvalues of (a + aᵀ)/2, ascending.
    """
    return np.linalg.eigvalsh(0.5 * (a + a.T))


def is_symmetric(a: np.ndarray, rtol: float = SYM_RTOL) -> bool:
    """Symmetry up to the project's tolerance (see the module docstring).

    Parameters
    ----------
    a : numpy.ndarray
        A square matrix.
    rtol : float, optional
        ``max|A − Aᵀ| <= rtol·max|A|`` counts as symmetric.

    Returns
    -------
    bool
        Whether ``a`` is symmetric.
    """
    scale = float(np.max(np.abs(a))) if a.size else 0.0
    return bool(np.max(np.abs(a - a.T), initial=0.0) <= rtol * scale)


def classify(a: np.ndarray, rtol: float = DEF_RTOL) -> Definiteness:
    """Classify a symmetric matrix as PD, PSD, ND, NSD, zero or indefinite.

    An eigenvalue counts as zero when ``|λ| <= rtol·‖A‖₂`` (see module docstring).

    Parameters
    ----------
    a : numpy.ndarray
        A symmetric matrix.
    rtol : float, optional
        The relative zero tolerance.

    Returns
    -------
    Definiteness
        Its class; sgn of the paper (Niu & Wu, Sec. 2.1) is ``.sign``.
    """
    if not np.any(a):
        return Definiteness.ZERO
    lam = sym_eigvalsh(a)
    tol = rtol * float(np.max(np.abs(lam)))
    lo, hi = float(lam[0]), float(lam[-1])
    if lo > tol:
        return Definiteness.PD
    if hi < -tol:
        return Definiteness.ND
    if lo >= -tol:
        return Definiteness.PSD
    if hi <= tol:
        return Definiteness.NSD
    return Definiteness.INDEFINITE


def pd(a: np.ndarray, rtol: float = DEF_RTOL) -> bool:
    """Whether a symmetric ``a`` is positive definite.

    Parameters
    ----------
    a : numpy.ndarray
        A symmetric matrix.
    rtol : float, optional
        The relative zero tolerance.

    Returns
    -------
    bool
        ``a ≻ 0``: its smallest eigenvalue is above ``rtol·‖a‖₂``.
    """
    return classify(a, rtol) is Definiteness.PD


#: Integer codes of :class:`Definiteness` used by the batched classifier.
DEF_CODES: tuple[Definiteness, ...] = (
    Definiteness.ZERO,
    Definiteness.PD,
    Definiteness.PSD,
    Definiteness.ND,
    Definiteness.NSD,
    Definiteness.INDEFINITE,
)
CODE_SIGN = np.array([0, 1, 1, -1, -1, 0], dtype=np.int8)
CODE_DEFINITE = np.array([False, True, False, True, False, False])


def classify_codes(a: np.ndarray, rtol: float = DEF_RTOL) -> np.ndarray:
    """:func:`classify` for a stack ``a`` of shape (E, d, d) with one batched
    ``eigvalsh`` (same rule, same tolerance).

    Parameters
    ----------
    a : numpy.ndarray
        Shape (E, d, d).
    rtol : float, optional
        The relative zero tolerance.

    Returns
    -------
    numpy.ndarray
        int8 indices into :data:`DEF_CODES`, length E.
    """
    lam = np.linalg.eigvalsh(0.5 * (a + a.transpose(0, 2, 1)))
    tol = rtol * np.max(np.abs(lam), axis=1)
    lo, hi = lam[:, 0], lam[:, -1]
    out = np.full(a.shape[0], 5, dtype=np.int8)
    out[hi <= tol] = 4
    out[lo >= -tol] = 2
    out[hi < -tol] = 3
    out[lo > tol] = 1
    out[~np.any(a, axis=(1, 2))] = 0
    return out


def pd_batch(a: np.ndarray, rtol: float = DEF_RTOL) -> np.ndarray:
    """:func:`pd` for a stack of symmetric matrices.

    Parameters
    ----------
    a : numpy.ndarray
        Shape (E, d, d).
    rtol : float, optional
        The relative zero tolerance.

    Returns
    -------
    numpy.ndarray
        E booleans.
    """
    return classify_codes(a, rtol) == 1


def require_dense(n: int, what: str, copies: float = 1.0, limit: float | None = None) -> None:
    """Refuse a dense n×n float step whose memory estimate exceeds ``DENSE_MAX_BYTES``
    (one line, :class:`~ntc_design.errors.InputError`), so no input ends in an
    out-of-memory kill.

    Parameters
    ----------
    n : int
        The matrix size.
    what : str
        What the step computes, for the message.
    copies : float, optional
        How many n×n arrays the step holds at once.
    limit : float, optional
        Bytes allowed instead of ``DENSE_MAX_BYTES``.

    Raises
    ------
    DenseRefused
        The estimate exceeds the limit (an :class:`~ntc_design.errors.InputError`).
    """
    need = copies * 8.0 * float(n) ** 2
    cap = DENSE_MAX_BYTES if limit is None else limit
    if need > cap:
        raise DenseRefused(
            f"a dense {n}×{n} step needs about {need / 2**30:.1f} GiB "
            f"(limit {cap / 2**30:.1f} GiB); refused — use the sparse path",
            field=what,
        )


#: Memory a dense step may take (bytes): estimated before the step, refused above.
DENSE_MAX_BYTES = 2.0 * 2**30


#: Memory a sparse Cholesky factor may take (bytes, estimated from the exact fill before
#: the numeric factorisation, :func:`cholesky_fill`): refused above, in one line.
SPARSE_FACTOR_MAX_BYTES = 4.0 * 2**30
#: Bytes per non-zero of a CHOLMOD factor while it is computed (value, row index,
#: supernodal workspace; measured 17-22 bytes per non-zero on random networks).
FACTOR_BYTES_PER_NNZ = 24.0
#: Floating-point operations a sparse Cholesky may take: refused above, so no input hangs
#: a certificate (CHOLMOD's supernodal factorisation ran at about 3e10 flop/s on 2 cores,
#: so this is about 100 s; a 100,000-agent random network needs 6.3e11).
SPARSE_FACTOR_MAX_FLOPS = 3e12


@dataclass(frozen=True)
class CholeskyFill:
    """The exact structure of a Cholesky factor of a sparse symmetric matrix under the
    approximate minimum degree ordering: non-zeros, the longest row (the longest inner
    product of the factorisation) and the operation count Σ_j colcount_j²."""

    n: int
    nnz: int
    row_max: int
    flops: float

    @property
    def bytes(self) -> float:
        """Estimated peak memory of the numeric factorisation (bytes)."""
        return FACTOR_BYTES_PER_NNZ * self.nnz


def _row_counts_py(indptr, indices, n):  # pragma: no cover - compiled by _row_counts
    """Elimination tree (Liu, with path compression) and row counts by row-subtree
    traversal of the strictly lower pattern (row i lists columns k < i), O(nnz(L))."""
    parent = np.full(n, -1, dtype=np.int64)
    anc = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        for p in range(indptr[i], indptr[i + 1]):
            k = indices[p]
            while k != -1 and k < i:
                nxt = anc[k]
                anc[k] = i
                if nxt == -1:
                    parent[k] = i
                k = nxt
    mark = np.full(n, -1, dtype=np.int64)
    rows = np.ones(n, dtype=np.int64)
    cols = np.ones(n, dtype=np.int64)
    for i in range(n):
        mark[i] = i
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            while j != -1 and mark[j] != i:
                mark[j] = i
                rows[i] += 1
                cols[j] += 1
                j = parent[j]
    return rows, cols


def numba_cache_dir() -> str | None:
    """Point Numba's on-disk cache at the user's cache folder (``$NUMBA_CACHE_DIR`` if set,
    else ``$XDG_CACHE_HOME/ntc-design/numba`` or ``~/.cache/ntc-design/numba``) before Numba
    is imported. By default Numba writes ``__pycache__`` beside the installed sources: a
    ``pip install .`` then leaves cache files in site-packages that ``pip uninstall`` does
    not remove, and the left-over ``ntc_design/simulate/`` folder shadows a later editable
    install as a namespace package. A folder that cannot be created or written is not used
    (Numba's default applies).

    Returns
    -------
    str or None
        The cache folder in force, or None for Numba's default.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return os.environ["NUMBA_CACHE_DIR"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = os.path.join(base, "ntc-design", "numba")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    if not os.access(path, os.W_OK):
        return None
    os.environ["NUMBA_CACHE_DIR"] = path
    return path


@functools.cache
def _row_counts():
    """The compiled kernel (numba is imported on first use: ``import ntc_design`` stays
    light)."""
    numba_cache_dir()
    import numba

    return numba.njit(cache=True, nogil=True)(_row_counts_py)


def cholesky_fill(a) -> CholeskyFill:
    """The structure of the Cholesky factor of a sparse symmetric matrix ``a`` under the
    approximate minimum degree ordering (AMD, Amestoy–Davis–Duff 1996, as CHOLMOD uses it),
    computed symbolically: the elimination tree and the row subtrees (Liu, "The role of
    elimination trees in sparse factorization", SIAM J. Matrix Anal. Appl. 11, 1990). It
    costs O(nnz(L)) integer work and no floating-point factorisation, so a factorisation
    that would not fit is refused before it starts.

    Parameters
    ----------
    a : scipy.sparse matrix
        Symmetric, n×n (its pattern is symmetrised).

    Returns
    -------
    CholeskyFill
        Non-zeros of the factor (diagonal included), its longest row and the flop count.
    """
    import scipy.sparse as sp
    from cvxopt import amd, matrix, spmatrix

    n = a.shape[0]
    if n == 0:
        return CholeskyFill(0, 0, 0, 0.0)
    low = sp.tril(abs(a) + abs(a.T), k=-1, format="coo")
    eye = np.arange(n)
    pat = spmatrix(
        matrix(np.ones(low.nnz + n)),
        matrix(np.concatenate([low.row, eye]).astype(np.int64)),
        matrix(np.concatenate([low.col, eye]).astype(np.int64)),
        (n, n),
    )
    perm = np.array(amd.order(pat, uplo="L"), dtype=np.int64).ravel()
    inv = np.empty(n, dtype=np.int64)
    inv[perm] = np.arange(n)
    r, c = inv[low.row], inv[low.col]
    r, c = np.maximum(r, c), np.minimum(r, c)  # lower triangle of the permuted matrix
    m = sp.csr_matrix((np.ones(r.size), (r, c)), shape=(n, n))
    m.sum_duplicates()
    rows, cols = _row_counts()(m.indptr.astype(np.int64), m.indices.astype(np.int64), n)
    return CholeskyFill(n, int(rows.sum()), int(rows.max()), float(np.sum(cols.astype(float) ** 2)))


def require_sparse_factor(fill: CholeskyFill, what: str, factorisations: int = 1) -> None:
    """Refuse, in one line, a sparse Cholesky factorisation whose factor would exceed
    ``SPARSE_FACTOR_MAX_BYTES`` or whose work would exceed ``SPARSE_FACTOR_MAX_FLOPS``.

    Parameters
    ----------
    fill : CholeskyFill
        The factor's structure (:func:`cholesky_fill`).
    what : str
        What the factorisation is for, for the message.
    factorisations : int, optional
        How many factorisations of this structure the step needs (the flops add up).

    Raises
    ------
    DenseRefused
        Above either limit (an :class:`~ntc_design.errors.InputError`).
    """
    flops = fill.flops * factorisations
    if fill.bytes > SPARSE_FACTOR_MAX_BYTES or flops > SPARSE_FACTOR_MAX_FLOPS:
        times = f"{factorisations} factorisations of " if factorisations > 1 else ""
        raise DenseRefused(
            f"{times}the sparse Cholesky factor of this {fill.n}×{fill.n} matrix has "
            f"{fill.nnz:.3g} non-zeros (about {fill.bytes / 2**30:.1f} GiB, limit "
            f"{SPARSE_FACTOR_MAX_BYTES / 2**30:.0f} GiB) and need {flops:.2g} flops "
            f"(limit {SPARSE_FACTOR_MAX_FLOPS:.2g}); refused — the network's symmetrised "
            "graph fills in too much",
            field=what,
        )


#: SHA-256 keys of the exact matrices (pattern, values and shift, as factorised) whose
#: sparse Cholesky succeeded in this process, newest last (at most ``PROVEN_KEEP``).
_PROVEN: dict[str, None] = {}
PROVEN_KEEP = 32


def _remember_proven(keys) -> None:
    """Record matrices whose factorisation succeeded (newest last, ``PROVEN_KEEP`` kept)."""
    for key in keys:
        _PROVEN.pop(key, None)
        _PROVEN[key] = None
    while len(_PROVEN) > PROVEN_KEEP:
        del _PROVEN[next(iter(_PROVEN))]


def _matrix_key(n: int, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> str:
    """SHA-256 of a lower-triangle matrix exactly as it is handed to CHOLMOD."""
    h = hashlib.sha256(np.array([n, rows.size], dtype=np.int64).tobytes())
    for a in (rows.astype(np.int64), cols.astype(np.int64), vals.astype(np.float64)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


class SPDFamily:
    """Sparse Cholesky (CHOLMOD via cvxopt, fill-reducing ordering, supernodal) of the
    symmetric matrices ``Σ_k c_k·M_k − shift·I`` over one fixed sparsity pattern (the union
    of the M_k and the diagonal), assembled once. Only lower triangles are read. The
    factor's size and work are estimated first (:func:`cholesky_fill`) and refused above
    the limits (:func:`require_sparse_factor`)."""

    def __init__(self, mats) -> None:
        import scipy.sparse as sp

        n = mats[0].shape[0]
        self.n = n
        parts = [sp.tril(m, format="coo") for m in mats] + [sp.identity(n, format="coo")]
        key = np.concatenate([p.row.astype(np.int64) * n + p.col for p in parts])
        tag = np.concatenate([np.full(p.nnz, k) for k, p in enumerate(parts)])
        data = np.concatenate([p.data.astype(float) for p in parts])
        uniq, inv = np.unique(key, return_inverse=True)
        self.vals = np.zeros((len(parts), uniq.size))
        np.add.at(self.vals, (tag, inv), data)
        self.rows = uniq // n
        self.cols = uniq % n
        self._symbolic = None
        self._ok = False
        self._fill: CholeskyFill | None = None

    @property
    def fill(self) -> CholeskyFill:
        """The factor's structure (computed once: the pattern is fixed)."""
        if self._fill is None:
            import scipy.sparse as sp

            pat = sp.coo_matrix((np.ones(self.rows.size), (self.rows, self.cols)), (self.n,) * 2)
            self._fill = cholesky_fill(pat)
        return self._fill

    def factor(self, coeffs, shift: float = 0.0, row_counts: bool = False, reuse: bool = False):
        """Factorise ``Σ c_k M_k − shift·I``.

        Parameters
        ----------
        coeffs : sequence of float
            The c_k, one per matrix of the family.
        shift : float, optional
            The diagonal shift.
        row_counts : bool, optional
            Also count the factor's non-zeros per row.
        reuse : bool, optional
            When a factorisation of the bit-identical matrix (same pattern, same float
            values after the shift) succeeded earlier in this process, answer True
            without factorising again and keep no factor (:meth:`solve` then refuses).
            The same float matrix gives the same CHOLMOD run, so nothing weaker is
            proven; ``ntc certify`` re-verifies its own certificate this way. The size
            limits are checked first either way.

        Returns
        -------
        tuple of (bool, int)
            ``ok`` when every pivot is positive (the matrix is positive definite);
            ``row_max`` (with ``row_counts``) the largest number of non-zeros in a row of
            the factor, i.e. the longest dot product of the factorisation (0 otherwise).

        Raises
        ------
        DenseRefused
            The factor would exceed the memory or work limits (:func:`require_sparse_factor`).
        """
        from cvxopt import cholmod, matrix, spmatrix

        require_sparse_factor(self.fill, "sparse Cholesky")
        c = np.concatenate([np.asarray(coeffs, dtype=float), [-float(shift)]])
        v = c @ self.vals
        if not np.all(np.isfinite(v)):  # CHOLMOD would take a NaN pivot for a positive one
            self._ok = False
            return False, 0
        key = _matrix_key(self.n, self.rows, self.cols, v)
        if reuse and not row_counts and key in _PROVEN:
            self._ok, self._symbolic = False, None
            return True, 0
        sm = spmatrix(matrix(v), matrix(self.rows), matrix(self.cols), (self.n, self.n))
        old = dict(cholmod.options)
        cholmod.options["supernodal"] = 2
        try:
            # a fresh symbolic analysis every time: refactorising a factor object that
            # was already factorised numerically gave wrong answers (cvxopt 1.3)
            self._symbolic = cholmod.symbolic(sm, uplo="L")
            cholmod.numeric(sm, self._symbolic)
            # CHOLMOD tests a pivot with "d <= 0", which a NaN passes (an overflow inside
            # the factorisation): success needs every diagonal entry finite and positive
            dg = np.array(cholmod.diag(self._symbolic)).ravel()
        except ArithmeticError:
            self._ok = False
            return False, 0
        finally:
            cholmod.options.clear()
            cholmod.options.update(old)
        if not (np.all(np.isfinite(dg)) and np.all(dg > 0)):
            self._ok = False
            return False, 0
        self._ok = True
        _remember_proven([key])
        if not row_counts:
            return True, 0
        fac = cholmod.getfactor(self._symbolic)
        cnt = np.bincount(np.array(fac.I, dtype=np.int64).ravel(), minlength=self.n)
        return True, int(cnt.max(initial=0))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve with the last successful factorisation: ``(Σ c_k M_k − shift·I) x = b``.

        Parameters
        ----------
        b : numpy.ndarray
            Right-hand side, length n.

        Returns
        -------
        numpy.ndarray
            x.

        Raises
        ------
        ValueError
            The last factorisation failed, or there was none.
        """
        from cvxopt import cholmod, matrix

        if not self._ok:
            raise ValueError("no successful factorisation to solve with")
        x = matrix(np.asarray(b, dtype=float).reshape(-1, 1))
        cholmod.solve(self._symbolic, x)
        return np.array(x).ravel()


def sparse_cholesky(a, shift: float = 0.0, row_counts: bool = True):
    """One sparse Cholesky of the symmetric ``a − shift·I`` (see :class:`SPDFamily`).

    Parameters
    ----------
    a : scipy.sparse matrix
        Symmetric (only the lower triangle is read).
    shift : float, optional
        The diagonal shift.
    row_counts : bool, optional
        Also count the factor's non-zeros per row.

    Returns
    -------
    tuple of (bool, int)
        ``(ok, row_max)`` as :meth:`SPDFamily.factor`.
    """
    return SPDFamily([a]).factor([1.0], shift, row_counts)


# -- the comparison vector of block diagonal dominance (issue 20): used by certify.scale
# -- for proofs and by simulate for the implicit scheme's guard
#: Jacobi sweeps :func:`comparison_solve` makes before it gives up on convergence.
COMPARISON_JACOBI_MAX_ITER = 5000
#: ... and the relative change of v that counts as converged.
COMPARISON_JACOBI_RTOL = 1e-13
#: Largest comparison matrix (agents) solved by a sparse LU when Jacobi does not converge
#: (an LU of a random graph fills in superlinearly: 0.2 s at 15,000 agents, minutes at
#: 150,000).
COMPARISON_LU_MAX_AGENTS = 20_000


def comparison_solve(m) -> np.ndarray:
    """Solve ``M v = 1`` for a comparison matrix M = D − N (D its diagonal, N >= 0 off it)
    by Jacobi sweeps ``v ← D⁻¹(1 + N v)`` from v = D⁻¹1: one sparse product per sweep, so
    the cost grows with the edges. When M is a non-singular M-matrix (exactly when
    dominance can hold, ρ(D⁻¹N) < 1) the sweeps increase monotonically to M⁻¹1 > 0, each
    iterate with M v > 0 once the change is small. When they do not converge, a sparse LU
    solves small matrices (up to ``COMPARISON_LU_MAX_AGENTS``); larger ones keep the last
    sweep. Nothing here needs to be exact: ``dominance_holds`` proves M v > 0 rigorously
    for whatever v is returned.

    Parameters
    ----------
    m : scipy.sparse.csr_matrix
        The comparison matrix (square).

    Returns
    -------
    numpy.ndarray
        v, with −1 where it is not finite (dominance then fails there).
    """
    import scipy.sparse as sparse
    from scipy.sparse.linalg import splu

    k = m.shape[0]
    dg = m.diagonal()
    off = (sparse.diags(dg) - m).tocsr()
    d = np.where(dg > 0, dg, 1.0)  # rows with μ <= 0 cannot be dominant anyway
    one = np.ones(k)
    v = one / d
    converged = False
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(COMPARISON_JACOBI_MAX_ITER):
            new = (one + off @ v) / d
            if not np.all(np.isfinite(new)):
                break
            change = np.max(np.abs(new - v) / np.abs(new), initial=0.0)
            v = new
            if change <= COMPARISON_JACOBI_RTOL:
                converged = True
                break
    if not converged and k <= COMPARISON_LU_MAX_AGENTS:
        try:
            v = splu(m.tocsc()).solve(one)
        except RuntimeError:  # singular comparison matrix
            return np.full(k, -1.0)
    return np.where(np.isfinite(v), v, -1.0)


# -- independent proofs on the machine's cores (forked: the inputs are inherited) --------

#: Calls that :func:`fork_map`'s children run, set in the parent just before the fork.
_FORK_CALLS: list = []


def _forked(i: int) -> tuple:
    fn, args = _FORK_CALLS[i]
    return fn(*args), list(_PROVEN)


def fork_map(calls: list, workers: int) -> list:
    """``[fn(*args) for fn, args in calls]`` in up to ``workers`` forked processes, in
    order. CHOLMOD here is single-threaded (cvxopt's BLAS), so two modes' factorisations
    on two cores take the time of one. The children inherit the calls (nothing large is
    pickled on the way in) and send back results and the factorisations they proved
    (:class:`SPDFamily`'s ``reuse`` works in the parent afterwards). Runs in this process
    with one worker, one call, or no ``fork``.

    Parameters
    ----------
    calls : list of (callable, tuple)
        Functions and their arguments.
    workers : int
        Processes at most (each holds its own factor: memory adds up).

    Returns
    -------
    list
        The results, in the order of ``calls``.

    Raises
    ------
    InputError
        A child died (e.g. killed for memory); exceptions raised in a child are re-raised.
    """
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    global _FORK_CALLS
    if (
        workers <= 1
        or len(calls) <= 1
        or "fork" not in mp.get_all_start_methods()
        or mp.current_process().daemon  # e.g. a Dask worker (a sweep's certify): no children
    ):
        return [fn(*args) for fn, args in calls]
    _FORK_CALLS = list(calls)
    ex = None
    try:
        ctx = mp.get_context("fork")
        ex = ProcessPoolExecutor(max_workers=min(workers, len(calls)), mp_context=ctx)
        got = list(ex.map(_forked, range(len(calls))))
    except BrokenProcessPool:
        raise InputError(
            f"a process proving one of {len(calls)} parts in parallel died (out of memory?); "
            "nothing is proven"
        ) from None
    finally:
        _FORK_CALLS = []
        if ex is not None:  # on a failure, do not wait for the proofs still queued
            ex.shutdown(wait=True, cancel_futures=True)
    for _, keys in got:
        _remember_proven(keys)
    return [r for r, _ in got]


def proof_workers(n_parts: int, bytes_each: float | None = None) -> int:
    """Processes for ``n_parts`` independent proofs: this machine's CPUs (affinity), at
    most ``n_parts``, and no more than the available memory holds at ``bytes_each`` per
    process (default: the largest factor a proof may make, ``SPARSE_FACTOR_MAX_BYTES``,
    so that the parallel proofs fit wherever one proof did).

    Parameters
    ----------
    n_parts : int
        Independent proofs.
    bytes_each : float, optional
        Memory one proof may take.

    Returns
    -------
    int

    Raises
    ------
    InputError
        ``NTC_AVAILABLE_MEMORY`` is set to something that is not a size.
    """
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cpus = os.cpu_count() or 1
    each = SPARSE_FACTOR_MAX_BYTES if bytes_each is None else bytes_each
    fit = int(available_memory() // max(each, 1.0))
    return max(1, min(cpus, n_parts, fit))
