"""The second-moment operators the optimal schedule integrates (:mod:`.optimal`).

With S = E[εεᵀ] flattened into a state vector y, the second-moment equation of
:mod:`ntc_design.simulate.moments` reads y' = c 𝓐₁y + c² (𝓐₂y + q), with
𝓐₁(S) = −(L_B S + S L_Bᵀ), 𝓐₂(S) = Σ_e G_e S G_eᵀ and q = GGᵀ. 𝓐₁ is applied by a
product with L_B, 𝓐₂ as a sparse matrix (it only writes agents' diagonal blocks, from the
blocks of each edge's ends), so an RK4 stage costs O((Nd)³ + E·d⁴). (A dense operator on
S's upper triangle, one BLAS product per stage, was measured as well: as fast at N·d = 21,
20× slower at N·d = 60.)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ..simulate.moments import MomentRhs
from ..simulate.system import ModeSystem


def spectral_radius(a: sps.csr_matrix) -> float:
    """ρ of a square sparse matrix: every eigenvalue up to 800 rows, else 60 power
    iterations (𝓐₂ maps the PSD cone into itself, so its Perron root is the radius)
    with 10 % added.

    Parameters
    ----------
    a : scipy.sparse matrix
        The matrix.

    Returns
    -------
    float
    """
    if a.shape[0] <= 800:
        return float(np.max(np.abs(np.linalg.eigvals(a.toarray())), initial=0.0))
    x = np.ones(a.shape[0])
    lam = 0.0
    for _ in range(60):
        y = a @ x
        lam = float(np.linalg.norm(y))
        if lam == 0:
            return 0.0
        x = y / lam
    return 1.1 * lam


class MomentOperators:
    """One mode's operators on the flattened S.

    Attributes
    ----------
    lap : numpy.ndarray
        L_B (dense).
    a2 : scipy.sparse.csr_matrix
        𝓐₂, the operator :meth:`~ntc_design.simulate.moments.MomentRhs.noise_operator`
        builds (the right-hand side the simulator integrates).
    q : numpy.ndarray
        GGᵀ, flattened.
    rho1, rho2 : float
        Bounds of ρ(𝓐₁) = 2ρ(L_B) and ρ(𝓐₂) (the step plan's).
    """

    def __init__(
        self, lap: np.ndarray, a2: sps.csr_matrix, q: np.ndarray, rho1: float, rho2: float
    ) -> None:
        self.lap, self.lapt = lap, np.ascontiguousarray(lap.T)
        self.a2, self.a2t = a2, a2.T.tocsr()
        self.q, self.rho1, self.rho2 = q, float(rho1), float(rho2)
        self.n = lap.shape[0]

    @classmethod
    def build(cls, system: ModeSystem, n: int, d: int) -> MomentOperators:
        """The operators of one mode.

        Parameters
        ----------
        system : ModeSystem
            The mode.
        n, d : int
            Agents and state dimension.

        Returns
        -------
        MomentOperators
        """
        rhs = MomentRhs(system, n, d)
        lap = rhs.l if isinstance(rhs.l, np.ndarray) else rhs.l.toarray()
        a2 = rhs.a2 if rhs.a2 is not None else rhs.noise_operator()
        return cls(lap, a2, rhs.q.ravel().copy(), 2 * system.spectral_radius, spectral_radius(a2))

    @staticmethod
    def pack(s: np.ndarray) -> np.ndarray:
        """The state vector of S.

        Parameters
        ----------
        s : numpy.ndarray
            Nd × Nd.

        Returns
        -------
        numpy.ndarray
        """
        return np.ascontiguousarray(s, dtype=float).ravel().copy()

    @staticmethod
    def diagonal(nd_: int) -> np.ndarray:
        """The state vector's indices of S's diagonal (tr S is their sum).

        Parameters
        ----------
        nd_ : int
            N·d.

        Returns
        -------
        numpy.ndarray
        """
        return np.arange(nd_) * (nd_ + 1)

    def products(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(𝓐₁y, 𝓐₂y) for the state y of S.

        Parameters
        ----------
        y : numpy.ndarray
            The state.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
        """
        m = y.reshape(self.n, self.n)
        # the general −(L S + S Lᵀ), not (L S)ᵀ for S Lᵀ: on rounding's antisymmetric part
        # that shortcut is another operator, with growing modes
        return -(self.lap @ m + m @ self.lapt).ravel(), self.a2 @ y

    def transpose(self, mu: np.ndarray, c: float) -> np.ndarray:
        """(c𝓐₁ + c²𝓐₂)ᵀ μ: the adjoint's step.

        Parameters
        ----------
        mu : numpy.ndarray
            An adjoint state.
        c : float
            The gain.

        Returns
        -------
        numpy.ndarray
        """
        m = mu.reshape(self.n, self.n)
        a1t = -(self.lapt @ m + m @ self.lap)
        return c * a1t.ravel() + (c * c) * (self.a2t @ mu)

    def radius(self, c: np.ndarray | float) -> np.ndarray | float:
        """A bound on ρ(c𝓐₁ + c²𝓐₂) (the step plan's).

        Parameters
        ----------
        c : float or numpy.ndarray
            The gain.

        Returns
        -------
        float or numpy.ndarray
        """
        return self.rho1 * c + self.rho2 * c * c


__all__ = ["MomentOperators", "spectral_radius"]
