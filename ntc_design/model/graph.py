"""Graph functions over a :class:`~ntc_design.model.Topology` (Niu & Wu, Sec. 2.3): the
antagonistic in-weights, in-degree dominance and the
positive-negative reachability of Lemma 1; each docstring states its definition.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable

import numpy as np

from ..numerics.linalg import DEF_RTOL
from .topology import Topology


def antagonistic_in_weight(top: Topology, i: int) -> np.ndarray:
    """The total antagonistic weight into agent i, ``Σ_{j∈Ω_i} |A_ij|`` (Lemma 1).

    Parameters
    ----------
    top : Topology
        The topology.
    i : int
        0-based agent index.

    Returns
    -------
    numpy.ndarray
        d×d, positive semidefinite.
    """
    return top.degree_sums[2][i].copy()


def in_out_difference(top: Topology, i: int) -> np.ndarray:
    """In- minus out-weight of agent i (Niu & Wu, Definition 4, eq. (10)).

    Parameters
    ----------
    top : Topology
        The topology.
    i : int
        0-based agent index.

    Returns
    -------
    numpy.ndarray
        ``Σ_{j∈N_i}|A_ij| - Σ_{j∈N'_i}|A_ji|``, d×d.
    """
    inn, out, _ = top.degree_sums
    return inn[i] - out[i]


def in_degree_dominated_all(top: Topology) -> np.ndarray:
    """:func:`in_degree_dominated` for every agent at once (batched eigenvalues).

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    numpy.ndarray
        N booleans.
    """
    inn, out, _ = top.degree_sums
    if top.n == 0:
        return np.zeros(0, dtype=bool)
    # ‖·‖₂ of the PSD sums is their largest eigenvalue
    scale = np.maximum(np.linalg.eigvalsh(inn)[:, -1], np.linalg.eigvalsh(out)[:, -1])
    lam = np.linalg.eigvalsh(inn - out)[:, 0]
    return (scale == 0.0) | (lam >= -DEF_RTOL * scale)


def in_degree_dominated(top: Topology, i: int) -> bool:
    """Niu & Wu, Definition 4 (eq. (10)): agent i is in-degree-dominated when
    ``Σ_{j∈N_i}|A_ij| - Σ_{j∈N'_i}|A_ji| ⪰ 0`` (zero eigenvalues up to the tolerance of
    :mod:`ntc_design.numerics.linalg`, relative to the norms of the two sums).

    Parameters
    ----------
    top : Topology
        The topology.
    i : int
        0-based agent index.

    Returns
    -------
    bool
        Whether agent i is in-degree-dominated.
    """
    inn, out, _ = top.degree_sums
    scale = max(np.linalg.norm(inn[i], 2), np.linalg.norm(out[i], 2))
    if scale == 0.0:
        return True
    lam = np.linalg.eigvalsh(inn[i] - out[i])
    return bool(lam[0] >= -DEF_RTOL * scale)


def positive_negative_reachable(top: Topology, sources: Iterable[int]) -> dict[int, list[int]]:
    """Agents reached from ``sources`` by positive-negative paths (Niu & Wu, Definition 3:
    every edge of the path is PD or ND), with one shortest such path to each (sources
    included, with the trivial path).

    Parameters
    ----------
    top : Topology
        The topology.
    sources : iterable of int
        0-based indices of the start agents.

    Returns
    -------
    dict of int to list of int
        Each reached agent -> a shortest positive-negative path to it (indices).
    """
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
