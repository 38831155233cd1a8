"""The signed matrix-weighted network model (paper, Sec. 2).

Conventions (NOTES.md): ``A_ij`` is the d×d symmetric weight of the directed edge from
agent j to agent i (i listens to j). Agents are indexed 0..N-1 internally and shown by
their labels. The algorithms are plain functions over a :class:`Topology`, each stating
the definition it implements.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from . import files
from .errors import InputError
from .linalg import DEF_RTOL, Definiteness, classify, is_symmetric

Label = files.Label


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

    def __post_init__(self) -> None:
        n, d = len(self.labels), self.dim
        if n < 1 or d < 1:
            raise InputError(self._where("topology", "needs at least one agent and dim >= 1"))
        frozen = {}
        for (i, j), a in self.weights.items():
            f = self.edge_field(i, j)
            if not (0 <= i < n and 0 <= j < n):
                raise InputError(self._where(f, "agent index out of range"))
            if i == j:
                raise InputError(self._where(f, "self-loop (an agent cannot listen to itself)"))
            a = np.array(a, dtype=float, copy=True)
            if a.shape != (d, d):
                raise InputError(self._where(f, f"weight has shape {a.shape}, expected ({d}, {d})"))
            if not np.all(np.isfinite(a)):
                raise InputError(self._where(f, "weight has a NaN or infinite entry"))
            if not is_symmetric(a):
                raise InputError(self._where(f, "weight is not symmetric (A_ij must equal A_ijᵀ)"))
            cls = classify(a)
            if cls is Definiteness.INDEFINITE:
                lam = np.linalg.eigvalsh(0.5 * (a + a.T))
                raise InputError(
                    self._where(
                        f,
                        f"weight is indefinite (eigenvalues {lam[0]:.4g} .. {lam[-1]:.4g}); "
                        "a weight must be positive or negative (semi)definite",
                    )
                )
            a.setflags(write=False)
            frozen[(i, j)] = a
        object.__setattr__(self, "weights", frozen)

    # -- construction -------------------------------------------------------------
    @classmethod
    def from_edges(
        cls,
        n_or_labels: int | Iterable[Label],
        dim: int,
        edges: Iterable[tuple[Label, Label, np.ndarray]],
        name: str | None = None,
    ) -> Topology:
        """Build from ``(from_label, to_label, A_ij)`` triples (edge j -> i)."""
        if isinstance(n_or_labels, int):
            labels: tuple[Label, ...] = tuple(range(1, n_or_labels + 1))
        else:
            labels = tuple(n_or_labels)
        index = {str(a): k for k, a in enumerate(labels)}
        weights: dict[tuple[int, int], np.ndarray] = {}
        for j, i, a in edges:
            f = f"edge {j}->{i}"
            if str(j) not in index or str(i) not in index:
                raise InputError(f"{f}: unknown agent label")
            key = (index[str(i)], index[str(j)])
            if key in weights:
                raise InputError(f"{f}: duplicated edge")
            weights[key] = np.asarray(a, dtype=float)
        return cls(labels, dim, weights, name=name)

    @classmethod
    def from_data(cls, data: files.TopologyData) -> Topology:
        index = {str(a): k for k, a in enumerate(data.labels)}
        weights, fields = {}, {}
        for e in data.edges:
            key = (index[str(e.target)], index[str(e.source)])
            weights[key] = e.weight
            fields[key] = e.field
        return cls(data.labels, data.dim, weights, data.name, data.source, fields)

    # -- basic accessors ----------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.labels)

    @property
    def nd(self) -> int:
        return self.n * self.dim

    def edge_field(self, i: int, j: int) -> str:
        if (i, j) in self.fields:
            return self.fields[(i, j)]
        lab = self.labels
        if 0 <= i < len(lab) and 0 <= j < len(lab):
            return f"edge {lab[j]}->{lab[i]}"
        return f"edge {j}->{i}"

    def _where(self, f: str, msg: str) -> str:
        return f"{self.source}: {f}: {msg}" if self.source else f"{f}: {msg}"

    def index(self, label: Label) -> int:
        for k, a in enumerate(self.labels):
            if str(a) == str(label):
                return k
        raise InputError(f"unknown agent label {label!r}")

    def weight(self, i: int, j: int) -> np.ndarray:
        """A_ij (zero matrix when there is no edge j -> i)."""
        a = self.weights.get((i, j))
        return a if a is not None else np.zeros((self.dim, self.dim))

    @cached_property
    def classes(self) -> dict[tuple[int, int], Definiteness]:
        """Definiteness class of every listed weight."""
        return {k: classify(a) for k, a in self.weights.items()}

    def sign(self, i: int, j: int) -> int:
        """sgn(A_ij) (paper, Sec. 2.1)."""
        c = self.classes.get((i, j))
        return c.sign if c is not None else 0

    def abs_weight(self, i: int, j: int) -> np.ndarray:
        """|A_ij| = sgn(A_ij)·A_ij."""
        return self.sign(i, j) * self.weight(i, j)

    @cached_property
    def edges(self) -> tuple[tuple[int, int], ...]:
        """Edges (i, j) with sgn(A_ij) ≠ 0, i.e. j -> i, in a stable order."""
        return tuple(sorted(k for k, c in self.classes.items() if c.sign != 0))

    def in_neighbours(self, i: int) -> list[int]:
        """N_i = {j : sgn(A_ij) ≠ 0}."""
        return [j for (a, j) in self.edges if a == i]

    def out_neighbours(self, i: int) -> list[int]:
        """N'_i = {j : sgn(A_ji) ≠ 0}."""
        return [a for (a, j) in self.edges if j == i]

    def omega(self, i: int) -> list[int]:
        """Ω_i = {j : sgn(A_ij) = -1}: in-neighbours with an antagonistic edge into i."""
        return [j for j in self.in_neighbours(i) if self.sign(i, j) == -1]

    def gamma(self, i: int) -> list[int]:
        """Γ_i = {j : sgn(A_ij) = +1}: in-neighbours with a cooperative edge into i."""
        return [j for j in self.in_neighbours(i) if self.sign(i, j) == 1]

    @cached_property
    def antagonised(self) -> tuple[int, ...]:
        """U = {i : ∃ j, sgn(A_ij) = -1}: agents with at least one negative in-edge."""
        return tuple(i for i in range(self.n) if self.omega(i))

    @cached_property
    def _laplacian(self) -> np.ndarray:
        return signed_laplacian(self)

    def laplacian(self) -> np.ndarray:
        """The signed Laplacian L (Nd×Nd); see :func:`signed_laplacian` (built once, a
        copy is returned)."""
        return self._laplacian.copy()

    def to_dict(self) -> dict:
        """A plain mapping in the topology-file form (round-trips through JSON/YAML)."""
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

    # -- interop (thin wrappers over ntc_design.interop) ------------------------------
    @classmethod
    def from_networkx(cls, graph, weight: str = "weight", dim: int | None = None) -> Topology:
        """From a ``networkx.DiGraph`` (edge u -> v carries A_vu as a d×d matrix, or a
        number for d = 1); see :func:`ntc_design.interop.topology_from_networkx`."""
        from .interop import topology_from_networkx

        return topology_from_networkx(graph, weight, dim)

    def to_networkx(self, weight: str = "weight"):
        """A ``networkx.DiGraph`` with the d×d weights as edge attributes (exact inverse of
        :meth:`from_networkx`)."""
        from .interop import topology_to_networkx

        return topology_to_networkx(self, weight)

    def save(self, path: str | Path) -> Path:
        """Write a topology file (YAML, or JSON by the suffix) that :func:`load` reads back."""
        from .interop import save_topology

        return save_topology(self, path)


def signed_laplacian(top: Topology) -> np.ndarray:
    """Signed Laplacian L (paper, Sec. 2.2): blocks ``L_ij = -A_ij`` (j ≠ i) and
    ``L_ii = Σ_{k≠i} |A_ik|``."""
    d = top.dim
    lap = np.zeros((top.nd, top.nd))
    for (i, j), a in top.weights.items():
        s = top.sign(i, j)
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += s * a
    return lap


def antagonistic_in_weight(top: Topology, i: int) -> np.ndarray:
    """``Σ_{j∈Ω_i} |A_ij|``: the total antagonistic weight into agent i (Lemma 1)."""
    return sum((top.abs_weight(i, j) for j in top.omega(i)), np.zeros((top.dim, top.dim)))


def _in_out_degrees(top: Topology, i: int) -> tuple[np.ndarray, np.ndarray]:
    z = np.zeros((top.dim, top.dim))
    inn = sum((top.abs_weight(i, j) for j in top.in_neighbours(i)), z)
    out = sum((top.abs_weight(j, i) for j in top.out_neighbours(i)), z)
    return inn, out


def in_out_difference(top: Topology, i: int) -> np.ndarray:
    """``Σ_{j∈N_i}|A_ij| - Σ_{j∈N'_i}|A_ji|`` (Definition 2)."""
    inn, out = _in_out_degrees(top, i)
    return inn - out


def in_degree_dominated(top: Topology, i: int) -> bool:
    """Definition 2: agent i is in-degree-dominated when
    ``Σ_{j∈N_i}|A_ij| - Σ_{j∈N'_i}|A_ji| ⪰ 0`` (zero eigenvalues up to the tolerance of
    :mod:`ntc_design.linalg`, relative to the norms of the two sums)."""
    inn, out = _in_out_degrees(top, i)
    scale = max(np.linalg.norm(inn, 2), np.linalg.norm(out, 2))
    if scale == 0.0:
        return True
    lam = np.linalg.eigvalsh(inn - out)
    return bool(lam[0] >= -DEF_RTOL * scale)


def positive_negative_reachable(top: Topology, sources: Iterable[int]) -> dict[int, list[int]]:
    """Agents reached from ``sources`` by positive-negative paths (Definition 1: every edge
    of the path is PD or ND), with one shortest such path to each (sources included,
    with the trivial path)."""
    succ: dict[int, list[int]] = {k: [] for k in range(top.n)}
    for (i, j), c in top.classes.items():
        if c.definite:
            succ[j].append(i)  # j -> i
    paths: dict[int, list[int]] = {}
    queue: deque[int] = deque()
    for s in sources:
        if s not in paths:
            paths[s] = [s]
            queue.append(s)
    while queue:
        u = queue.popleft()
        for v in sorted(succ[u]):
            if v not in paths:
                paths[v] = paths[u] + [v]
                queue.append(v)
    return paths


@dataclass(frozen=True, eq=False)
class SwitchingTopology:
    """Modes (topologies over the same agents and d) and a periodic schedule of
    ``(mode, duration)``; G(t) = mode active at ``t mod period``, intervals half-open."""

    modes: Mapping[str, Topology]
    schedule: tuple[tuple[str, float], ...]
    source: str | None = None

    def __post_init__(self) -> None:
        where = f"{self.source}: " if self.source else ""
        if not self.modes:
            raise InputError(f"{where}modes: at least one mode is needed")
        first_name, first = next(iter(self.modes.items()))
        for name, top in self.modes.items():
            if top.dim != first.dim or top.n != first.n:
                raise InputError(
                    f"{where}modes.{name}: has N={top.n}, d={top.dim} but mode {first_name} "
                    f"has N={first.n}, d={first.dim}; all modes must share the agents"
                )
            if [str(a) for a in top.labels] != [str(a) for a in first.labels]:
                raise InputError(f"{where}modes.{name}: agent labels differ from mode {first_name}")
        if not self.schedule:
            raise InputError(f"{where}schedule: must not be empty")
        for k, (m, dur) in enumerate(self.schedule):
            if m not in self.modes:
                raise InputError(
                    f"{where}schedule[{k}]: unknown mode {m!r} (modes: {', '.join(self.modes)})"
                )
            if not dur > 0:
                raise InputError(f"{where}schedule[{k}].duration: must be positive, got {dur}")

    @classmethod
    def from_data(cls, data: files.SwitchingData) -> SwitchingTopology:
        modes = {k: Topology.from_data(v) for k, v in data.modes.items()}
        return cls(modes, data.schedule, data.source)

    @property
    def labels(self) -> tuple[Label, ...]:
        return next(iter(self.modes.values())).labels

    @property
    def dim(self) -> int:
        return next(iter(self.modes.values())).dim

    @property
    def n(self) -> int:
        return len(self.labels)

    @property
    def period(self) -> float:
        return float(sum(d for _, d in self.schedule))

    def segments(self, t_end: float, t_start: float = 0.0) -> list[tuple[float, float, str]]:
        """The schedule unrolled on [t_start, t_end): ``(start, stop, mode)`` triples.
        Switch times are ``k·period + offset`` (no drift from repeated addition), and each
        segment stops exactly where the next one starts."""
        offsets = np.concatenate([[0.0], np.cumsum([d for _, d in self.schedule])[:-1]])
        per = self.period
        m_n = len(self.schedule)

        def start(k: int, m: int) -> float:
            k, m = k + m // m_n, m % m_n
            return float(k * per + offsets[m])

        out: list[tuple[float, float, str]] = []
        k = int(np.floor(t_start / per))
        while True:
            for m, (mode, _) in enumerate(self.schedule):
                a, b = start(k, m), start(k, m + 1)
                if b <= t_start:
                    continue
                if a >= t_end:
                    return out
                out.append((max(a, t_start), min(b, t_end), mode))
            k += 1

    def mode_at(self, t: float) -> str:
        """Name of the mode active at time t (a switching instant belongs to the next mode)."""
        per = self.period
        tau = t - np.floor(t / per) * per
        ends = np.cumsum([d for _, d in self.schedule])
        k = min(int(np.searchsorted(ends, tau, side="right")), len(self.schedule) - 1)
        return self.schedule[k][0]


@dataclass(frozen=True, eq=False)
class TimeVaryingTopology:
    """A topology whose weights are functions of time: ``weights[(from, to)] = A(t)``,
    keyed by agent labels, each ``A(t)`` a d×d symmetric matrix of one sign at every t.
    ``at(t)`` freezes it into a :class:`Topology` (validated at that t)."""

    labels: tuple[Label, ...]
    dim: int
    weights: Mapping[tuple[Label, Label], Callable[[float], np.ndarray]]
    name: str | None = None

    def at(self, t: float) -> Topology:
        index = {str(a): k for k, a in enumerate(self.labels)}
        w, fields = {}, {}
        for (j, i), fn in self.weights.items():
            if str(j) not in index or str(i) not in index:
                raise InputError(f"edge {j}->{i}: unknown agent label")
            key = (index[str(i)], index[str(j)])
            w[key] = np.asarray(fn(t), dtype=float)
            fields[key] = f"edge {j}->{i} at t={t:g}"
        return Topology(self.labels, self.dim, w, self.name, None, fields)

    @property
    def n(self) -> int:
        return len(self.labels)


def load(path: str | Path):
    """Load a topology file, a switching file or a time-varying topology file (YAML or
    JSON). A time-varying file gives an :class:`~ntc_design.timevarying.ExpressionTopology`,
    or the fixed :class:`Topology` when every weight is a constant expression."""
    data = files.parse_file(path)
    if isinstance(data, files.SwitchingData):
        return SwitchingTopology.from_data(data)
    if isinstance(data, files.TopologyData):
        return Topology.from_data(data)
    from .timevarying import ExpressionTopology  # built on this module

    tv = ExpressionTopology.from_data(data)
    return tv.fixed() if tv.constant else tv
