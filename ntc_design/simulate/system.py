"""The semi-autonomous network with compound noise (eq. SAN_noise) as matrices.

For one mode with design (L_B, x0, B_i) and noise (σ_ji, f_ji), on the stacked state
x ∈ R^{Nd}:

    dx = c(t) [ (u − L_B x) dt + Σ_e g_e dw_1e + Σ_e |A_ij| f(x_j − x_i) dw_2e ]

with one edge e = (j -> i) per nonzero A_ij, ``u = (Δ⊗I_d) B x0`` and
``g_e = e_i ⊗ (σ_ji |A_ij| 1_d)``. The drift is Lemma 1's SAN drift: Σ|A_ij|(sgn x_j − x_i)
+ δ_i|B_i|(x0 − x_i) = −(L_B x)_i + u_i. In the hot path the edge differences are one
matrix product: ``diff = D x`` (D: Ed×Nd), the multiplicative term is
``W (f(diff) ⊙ dw_2)`` with W (Nd×Ed) holding |A_ij| in block (i, e), and the additive term is
``G dw_1`` (G: Nd×E).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ..design import ProtocolDesign
from ..errors import InputError


@dataclass(frozen=True)
class NoiseModel:
    """σ_ji (a default and per-edge overrides keyed by (from, to) labels) and f_ji: a
    scalar s (f(x) = s·x), a d×d matrix F (f(x) = F x) or a callable acting on arrays of
    differences of shape (..., d) (it must satisfy Assumption 1: ‖f(x)‖ <= σ̄‖x‖)."""

    sigma: float = 0.4
    f: float | np.ndarray | Callable[[np.ndarray], np.ndarray] = 0.3
    sigma_edges: Mapping[tuple, float] = field(default_factory=dict)

    @property
    def linear(self) -> bool:
        return not callable(self.f)

    def f_matrix(self, d: int) -> np.ndarray:
        if callable(self.f):
            raise ValueError("f is a callable")
        f = np.asarray(self.f, dtype=float)
        if f.ndim == 0:
            return float(f) * np.eye(d)
        if f.shape != (d, d):
            raise InputError(f"noise.f: expected a scalar or a {d}x{d} matrix, got shape {f.shape}")
        return f


@dataclass(frozen=True, eq=False)
class ModeSystem:
    """Matrices of one mode; see the module docstring."""

    name: str
    lap_b: np.ndarray  # Nd×Nd
    u: np.ndarray  # Nd
    g: np.ndarray  # Nd×E   additive noise directions
    dmat: np.ndarray  # Ed×Nd  edge differences x_j − x_i (F applied when f is linear)
    wmat: np.ndarray  # Nd×Ed  |A_ij| into the rows of agent i
    f: Callable[[np.ndarray], np.ndarray] | None  # None when f is linear (inside dmat)
    n_edges: int
    h_blocks: tuple  # (i, j, K_e = |A_ij| F) per edge, for the exact moments
    spectral_radius: float
    stability_bound: float  # explicit Euler on ε' = −c L_B ε is stable for c·h < this


def mode_system(des: ProtocolDesign, noise: NoiseModel, name: str = "") -> ModeSystem:
    top = des.topology
    d = top.dim
    nd_ = top.nd
    edges = top.edges  # (i, j): j -> i
    e_n = len(edges)
    fmat = noise.f_matrix(d) if noise.linear else np.eye(d)
    g = np.zeros((nd_, e_n))
    dmat = np.zeros((e_n * d, nd_))
    wmat = np.zeros((nd_, e_n * d))
    hb = []
    lab = top.labels
    sig_by = {(str(a), str(b)): float(s) for (a, b), s in noise.sigma_edges.items()}
    for e, (i, j) in enumerate(edges):
        a = top.abs_weight(i, j)
        sig = sig_by.get((str(lab[j]), str(lab[i])), noise.sigma)
        g[i * d : (i + 1) * d, e] = sig * a @ np.ones(d)
        dmat[e * d : (e + 1) * d, j * d : (j + 1) * d] = fmat
        dmat[e * d : (e + 1) * d, i * d : (i + 1) * d] = -fmat
        wmat[i * d : (i + 1) * d, e * d : (e + 1) * d] = a
        hb.append((i, j, a @ fmat))
    known = {(str(lab[j]), str(lab[i])) for i, j in edges}
    for key in sig_by:
        if key not in known:
            raise InputError(
                f"noise.sigma_edges: no edge {key[0]}->{key[1]} in {name or 'the topology'}"
            )
    lap_b = des.grounded_laplacian()
    lam = np.linalg.eigvals(lap_b)
    rho = float(np.max(np.abs(lam))) if lam.size else 0.0
    # |1 − c h λ| < 1 for every eigenvalue λ of L_B  <=>  c h < 2 Re λ / |λ|²
    with np.errstate(divide="ignore", invalid="ignore"):
        bounds = np.where(lam.real > 0, 2 * lam.real / np.abs(lam) ** 2, 0.0)
    return ModeSystem(
        name=name,
        lap_b=lap_b,
        u=des.input_vector(),
        g=g,
        dmat=dmat,
        wmat=wmat,
        f=None if noise.linear else noise.f,
        n_edges=e_n,
        h_blocks=tuple(hb),
        spectral_radius=rho,
        stability_bound=float(np.min(bounds)) if bounds.size else np.inf,
    )
