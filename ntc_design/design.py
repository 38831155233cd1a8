"""Assumption 2 and the Lemma 1 protocol design (Niu & Wu, Sec. 3), with the exact critical
couplings of the same design family (:mod:`ntc_design.thresholds`)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sparse
from scipy.sparse import csgraph

from .errors import require_positive, require_theta
from .linalg import pd_batch, require_dense
from .model import (
    SwitchingTopology,
    Topology,
    antagonistic_in_weight,
    block_coo,
    in_degree_dominated_all,
    in_out_difference,
)
from .thresholds import CriticalCouplings, critical_couplings, critical_couplings_sparse

#: Up to this Nd the critical couplings are computed densely (exact Kronecker pencil /
#: eigenvalue scans, :func:`critical_couplings`); above it by the sparse method
#: (:func:`~ntc_design.thresholds.critical_couplings_sparse`), which says what it computed.
THRESHOLDS_MAX_ND = 200
#: By default the critical couplings are computed up to this Nd; above it only when asked
#: (``thresholds=True``, ``ntc design --thresholds``), and a note says so.
THRESHOLDS_DEFAULT_MAX_ND = 30_000


class AssumptionWarning(UserWarning):
    """Assumption 2 fails for a topology being designed: Lemma 1 does not apply and the
    design must be certified before it is trusted (also flagged by
    ``ProtocolDesign.assumption_holds``)."""


@dataclass(frozen=True)
class Violation:
    """An agent that can be in neither V1 nor V2 of Assumption 2, and why."""

    agent: int  # index (internal); labels in to_dict()/structure_report
    reason: str


class _Paths(Mapping):
    """V2 agent -> one shortest positive-negative path from V1 (agent indices), read
    lazily from a BFS predecessor array (storing every path would cost O(N·depth))."""

    def __init__(self, keys: Sequence[int], pred: np.ndarray, root: int) -> None:
        self._keys = tuple(keys)
        self._set = frozenset(self._keys)
        self._pred = pred
        self._root = root

    def __getitem__(self, i: int) -> tuple[int, ...]:
        if i not in self._set:
            raise KeyError(i)
        path = [int(i)]
        while True:
            p = int(self._pred[path[-1]])
            if p == self._root or p < 0:
                break
            path.append(p)
        return tuple(reversed(path))

    def __iter__(self):
        return iter(self._keys)

    def __len__(self) -> int:
        return len(self._keys)


@dataclass(frozen=True)
class Decomposition:
    """Result of the Assumption 2 check (agent indices; labels via
    :meth:`ProtocolDesign.to_dict` or :meth:`agents`): ``holds`` with the C-minimising V1,
    or the violations. ``coefficients`` holds C_i for every agent whose
    Σ_{Ω_i}|A_ij| ≻ 0. When Assumption 2 fails, V1 is every agent that can be in V1 and
    V2 only the agents that satisfy the V2 conditions; the violating agents are in
    neither."""

    holds: bool
    v1: tuple[int, ...]
    v2: tuple[int, ...]
    coefficients: Mapping[int, float]
    violations: tuple[Violation, ...]
    paths: Mapping[int, tuple[int, ...]]  # V2 agent -> a positive-negative path from V1

    def agents(self, top: Topology) -> dict:
        """V1, V2 and the violating agents as labels.

        Parameters
        ----------
        top : Topology
            The topology this decomposition is of.

        Returns
        -------
        dict
            ``V1``, ``V2`` and ``violating``, each a list of labels.
        """
        lab = top.labels
        return {
            "V1": [lab[i] for i in self.v1],
            "V2": [lab[i] for i in self.v2],
            "violating": [lab[v.agent] for v in self.violations],
        }


def lemma1_coefficient(top: Topology, i: int) -> float:
    """Lemma 1: ``C_i = ½ λ_max[(Σ_{Ω_i}|A_ij|)^{-1} (Σ_{N'_i}|A_ji| - Σ_{N_i}|A_ij|)]``.

    Requires ``Σ_{Ω_i}|A_ij| ≻ 0``. The eigenvalues are real: with S = Σ_{Ω_i}|A_ij| ≻ 0
    the product is similar to ``S^{-1/2} M S^{-1/2}`` (M symmetric), which is what is
    computed (a symmetric-definite generalised eigenproblem).

    Parameters
    ----------
    top : Topology
        The topology.
    i : int
        0-based agent index, with a positive definite antagonistic in-weight.

    Returns
    -------
    float
        C_i.
    """
    import scipy.linalg as sla

    s = antagonistic_in_weight(top, i)
    m = -in_out_difference(top, i)
    return 0.5 * float(sla.eigh(0.5 * (m + m.T), 0.5 * (s + s.T), eigvals_only=True)[-1])


def lemma1_coefficients(top: Topology) -> tuple[np.ndarray, np.ndarray]:
    """:func:`lemma1_coefficient` for every agent at once: ``(candidate, C)`` arrays of
    length N, ``candidate[i]`` when Σ_{Ω_i}|A_ij| ≻ 0 (C_i is NaN otherwise). The
    generalised eigenproblems are solved batched: with S = R Rᵀ (Cholesky),
    λ(S⁻¹M) = λ(R⁻¹ M R⁻ᵀ)."""
    inn, out, ant = top.degree_sums
    cand = pd_batch(ant) if top.n else np.zeros(0, dtype=bool)
    c = np.full(top.n, np.nan)
    k = np.flatnonzero(cand)
    if k.size:
        s = ant[k]
        m = out[k] - inn[k]
        m = 0.5 * (m + m.transpose(0, 2, 1))
        r = np.linalg.cholesky(0.5 * (s + s.transpose(0, 2, 1)))
        x = np.linalg.solve(r, m)  # R⁻¹ M
        y = np.linalg.solve(r, x.transpose(0, 2, 1))  # R⁻¹ (R⁻¹ M)ᵀ = R⁻¹ M R⁻ᵀ
        c[k] = 0.5 * np.linalg.eigvalsh(0.5 * (y + y.transpose(0, 2, 1)))[:, -1]
    return cand, c


def _reach(top: Topology, graph: sparse.csr_matrix, sources: np.ndarray):
    """BFS over the definite edges from a virtual root joined to ``sources``: returns
    (reached mask, predecessor array, root index)."""
    n = top.n
    root = n
    extra = sparse.csr_matrix(
        (np.ones(sources.size, dtype=np.int8), (np.full(sources.size, root), sources)),
        shape=(n + 1, n + 1),
    )
    g = sparse.bmat([[graph, None], [None, sparse.csr_matrix((1, 1), dtype=np.int8)]]).tocsr()
    g = (g + extra).tocsr()
    g.sort_indices()
    order, pred = csgraph.breadth_first_order(g, root, directed=True, return_predecessors=True)
    reached = np.zeros(n + 1, dtype=bool)
    reached[order] = True
    return reached[:n], pred, root


def assumption2(top: Topology) -> Decomposition:
    """Decide Assumption 2 and return the decomposition V = V1 ∪ V2 minimising C.

    A V2 agent must be in-degree-dominated (Niu & Wu, Definition 4) and reached from V1 by
    a positive-negative path (Definition 3); a V1 agent needs Σ_{Ω_i}|A_ij| ≻ 0 so that C_i
    is defined. Validity only improves as V1 grows, so the least C is the least level
    ``c`` for which V1 = {candidates with C_i <= c} covers the rest; as coverage is
    monotone in c the level is found by bisection over the sorted C_i (O(E log N)).
    Everything is vectorised over agents and edges; reachability is a BFS
    (``scipy.sparse.csgraph``) from a virtual root joined to V1.

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    Decomposition
        ``holds`` with V1, V2, C_i and a path to each V2 agent, or the violations.
    """
    n = top.n
    idd = in_degree_dominated_all(top)
    cand, cvals = lemma1_coefficients(top)
    cands = {int(i): float(cvals[i]) for i in np.flatnonzero(cand)}
    ant = set(top.antagonised)
    violations: list[Violation] = []
    for i in np.flatnonzero(~idd & ~cand).tolist():
        why = (
            "has no antagonistic in-edge"
            if i not in ant
            else "its antagonistic in-weight Σ_{Ω_i}|A_ij| is only semidefinite"
        )
        violations.append(
            Violation(i, f"not in-degree-dominated and {why}, so it can be neither in V1 nor in V2")
        )
    required = ~idd & cand
    floor = float(np.max(cvals[required])) if required.any() else -math.inf
    levels = np.unique(cvals[cand & (cvals >= floor)]) if cand.any() else np.zeros(0)
    graph = top.definite_graph()
    if not violations and levels.size:

        def covers(level: float):
            v1 = np.flatnonzero(cand & (cvals <= level))
            reached, pred, root = _reach(top, graph, v1)
            return bool(reached.all()), v1, pred, root

        lo, hi = 0, levels.size - 1
        ok_hi = covers(levels[hi])
        if ok_hi[0]:
            best = ok_hi
            while lo < hi:
                mid = (lo + hi) // 2
                res = covers(levels[mid])
                if res[0]:
                    hi, best = mid, res
                else:
                    lo = mid + 1
            _, v1, pred, root = best
            in_v1 = np.zeros(n, dtype=bool)
            in_v1[v1] = True
            v2 = tuple(np.flatnonzero(~in_v1).tolist())
            return Decomposition(True, tuple(v1.tolist()), v2, cands, (), _Paths(v2, pred, root))
    # Report who cannot be covered even with every candidate in V1.
    v1a = np.flatnonzero(cand)
    reached, pred, root = _reach(top, graph, v1a)
    bad = np.zeros(n, dtype=bool)
    bad[[v.agent for v in violations]] = True
    for i in np.flatnonzero(~reached & ~bad).tolist():
        violations.append(
            Violation(
                i,
                "not reached by any positive-negative path from an agent that can be in V1"
                + (
                    " (no agent has a positive definite antagonistic in-weight)"
                    if not v1a.size
                    else ""
                ),
            )
        )
    violations.sort(key=lambda v: v.agent)
    for v in violations:
        bad[v.agent] = True
    # V2: only agents that meet the V2 conditions (issue 8: violators are in neither set)
    v2 = tuple(np.flatnonzero(~cand & idd & reached & ~bad).tolist())
    return Decomposition(
        False, tuple(v1a.tolist()), v2, cands, tuple(violations), _Paths(v2, pred, root)
    )


#: Keys of the stable ``ntc design --json`` format (per mode for a switching file).
DESIGN_KEYS = (
    "C",
    "delta",
    "k1",
    "x0",
    "informed",
    "B",
    "V1",
    "V2",
    "assumption_holds",
    "violations",
    "identity_residual",
    "thresholds",
)


@dataclass(frozen=True, eq=False, kw_only=True)
class ProtocolDesign:
    """Lemma 1 parameters for one topology and target θ.

    ``informed = U``; ``B_i = Σ_{Ω_i}|A_ij|`` (sgn B_i = +1); δ_i = δ on informed agents;
    ``k1 = 1 + 2/δ``; ``x0 = k1·θ``; ``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)`` (Niu & Wu,
    Lemma 1 and eq. (8)).
    """

    topology: Topology
    theta: np.ndarray
    margin: float
    decomposition: Decomposition
    C: float | None
    delta: float
    k1: float
    x0: np.ndarray
    informed: tuple[int, ...]
    B: Mapping[int, np.ndarray]
    identity_residual: float
    thresholds: CriticalCouplings | None
    notes: tuple[str, ...] = field(default=())

    @property
    def assumption_holds(self) -> bool:
        """Whether Assumption 2 holds (else Lemma 1 does not apply: certify first)."""
        return self.decomposition.holds

    @property
    def informed_agents(self) -> tuple:
        """V_I = U as agent labels (``informed`` holds the internal 0-based indices)."""
        lab = self.topology.labels
        return tuple(lab[i] for i in self.informed)

    @property
    def v1_agents(self) -> tuple:
        """V1 as agent labels."""
        return tuple(self.decomposition.agents(self.topology)["V1"])

    @property
    def v2_agents(self) -> tuple:
        """V2 as agent labels."""
        return tuple(self.decomposition.agents(self.topology)["V2"])

    @property
    def violating_agents(self) -> tuple:
        """Agents that violate Assumption 2, as labels (empty when it holds)."""
        return tuple(self.decomposition.agents(self.topology)["violating"])

    @property
    def B_by_agent(self) -> dict:  # noqa: N802 - B_i is the paper's name
        """B_i keyed by agent label."""
        lab = self.topology.labels
        return {lab[i]: b for i, b in self.B.items()}

    def coupling_matrix_sparse(self) -> sparse.csr_matrix:
        """``D = blockdiag(|B_i|)`` as a sparse matrix.

        Returns
        -------
        scipy.sparse.csr_matrix
            D, Nd×Nd, zero blocks for naive agents.
        """
        return coupling_matrix_sparse(self.topology, self.B)

    def grounded_laplacian_sparse(self, delta: float | None = None) -> sparse.csr_matrix:
        """``L_B = L + δD`` (eq. (8)) as a sparse matrix, linear in the edges.

        Parameters
        ----------
        delta : float, optional
            δ; this design's when omitted.

        Returns
        -------
        scipy.sparse.csr_matrix
            L_B, Nd×Nd (d×d blocks).
        """
        dl = self.delta if delta is None else delta
        return (self.topology.laplacian_sparse() + dl * self.coupling_matrix_sparse()).tocsr()

    def coupling_matrix(self) -> np.ndarray:
        """``D = blockdiag(|B_i|)`` with zero blocks for naive agents, so L_B = L + δD.

        Returns
        -------
        numpy.ndarray
            D, Nd×Nd, dense.
        """
        return coupling_matrix(self.topology, self.B)

    def grounded_laplacian(self, delta: float | None = None) -> np.ndarray:
        """``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)`` (Niu & Wu, eq. (8)).

        Parameters
        ----------
        delta : float, optional
            δ; this design's when omitted.

        Returns
        -------
        numpy.ndarray
            L_B, Nd×Nd, dense.
        """
        dl = self.delta if delta is None else delta
        return self.topology.laplacian() + dl * self.coupling_matrix()

    def input_vector(self) -> np.ndarray:
        """The constant drift from the external signal, ``k1 (Δ⊗I_d) B θ = (Δ⊗I_d) B x0``.

        Returns
        -------
        numpy.ndarray
            A vector of length Nd.
        """
        return input_vector(self.topology, self.B, self.delta, self.x0)

    def to_dict(self) -> dict:
        """The design as a JSON-ready mapping, agents as labels.

        Returns
        -------
        dict
            θ, ΔC, C and C_i, δ, k1, x0, the informed agents and B_i, V1, V2, the
            violations, the identity residual, the critical couplings and notes.
        """
        lab = self.topology.labels
        dec = self.decomposition
        th = self.thresholds
        return {
            "topology": self.topology.name,
            "theta": self.theta.tolist(),
            "margin": self.margin,
            "C": self.C,
            "C_i": {str(lab[i]): c for i, c in sorted(dec.coefficients.items())},
            "delta": self.delta,
            "k1": self.k1,
            "x0": self.x0.tolist(),
            "informed": [lab[i] for i in self.informed],
            "B": {str(lab[i]): b.tolist() for i, b in sorted(self.B.items())},
            "V1": [lab[i] for i in dec.v1],
            "V2": [lab[i] for i in dec.v2],
            "assumption_holds": dec.holds,
            "violations": [{"agent": lab[v.agent], "reason": v.reason} for v in dec.violations],
            "identity_residual": self.identity_residual,
            "thresholds": th.to_dict() if th is not None else None,
            "conservatism": (self.delta / th.hurwitz if th is not None and th.hurwitz else None),
            "notes": list(self.notes),
        }


@dataclass(frozen=True, eq=False)
class SwitchingDesign:
    """One Lemma 1 design per mode of a switching topology."""

    switching: SwitchingTopology
    modes: Mapping[str, ProtocolDesign]

    def to_dict(self) -> dict:
        """The designs as a JSON-ready mapping.

        Returns
        -------
        dict
            The schedule, its period and each mode's :meth:`ProtocolDesign.to_dict`.
        """
        return {
            "schedule": [{"mode": m, "duration": d} for m, d in self.switching.schedule],
            "period": self.switching.period,
            "modes": {k: v.to_dict() for k, v in self.modes.items()},
        }


def coupling_matrix_sparse(top: Topology, b: Mapping[int, np.ndarray]) -> sparse.csr_matrix:
    """``blockdiag(B_i)`` (zero blocks for agents not in ``b``) as CSR."""

    idx = np.array(sorted(b), dtype=np.int64)
    blocks = np.array([b[i] for i in idx.tolist()]).reshape(-1, top.dim, top.dim)
    return block_coo(top.n, top.dim, idx, idx, blocks)


def coupling_matrix(top: Topology, b: Mapping[int, np.ndarray]) -> np.ndarray:
    require_dense(top.nd, "coupling matrix D")
    d = top.dim
    out = np.zeros((top.nd, top.nd))
    for i, bi in b.items():
        out[i * d : (i + 1) * d, i * d : (i + 1) * d] = bi
    return out


def input_vector(
    top: Topology, b: Mapping[int, np.ndarray], delta: float, x0: np.ndarray
) -> np.ndarray:
    """``(Δ⊗I_d) B x0`` with δ_i = δ on the informed agents (the keys of ``b``)."""
    d = top.dim
    u = np.zeros((top.n, d))
    if b:
        idx = np.array(list(b), dtype=np.int64)
        u[idx] = delta * (np.array([b[i] for i in idx.tolist()]) @ x0)
    return u.reshape(-1)


def identity_residual(lap_b, u: np.ndarray, theta: np.ndarray) -> float:
    """``‖-L_B(1⊗θ) + k1(Δ⊗I_d)Bθ‖_∞`` relative to ``‖L_B‖_∞‖θ‖_∞`` (Niu & Wu, eq. (11));
    ``lap_b`` dense or sparse."""
    n = lap_b.shape[0] // theta.size
    r = -(lap_b @ np.tile(theta, n)) + u
    if sparse.issparse(lap_b):
        norm = float(abs(lap_b).sum(axis=1).max()) if lap_b.nnz else 0.0
    else:
        norm = float(np.linalg.norm(lap_b, np.inf))
    scale = max(norm * np.max(np.abs(theta)), 1e-300)
    return float(np.max(np.abs(r)) / scale)


#: Up to this Nd the design also assembles the dense L_B (results identical to the
#: dense-only releases at the paper's size); above it everything is sparse.
DENSE_DESIGN_MAX_ND = 600


def design_topology(
    top: Topology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign:
    """Lemma 1 design for one topology: δ = C + ΔC (``margin``), or an explicit δ.

    Parameters
    ----------
    top : Topology
        The topology.
    theta : sequence of float
        The target consensus state θ ≠ 0 (d numbers).
    margin : float, optional
        ΔC > 0.
    delta : float, optional
        An explicit δ > 0 instead of C + ΔC.
    thresholds : bool, optional
        Compute the critical couplings δ_H, δ_S; by default only up to
        ``THRESHOLDS_DEFAULT_MAX_ND``.

    Returns
    -------
    ProtocolDesign
        The parameters; ``assumption_holds`` False (with an :class:`AssumptionWarning`)
        when Assumption 2 fails.

    Raises
    ------
    InputError
        A bad θ, margin or δ.
    """
    th = require_theta(theta, top.dim)
    require_positive("margin (ΔC)", margin)
    dec = assumption2(top)
    notes: list[str] = []
    if dec.holds:
        c = max((dec.coefficients[i] for i in dec.v1), default=None)
    else:
        c = max(dec.coefficients.values(), default=None)
        notes.append(
            "Assumption 2 fails: C is taken over the agents of U whose antagonistic "
            "in-weight is positive definite; certify the design before trusting it"
        )
    dl = _choose_delta(c, margin, delta, notes)
    if not dec.holds:
        warnings.warn(
            f"Assumption 2 fails for {top.name or 'the topology'} "
            f"({len(dec.violations)} violating agent(s), e.g. "
            f"{top.labels[dec.violations[0].agent]}): Lemma 1 does not apply",
            AssumptionWarning,
            stacklevel=3,
        )
    informed = top.antagonised
    ant = top.degree_sums[2]
    b = {i: ant[i].copy() for i in informed}
    k1 = 1.0 + 2.0 / dl
    x0 = k1 * th
    u = input_vector(top, b, dl, x0)
    res, crit = _residual_and_thresholds(top, b, dl, u, th, thresholds, notes)
    return ProtocolDesign(
        topology=top,
        theta=th,
        margin=float(margin),
        decomposition=dec,
        C=c,
        delta=dl,
        k1=k1,
        x0=x0,
        informed=informed,
        B=b,
        identity_residual=res,
        thresholds=crit,
        notes=tuple(notes),
    )


def _choose_delta(c: float | None, margin: float, delta: float | None, notes: list[str]) -> float:
    """δ = C + ΔC (Lemma 1), or ΔC when C is undefined or C + ΔC <= 0; an explicit δ as
    given, with a note when it is not above C."""
    if delta is None:
        if c is None:
            dl = float(margin)
            notes.append("no agent can be in V1: C is undefined, δ = ΔC")
        elif c + margin <= 0:
            dl = float(margin)
            notes.append(f"C = {c:.6g} < 0 but δ must be positive: δ = ΔC")
        else:
            dl = float(c + margin)
    else:
        require_positive("delta", delta)
        dl = float(delta)
        if c is not None and dl <= c:
            notes.append(f"explicit δ = {dl:.6g} is not above C = {c:.6g}: Lemma 1 does not apply")
    return dl


def _residual_and_thresholds(top, b, dl, u, th, thresholds, notes):
    """‖L_B(1⊗θ) − u‖ relative (dense or sparse by size) and the critical couplings when
    asked for (by default up to THRESHOLDS_DEFAULT_MAX_ND)."""
    if top.nd <= DENSE_DESIGN_MAX_ND:
        lap = top.laplacian()
        dmat = coupling_matrix(top, b)
        res = identity_residual(lap + dl * dmat, u, th)
    else:
        lap_s = top.laplacian_sparse()
        dmat_s = coupling_matrix_sparse(top, b)
        res = identity_residual((lap_s + dl * dmat_s).tocsr(), u, th)
    want = top.nd <= THRESHOLDS_DEFAULT_MAX_ND if thresholds is None else bool(thresholds)
    if want and top.nd <= THRESHOLDS_MAX_ND:
        crit = critical_couplings(lap, dmat)
    elif want:
        crit = critical_couplings_sparse(
            top.laplacian_sparse(), coupling_matrix_sparse(top, b), top.dim
        )
    else:
        crit = None
        notes.append(
            "critical couplings δ_H, δ_S not computed "
            + (
                "(thresholds=False)"
                if thresholds is False
                else f"by default above Nd = {THRESHOLDS_DEFAULT_MAX_ND} (ask with thresholds=True)"
            )
        )
    return res, crit


def design(
    topology: Topology | SwitchingTopology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign | SwitchingDesign:
    """Lemma 1 design for a topology, or one per mode for a switching topology.

    For a topology given as functions of time use ``design(tv.at(t), theta)``.

    Parameters
    ----------
    topology : Topology or SwitchingTopology
        The network.
    theta : sequence of float
        The target consensus state θ ≠ 0 (d numbers).
    margin : float, optional
        ΔC > 0: δ = C + ΔC.
    delta : float, optional
        An explicit δ > 0 instead of C + ΔC.
    thresholds : bool, optional
        Compute the critical couplings δ_H, δ_S (see :func:`design_topology`).

    Returns
    -------
    ProtocolDesign or SwitchingDesign
        One design, or one per mode.

    Raises
    ------
    InputError
        A bad θ, margin or δ.
    """
    if isinstance(topology, SwitchingTopology):
        return SwitchingDesign(
            topology,
            {
                name: design_topology(top, theta, margin, delta, thresholds)
                for name, top in topology.modes.items()
            },
        )
    return design_topology(topology, theta, margin, delta, thresholds)


def structure_report(top: Topology) -> dict:
    """What ``ntc check`` shows about a topology's structure.

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    dict
        Edge classes, N_i, N'_i, Ω_i, Γ_i, U, the in-degree-dominated test and C_i per
        agent, and the Assumption 2 decomposition or its violations (labels, not indices).
    """
    lab = top.labels
    dec = assumption2(top)
    idd = in_degree_dominated_all(top)
    agents = {}
    for i in range(top.n):
        agents[str(lab[i])] = {
            "in_neighbours": [lab[j] for j in top.in_neighbours(i)],
            "out_neighbours": [lab[j] for j in top.out_neighbours(i)],
            "omega": [lab[j] for j in top.omega(i)],
            "gamma": [lab[j] for j in top.gamma(i)],
            "in_degree_dominated": bool(idd[i]),
            "C_i": dec.coefficients.get(i),
        }
    return {
        "topology": top.name,
        "dim": top.dim,
        "agents": list(lab),
        "edges": [
            {"from": lab[j], "to": lab[i], "class": c.value}
            for (i, j), c in sorted(top.classes.items())
        ],
        "U": [lab[i] for i in top.antagonised],
        "per_agent": agents,
        "assumption_holds": dec.holds,
        "V1": [lab[i] for i in dec.v1],
        "V2": [lab[i] for i in dec.v2],
        "paths": {str(lab[i]): [lab[k] for k in p] for i, p in dec.paths.items()},
        "violations": [{"agent": lab[v.agent], "reason": v.reason} for v in dec.violations],
    }


__all__ = [
    "Decomposition",
    "ProtocolDesign",
    "SwitchingDesign",
    "Violation",
    "assumption2",
    "design",
    "design_topology",
    "lemma1_coefficient",
    "structure_report",
]
