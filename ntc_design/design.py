"""Assumption 2 and the Lemma 1 protocol design (paper, Sec. 3), with the exact critical
couplings of the same design family (:mod:`ntc_design.thresholds`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, require_positive
from .linalg import pd
from .model import (
    SwitchingTopology,
    Topology,
    antagonistic_in_weight,
    in_degree_dominated,
    in_out_difference,
    positive_negative_reachable,
)
from .thresholds import CriticalCouplings, critical_couplings

THRESHOLDS_MAX_ND = 200  # above this Nd the thresholds are skipped unless asked for


@dataclass(frozen=True)
class Violation:
    agent: int  # index
    reason: str


@dataclass(frozen=True)
class Decomposition:
    """Result of the Assumption 2 check: ``holds`` with the C-minimising V1, or the
    violations. ``coefficients`` holds C_i for every agent whose Σ_{Ω_i}|A_ij| ≻ 0."""

    holds: bool
    v1: tuple[int, ...]
    v2: tuple[int, ...]
    coefficients: Mapping[int, float]
    violations: tuple[Violation, ...]
    paths: Mapping[int, tuple[int, ...]]  # V2 agent -> a positive-negative path from V1


def lemma1_coefficient(top: Topology, i: int) -> float:
    """Lemma 1: ``C_i = ½ λ_max[(Σ_{Ω_i}|A_ij|)^{-1} (Σ_{N'_i}|A_ji| - Σ_{N_i}|A_ij|)]``.

    Requires ``Σ_{Ω_i}|A_ij| ≻ 0``. The eigenvalues are real: with S = Σ_{Ω_i}|A_ij| ≻ 0
    the product is similar to ``S^{-1/2} M S^{-1/2}`` (M symmetric), which is what is
    computed (a symmetric-definite generalised eigenproblem)."""
    import scipy.linalg as sla

    s = antagonistic_in_weight(top, i)
    m = -in_out_difference(top, i)
    return 0.5 * float(sla.eigh(0.5 * (m + m.T), 0.5 * (s + s.T), eigvals_only=True)[-1])


def assumption2(top: Topology) -> Decomposition:
    """Decide Assumption 2 and return the decomposition V = V1 ∪ V2 minimising C.

    A V2 agent must be in-degree-dominated (Definition 2) and reached from V1 by a
    positive-negative path (Definition 1); a V1 agent needs Σ_{Ω_i}|A_ij| ≻ 0 so that C_i
    is defined. Validity only improves as V1 grows, so the least C is found by taking the
    candidates in order of C_i and growing V1 until the rest is covered; V1 is then every
    candidate with C_i <= C.
    """
    n = top.n
    idd = [in_degree_dominated(top, i) for i in range(n)]
    cands = {i: lemma1_coefficient(top, i) for i in range(n) if pd(antagonistic_in_weight(top, i))}
    violations: list[Violation] = []
    for i in range(n):
        if not idd[i] and i not in cands:
            why = (
                "has no antagonistic in-edge"
                if not top.omega(i)
                else "its antagonistic in-weight Σ_{Ω_i}|A_ij| is only semidefinite"
            )
            violations.append(
                Violation(
                    i, f"not in-degree-dominated and {why}, so it can be neither in V1 nor in V2"
                )
            )
    required = [i for i in range(n) if not idd[i] and i in cands]
    floor = max((cands[i] for i in required), default=-math.inf)
    levels = sorted({c for c in cands.values() if c >= floor})
    if not violations:
        for level in levels:
            v1 = [i for i in sorted(cands) if cands[i] <= level]
            paths = positive_negative_reachable(top, v1)
            if all(i in paths for i in range(n)):
                v1s = tuple(v1)
                v2 = tuple(i for i in range(n) if i not in v1s)
                return Decomposition(True, v1s, v2, cands, (), {i: tuple(paths[i]) for i in v2})
    # Report who cannot be covered even with every candidate in V1.
    v1 = tuple(sorted(cands))
    paths = positive_negative_reachable(top, v1)
    bad = {v.agent for v in violations}
    for i in range(n):
        if i not in paths and i not in bad:
            violations.append(
                Violation(
                    i,
                    "not reached by any positive-negative path from an agent that can be in V1"
                    + (
                        " (no agent has a positive definite antagonistic in-weight)"
                        if not v1
                        else ""
                    ),
                )
            )
    violations.sort(key=lambda v: v.agent)
    v2 = tuple(i for i in range(n) if i not in v1)
    return Decomposition(False, v1, v2, cands, tuple(violations), {})


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


@dataclass(frozen=True, eq=False)
class ProtocolDesign:
    """Lemma 1 parameters for one topology and target θ.

    ``informed = U``; ``B_i = Σ_{Ω_i}|A_ij|`` (sgn B_i = +1); δ_i = δ on informed agents;
    ``k1 = 1 + 2/δ``; ``x0 = k1·θ``; ``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)``.
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
        return self.decomposition.holds

    def coupling_matrix(self) -> np.ndarray:
        """``D = blockdiag(|B_i|)`` with zero blocks for naive agents, so L_B = L + δD."""
        return coupling_matrix(self.topology, self.B)

    def grounded_laplacian(self, delta: float | None = None) -> np.ndarray:
        """``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)`` (eq. LB), at this design's δ or another."""
        dl = self.delta if delta is None else delta
        return self.topology.laplacian() + dl * self.coupling_matrix()

    def input_vector(self) -> np.ndarray:
        """``k1 (Δ⊗I_d) B θ`` = ``(Δ⊗I_d) B x0``: the constant drift from the external signal."""
        return input_vector(self.topology, self.B, self.delta, self.x0)

    def to_dict(self) -> dict:
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

    def to_statespace(self):
        """The noise-free protocol at c = 1 as a ``control.StateSpace`` (state x, input θ,
        output x; DC gain 1_N ⊗ I_d); see :func:`ntc_design.interop.design_statespace`."""
        from .interop import design_statespace

        return design_statespace(self)


@dataclass(frozen=True, eq=False)
class SwitchingDesign:
    """One Lemma 1 design per mode of a switching topology."""

    switching: SwitchingTopology
    modes: Mapping[str, ProtocolDesign]

    def to_dict(self) -> dict:
        return {
            "schedule": [{"mode": m, "duration": d} for m, d in self.switching.schedule],
            "period": self.switching.period,
            "modes": {k: v.to_dict() for k, v in self.modes.items()},
        }


def coupling_matrix(top: Topology, b: Mapping[int, np.ndarray]) -> np.ndarray:
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
    u = np.zeros(top.nd)
    for i, bi in b.items():
        u[i * d : (i + 1) * d] = delta * bi @ x0
    return u


def _theta(theta: Sequence[float] | np.ndarray, dim: int) -> np.ndarray:
    try:
        th = np.asarray(theta, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"theta: expected {dim} numbers, got {theta!r}") from None
    if th.size != dim:
        raise InputError(f"theta: expected {dim} numbers (the state dimension d), got {th.size}")
    if not np.all(np.isfinite(th)):
        raise InputError("theta: entries must be finite")
    if not np.any(th):
        raise InputError("theta: must be non-zero (the target of non-trivial consensus)")
    return th


def identity_residual(lap_b: np.ndarray, u: np.ndarray, theta: np.ndarray) -> float:
    """``‖-L_B(1⊗θ) + k1(Δ⊗I_d)Bθ‖_∞`` relative to ``‖L_B‖_∞‖θ‖_∞`` (eq. LBt property)."""
    n = lap_b.shape[0] // theta.size
    r = -lap_b @ np.tile(theta, n) + u
    scale = max(np.linalg.norm(lap_b, np.inf) * np.max(np.abs(theta)), 1e-300)
    return float(np.max(np.abs(r)) / scale)


def design_topology(
    top: Topology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign:
    """Lemma 1 design for one topology: δ = C + ΔC (``margin``), or an explicit δ."""
    th = _theta(theta, top.dim)
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
    informed = top.antagonised
    b = {i: antagonistic_in_weight(top, i) for i in informed}
    k1 = 1.0 + 2.0 / dl
    x0 = k1 * th
    lap = top.laplacian()
    dmat = coupling_matrix(top, b)
    res = identity_residual(lap + dl * dmat, input_vector(top, b, dl, x0), th)
    want = thresholds if thresholds is not None else top.nd <= THRESHOLDS_MAX_ND
    crit = critical_couplings(lap, dmat) if want else None
    if not want:
        notes.append(f"critical couplings skipped (Nd = {top.nd} > {THRESHOLDS_MAX_ND})")
    return ProtocolDesign(
        top, th, float(margin), dec, c, dl, k1, x0, informed, b, res, crit, tuple(notes)
    )


def design(
    topology: Topology | SwitchingTopology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign | SwitchingDesign:
    """Lemma 1 design for a topology, or one per mode for a switching topology.

    For a topology given as functions of time use ``design(tv.at(t), theta)``."""
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
    """What ``ntc check`` shows: edge classes, N_i, N'_i, Ω_i, Γ_i, U, the
    in-degree-dominated test and C_i per agent, and the Assumption 2 decomposition or its
    violations (labels, not indices)."""
    lab = top.labels
    dec = assumption2(top)
    agents = {}
    for i in range(top.n):
        agents[str(lab[i])] = {
            "in_neighbours": [lab[j] for j in top.in_neighbours(i)],
            "out_neighbours": [lab[j] for j in top.out_neighbours(i)],
            "omega": [lab[j] for j in top.omega(i)],
            "gamma": [lab[j] for j in top.gamma(i)],
            "in_degree_dominated": in_degree_dominated(top, i),
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
