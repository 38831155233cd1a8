"""Bridges to the libraries users already hold their networks and models in.

* networkx: :func:`topology_from_networkx` / :func:`topology_to_networkx` (a ``DiGraph``
  whose edge u -> v carries A_vu, agent v listening to u, as the d×d matrix under an
  attribute, default ``"weight"``; a scalar is accepted for d = 1). Round trips are exact.
* files: :func:`save_topology` writes the topology-file form (YAML, or JSON by the
  ``.json`` suffix) that :func:`ntc_design.model.load.load` reads back exactly.
* python-control: :func:`design_statespace`, the noise-free protocol at c = 1 as a
  ``control.StateSpace`` with state x (Nd), input θ (d) and output x.
* pandas: :func:`simulation_frame`, a simulation result as a tidy DataFrame.

Only the model and design layers are imported here; the simulation result is duck-typed
so that this module sits below the simulation layer.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml

from .errors import InputError, optional_module
from .io.files import jsonable
from .io.outputs import write_atomic
from .model import Topology
from .simulate.result import simulation_frame

if TYPE_CHECKING:  # pragma: no cover - typing only
    import control
    import networkx as nx

    from .protocol import ProtocolDesign


# ---------------------------------------------------------------------------- networkx


def topology_from_networkx(
    graph: nx.DiGraph,
    weight: str = "weight",
    dim: int | None = None,
    name: str | None = None,
) -> Topology:
    """A :class:`~ntc_design.model.Topology` from a directed networkx graph.

    Parameters
    ----------
    graph
        A ``networkx.DiGraph``; its nodes (in graph order) are the agent labels and an
        edge u -> v means that v listens to u, carrying ``A_vu``.
    weight
        The edge attribute holding ``A_vu``: a d×d symmetric matrix, or a number for d = 1.
    dim
        The state dimension d; by default taken from the first edge (or
        ``graph.graph["dim"]``, or 1 for a graph without edges).
    name
        The topology's name; by default ``graph.graph.get("name")``.

    Returns
    -------
    Topology
        Validated as any topology file is (symmetric weights of one sign, no self-loop).

    Raises
    ------
    InputError
        Not a simple directed graph, a missing or non-numeric attribute, a weight of the
        wrong shape; the message names the edge.
    """
    nx = optional_module("networkx", "interop", "from_networkx")

    if not isinstance(graph, nx.DiGraph) or graph.is_multigraph():
        raise InputError(
            f"expected a networkx.DiGraph, got {type(graph).__name__} "
            "(convert an undirected graph with graph.to_directed())",
            field="from_networkx",
        )
    labels = tuple(graph.nodes)
    if len(set(map(str, labels))) != len(labels):
        raise InputError("node labels must stay distinct as text", field="from_networkx")
    mats = []
    for u, v, data in graph.edges(data=True):
        where = f"from_networkx: edge {u}->{v}"
        if weight not in data:
            raise InputError(f"no '{weight}' attribute", field=where)
        try:
            a = np.array(data[weight], dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"'{weight}' is not a number or a matrix", field=where) from None
        if a.ndim == 0:
            a = a.reshape(1, 1)
        if a.ndim != 2 or a.shape[0] != a.shape[1]:
            raise InputError(
                f"'{weight}' has shape {a.shape}, expected a square matrix", field=where
            )
        if dim is None:
            dim = a.shape[0]
        if a.shape != (dim, dim):
            raise InputError(
                f"'{weight}' has shape {a.shape}, expected ({dim}, {dim})", field=where
            )
        mats.append((u, v, a))
    if dim is None:
        dim = int(graph.graph.get("dim", 1))
    return Topology.from_edges(labels, dim, mats, name=name or graph.graph.get("name"))


def topology_to_networkx(top: Topology, weight: str = "weight") -> nx.DiGraph:
    """The topology as a ``networkx.DiGraph``: nodes are the labels (in order), edge
    j -> i carries a copy of the d×d matrix ``A_ij`` under ``weight``; ``graph.graph``
    holds ``dim`` and ``name``. :func:`topology_from_networkx` inverts it exactly.

    Parameters
    ----------
    top
        The topology.
    weight
        The edge attribute name.

    Returns
    -------
    networkx.DiGraph
    """
    nx = optional_module("networkx", "interop", "to_networkx")

    g = nx.DiGraph(dim=top.dim, name=top.name)
    g.add_nodes_from(top.labels)
    for (i, j), a in sorted(top.weights.items()):
        g.add_edge(top.labels[j], top.labels[i], **{weight: np.array(a, dtype=float)})
    return g


# ------------------------------------------------------------------------------- files


def save_topology(top: Topology, path: str | Path) -> Path:
    """Write the topology file (YAML, or JSON when the suffix is ``.json``) atomically;
    :func:`ntc_design.model.load.load` reads it back exactly (floats are written in full).

    Parameters
    ----------
    top
        The topology.
    path
        Target file; its directory must exist.

    Returns
    -------
    Path
        The written path.

    Raises
    ------
    InputError
        The directory does not exist or a float is not finite.
    """
    p = Path(path)
    if not p.parent.is_dir():
        raise InputError(f"directory {p.parent} does not exist", field=str(p))
    doc = jsonable(top.to_dict())
    if p.suffix.lower() == ".json":
        text = json.dumps(doc, indent=1, ensure_ascii=False) + "\n"
    else:
        text = yaml.safe_dump(doc, sort_keys=False, allow_unicode=True, default_flow_style=None)
    return write_atomic(p, text)


# ---------------------------------------------------------------------- python-control


def design_statespace(des: ProtocolDesign) -> control.StateSpace:
    """The noise-free protocol at c = 1 as a ``control.StateSpace``:
    ``ẋ = −L_B x + k1 (Δ⊗I_d) B θ``, input θ (d), output x (Nd).

    Its DC gain ``L_B⁻¹ k1 (Δ⊗I_d) B`` is ``1_N ⊗ I_d`` exactly when the identity
    ``−L_B(1⊗θ) + k1(Δ⊗I_d)Bθ = 0`` holds (Niu & Wu, Lemma 1, eq. (11)) and −L_B is Hurwitz.

    Parameters
    ----------
    des
        A Lemma 1 design (one topology).

    Returns
    -------
    control.StateSpace
        A = −L_B, B = k1·δ·[B_i for informed i, 0 otherwise] (Nd×d), C = I_Nd, D = 0;
        states, inputs and outputs named ``x[agent,k]`` and ``theta[k]``.

    Raises
    ------
    InputError
        python-control is not installed (the ``interop`` extra).
    """
    control = optional_module("control", "interop", "design_statespace")
    top, d = des.topology, des.topology.dim
    b_in = np.zeros((top.nd, d))
    for i, bi in des.B.items():
        b_in[i * d : (i + 1) * d, :] = des.k1 * des.delta * np.asarray(bi)
    names = [f"x[{a},{k + 1}]" for a in top.labels for k in range(d)]
    return control.ss(
        -des.grounded_laplacian(),
        b_in,
        np.eye(top.nd),
        np.zeros((top.nd, d)),
        states=names,
        inputs=[f"theta[{k + 1}]" for k in range(d)],
        outputs=names,
        name=f"ntc protocol {top.name or ''}".strip(),
    )


# ------------------------------------------------------------------------------ pandas


__all__ = [
    "design_statespace",
    "save_topology",
    "simulation_frame",
    "topology_from_networkx",
    "topology_to_networkx",
]
