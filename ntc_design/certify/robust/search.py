"""Robust certification: Lemma 1's protocol when every weight is known only within a
relative Loewner interval.

**The set.** For a radius ρ ∈ [0, 1], a realisation A' keeps each weight's sign and lies in

    (1 − ρ)|A_ij| ⪯ |A'_ij| ⪯ (1 + ρ)|A_ij|,

equivalently ``|A'_ij| = F(I + E)F`` with ``F = |A_ij|^{1/2}``, E symmetric, ‖E‖₂ <= ρ (so
each weight keeps its sign and its kernel). The protocol (informed agents, B_i, δ, x0) stays
at its nominal design; only L changes, ``L_B(A') = L_B + Σ_e E_i Δ_e D_eᵀ`` with
``Δ_e = |A'_e| − |A_e|``, ``E_i = e_i ⊗ I_d`` and ``D_e = E_i − s_e E_j`` for the edge
e = (j → i) of sign s_e.

**Three brackets**, each a certified end and a realisation attaining the other:

* *decay* α: every realisation has ``min Re λ(L_B(A')) >= α_lower`` (quadratic stability
  with one S-procedure multiplier per edge, below); a hill-climbed realisation attains
  ``α_upper``;
* *consensus offset* ``‖x*(A') − 1⊗θ‖₂``: at most ``offset_upper`` for every realisation
  (an S-procedure bound on the equilibrium equation, below); a hill-climbed realisation
  attains ``offset_lower``. Only antagonistic weights move x*: ``D_eᵀ(1⊗θ) = (1 − s_e)θ``;
* *margin*: −L_B(A') Hurwitz for every realisation of radius ρ_lower (the decay LMI at
  α = 0); a realisation of radius ρ_upper is not Hurwitz (hill-climbed, or every weight
  vanishing at ρ = 1).

**Channels without square roots** (so that ``ntc verify`` re-checks them exactly). For an
edge with ``W = |A_e|``, ``w = Δ_e v`` lies in range(W) and ``w = W y`` with
``yᵀ W y = wᵀ W⁺ w <= ρ² vᵀ W v`` (as ``E² ⪯ ρ² I``). ``y`` is written ``V η`` with V the
pivot columns of W (an exact basis of its range). Then

* decay: ``Ψ = [[M − Σ τ_e ρ² D_e W_e D_eᵀ, P E_i W_e V_e], [·ᵀ, τ_e V_eᵀ W_e V_e]] ≻ 0``
  with ``M = P(L_B − αI) + (L_B − αI)ᵀP`` and P ≻ 0 proves ``min Re λ(L_B(A')) > α``
  for every realisation (S-procedure; Boyd, El Ghaoui, Feron & Balakrishnan, *Linear
  Matrix Inequalities in System and Control Theory*, SIAM 1994, §2.6.3 and §5.1);
* offset: with ``ξ = (z, η, 1)`` and z = x* − 1⊗θ, every realisation gives
  ``L_B z + Σ_e E_i W_e V_e η_e = 0`` and ``η_eᵀ V_eᵀ W_e V_e η_e <= ρ² ‖D_eᵀ(z + 1⊗θ)‖²_{W_e}``;
  ``Γ = γ·e eᵀ − zzᵀ-form − Σ λ_e g_e + sym(Aᵀ Y) ≻ 0`` (Finsler's lemma for the equation,
  λ_e >= 0) proves ``‖z‖² <= γ``, given that every L_B(A') is invertible (the decay
  bracket's certified end at the same ρ).

**Edges of radius 0** are not perturbed and get no channel: at ρ = 0, Ψ is the nominal
Lyapunov inequality P(L_B − αI) + (L_B − αI)ᵀP ≻ 0 and Γ bounds the nominal equilibrium,
so the brackets are the nominal figures (:func:`robust`). **A weight singular only by
rounding** (v vᵀ written in floating point: exactly it is full rank, even indefinite, by
1e−18) has no positive definite VᵀWV, so no Ψ could be ≻ 0; its channels bound the change
by W̄ = W + ηI ⪰ W instead (:func:`channel_bound`), a set that holds the one above.

Past ROBUST_MAX_ND the sparse bounds of :mod:`.robust_scale` are tightened up to
RICCATI_MAX_ND: decay and margin by the Riccati search (:mod:`.robust_are`), the offset by
the same S-procedure with the equation eliminated (:mod:`.robust_offset`).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from ...errors import InputError, format_seconds, require_radius, warn_user
from ...model import Topology
from ...numerics.linalg import require_dense
from ...present.rows import Table, fmt
from ...protocol import ProtocolDesign
from .lmi import _channels, _DecayLMI, _descend, _offset_sdp
from .realise import abscissa, climb, offset_of

#: Robust LMIs are solved up to this Nd (dense P; the S-procedure adds Σ rank(W_e) rows).
ROBUST_MAX_ND = 40  # dense LMIs up to here (one solve took 2.4 s at Nd = 36, 92 s at 75)
DEFAULT_RADIUS = 0.05
#: The work model of :func:`robust_seconds`, measured on a loaded 2-core machine: a
#: decay LMI with m unknowns (P and the τ_e) about DECAY_SECONDS·m² (8.1 s at Nd = 39,
#: m = 794), the offset SDP (Y and the λ_e) OFFSET_SECONDS·m² (49 s at m = 3198), the
#: Riccati brackets RICCATI_SECONDS·(Nd)³ (19 s at Nd = 120, 68 s at 198), the sparse
#: ones SPARSE_SECONDS per weight entry (N + E)·d² (62 s at N = 10⁵, d = 3), each plus
#: BASE_SECONDS (the realisation searches, the certificate's check).
DECAY_SECONDS = 1.3e-5
OFFSET_SECONDS = 5.5e-6
RICCATI_SECONDS = 1.2e-5
SPARSE_SECONDS = 3.5e-5
BASE_SECONDS = 5.0
#: A robust run estimated longer than LONG_SECONDS says how long before it starts; one
#: longer than MAX_SECONDS is refused.
LONG_SECONDS = 60.0
MAX_SECONDS = 3600.0


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


check_radius = require_radius  # the one radius check (errors.require_radius)

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
class _Problem:
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
        return int(self.lap_b.shape[0])

    @property
    def d(self) -> int:
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
        return np.einsum("kab,kbc,kcd->kad", self.f, es, self.f)

    def lap(self, es: np.ndarray) -> np.ndarray:
        return self.lap_b + self.delta_l(self.deltas(es))

    def weights(self, es: np.ndarray) -> np.ndarray:
        """The realised A'_e = s_e (W_e + F E F), symmetrised."""
        a = self.edges.w + self.deltas(es)
        a = 0.5 * (a + np.transpose(a, (0, 2, 1)))
        return self.edges.s[:, None, None] * a


def _problem(des: ProtocolDesign) -> _Problem:
    top = des.topology
    require_dense(top.nd, "robust brackets")
    ed = uncertain_edges(top)
    lap_b = des.grounded_laplacian()
    return _Problem(
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


# -- the brackets ----------------------------------------------------------------------------


def _worst(p: _Problem, rad: np.ndarray, objective: str, starts: int, seed: int) -> Realisation:
    """The realisation :func:`.robust_search.climb` finds, with what it attains (min Re λ, or the offset)."""
    es = climb(p, rad, objective, starts, seed)
    lap = p.lap(es)
    value = abscissa(lap) if objective == "decay" else offset_of(p, lap)
    return Realisation(float(np.max(rad, initial=0.0)), p.weights(es), value)


@dataclass(frozen=True)
class Bracket:
    """A certified end and a realisation attaining the other end (``lower <= upper``)."""

    lower: float | None
    upper: float | None
    realisation: Realisation | None
    certified: str  # "lower" or "upper": which end is proven
    method: str


@dataclass(frozen=True)
class RobustReport:
    """The three brackets at one radius, with the matrices that prove the certified ends
    (``lmi``: P, τ for the decay and margin LMIs; γ, λ, Y for the offset)."""

    design: ProtocolDesign
    radius: float  # the largest ρ_e (ρ itself when every edge has the same)
    radii: tuple[float, ...]  # ρ_e per uncertain edge (UncertainEdges order)
    nominal_decay: float
    decay: Bracket
    offset: Bracket
    margin: Bracket
    proofs: dict = field(repr=False)
    seconds: float = 0.0

    def table(self, title: str | None = None) -> Table:
        """The three brackets as the table every face shows.

        Parameters
        ----------
        title : str, optional
            The table's title.

        Returns
        -------
        ntc_design.present.rows.Table
        """

        num = functools.partial(fmt, digits=6)  # None shows as "—"
        top = self.design.topology
        d, o, m = (_proven_by(b.method) for b in (self.decay, self.offset, self.margin))
        rows = [
            ("decay rate min Re λ(L_B(A'))", num(self.decay.lower), num(self.decay.upper),
             f"lower proven ({d}); upper attained by a realisation"),
            ("consensus offset ‖x* − 1⊗θ‖₂", num(self.offset.lower), num(self.offset.upper),
             f"upper proven ({o}); lower attained by a realisation"),
            ("margin radius ρ", num(self.margin.lower), num(self.margin.upper),
             f"lower proven ({m} at α = 0); upper: a destabilising realisation"),
        ]  # fmt: skip
        ed = uncertain_edges(top)
        antag = int(np.sum(ed.s < 0))
        notes: tuple[str, ...] = (
            f"nominal decay rate {self.nominal_decay:.6g}; the protocol (informed agents, B_i, "
            f"δ = {self.design.delta:.6g}, x0) is kept at its nominal design",
            f"only the {antag} antagonistic weight(s) move the consensus point "
            "(D_eᵀ(1⊗θ) = 0 on cooperative edges)",
        )
        if len(set(self.radii)) > 1:  # what each bracket is about, said where it differs
            notes += (
                "the decay and offset brackets hold for the per-edge radii; the margin radius "
                "is one ρ on every edge",
            )
        phrase = radius_phrase(self.radii, self.radius, ed.labels(top))
        return Table.build(
            title or f"{top.name or 'topology'}: robust brackets {phrase}",
            ("bracket", "lower", "upper", "which end is proven"),
            rows,
            notes,
        )

    def to_dict(self) -> dict:
        """The report in the ``--json`` form: radius, decay, offset and margin, each
        realisation as topology-file edges.

        Returns
        -------
        dict
        """
        top = self.design.topology
        ed = uncertain_edges(top)

        def real(b: Bracket) -> list[dict] | None:
            return None if b.realisation is None else b.realisation.edges(top, ed)

        uniform = len(set(self.radii)) <= 1
        return {
            "radius": self.radius if uniform else list(self.radii),
            "nominal_decay": self.nominal_decay,
            "decay": {
                "lower": self.decay.lower,
                "upper": self.decay.upper,
                "realization": real(self.decay),
                "method": self.decay.method,
            },
            "offset": {
                "lower": self.offset.lower,
                "upper": self.offset.upper,
                "realization": real(self.offset),
                "method": self.offset.method,
            },
            "margin": {
                "lower": self.margin.lower,
                "upper": self.margin.upper,
                "destabilizing": real(self.margin),
                "realization_radius": None
                if self.margin.realisation is None
                else self.margin.realisation.radius,
                "method": self.margin.method,
            },
        }


def _proven_by(method: str) -> str:
    """A short name for the method that proves a bracket's end (the table's last column)."""
    for key, name in (
        ("Riccati", "Riccati search"),
        ("comparison", "comparison bound"),
        ("dominance", "block dominance"),
        ("Finsler", "S-procedure"),
        ("eliminated", "S-procedure, reduced"),
    ):
        if key in method:
            return name
    return "LMI"


def robust_seconds(
    design: ProtocolDesign, bisection_steps: int = 3, margin: bool = True
) -> tuple[float, str]:
    """The estimated time of :func:`robust` before it starts (the model of
    :data:`DECAY_SECONDS` and its peers; within a factor of a few): what is solved, by
    size.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    bisection_steps : int, optional
        As for :func:`robust`.
    margin : bool, optional
        Whether the margin bracket is computed too.

    Returns
    -------
    (float, str)
        Seconds, and what they are spent on.
    """
    top = design.topology
    nd_ = top.nd
    if nd_ > ROBUST_MAX_ND:
        from .are import RICCATI_MAX_ND

        entries = (top.n + int(top.edge_arrays.rows.size)) * top.dim**2
        sparse = SPARSE_SECONDS * entries
        if nd_ > RICCATI_MAX_ND:
            return BASE_SECONDS + sparse, f"sparse bounds over {entries:.3g} weight entries"
        return (
            BASE_SECONDS + sparse + RICCATI_SECONDS * nd_**3,
            f"Riccati searches on N·d = {nd_}",
        )
    ed = uncertain_edges(top)
    rank = sum(len(p) for p in ed.pivots)
    m_decay = nd_ * (nd_ + 1) // 2 + ed.m
    m_offset = nd_ * (nd_ + rank + 1) + ed.m + 1
    solves = (1 + bisection_steps) * (2 if margin else 1)  # the first fraction, bisection
    seconds = BASE_SECONDS + solves * DECAY_SECONDS * m_decay**2 + OFFSET_SECONDS * m_offset**2
    return seconds, (
        f"about {solves} decay LMIs of {m_decay} unknowns and an offset SDP of {m_offset}, "
        f"dense, on N·d = {nd_}"
    )


def check_robust_work(
    design: ProtocolDesign, bisection_steps: int = 3, margin: bool = True
) -> None:
    """Refuse a robust run estimated above :data:`MAX_SECONDS` (one line naming the size);
    warn with the estimate above :data:`LONG_SECONDS`.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    bisection_steps : int, optional
        As for :func:`robust`.
    margin : bool, optional
        Whether the margin bracket is computed too.

    Raises
    ------
    InputError
        The estimate exceeds :data:`MAX_SECONDS`.
    """
    seconds, what = robust_seconds(design, bisection_steps, margin)
    line = f"robust: roughly {format_seconds(seconds)} ({what})"
    if not seconds <= MAX_SECONDS:
        raise InputError(
            f"{line}, more than the limit of {format_seconds(MAX_SECONDS)}; the network is "
            "too large for the robust brackets"
        )
    if seconds > LONG_SECONDS:
        warn_user(f"{line}; Ctrl-C stops cleanly", UserWarning)


def robust(
    design: ProtocolDesign,
    radius: float = DEFAULT_RADIUS,
    starts: int = 6,
    seed: int = 0,
    bisection_steps: int = 3,
    margin: bool = True,
) -> RobustReport:
    """The decay, offset and margin brackets of a Lemma 1 design under relative weight
    uncertainty of radius ρ (see the module docstring for the set and the methods).

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design (its protocol is kept for every realisation).
    radius : float, optional
        ρ in [0, 1) for every edge whose file gives no ``uncertainty:`` of its own
        (:attr:`ntc_design.model.Topology.uncertainty`).
    starts : int, optional
        Random starts of the realisation searches (besides the nominal point and ±ρI).
    seed : int, optional
        Their seed (SeedSequence).
    bisection_steps : int, optional
        Bisection steps on α and on ρ after the first fraction of the attained end that
        verifies (:data:`FRACTIONS`).
    margin : bool, optional
        Also the margin bracket (the most expensive; a sweep over ρ needs it once).

    Returns
    -------
    RobustReport
        At ρ = 0 (every edge unperturbed) the brackets are the nominal figures: the decay's
        proven end within ``(1 − FRACTIONS[0])/2**bisection_steps`` of the nominal rate,
        relative (6.25e−4 with the defaults), its other end the nominal rate; the offset's
        proven end within 1e−4·‖1⊗θ‖ of the nominal offset (the SDP's strict margin).
        Above :data:`ROBUST_MAX_ND`, the sparse brackets of
        :func:`ntc_design.certify.robust.scale.robust_scale`, up to
        :data:`ntc_design.certify.robust.are.RICCATI_MAX_ND` tightened by the Riccati
        search and the dense realisation searches; the Riccati proofs are kept for
        the certificate (:func:`ntc_design.certify.kinds.robust.robust_certificate`).

    Raises
    ------
    InputError
        A bad radius, a nominal −L_B that is not Hurwitz, or work estimated above
        :data:`MAX_SECONDS` (:func:`check_robust_work`).

    Examples
    --------
    >>> import ntc_design as nd
    >>> d = nd.design(nd.load(nd.example_path("g1.yaml")), [1, 2, -1], thresholds=False)
    >>> rep = robust(d, 0.05, starts=0, bisection_steps=2)
    >>> rep.decay.lower <= rep.decay.upper <= rep.nominal_decay + 1e-9
    True
    """
    t0 = time.perf_counter()
    rho = check_radius(radius)
    check_robust_work(design, bisection_steps, margin)
    if design.topology.nd > ROBUST_MAX_ND:  # sparse bounds, tightened by Riccati if dense
        from .are import RICCATI_MAX_ND
        from .scale import robust_scale

        rep = robust_scale(design, rho)
        if design.topology.nd <= RICCATI_MAX_ND:
            rep = _riccati_brackets(rep, rho, starts, seed, bisection_steps, margin, t0)
        return rep
    p = _problem(design)
    rad = p.edges.radii(design.topology, rho)
    rmax = float(np.max(rad, initial=0.0))
    alpha0 = abscissa(p.lap_b)
    if not alpha0 > 0:
        raise InputError(
            f"robust: the nominal −L_B is not Hurwitz (min Re λ(L_B) = {alpha0:.6g}); "
            "certify the nominal design first"
        )
    ch = _channels(p)
    lmi = _DecayLMI(p, ch)
    # decay: the realisation first, so that the bisection runs below what it attains
    wd = _worst(p, rad, "decay", starts, seed)
    a_lo, dec = _descend(lambda a: lmi(a, rad), max(wd.value, 0.0), bisection_steps)
    decay = Bracket(
        a_lo if dec is not None else None,
        wd.value,
        wd,
        "lower",
        "quadratic stability, one S-procedure multiplier per edge (Clarabel); realisation "
        "by projected gradient on the eigenvalue",
    )
    # offset
    off = _offset_sdp(p, ch, rad) if dec is not None else None  # x* exists: decay proven
    wo = _worst(p, rad, "offset", starts, seed + 1)
    offset = Bracket(
        wo.value,
        None if off is None else math.sqrt(off[0]),
        wo,
        "upper",
        "S-procedure on the equilibrium equation with Finsler's multiplier (Clarabel); "
        "realisation by projected gradient",
    )
    # margin
    destab = _destabilising(p, rmax, starts, seed + 2) if margin else None
    r_top = 1.0 if destab is None else destab.radius
    r_lo, mar = _descend(lambda r: lmi(0.0, r), r_top, bisection_steps) if margin else (0.0, None)
    margin_b = Bracket(
        r_lo if mar is not None else None,
        None if destab is None else destab.radius,
        destab,
        "lower",
        "the decay LMI at α = 0, bisection on ρ; destabilising realisation by bisection on "
        "ρ with the eigenvalue search, else every weight vanishing at ρ = 1",
    )
    proofs = {"decay": dec, "alpha": a_lo, "offset": off, "margin": mar, "margin_radius": r_lo}
    return RobustReport(
        design,
        rmax,
        tuple(rad.tolist()),
        alpha0,
        decay,
        offset,
        margin_b,
        proofs,
        time.perf_counter() - t0,
    )


def robust_sweep(design: ProtocolDesign, radii, **options: Any) -> list[RobustReport]:
    """The decay and offset brackets at each radius (one :func:`robust` each, without the
    margin), for a figure of the brackets against ρ.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    radii : sequence of float
        The radii ρ, each in [0, 1).
    **options
        ``starts``, ``seed``, ``bisection_steps`` of :func:`robust`.

    Returns
    -------
    list of RobustReport

    Raises
    ------
    InputError
        A bad radius, or a nominal −L_B that is not Hurwitz.
    """
    return [robust(design, float(r), margin=False, **options) for r in radii]


def _riccati_brackets(
    rep: RobustReport, rho: float, starts: int, seed: int, steps: int, margin: bool, t0: float
) -> RobustReport:
    """The sparse report ``rep`` of a design of at most RICCATI_MAX_ND, tightened: decay
    and margin lower ends by the Riccati search (:mod:`.robust_are`, proven in the
    process), the attained ends by the dense searches; each end keeps the better of the
    two methods, and says which."""
    from ..dense import lap_b_float
    from .are import RiccatiSearch
    from .offset import offset_search

    des = rep.design
    p = _problem(des)
    rad = p.edges.radii(des.topology, rho)
    rmax = float(np.max(rad, initial=0.0))
    lap = lap_b_float(des.topology, des.B, des.delta)
    search = RiccatiSearch(*lap, p.edges, p.d)
    proofs: dict[str, Any] = dict.fromkeys(("decay", "alpha", "offset", "margin"))
    proofs["margin_radius"] = 0.0
    riccati = "quadratic stability with one multiplier per edge, P by a Riccati equation "
    riccati += "alternating with the multipliers (proven by verified Cholesky)"
    wd = _worst(p, rad, "decay", starts, seed)
    dec = rep.decay
    if dec.upper is None or wd.value < dec.upper:
        dec = Bracket(dec.lower, wd.value, wd, "lower", dec.method)
    a_lo, got = _descend(lambda a: search(a, rad), max(float(dec.upper or 0.0), 0.0), steps)
    if got is not None:  # kept for the certificate even when dominance proves more
        proofs.update(decay=got, alpha=a_lo)
    if got is not None and (dec.lower is None or a_lo > dec.lower):
        dec = Bracket(a_lo, dec.upper, dec.realisation, "lower", riccati + "; upper: a "
                      "realisation by projected gradient on the eigenvalue")  # fmt: skip
    off = rep.offset
    wo = _worst(p, rad, "offset", starts, seed + 1)
    if off.lower is None or wo.value > off.lower:
        off = Bracket(wo.value, off.upper, wo, "upper", off.method.split("; lower")[0]
                      + "; lower: a realisation by projected gradient")  # fmt: skip
    # the S-procedure offset, when every L_B(A') is proven invertible (decay, any method)
    got_o = offset_search(des, lap)(rad) if dec.lower is not None else None
    if got_o is not None and proofs["decay"] is not None:  # the certificate needs both
        proofs["offset"] = (got_o[0], got_o[1], None)
    if got_o is not None and (off.upper is None or math.sqrt(got_o[0]) < off.upper):
        off = Bracket(off.lower, math.sqrt(got_o[0]), off.realisation, "upper",
                      "S-procedure on the equilibrium equation with the equation eliminated "
                      "(one multiplier per edge, CVXOPT; proven by verified Cholesky); "
                      "lower: a realisation by projected gradient")  # fmt: skip
    mar = rep.margin
    if margin:
        destab = _destabilising(p, rmax, starts, seed + 2)
        if destab is not None and (mar.upper is None or destab.radius < mar.upper):
            mar = Bracket(mar.lower, destab.radius, destab, "lower", mar.method)
        r_lo, got_m = _descend(lambda r: search(0.0, r), float(mar.upper or 1.0), steps)
        if got_m is not None:
            proofs.update(margin=got_m, margin_radius=r_lo)
        if got_m is not None and (mar.lower is None or r_lo > mar.lower):
            mar = Bracket(r_lo, mar.upper, mar.realisation, "lower", "the Riccati search at "
                          "α = 0, bisection on ρ; upper: " + mar.method.split("upper: ")[-1])  # fmt: skip
    proofs["method"] = "riccati"  # the certificate's claims are checked in the Schur form
    return RobustReport(
        des, rep.radius, rep.radii, rep.nominal_decay, dec, off, mar, proofs,
        time.perf_counter() - t0,
    )  # fmt: skip


def _destabilising(p: _Problem, r_lo: float, starts: int, seed: int) -> Realisation | None:
    """The smallest radius (bisection in [r_lo, 1)) at which the eigenvalue search finds a
    realisation with min Re λ <= 0; else the all-vanishing realisation at ρ = 1 when it is
    not Hurwitz; None when neither."""
    m, d = p.edges.m, p.d

    def found(r: float) -> np.ndarray | None:
        es = climb(p, r, "decay", starts, seed)
        return es if abscissa(p.lap(es)) <= 0 else None

    top = found(1.0 - 1e-6)
    if top is None:
        es1 = -np.broadcast_to(np.eye(d), (m, d, d)).copy()
        lap1 = p.lap(es1)
        if abscissa(lap1) <= 1e-12 * max(1.0, float(np.max(np.abs(p.lap_b)))):
            return Realisation(1.0, p.weights(es1) * 0.0, abscissa(lap1))
        return None
    lo, hi, best = r_lo, 1.0 - 1e-6, top
    for _ in range(10):
        mid = 0.5 * (lo + hi)
        got = found(mid)
        if got is None:
            lo = mid
        else:
            hi, best = mid, got
    return Realisation(hi, p.weights(best), abscissa(p.lap(best)))


__all__ = [
    "DEFAULT_RADIUS",
    "ROBUST_MAX_ND",
    "Bracket",
    "Realisation",
    "RobustReport",
    "UncertainEdges",
    "abscissa",
    "CHANNEL_FLOOR",
    "channel_bound",
    "whitening_basis",
    "check_radius",
    "check_robust_work",
    "radius_phrase",
    "radius_text",
    "pivot_columns",
    "realised_topology",
    "robust",
    "robust_seconds",
    "robust_sweep",
    "uncertain_edges",
]
