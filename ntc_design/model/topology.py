"""The network topology (Niu & Wu, Sec. 2): agents, edges and their d×d symmetric
weights, with each weight's definiteness class.

Conventions: ``A_ij`` is the d×d symmetric weight of the directed edge from agent j to
agent i (i listens to j). Agents are indexed 0..N-1 internally and shown by their labels.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sparse

from ..errors import InputError
from ..io import files
from ..io.edgelist import EdgeListData
from ..numerics.linalg import (
    CODE_DEFINITE,
    CODE_SIGN,
    DEF_CODES,
    MAGNITUDE_EXP,
    SYM_RTOL,
    Definiteness,
    classify_codes,
    require_dense,
)
from ..present.rows import Table, set_text
from ..present.svg import network_svg

Label = files.Label
_INDEF = 5  # code of Definiteness.INDEFINITE in linalg.DEF_CODES


@dataclass(frozen=True, eq=False)
class EdgeArrays:
    """The listed weights as arrays (internal, 0-based): edge k is ``cols[k] -> rows[k]``
    with weight ``w[k] = A_{rows[k], cols[k]}`` and class ``DEF_CODES[codes[k]]``."""

    rows: np.ndarray
    cols: np.ndarray
    w: np.ndarray
    codes: np.ndarray

    @cached_property
    def sign(self) -> np.ndarray:
        return CODE_SIGN[self.codes].astype(float)

    @cached_property
    def abs_w(self) -> np.ndarray:
        """|A_ij| = sgn(A_ij)·A_ij per edge."""
        return self.sign[:, None, None] * self.w


@dataclass(frozen=True, eq=False)
class Topology:
    """A directed signed matrix-weighted graph G = (V, E, A).

    ``weights[(i, j)]`` is ``A_ij`` (edge j -> i), 0-based agent indices. Every weight is
    symmetric and of one sign (PD, PSD, ND, NSD or zero); construction checks this and
    raises :class:`InputError` naming the edge otherwise.
    """

    labels: tuple[Label, ...]
    dim: int
    weights: Mapping[tuple[int, int], np.ndarray]
    name: str | None = None
    source: str | None = None
    fields: Mapping[tuple[int, int], str] = field(default_factory=dict, repr=False)
    #: Relative radius ρ_e of an edge's Loewner interval, where the file gives one (an
    #: ``uncertainty:`` value; :mod:`ntc_design.certify.robust.search`). Not part of the nominal
    #: network: left out of :meth:`to_dict` and of the topology hash.
    uncertainty: Mapping[tuple[int, int], float] = field(
        default_factory=dict, repr=False, compare=False
    )
    #: Message loss p_e of an edge in the digital protocol, where the file gives one (a
    #: ``loss:`` value; :mod:`ntc_design.protocol.loss`). Not part of the nominal network:
    #: left out of :meth:`to_dict` and of the topology hash.
    loss: Mapping[tuple[int, int], float] = field(default_factory=dict, repr=False, compare=False)
    _arrays: EdgeArrays = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n, d = len(self.labels), self.dim
        if n < 1 or d < 1:
            raise self._error("topology", "needs at least one agent and dim >= 1")
        keys = list(self.weights.keys())
        e = len(keys)
        ij = np.array(keys, dtype=np.int64).reshape(e, 2)
        rows, cols = ij[:, 0], ij[:, 1]
        bad = np.flatnonzero((rows < 0) | (rows >= n) | (cols < 0) | (cols >= n))
        if bad.size:
            k = keys[bad[0]]
            raise self._error(self.edge_field(*k), "agent index out of range")
        loop = np.flatnonzero(rows == cols)
        if loop.size:
            k = keys[loop[0]]
            raise self._error(self.edge_field(*k), "self-loop (an agent cannot listen to itself)")
        w = self._stack(keys, d)
        # Checks vectorised over all edges; the first offending edge is named.
        finite = np.all(np.isfinite(w), axis=(1, 2))
        asym = np.max(np.abs(w - w.transpose(0, 2, 1)), axis=(1, 2), initial=0.0)
        scale = np.max(np.abs(w), axis=(1, 2), initial=0.0)
        # nonzero magnitudes in [2^-MAGNITUDE_EXP, 2^MAGNITUDE_EXP]: beyond, the sums and
        # eigenvalues of the design overflow or underflow (and no proof can bound them)
        mag = np.abs(np.where(np.isfinite(w), w, 0.0))
        tiny = np.min(np.where(mag > 0, mag, np.inf), axis=(1, 2), initial=np.inf)
        out = (scale > 2.0**MAGNITUDE_EXP) | (tiny < 2.0**-MAGNITUDE_EXP)
        codes = (
            classify_codes(np.where(np.isfinite(w), w, 0.0) * ~out[:, None, None])
            if e
            else np.zeros(0, dtype=np.int8)
        )
        for k in np.flatnonzero(~finite | out | (asym > SYM_RTOL * scale) | (codes == _INDEF)):
            f = self.edge_field(*keys[k])
            if not finite[k]:
                raise self._error(f, "weight has a NaN or infinite entry")
            if out[k]:
                x = scale[k] if scale[k] > 2.0**MAGNITUDE_EXP else tiny[k]
                raise self._error(
                    f,
                    f"weight has an entry of magnitude {x:.3g}, outside "
                    f"[2^-{MAGNITUDE_EXP}, 2^{MAGNITUDE_EXP}] ≈ [5.5e-76, 1.8e75] (or 0): "
                    "its sums and eigenvalues would overflow or underflow; rescale the weights",
                )
            if asym[k] > SYM_RTOL * scale[k]:
                raise self._error(f, "weight is not symmetric (A_ij must equal A_ijᵀ)")
            lam = np.linalg.eigvalsh(0.5 * (w[k] + w[k].T))
            raise self._error(
                f,
                f"weight is indefinite (eigenvalues {lam[0]:.4g} .. {lam[-1]:.4g}); "
                "a weight must be positive or negative (semi)definite",
            )
        w.setflags(write=False)
        pos = {k: m for m, k in enumerate(keys)} if self.uncertainty else {}
        for key in self.uncertainty:
            if key not in pos:
                raise self._error(self.edge_field(*key), "uncertainty on a missing edge")
            if not np.any(w[pos[key]]):
                raise self._error(
                    self.edge_field(*key),
                    "uncertainty on a zero weight (its interval is {0}; remove the value)",
                )
        for key in self.loss:
            if key not in self.weights:
                raise self._error(self.edge_field(*key), "loss on a missing edge")
        object.__setattr__(self, "weights", {k: w[m] for m, k in enumerate(keys)})
        object.__setattr__(self, "_arrays", EdgeArrays(rows, cols, w, codes))

    def _stack(self, keys: list, d: int) -> np.ndarray:
        """All weights as one (E, d, d) float array (a copy); a bad shape or entry is
        reported for its edge."""
        vals = list(self.weights.values())
        if not vals:
            return np.zeros((0, d, d))
        try:
            w = np.array(vals, dtype=float)
            if w.shape == (len(keys), d, d):
                return w
        except (TypeError, ValueError):
            pass
        for k, a in zip(keys, vals, strict=True):
            try:
                a = np.array(a, dtype=float)
            except (TypeError, ValueError):
                raise self._error(self.edge_field(*k), "weight has a non-numeric entry") from None
            if a.shape != (d, d):
                raise self._error(
                    self.edge_field(*k), f"weight has shape {a.shape}, expected ({d}, {d})"
                )
        raise self._error("edges", "weights could not be read")  # unreachable

    # -- construction -------------------------------------------------------------
    @classmethod
    def from_edges(
        cls,
        n_or_labels: int | Iterable[Label],
        dim: int,
        edges: Iterable[tuple[Label, Label, np.ndarray]],
        name: str | None = None,
    ) -> Topology:
        """Build from ``(from_label, to_label, A_ij)`` triples (edge j -> i).

        Parameters
        ----------
        n_or_labels : int or iterable of label
            The agent labels, or N for the labels 1..N.
        dim : int
            The weight size d.
        edges : iterable of (label, label, array_like)
            ``(j, i, A_ij)`` for each edge j -> i.
        name : str, optional
            The topology's name.

        Returns
        -------
        Topology
            The validated topology.

        Raises
        ------
        InputError
            An unknown label, a duplicated edge, or a weight that is not symmetric and of
            one sign.
        """
        if isinstance(n_or_labels, int):
            labels: tuple[Label, ...] = tuple(range(1, n_or_labels + 1))
        else:
            labels = tuple(n_or_labels)
        index = {str(a): k for k, a in enumerate(labels)}
        weights: dict[tuple[int, int], np.ndarray] = {}
        for j, i, a in edges:
            f = f"edge {j}->{i}"
            if str(j) not in index or str(i) not in index:
                raise InputError("unknown agent label", field=f)
            key = (index[str(i)], index[str(j)])
            if key in weights:
                raise InputError("duplicated edge", field=f)
            weights[key] = np.asarray(a, dtype=float)
        return cls(labels, dim, weights, name=name)

    @classmethod
    def from_arrays(
        cls,
        labels: Iterable[Label],
        dim: int,
        rows: np.ndarray,
        cols: np.ndarray,
        weights: np.ndarray,
        name: str | None = None,
        source: str | None = None,
        uncertainty: np.ndarray | None = None,
        loss: np.ndarray | None = None,
    ) -> Topology:
        """Build from arrays: edge k is ``cols[k] -> rows[k]`` (0-based agent indices)
        with weight ``weights[k] = A_{rows[k], cols[k]}``.

        Parameters
        ----------
        labels : iterable of label
            The agent labels, in index order.
        dim : int
            The weight size d.
        rows, cols : numpy.ndarray
            0-based target and source index of each edge.
        weights : numpy.ndarray
            The weights, shape (E, d, d).
        name : str, optional
            The topology's name.
        source : str, optional
            The file it came from, for messages.
        uncertainty : numpy.ndarray, optional
            Per edge, the relative radius ρ_e of its weight (NaN: none given).
        loss : numpy.ndarray, optional
            Per edge, its message loss p_e in the digital protocol (NaN: none given).

        Returns
        -------
        Topology
            The validated topology.

        Raises
        ------
        InputError
            A duplicated edge, a weight that is not symmetric and of one sign, or an
            uncertainty on a zero weight.
        """
        rows = np.asarray(rows, dtype=np.int64)
        cols = np.asarray(cols, dtype=np.int64)
        w = np.asarray(weights, dtype=float)
        keys = list(zip(rows.tolist(), cols.tolist(), strict=True))
        mapping = dict(zip(keys, w, strict=True))
        if len(mapping) != len(keys):
            raise InputError("duplicated edge", field=f"{source + ': ' if source else ''}edges")
        unc: dict[tuple[int, int], float] = {}
        if uncertainty is not None:
            u = np.asarray(uncertainty, dtype=float)
            unc = {keys[k]: float(u[k]) for k in np.flatnonzero(~np.isnan(u)).tolist()}
        lost: dict[tuple[int, int], float] = {}
        if loss is not None:
            lv = np.asarray(loss, dtype=float)
            lost = {keys[k]: float(lv[k]) for k in np.flatnonzero(~np.isnan(lv)).tolist()}
        return cls(
            tuple(labels), dim, mapping, name=name, source=source, uncertainty=unc, loss=lost
        )

    @classmethod
    def from_data(cls, data) -> Topology:
        """Build from a parsed topology file or ``.npz`` edge list.

        Parameters
        ----------
        data : ntc_design.io.files.TopologyData or ntc_design.io.edgelist.EdgeListData
            As :func:`ntc_design.io.files.parse_topology` or
            :func:`ntc_design.io.edgelist.read_npz` returns it.

        Returns
        -------
        Topology
            The validated topology (messages name the file's edges).
        """
        if isinstance(data, EdgeListData):
            return cls.from_arrays(
                data.labels,
                data.dim,
                data.rows,
                data.cols,
                data.w,
                data.name,
                data.source,
                data.uncertainty,
                data.loss,
            )
        index = {str(a): k for k, a in enumerate(data.labels)}
        weights, fields, unc, lost = {}, {}, {}, {}
        for e in data.edges:
            key = (index[str(e.target)], index[str(e.source)])
            weights[key] = e.weight
            fields[key] = e.field
            rho = e.uncertainty if e.uncertainty is not None else data.uncertainty
            if rho is not None and (e.uncertainty is not None or np.any(e.weight)):
                unc[key] = rho  # a file-wide default skips zero weights
            if getattr(e, "loss", None) is not None:
                lost[key] = e.loss
        return cls(data.labels, data.dim, weights, data.name, data.source, fields, unc, lost)

    # -- basic accessors ----------------------------------------------------------
    @property
    def edge_arrays(self) -> EdgeArrays:
        """Every listed weight as arrays (0-based indices, in listing order)."""
        return self._arrays

    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)

    @property
    def nd(self) -> int:
        """N·d, the size of the stacked state."""
        return self.n * self.dim

    def edge_field(self, i: int, j: int) -> str:
        """How messages name the edge j -> i (as the file wrote it, when known).

        Parameters
        ----------
        i, j : int
            0-based target and source indices.

        Returns
        -------
        str
            E.g. ``"edge 2->1"``.
        """
        if (i, j) in self.fields:
            return self.fields[(i, j)]
        lab = self.labels
        if 0 <= i < len(lab) and 0 <= j < len(lab):
            return f"edge {lab[j]}->{lab[i]}"
        return f"edge {j}->{i}"

    def _error(self, f: str, msg: str) -> InputError:
        return InputError(msg, field=f"{self.source}: {f}" if self.source else f)

    @cached_property
    def _label_index(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for k, a in enumerate(self.labels):
            out.setdefault(str(a), k)
        return out

    def index(self, label: Label) -> int:
        """0-based index of an agent label (O(1)).

        Parameters
        ----------
        label : int or str
            An agent label (compared as text).

        Returns
        -------
        int
            Its index.

        Raises
        ------
        InputError
            The label is not an agent's.
        """
        k = self._label_index.get(str(label))
        if k is None:
            raise InputError(f"unknown agent label {label!r}")
        return k

    def weight(self, i: int, j: int) -> np.ndarray:
        """The weight A_ij of the edge j -> i.

        Parameters
        ----------
        i, j : int
            0-based target and source indices.

        Returns
        -------
        numpy.ndarray
            A_ij, d×d (zero when there is no edge j -> i).
        """
        a = self.weights.get((i, j))
        return a if a is not None else np.zeros((self.dim, self.dim))

    @cached_property
    def classes(self) -> dict[tuple[int, int], Definiteness]:
        """Definiteness class of every listed weight."""
        ea = self._arrays
        return {
            (int(i), int(j)): DEF_CODES[c]
            for i, j, c in zip(ea.rows.tolist(), ea.cols.tolist(), ea.codes.tolist(), strict=True)
        }

    def sign(self, i: int, j: int) -> int:
        """The matrix sign sgn(A_ij) (Niu & Wu, Sec. 2.1).

        Parameters
        ----------
        i, j : int
            0-based target and source indices.

        Returns
        -------
        int
            1 for A_ij ⪰ 0, −1 for A_ij ⪯ 0 (nonzero), 0 for no edge or a zero weight.
        """
        c = self.classes.get((i, j))
        return c.sign if c is not None else 0

    def abs_weight(self, i: int, j: int) -> np.ndarray:
        """|A_ij| = sgn(A_ij)·A_ij (Niu & Wu, Sec. 2.1).

        Parameters
        ----------
        i, j : int
            0-based target and source indices.

        Returns
        -------
        numpy.ndarray
            |A_ij|, d×d, positive semidefinite.
        """
        return self.sign(i, j) * self.weight(i, j)

    @cached_property
    def edges(self) -> tuple[tuple[int, int], ...]:
        """Edges (i, j) with sgn(A_ij) ≠ 0, i.e. j -> i, in a stable order."""
        ea = self._arrays
        k = np.flatnonzero(CODE_SIGN[ea.codes] != 0)
        order = np.lexsort((ea.cols[k], ea.rows[k]))
        return tuple(zip(ea.rows[k][order].tolist(), ea.cols[k][order].tolist(), strict=True))

    @cached_property
    def _adjacency(self) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
        """Signed agent adjacency (entry (i, j) = sgn(A_ij)) by rows and by columns."""
        ea = self._arrays
        sg = CODE_SIGN[ea.codes]
        k = sg != 0
        a = sparse.csr_matrix(
            (sg[k].astype(np.int8), (ea.rows[k], ea.cols[k])), shape=(self.n, self.n)
        )
        a.sort_indices()
        at = a.T.tocsr()
        at.sort_indices()
        return a, at

    def in_neighbours(self, i: int) -> list[int]:
        """The in-neighbours N_i = {j : sgn(A_ij) ≠ 0} (Niu & Wu, Sec. 2.2).

        Parameters
        ----------
        i : int
            0-based agent index.

        Returns
        -------
        list of int
            0-based indices, ascending.
        """
        a = self._adjacency[0]
        return a.indices[a.indptr[i] : a.indptr[i + 1]].tolist()

    def out_neighbours(self, i: int) -> list[int]:
        """The out-neighbours N'_i = {j : sgn(A_ji) ≠ 0} (Niu & Wu, Sec. 2.2).

        Parameters
        ----------
        i : int
            0-based agent index.

        Returns
        -------
        list of int
            0-based indices, ascending.
        """
        a = self._adjacency[1]
        return a.indices[a.indptr[i] : a.indptr[i + 1]].tolist()

    def omega(self, i: int) -> list[int]:
        """Ω_i = {j : sgn(A_ij) = −1}: in-neighbours with an antagonistic edge into i
        (Niu & Wu, Sec. 2.2).

        Parameters
        ----------
        i : int
            0-based agent index.

        Returns
        -------
        list of int
            0-based indices, ascending.
        """
        a = self._adjacency[0]
        sl = slice(a.indptr[i], a.indptr[i + 1])
        return a.indices[sl][a.data[sl] < 0].tolist()

    def gamma(self, i: int) -> list[int]:
        """Γ_i = {j : sgn(A_ij) = +1}: in-neighbours with a cooperative edge into i
        (Niu & Wu, Sec. 2.2).

        Parameters
        ----------
        i : int
            0-based agent index.

        Returns
        -------
        list of int
            0-based indices, ascending.
        """
        a = self._adjacency[0]
        sl = slice(a.indptr[i], a.indptr[i + 1])
        return a.indices[sl][a.data[sl] > 0].tolist()

    @cached_property
    def antagonised(self) -> tuple[int, ...]:
        """U = {i : ∃ j, sgn(A_ij) = -1}: agents with at least one negative in-edge."""
        ea = self._arrays
        return tuple(np.unique(ea.rows[CODE_SIGN[ea.codes] < 0]).tolist())

    @cached_property
    def degree_sums(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per agent (arrays of shape (N, d, d)): ``Σ_{N_i}|A_ij|`` (in),
        ``Σ_{N'_i}|A_ji|`` (out) and ``Σ_{Ω_i}|A_ij|`` (antagonistic in-weight), summed
        in edge order."""
        ea, d = self._arrays, self.dim
        inn = np.zeros((self.n, d, d))
        out = np.zeros((self.n, d, d))
        ant = np.zeros((self.n, d, d))
        np.add.at(inn, ea.rows, ea.abs_w)
        np.add.at(out, ea.cols, ea.abs_w)
        neg = CODE_SIGN[ea.codes] < 0
        np.add.at(ant, ea.rows[neg], ea.abs_w[neg])
        for x in (inn, out, ant):
            x.setflags(write=False)
        return inn, out, ant

    def definite_graph(self) -> sparse.csr_matrix:
        """Agent graph of the definite (PD or ND) edges (the edges a positive-negative
        path may use, Niu & Wu, Definition 3).

        Returns
        -------
        scipy.sparse.csr_matrix
            N×N, entry (j, i) = 1 for a definite edge j -> i.
        """
        ea = self._arrays
        k = CODE_DEFINITE[ea.codes]
        return sparse.csr_matrix(
            (np.ones(int(k.sum()), dtype=np.int8), (ea.cols[k], ea.rows[k])),
            shape=(self.n, self.n),
        )

    @cached_property
    def _laplacian(self) -> np.ndarray:
        lap = signed_laplacian(self)
        lap.setflags(write=False)
        return lap

    def laplacian(self) -> np.ndarray:
        """The signed Laplacian L (Niu & Wu, Sec. 2.3); see :func:`signed_laplacian`.

        Returns
        -------
        numpy.ndarray
            L, Nd×Nd (built once, a copy is returned).

        Raises
        ------
        InputError
            Above ``linalg.DENSE_MAX_BYTES``: use :meth:`laplacian_sparse`.
        """
        return self._laplacian.copy()

    def laplacian_sparse(self) -> sparse.csr_matrix:
        """The signed Laplacian L as a sparse matrix, assembled from the edge list in time
        and memory linear in the edges.

        Returns
        -------
        scipy.sparse.csr_matrix
            L, Nd×Nd (d×d blocks).
        """
        return signed_laplacian_sparse(self)

    def __repr__(self) -> str:
        ea = self._arrays
        neg = int(np.sum(CODE_SIGN[ea.codes] < 0))
        return (
            f"Topology({self.name or 'unnamed'!r}, N={self.n}, d={self.dim}, "
            f"{len(ea.rows)} edges ({neg} antagonistic), U={set_text(self.labels[i] for i in self.antagonised)})"
        )

    def table(self) -> Table:
        """What the topology is, as every face shows it: size, edges by class, U.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        ea = self._arrays
        counts = {c: int(np.sum(ea.codes == k)) for k, c in enumerate(DEF_CODES)}
        rows = [
            ("agents N", self.n),
            ("state dimension d", self.dim),
            ("edges j → i", len(ea.rows)),
            *[(f"edges {c.value}", k) for c, k in counts.items() if k],
            (
                "antagonised U (informed agents)",
                set_text((self.labels[i] for i in self.antagonised), 12),
            ),
        ]
        return Table.build(f"topology {self.name or ''}".strip(), ("quantity", "value"), rows)

    def _repr_html_(self) -> str:
        ea = self._arrays
        edges = [
            (int(i), int(j), int(CODE_SIGN[c]), bool(CODE_DEFINITE[c]))
            for i, j, c in zip(ea.rows, ea.cols, ea.codes, strict=True)
            if CODE_SIGN[c] != 0
        ]
        return network_svg(self.labels, edges, self.antagonised) + self.table().html()

    def to_dict(self) -> dict:
        """The topology in the topology-file form.

        Returns
        -------
        dict
            ``name``, ``dim``, ``agents`` and ``edges`` (round-trips through JSON/YAML).
        """
        doc: dict = {}
        if self.name is not None:
            doc["name"] = self.name
        doc["dim"] = self.dim
        doc["agents"] = list(self.labels)
        doc["edges"] = [
            {
                "from": self.labels[j],
                "to": self.labels[i],
                "weight": np.asarray(a).tolist(),
            }
            for (i, j), a in sorted(self.weights.items())
        ]
        return doc


def signed_laplacian(top: Topology) -> np.ndarray:
    """Signed Laplacian L (Niu & Wu, Sec. 2.3): blocks ``L_ij = -A_ij`` (j ≠ i) and
    ``L_ii = Σ_{k≠i} |A_ik|``.

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    numpy.ndarray
        L, Nd×Nd, dense.

    Raises
    ------
    InputError
        The dense matrix would exceed ``linalg.DENSE_MAX_BYTES`` (estimated first).
    """
    require_dense(top.nd, "signed Laplacian L")
    d, n = top.dim, top.n
    ea = top._arrays
    lap4 = np.zeros((n, d, n, d))
    lap4[ea.rows, :, ea.cols, :] = -ea.w
    diag = top.degree_sums[0]
    idx = np.arange(n)
    lap4[idx, :, idx, :] = diag
    return lap4.reshape(top.nd, top.nd)


def block_coo(
    n: int, d: int, rows: np.ndarray, cols: np.ndarray, blocks: np.ndarray
) -> sparse.csr_matrix:
    """CSR (nd×nd) from d×d blocks placed at agent positions (rows[k], cols[k]).

    Parameters
    ----------
    n, d : int
        Agents and block size.
    rows, cols : numpy.ndarray
        The agent position of each block.
    blocks : numpy.ndarray
        The blocks, shape (K, d, d); repeated positions are summed.

    Returns
    -------
    scipy.sparse.csr_matrix
    """
    a, b = np.meshgrid(np.arange(d), np.arange(d), indexing="ij")
    r = (rows[:, None, None] * d + a).ravel()
    c = (cols[:, None, None] * d + b).ravel()
    m = sparse.csr_matrix((blocks.ravel(), (r, c)), shape=(n * d, n * d))
    m.sum_duplicates()
    return m


def signed_laplacian_sparse(top: Topology) -> sparse.csr_matrix:
    """:func:`signed_laplacian` as a sparse matrix, in O(E·d²) time and memory.

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    scipy.sparse.csr_matrix
        L, Nd×Nd.
    """
    ea, n, d = top._arrays, top.n, top.dim
    idx = np.arange(n)
    rows = np.concatenate([ea.rows, idx])
    cols = np.concatenate([ea.cols, idx])
    blocks = np.concatenate([-ea.w, top.degree_sums[0]])
    return block_coo(n, d, rows, cols, blocks)
