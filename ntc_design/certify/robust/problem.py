"""The robust problem's data (:mod:`.search` states the set and the bounds): the uncertain
edges with the matrices their channels use, how a set of radii is said, the dense nominal
data every bound and search shares, and the realisations and brackets the bounds produce.
Nothing here solves anything, so every other module of the package imports it and none of
them imports another in a circle."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ...model import Topology
from ...numerics.linalg import require_dense
from ...protocol import ProtocolDesign

# -- the uncertain edges ---------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class UncertainEdges:
    """The listed non-zero weights as the robust bounds use them: edge e = (src → dst),
    sign ``s``, ``W = |A_e|``, the matrix ``W̄_e`` the S-procedure's channels bound the
    change by (:func:`channel_bound`: W itself unless W is singular only by rounding) and
    ``V`` (the pivot columns of W̄, a basis of its range)."""

    dst: np.ndarray
    src: np.ndarray
    s: np.ndarray
    w: np.ndarray  # (m, d, d)
    pivots: tuple[tuple[int, ...], ...]  # of the channel matrix W̄
    bound: np.ndarray | None = None  # W̄ (m, d, d); None: W̄ = W

    @property
    def channel_w(self) -> np.ndarray:
        """W̄_e for every edge (m, d, d): what the channels use (:func:`channel_bound`)."""
        return self.w if self.bound is None else self.bound

    @property
    def m(self) -> int:
        """The number of uncertain edges."""
        return int(self.dst.size)

    def radii(self, top: Topology, default: float) -> np.ndarray:
        """ρ_e per edge: the topology file's ``uncertainty:``, else ``default``.

        Parameters
        ----------
        top : Topology
            The topology these edges are of.
        default : float
            ρ for an edge without a value of its own.

        Returns
        -------
        numpy.ndarray
        """
        unc = top.uncertainty
        return np.array(
            [unc.get((int(i), int(j)), default) for i, j in zip(self.dst, self.src, strict=True)]
        )

    def labels(self, top: Topology) -> list[str]:
        """Each edge as ``from→to`` with the topology's agent labels.

        Parameters
        ----------
        top : Topology
            The topology these edges are of.

        Returns
        -------
        list of str
        """
        lab = top.labels
        return [f"{lab[int(j)]}→{lab[int(i)]}" for i, j in zip(self.dst, self.src, strict=True)]

    def basis(self, e: int) -> np.ndarray:
        """V_e: the pivot columns of W̄_e (d × rank); where W̄_e = W_e + ηI, a whitening
        basis (:func:`whitening_basis`).

        Parameters
        ----------
        e : int
            The edge.

        Returns
        -------
        numpy.ndarray
        """
        return self._bases[e]

    @functools.cached_property
    def _bases(self) -> tuple[np.ndarray, ...]:
        # where W̄ = W + ηI (channel_bound), a whitening basis: VᵀW̄V ≈ I, so the block
        # τ VᵀW̄V is as well conditioned as the solver needs (any basis of the range gives
        # a congruent Ψ)
        out = []
        for e in range(self.m):
            if self.bound is not None and not np.array_equal(self.bound[e], self.w[e]):
                out.append(whitening_basis(self.bound[e]))
            else:
                out.append(self.channel_w[e][:, list(self.pivots[e])])
        return tuple(out)


#: A weight's magnitude W is kept as the channels' bound when the exact LDLᵀ of its
#: principal block on the pivot columns has every pivot >= this × max|W| (so the block
#: τ VᵀWV of Ψ is well conditioned); else it is singular or indefinite only by rounding (a
#: rank-deficient weight written in floating point: its kernel lost in the last bits), and
#: the channels use W̄ = W + ηI, η the power of two >= this × max|W|.
CHANNEL_FLOOR = 2.0**-20


def channel_bound(w: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    """The matrix W̄ that the S-procedure's channels bound a weight's change by, and its
    pivot columns.

    The set is every |A'| = W + Δ with −ρW̄ ⪯ Δ ⪯ ρW̄. For a weight whose magnitude W is
    well conditioned on its range, W̄ = W: the set of the module docstring. Otherwise
    W̄ = W + ηI (each diagonal entry rounded, never below W's): W̄ ⪰ W, so the set holds
    the documented one and every bound proven for it holds there too, while τVᵀW̄V ≻ 0
    stays within a solver's reach (with W itself, Ψ ≻ 0 would need VᵀWV ≻ 0, which a
    weight singular or indefinite by 1e−18 does not have, and nothing is proven at any
    radius, ρ = 0 included). Decided in exact arithmetic, so issuer and verifier agree.

    Parameters
    ----------
    w : numpy.ndarray
        W = |A_e| (d × d, non-zero).

    Returns
    -------
    tuple of (numpy.ndarray, tuple of int)
        W̄ and its pivot columns (:func:`pivot_columns`).

    Examples
    --------
    >>> channel_bound(np.diag([2.0, 0.0]))[1]  # an exact kernel is kept: one channel
    (0,)
    >>> wb, piv = channel_bound(np.array([[1.0, 1.0], [1.0, 1.0 + 2.0**-52]]))
    >>> piv, bool(wb[0, 0] > 1.0)  # singular by rounding: W + ηI, two channels
    ((0, 1), True)
    """
    w = np.asarray(w, dtype=float)
    piv = pivot_columns(w)
    scale = float(np.max(np.abs(w)))
    floor = Fraction(CHANNEL_FLOOR) * Fraction(scale)
    block = [[Fraction(float(w[i, j])) for j in piv] for i in piv]
    for k in range(len(block)):  # LDLᵀ without pivoting: every pivot well above 0
        if block[k][k] < floor:
            break
        for i in range(k + 1, len(block)):
            f = block[i][k] / block[k][k]
            block[i] = [a - f * b for a, b in zip(block[i], block[k], strict=True)]
    else:
        return w, piv
    eta = 2.0 ** math.ceil(math.log2(CHANNEL_FLOOR * scale))
    wb = w + eta * np.eye(w.shape[0])  # rounding keeps each diagonal entry >= W's
    return wb, pivot_columns(wb)


def whitening_basis(w: np.ndarray) -> np.ndarray:
    """V = L⁻ᵀ D^(−1/2) from the exact LDLᵀ of a positive definite W (so VᵀWV ≈ I), each
    entry correctly rounded: the same doubles on every machine, as issuer and verifier
    need. The identity when W is not positive definite (nothing can be proven with it).

    Parameters
    ----------
    w : numpy.ndarray
        A symmetric d×d matrix of doubles.

    Returns
    -------
    numpy.ndarray
        d × d.

    Examples
    --------
    >>> v = whitening_basis(np.array([[4.0, 2.0], [2.0, 2.0]]))
    >>> np.allclose(v.T @ np.array([[4.0, 2.0], [2.0, 2.0]]) @ v, np.eye(2))
    True
    """
    d = w.shape[0]
    a = [[Fraction(float(x)) for x in r] for r in np.asarray(w, dtype=float)]
    low = [[Fraction(int(i == j)) for j in range(d)] for i in range(d)]
    piv: list[Fraction] = []
    for k in range(d):
        pk = a[k][k] - sum(low[k][j] ** 2 * piv[j] for j in range(k))
        if pk <= 0:
            return np.eye(d)
        piv.append(pk)
        for i in range(k + 1, d):
            s = a[i][k] - sum(low[i][j] * low[k][j] * piv[j] for j in range(k))
            low[i][k] = s / pk
    inv = [[Fraction(int(i == j)) for j in range(d)] for i in range(d)]  # L⁻¹, forward
    for i in range(d):
        for j in range(i):
            inv[i][j] = -sum((low[i][k] * inv[k][j] for k in range(j, i)), Fraction(0))
    # V[i][j] = (L⁻ᵀ)[i][j] / √D_j = L⁻¹[j][i] / √D_j
    return np.array(
        [[float(inv[j][i]) / math.sqrt(float(piv[j])) for j in range(d)] for i in range(d)]
    )


def pivot_columns(w: np.ndarray) -> tuple[int, ...]:
    """The pivot columns of a matrix of doubles, found in exact rational arithmetic: a
    basis of its column space chosen among its own columns (so the basis is exact).

    Parameters
    ----------
    w : numpy.ndarray
        A d×d matrix of doubles.

    Returns
    -------
    tuple of int
        Column indices, ascending.

    Examples
    --------
    >>> pivot_columns(np.diag([1.0, 0.0, 2.0]))
    (0, 2)
    """
    rows = [[Fraction(float(x)) for x in r] for r in np.asarray(w, dtype=float)]
    n_rows, n_cols = len(rows), len(rows[0]) if rows else 0
    piv: list[int] = []
    r = 0
    for c in range(n_cols):
        k = next((i for i in range(r, n_rows) if rows[i][c] != 0), None)
        if k is None:
            continue
        rows[r], rows[k] = rows[k], rows[r]
        for i in range(r + 1, n_rows):
            f = rows[i][c] / rows[r][c]
            if f:
                rows[i] = [a - f * b for a, b in zip(rows[i], rows[r], strict=True)]
        piv.append(c)
        r += 1
    return tuple(piv)


def uncertain_edges(top: Topology) -> UncertainEdges:
    """The topology's non-zero weights as :class:`UncertainEdges` (zero weights carry no
    uncertainty: their interval is {0}), ordered by (receiving agent, sending agent): the
    order of a certificate's multipliers and realisations.

    Parameters
    ----------
    top : Topology
        The nominal topology.

    Returns
    -------
    UncertainEdges
    """
    ea = top._arrays
    keep = np.flatnonzero(ea.sign != 0)
    keep = keep[np.lexsort((ea.cols[keep], ea.rows[keep]))]  # canonical: by (to, from)
    w = ea.abs_w[keep]
    # a strictly diagonally dominant W whose Gershgorin margin clears the channel floor is
    # nonsingular (Lévy–Desplanques) with every LDLᵀ pivot ≥ λ_min ≥ the margin: W̄ = W and
    # every column a pivot, with no rational elimination (the usual weight, diagonal or
    # dominant; 1e−10 covers the rounding of the d − 1 off-diagonal sums)
    dg = np.abs(np.diagonal(w, axis1=1, axis2=2))
    off = np.abs(w).sum(axis=2) - dg
    scale = np.abs(w).max(axis=(1, 2)) if w.size else np.zeros(0)
    margin = (dg - off * (1 + 1e-10)).min(axis=1) if w.size else np.zeros(0)
    dominant = margin > 2 * CHANNEL_FLOOR * scale
    every = tuple(range(top.dim))
    bounds = [(x, every) if ok else channel_bound(x) for x, ok in zip(w, dominant, strict=True)]
    return UncertainEdges(
        ea.rows[keep].astype(np.int64),
        ea.cols[keep].astype(np.int64),
        ea.sign[keep].astype(float),
        w,
        tuple(piv for _, piv in bounds),
        np.array([b for b, _ in bounds]).reshape(w.shape),
    )


#: Per-edge radii named in a statement (the rest counted).
RADII_SHOWN = 8


def radius_text(
    radii: Sequence[float],
    radius: float,
    short: bool = False,
    edges: Sequence[str] | None = None,
) -> str:
    """The uncertainty set as a statement names it: ``ρ = 0.05`` when every edge has the
    same radius, else ``the per-edge radii (max 0.5; 1→2: 0.02, 2→3: 0.5, 3→1: 0.02)``: a
    bound proven for per-edge radii is not one for every weight at the largest of them.

    Parameters
    ----------
    radii : sequence of float
        ρ_e per uncertain edge (:attr:`RobustReport.radii`; empty: no uncertain edge).
    radius : float
        The largest (ρ itself when every edge has the same).
    short : bool, optional
        Leave the list of ρ_e out (a figure's title).
    edges : sequence of str, optional
        The edges' names (:meth:`UncertainEdges.labels`), in the order of ``radii``;
        without them the radii are listed as ``ρ_e = 0.02, 0.5, …``.

    Returns
    -------
    str
    """
    vals = [float(r) for r in radii]
    if len(set(vals)) <= 1:
        return f"ρ = {radius:.6g}"
    if short:
        return f"the per-edge radii (max {radius:.6g})"
    if edges is not None and len(edges) == len(vals):
        shown = ", ".join(
            f"{e}: {r:.6g}" for e, r in list(zip(edges, vals, strict=True))[:RADII_SHOWN]
        )
    else:
        shown = "ρ_e = " + ", ".join(f"{r:.6g}" for r in vals[:RADII_SHOWN])
    more = f", …; {len(vals)} edges" if len(vals) > RADII_SHOWN else ""
    return f"the per-edge radii (max {radius:.6g}; {shown}{more})"


def radius_phrase(radii: Sequence[float], radius: float, edges: Sequence[str] | None = None) -> str:
    """What a proven number holds for: ``at ρ = 0.05``, or ``for the per-edge radii (max
    0.5; …)`` (:func:`radius_text`).

    Parameters
    ----------
    radii : sequence of float
        ρ_e per uncertain edge.
    radius : float
        The largest.
    edges : sequence of str, optional
        The edges' names, in the order of ``radii``.

    Returns
    -------
    str
    """
    text = radius_text(radii, radius, edges=edges)
    return f"at {text}" if text.startswith("ρ = ") else f"for {text}"


# -- realisations ----------------------------------------------------------------------


def _sqrtm_psd(w: np.ndarray) -> np.ndarray:
    lam, q = np.linalg.eigh(0.5 * (w + w.T))
    return (q * np.sqrt(np.clip(lam, 0, None))) @ q.T


@dataclass(frozen=True, eq=False)
class Problem:
    """The nominal data every bound and search uses (dense)."""

    design: ProtocolDesign
    edges: UncertainEdges
    lap_b: np.ndarray
    u: np.ndarray
    target: np.ndarray  # 1⊗θ
    f: np.ndarray  # (m, d, d): W_e^{1/2}

    @property
    def r0(self) -> np.ndarray:
        """u − L_B(1⊗θ): zero in exact arithmetic up to the rounding of x0 = k1·θ."""
        return self.u - self.lap_b @ self.target

    @property
    def n(self) -> int:
        """N·d."""
        return int(self.lap_b.shape[0])

    @property
    def d(self) -> int:
        """The weights' dimension d."""
        return int(self.design.topology.dim)

    def delta_l(self, deltas: np.ndarray) -> np.ndarray:
        """Σ_e E_i Δ_e D_eᵀ for the weight changes Δ_e (m, d, d)."""
        d, out = self.d, np.zeros((self.n, self.n))
        ed = self.edges
        for k in range(ed.m):
            i, j = int(ed.dst[k]) * d, int(ed.src[k]) * d
            out[i : i + d, i : i + d] += deltas[k]
            out[i : i + d, j : j + d] -= ed.s[k] * deltas[k]
        return out

    def deltas(self, es: np.ndarray) -> np.ndarray:
        """Δ_e = F_e E_e F_e for the normalised changes E_e (m, d, d)."""
        return np.einsum("kab,kbc,kcd->kad", self.f, es, self.f)

    def lap(self, es: np.ndarray) -> np.ndarray:
        """L_B(A') of the realisation with normalised changes E_e."""
        return self.lap_b + self.delta_l(self.deltas(es))

    def weights(self, es: np.ndarray) -> np.ndarray:
        """The realised A'_e = s_e (W_e + F E F), symmetrised."""
        a = self.edges.w + self.deltas(es)
        a = 0.5 * (a + np.transpose(a, (0, 2, 1)))
        return self.edges.s[:, None, None] * a


def dense_problem(des: ProtocolDesign) -> Problem:
    """The dense nominal data of a design (refused past the dense size)."""
    top = des.topology
    require_dense(top.nd, "robust brackets")
    ed = uncertain_edges(top)
    lap_b = des.grounded_laplacian()
    return Problem(
        des,
        ed,
        lap_b,
        des.input_vector(),
        np.tile(des.theta, top.n),
        np.array([_sqrtm_psd(w) for w in ed.w]).reshape(ed.w.shape),
    )


@dataclass(frozen=True)
class Realisation:
    """A point of the uncertainty set: its radius, the realised weights (edge order of
    :class:`UncertainEdges`) and what it attains."""

    radius: float
    weights: np.ndarray
    value: float

    def edges(self, top: Topology, edges: UncertainEdges) -> list[dict]:
        """The realisation as topology-file edges ``{from, to, weight}``.

        Parameters
        ----------
        top : Topology
            The nominal topology (labels).
        edges : UncertainEdges
            Its uncertain edges.

        Returns
        -------
        list of dict
        """
        lab = top.labels
        return [
            {"from": lab[int(j)], "to": lab[int(i)], "weight": a.tolist()}
            for i, j, a in zip(edges.dst, edges.src, self.weights, strict=True)
        ]


def realised_topology(top: Topology, edges: UncertainEdges, weights: np.ndarray) -> Topology:
    """The nominal topology with the uncertain edges' weights replaced.

    Parameters
    ----------
    top : Topology
        The nominal topology.
    edges : UncertainEdges
        Its uncertain edges.
    weights : numpy.ndarray
        (m, d, d) realised weights.

    Returns
    -------
    Topology
    """
    w = dict(top.weights)
    for i, j, a in zip(edges.dst, edges.src, weights, strict=True):
        w[(int(i), int(j))] = np.asarray(a, dtype=float)
    return Topology(top.labels, top.dim, w, name=top.name)


@dataclass(frozen=True)
class Bracket:
    """A certified end and a realisation attaining the other end (``lower <= upper``)."""

    lower: float | None
    upper: float | None
    realisation: Realisation | None
    certified: str  # "lower" or "upper": which end is proven
    method: str


__all__ = [
    "CHANNEL_FLOOR",
    "RADII_SHOWN",
    "Bracket",
    "Problem",
    "Realisation",
    "UncertainEdges",
    "channel_bound",
    "dense_problem",
    "pivot_columns",
    "radius_phrase",
    "radius_text",
    "realised_topology",
    "uncertain_edges",
    "whitening_basis",
]
