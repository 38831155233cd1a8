"""The drift-implicit step's linear system ``(I + c h L_B) y = b``, solved in time linear
in the edges at any size (issue 20).

Three methods, chosen by :class:`ImplicitSolver` (``method="auto"``):

* ``"lu"``: SuperLU, exact up to rounding, for Nd <= ``IMPLICIT_LU_MAX_ND`` (a random
  graph's LU fills in superlinearly: 8 s per factorisation at Nd = 3·10⁵).
* ``"jacobi"``: block Jacobi. Split ``I + c h L_B = D + O`` with D its d×d diagonal blocks
  (``I + c h (Σ_j|A_ij| + δ|B_i|)``, positive definite) and O the rest, and let
  ``J = D⁻¹O``. When ``q = ‖J‖_∞ < 1`` the sweeps ``y ← D⁻¹b − J y`` from ``y₀ = D⁻¹b``
  contract, and after m sweeps ``‖y_m − y‖_∞ <= q^(m+1) ‖y‖_∞`` (as y₀ − y = J y). m is
  fixed in advance from q for a relative bound ``IMPLICIT_RTOL``, so every path takes
  the same sweeps whichever block or worker it runs in. Used when q <= ``JACOBI_MAX_Q``
  (at most 43 sweeps); small steps make q small (q ≈ c h ρ of the off-diagonal part).
* ``"gmres"``: restarted GMRES preconditioned by D⁻¹, one column at a time, from
  ``D⁻¹b``, when neither applies, to a relative residual ``GMRES_RTOL``; a system it
  cannot solve is refused in one line (a smaller ``ds`` makes q smaller).

Steps whose c·h differ only by rounding share one solver: c·h is rounded to
``CH_DIGITS`` significant digits (a relative change of at most 5·10⁻¹² in the
coefficient, far below the scheme's O(h) error).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..choices import Solver, choices
from ..errors import InputError

#: Largest Nd solved by a sparse LU.
IMPLICIT_LU_MAX_ND = 30_000
#: Largest ‖D⁻¹O‖_∞ for which block Jacobi is used.
JACOBI_MAX_Q = 0.5
#: Relative accuracy of the iterative solves (∞-norm, relative to the solution).
IMPLICIT_RTOL = 1e-13
#: GMRES's relative residual ‖b − A y‖₂ / ‖b‖₂.
GMRES_RTOL = 1e-10
#: GMRES restart length and restarts.
GMRES_RESTART, GMRES_MAX_RESTARTS = 40, 50
#: Significant digits of c·h that key the solvers.
CH_DIGITS = 12

METHODS = choices(Solver)


def ch_key(ch: float) -> float:
    """c·h rounded to ``CH_DIGITS`` significant digits (the solver's key and coefficient).

    Parameters
    ----------
    ch : float
        c(t_k)·h_k.

    Returns
    -------
    float
    """
    return float(f"{float(ch):.{CH_DIGITS}g}")


def diagonal_blocks(lap_b: sp.spmatrix, d: int) -> np.ndarray:
    """(N, d, d) diagonal blocks of a block matrix with d×d blocks.

    Parameters
    ----------
    lap_b : scipy.sparse matrix
        Nd×Nd.
    d : int
        Block size.

    Returns
    -------
    numpy.ndarray
    """
    coo = lap_b.tocoo()
    keep = coo.row // d == coo.col // d
    out = np.zeros((lap_b.shape[0] // d, d, d))
    r, c = coo.row[keep], coo.col[keep]
    out[r // d, r % d, c % d] = coo.data[keep]
    return out


class ImplicitSolver:
    """``(I + c h L_B)⁻¹ b`` for one c·h; see the module docstring.

    Parameters
    ----------
    lap_b : scipy.sparse matrix
        L_B, Nd×Nd.
    ch : float
        c·h (used as given: round it with :func:`ch_key` first to share solvers).
    d : int
        The state dimension (block size of the Jacobi splitting).
    method : {"auto", "lu", "jacobi", "gmres"}
        ``"auto"``: LU up to ``IMPLICIT_LU_MAX_ND``, else Jacobi when q <= ``JACOBI_MAX_Q``,
        else GMRES.

    Attributes
    ----------
    method : str
        The method used.
    q : float
        ‖D⁻¹O‖_∞ (nan for the LU).
    sweeps : int
        Jacobi sweeps per solve (0 otherwise).
    """

    def __init__(self, lap_b: sp.spmatrix, ch: float, d: int, method: str = "auto"):
        if method not in METHODS:
            raise InputError(
                f"implicit solver: must be one of {', '.join(METHODS)}, got {method!r}"
            )
        nd_ = lap_b.shape[0]
        self.ch, self.nd, self.q, self.sweeps = float(ch), nd_, math.nan, 0
        a = (sp.identity(nd_, format="csr") + self.ch * sp.csr_matrix(lap_b)).tocsr()
        if method == "lu" or (method == "auto" and nd_ <= IMPLICIT_LU_MAX_ND):
            from scipy.sparse.linalg import splu

            self.method, self._lu = "lu", splu(a.tocsc())
            return
        blocks = diagonal_blocks(a, d)
        inv = np.linalg.inv(blocks)  # I + c h (PSD) blocks: positive definite
        n = nd_ // d
        self._dinv = sp.bsr_matrix((inv, np.arange(n), np.arange(n + 1)), shape=(nd_, nd_)).tocsr()
        self._a = a
        off = a - sp.bsr_matrix((blocks, np.arange(n), np.arange(n + 1)), shape=(nd_, nd_)).tocsr()
        self._j = (self._dinv @ off).tocsr()
        self.q = float(abs(self._j).sum(axis=1).max()) if nd_ else 0.0
        if method == "jacobi" or (method == "auto" and self.q <= JACOBI_MAX_Q):
            if not self.q < 1:
                raise InputError(
                    f"implicit solver: block Jacobi needs ‖D⁻¹O‖_∞ < 1, got {self.q:.4g} at c·h = {self.ch:.4g}"
                )
            # q^(m+1) <= rtol
            self.sweeps = (
                0
                if self.q == 0
                else max(0, math.ceil(math.log(IMPLICIT_RTOL) / math.log(self.q)) - 1)
            )
            self.method = "jacobi"
        else:
            self.method = "gmres"

    def solve(self, b: np.ndarray) -> np.ndarray:
        """y with (I + c h L_B) y = b.

        Parameters
        ----------
        b : numpy.ndarray
            Nd, or Nd×k (k right-hand sides).

        Returns
        -------
        numpy.ndarray
            The same shape as ``b``.

        Raises
        ------
        InputError
            GMRES did not reach ``GMRES_RTOL``.
        """
        if self.method == "lu":
            return self._lu.solve(np.asarray(b, dtype=float))
        y0 = self._dinv @ b
        if self.method == "jacobi":
            y = y0
            for _ in range(self.sweeps):
                y = y0 - self._j @ y
            return y
        return self._gmres(np.asarray(b, dtype=float), y0)

    def _gmres(self, b: np.ndarray, y0: np.ndarray) -> np.ndarray:
        from scipy.sparse.linalg import LinearOperator, gmres

        pre = LinearOperator(self._a.shape, matvec=lambda v: self._dinv @ v, dtype=float)
        cols = b.reshape(self.nd, -1)
        out = np.empty_like(cols)
        for k in range(cols.shape[1]):
            y, info = gmres(
                self._a, cols[:, k], x0=y0.reshape(self.nd, -1)[:, k], rtol=GMRES_RTOL,
                atol=0.0, restart=GMRES_RESTART, maxiter=GMRES_MAX_RESTARTS, M=pre,
            )  # fmt: skip
            if info != 0:
                raise InputError(
                    f"implicit: GMRES did not solve (I + c h L_B) y = b to {GMRES_RTOL:g} "
                    f"at c·h = {self.ch:.4g} (‖D⁻¹O‖_∞ = {self.q:.3g}); use a smaller ds",
                    field="scheme",
                )
            out[:, k] = y
        return out.reshape(b.shape)


#: Solvers a :class:`SolverCache` keeps (the most recently used): steps come in time order,
#: and a decaying gain under the ``h_max`` cap gives a new c·h at every capped step.
CACHE_SOLVERS = 4


class SolverCache:
    """One :class:`ImplicitSolver` per distinct c·h (keyed by :func:`ch_key`), built on
    first use; the ``CACHE_SOLVERS`` most recently used are kept.

    Parameters
    ----------
    lap_b : scipy.sparse matrix
        L_B.
    d : int
        The state dimension.
    method : str, optional
        Passed to :class:`ImplicitSolver`.
    """

    def __init__(self, lap_b: sp.spmatrix, d: int, method: str = "auto"):
        self.lap_b, self.d, self.method = lap_b, d, method
        self._by_ch: dict[float, ImplicitSolver] = {}

    def __call__(self, ch: float) -> ImplicitSolver:
        """The solver for c·h (rounded by :func:`ch_key`).

        Parameters
        ----------
        ch : float
            c·h.

        Returns
        -------
        ImplicitSolver
        """
        key = ch_key(ch)
        s = self._by_ch.pop(key, None)
        if s is None:
            s = ImplicitSolver(self.lap_b, key, self.d, self.method)
        self._by_ch[key] = s  # newest last
        while len(self._by_ch) > CACHE_SOLVERS:
            del self._by_ch[next(iter(self._by_ch))]
        return s


__all__ = ["ImplicitSolver", "SolverCache", "ch_key", "diagonal_blocks"]
