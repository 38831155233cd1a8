"""Assumption 2 (Niu & Wu, Sec. 3): the V1 / V2 decomposition, Lemma 1's coefficients
C_i, the violations, and the structure ``ntc check`` shows."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sparse
from scipy.sparse import csgraph

from ..errors import AssumptionWarning, Option, one_line
from ..model import Topology, antagonistic_in_weight, in_degree_dominated_all, in_out_difference
from ..numerics.linalg import pd_batch
from ..present.rows import Table, counted, set_text, verdict

#: What makes each kind of violating agent admissible (one of them suffices).
FIX_NOT_DOMINATED = (
    "give the agent an antagonistic in-edge with a negative definite weight (it is then "
    "informed and can be in V1), or raise its in-weights until Σ_{N_i}|A_ij| ⪰ "
    "Σ_{N'_i}|A_ji| (in-degree-dominated, it can be in V2)"
)
FIX_SEMIDEFINITE = (
    "make the agent's antagonistic in-weight Σ_{Ω_i}|A_ij| positive definite (an "
    "antagonistic in-edge covering the missing directions), or make it in-degree-dominated"
)
FIX_UNREACHED = (
    "join the agent by definite (≻ 0 or ≺ 0) edges to an agent that can be in V1, or give "
    "it an antagonistic in-edge with a negative definite weight"
)
FIX_NO_V1 = (
    "no agent can be in V1: give at least one agent antagonistic in-edges whose weights sum "
    "to a negative definite matrix (Lemma 1 needs an informed agent with Σ_{Ω_i}|A_ij| ≻ 0)"
)


@dataclass(frozen=True)
class Violation:
    """An agent that can be in neither V1 nor V2 of Assumption 2, why, and what would
    make it admissible."""

    agent: int  # index (internal); labels in to_dict()/structure_report
    reason: str
    fix: str = ""


def violation_fixes(violations: Sequence[Violation]) -> dict[str, tuple[int, ...]]:
    """The distinct fixes of ``violations``, each with the agents it is for, in the order
    they first occur (each fix said once, however many agents share it).

    Parameters
    ----------
    violations : sequence of Violation
        Assumption 2's violations.

    Returns
    -------
    dict of str to tuple of int
        fix -> the agents (indices) it applies to.
    """
    out: dict[str, list[int]] = {}
    for v in violations:
        if v.fix:
            out.setdefault(v.fix, []).append(v.agent)
    return {f: tuple(a) for f, a in out.items()}


def fix_notes(violations: Sequence[Violation], labels: Sequence[Any]) -> list[str]:
    """The fixes of ``violations`` as notes: ``fix (agents 2, 3): ...``, one per fix.

    Parameters
    ----------
    violations : sequence of Violation
        Assumption 2's violations.
    labels : sequence
        The topology's agent labels.

    Returns
    -------
    list of str
    """
    return _fix_lines([(labels[v.agent], v.fix) for v in violations])


def _fix_lines(pairs: Sequence[tuple[Any, str]], most: int = 12) -> list[str]:
    """``fix (agents a, b): FIX`` per distinct fix of (agent label, fix) pairs, the first
    ``most`` agents named."""
    fixes: dict[str, list[str]] = {}
    for agent, fix in pairs:
        if fix:
            fixes.setdefault(fix, []).append(one_line(str(agent)))
    out = []
    for fix, names in fixes.items():
        who = ", ".join(names[:most]) + (f", … ({len(names)} in all)" if len(names) > most else "")
        out.append(f"fix (agent{'s' if len(names) > 1 else ''} {who}): {fix}")
    return out


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
        fix = FIX_NOT_DOMINATED if i not in ant else FIX_SEMIDEFINITE
        violations.append(
            Violation(
                i, f"not in-degree-dominated and {why}, so it can be neither in V1 nor in V2", fix
            )
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
                FIX_UNREACHED if v1a.size else FIX_NO_V1,
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


#: Keys of the stable JSON format of ``ntc design`` (per mode for a switching file).


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
        "violations": [
            {"agent": lab[v.agent], "reason": v.reason, "fix": v.fix} for v in dec.violations
        ],
    }


def structure_tables(rep: dict, title: str, most: int = 10) -> list[Table]:
    """:func:`structure_report` as the tables every face shows (the terminal's ``ntc
    check``): the edges and their classes, the agents' sets and C_i, and Assumption 2's
    decomposition with the positive-negative paths, or its first violations.

    Parameters
    ----------
    rep : dict
        :func:`structure_report`'s mapping.
    title : str
        The topology's name.
    most : int, optional
        Violations listed (``--json`` has them all).

    Returns
    -------
    list of ntc_design.present.rows.Table
    """

    # labels and names come from files: each on one line, control characters escaped
    def lab(x: Any) -> str:
        return one_line(str(x))

    def labs(xs: Sequence[Any]) -> str:
        return set_text([lab(x) for x in xs])

    name = lab(title)
    edges = Table.build(
        f"{name}: d = {rep['dim']}, N = {len(rep['agents'])}; edges (j -> i carries A_ij)",
        ("edge", "class"),
        [(f"{lab(e['from'])} -> {lab(e['to'])}", e["class"]) for e in rep["edges"]],
    )
    agents = Table.build(
        f"agents (U = {labs(rep['U'])})",
        ("agent", "N_i", "N'_i", "Ω_i", "in-degree-dominated", "C_i"),
        [
            (
                lab(a),
                labs(info["in_neighbours"]),
                labs(info["out_neighbours"]),
                labs(info["omega"]),
                "yes" if info["in_degree_dominated"] else "no",
                info["C_i"],
            )
            for a, info in rep["per_agent"].items()
        ],
    )
    rows: list[tuple[str, Any]]
    if rep["assumption_holds"]:
        v = f"(V1 = {labs(rep['V1'])}, V2 = {labs(rep['V2'])})"
        rows = [("Assumption 2", verdict(True, v, word="holds"))]
        rows += [
            (f"agent {lab(a)}", "reached by the positive-negative path " + " -> ".join(map(lab, p)))
            for a, p in rep["paths"].items()
        ]
        notes: list[str] = []
    else:
        vs = rep["violations"]
        rows = [
            (
                "Assumption 2",
                verdict(
                    False,
                    f"({counted(len(vs), 'agent')} violate{'s' if len(vs) == 1 else ''} it)",
                    word="fails",
                ),
            )
        ]
        rows += [(f"agent {lab(v['agent'])}", lab(v["reason"])) for v in vs[:most]]
        more = f"{len(vs) - most} more ({Option('json', alias='to_dict()')} lists them all)"
        notes = [more] if len(vs) > most else []
        notes += _fix_lines([(v["agent"], v.get("fix", "")) for v in vs])
    return [
        edges,
        agents,
        Table.build(f"{name}: Assumption 2", ("", ""), rows, notes, layout="list"),
    ]


#: ``ntc check`` prints every edge and agent up to this many agents, a summary above
#: (``--full`` asks for the whole table).
SUMMARY_ABOVE = 50
SHOWN = 10  # members of a set a summary names


def structure_summary(top: Topology) -> dict:
    """What ``ntc check`` shows about a large topology: counts instead of one row per
    edge and agent (cost O(N + E): a 10⁶-agent file is summarised in seconds).

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    dict
        N, d, E, the edge classes counted, |U|, how many agents are in-degree-dominated,
        the Assumption 2 verdict with |V1|, |V2| and the first :data:`SHOWN` members of
        U, V1, V2 and of the violations (labels), and the violations counted.
    """
    lab = top.labels
    dec = assumption2(top)
    idd = in_degree_dominated_all(top)
    counts: dict[str, int] = {}
    for c in top.classes.values():
        counts[c.value] = counts.get(c.value, 0) + 1

    def first(idx) -> list:
        return [lab[i] for i in list(idx)[:SHOWN]]

    return {
        "topology": top.name,
        "dim": top.dim,
        "N": top.n,
        "E": len(top.classes),
        "edge_classes": dict(sorted(counts.items())),
        "U_count": len(top.antagonised),
        "U": first(top.antagonised),
        "in_degree_dominated": int(np.count_nonzero(idd)),
        "assumption_holds": dec.holds,
        "V1_count": len(dec.v1),
        "V1": first(dec.v1),
        "V2_count": len(dec.v2),
        "V2": first(dec.v2),
        "violations_count": len(dec.violations),
        "violations": [
            {"agent": lab[v.agent], "reason": v.reason, "fix": v.fix}
            for v in dec.violations[:SHOWN]
        ],
    }


def summary_table(summary: dict, title: str) -> Table:
    """:func:`structure_summary` as the table every face shows.

    Parameters
    ----------
    summary : dict
        :func:`structure_summary`'s mapping.
    title : str
        The topology's name.

    Returns
    -------
    ntc_design.present.rows.Table
    """

    def some(items: list, count: int) -> str:
        more = f" … ({count} in all)" if count > len(items) else ""
        return set_text(items) + more

    s = summary
    classes = ", ".join(f"{k} {v}" for k, v in s["edge_classes"].items()) or "none"
    rows = [
        ("agents N, dimension d", f"{s['N']}, {s['dim']}"),
        ("edges (by class)", f"{s['E']} ({classes})"),
        ("U (agents with an antagonistic in-edge)", some(s["U"], s["U_count"])),
        ("in-degree-dominated agents", f"{s['in_degree_dominated']} of {s['N']}"),
        ("Assumption 2", verdict(s["assumption_holds"])),
        ("V1", some(s["V1"], s["V1_count"])),
        ("V2", some(s["V2"], s["V2_count"])),
    ]
    rows += [(f"violation: agent {v['agent']}", v["reason"]) for v in s["violations"]]
    notes = []
    if s["violations_count"] > len(s["violations"]):
        notes.append(f"{s['violations_count']} agents violate Assumption 2; {SHOWN} are shown")
    notes += _fix_lines([(v["agent"], v.get("fix", "")) for v in s["violations"]])
    full, json = Option("full", alias="full=True"), Option("json", alias="to_dict()")
    notes.append(f"{full} prints every edge and agent; {full} {json} lists them as data")
    return Table.build(f"{title}: structure (summary)", ("quantity", "value"), rows, notes)


__all__ = [
    "SUMMARY_ABOVE",
    "AssumptionWarning",
    "Decomposition",
    "Violation",
    "assumption2",
    "lemma1_coefficient",
    "structure_report",
    "structure_summary",
    "structure_tables",
    "fix_notes",
    "summary_table",
    "violation_fixes",
]
