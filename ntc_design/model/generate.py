"""Random directed signed matrix-weighted networks that satisfy Assumption 2 by
construction (Niu & Wu, Assumption 2 with Definitions 3–4), for users and
benchmarks.

Construction (every step vectorised, O(E·d³)):

1. An undirected base graph of the chosen ``family``: ``random`` (a random recursive
   tree plus ``extra·N`` random chords: about 1.1·N edges by default), ``ring``
   (k nearest neighbours on a cycle), ``grid`` (a square lattice), ``small-world``
   (Newman–Watts–Strogatz: the ring plus a shortcut from each lattice edge with probability
   0.1, connected by construction) or ``scale-free`` (Barabási–Albert preferential
   attachment from a path of m + 1 agents, m = max(1, k/2) links per new agent, drawn
   vectorised: :func:`preferential_attachment`).
2. A set V1 of root agents (a fraction ``v1_fraction``); a breadth-first spanning forest
   of the base graph from V1 gives every other agent a parent. Each tree edge is
   oriented parent -> child and is *definite* (PD or ND, sign drawn with probability
   ``p_negative`` for ND), so every agent is reached from V1 by a positive-negative path
   (Definition 3).
3. Every V1 agent gets one extra *ND* in-edge from a random other agent, so its
   antagonistic in-weight Σ_{Ω_i}|A_ij| is positive definite (it can be in V1).
4. The remaining base edges become chords, oriented at random, with random-signed PD or
   PSD weights of size ``chord_scale``.
5. In-degree domination of every V2 agent (Definition 4): agents are processed from the
   deepest tree level up; a V2 agent's tree in-edge gets
   ``|A_{i,parent}| = Σ_{N'_i}|A_ji| − Σ_{other in-edges}|A_ij| (clipped) + R_i`` with a
   random R_i ≻ 0, so ``Σ_{N_i}|A_ij| − Σ_{N'_i}|A_ji| ⪰ R_i ≻ 0``. Its out-weight is
   known by then because every out-edge ends at a deeper agent (tree) or was drawn in
   step 3–4.

Randomness comes only from ``numpy.random.SeedSequence(seed)``: the same arguments give
the same network on every machine.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sparse
import yaml
from scipy.sparse import csgraph

from ..errors import InputError, format_bytes, require_positive
from ..io.edgelist import MAX_AGENTS, MAX_DIM, MAX_EDGES, write_npz
from ..io.outputs import check_output_file, write_atomic
from ..numerics.memory import available_memory
from . import Topology

TOPOLOGY_SUFFIXES = (".npz", ".json", ".yaml", ".yml")
_SAFE_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)

FAMILIES = ("random", "ring", "grid", "small-world", "scale-free")


def _random_pd(rng: np.random.Generator, m: int, d: int, scale: float = 1.0) -> np.ndarray:
    """m random symmetric PD d×d matrices, eigenvalues roughly in [0.5, 2]·scale."""
    g = rng.normal(size=(m, d, d))
    return scale * (g @ g.transpose(0, 2, 1) / (2.0 * d) + 0.5 * np.eye(d))


def _random_psd(rng: np.random.Generator, m: int, d: int, scale: float = 1.0) -> np.ndarray:
    """m random symmetric PSD d×d matrices of rank d−1 (rank 1 when d = 1 is PD)."""
    if d == 1:
        return _random_pd(rng, m, d, scale)
    g = rng.normal(size=(m, d, d - 1))
    return scale * (g @ g.transpose(0, 2, 1)) / d


#: Newman–Watts–Strogatz: each lattice edge adds a shortcut to a uniform agent this often.
SHORTCUT_PROBABILITY = 0.1


def preferential_attachment(
    n: int, m: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Barabási–Albert edges: agents 0…m form a path; each later agent t links to m agents
    drawn with probability proportional to their degree (a uniform entry of the list of
    every earlier edge's two ends; a repeated draw is one edge).

    The draws are independent of the graph (entry ⌊U·c_t⌋ of the c_t entries before t), so
    every entry of the list is resolved at once by pointer jumping: O(n·m·log n), vectorised.

    Parameters
    ----------
    n : int
        Agents.
    m : int
        Links per new agent.
    rng : numpy.random.Generator
        The stream (seeded by the caller).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The edges' ends (u, v), u the later agent; self-loops none, repeats possible.

    Examples
    --------
    >>> u, v = preferential_attachment(6, 2, np.random.default_rng(0))
    >>> bool(np.all(v < u)), int(u.max())
    (True, 5)
    """
    m0 = min(m, n - 1)
    path = np.arange(m0)
    if n <= m0 + 1:
        return path + 1, path
    steps = n - m0 - 1
    new = np.repeat(np.arange(m0 + 1, n), m)  # the later end of each drawn edge
    start = 2 * m0  # the path's entries come first: (1, 0), (2, 1), …
    # entry 2q is edge q's new agent, 2q + 1 its target: a copy of an earlier entry
    before = start + 2 * m * np.repeat(np.arange(steps), m)
    size = start + 2 * new.size
    val = np.empty(size, dtype=np.int64)
    val[:start:2], val[1:start:2] = path + 1, path
    val[start::2] = new
    known = np.ones(size, dtype=bool)
    known[start + 1 :: 2] = False
    ptr = np.arange(size)
    ptr[start + 1 :: 2] = (rng.random(new.size) * before).astype(np.int64)
    todo = np.arange(start + 1, size, 2)
    while todo.size:  # each round halves the chains of copies
        nxt = ptr[todo]
        done = known[nxt]
        val[todo[done]] = val[nxt[done]]
        known[todo[done]] = True
        todo = todo[~done]
        ptr[todo] = ptr[ptr[todo]]
    return np.concatenate([path + 1, new]), np.concatenate([path, val[start + 1 :: 2]])


def _base_edges(
    family: str, n: int, rng: np.random.Generator, extra: float, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Undirected base graph as (u, v) arrays without self-loops or duplicates."""
    if family == "random":
        # random recursive tree: agent t > 0 attaches to a uniform earlier agent
        u = np.arange(1, n)
        v = (rng.random(n - 1) * u).astype(np.int64)
        m = int(round(extra * n))
        cu, cv = rng.integers(0, n, m), rng.integers(0, n, m)
        u, v = np.concatenate([u, cu]), np.concatenate([v, cv])
    elif family == "ring":
        idx = np.arange(n)
        hops = np.arange(1, max(1, k // 2) + 1)
        u = np.repeat(idx, hops.size)
        v = (u + np.tile(hops, n)) % n
    elif family == "grid":
        side = int(np.ceil(np.sqrt(n)))
        idx = np.arange(n)
        right = idx + 1
        ok_r = (right % side != 0) & (right < n)
        down = idx + side
        ok_d = down < n
        u = np.concatenate([idx[ok_r], idx[ok_d]])
        v = np.concatenate([right[ok_r], down[ok_d]])
    elif family == "small-world":
        hops = np.arange(1, max(1, k // 2) + 1)
        u = np.repeat(np.arange(n), hops.size)
        v = (u + np.tile(hops, n)) % n
        short = rng.random(u.size) < SHORTCUT_PROBABILITY
        u = np.concatenate([u, u[short]])
        v = np.concatenate([v, rng.integers(0, n, int(short.sum()))])
    else:
        u, v = preferential_attachment(n, max(1, k // 2), rng)
    keep = u != v
    u, v = np.minimum(u[keep], v[keep]), np.maximum(u[keep], v[keep])
    key = np.unique(u * n + v)
    return key // n, key % n


def random_network(
    n: int,
    d: int = 3,
    seed: int = 0,
    family: str = "random",
    *,
    p_negative: float = 0.3,
    v1_fraction: float = 0.05,
    extra: float = 0.1,
    k: int = 4,
    chord_scale: float = 0.2,
    name: str | None = None,
) -> Topology:
    """A random network of ``n`` agents with d×d weights that satisfies Assumption 2.

    Parameters
    ----------
    n, d : int
        Number of agents (>= 2) and state dimension (>= 1).
    seed : int
        Seed of the ``SeedSequence`` all randomness comes from.
    family : str
        Base graph: one of :data:`FAMILIES` (see the module docstring).
    p_negative : float
        Probability that a tree edge or chord is antagonistic (ND/NSD), in [0, 1].
    v1_fraction : float
        Fraction of agents drawn as V1 roots (at least one), in (0, 1].
    extra : float
        ``random`` family: chords per agent.
    k : int
        ``ring``/``small-world``: neighbours per agent; ``scale-free``: 2·(edges per new
        agent).
    chord_scale : float
        Size of the chord weights relative to the tree weights.
    name : str, optional
        Name of the topology (default: ``family-n-d-seed``).

    Returns
    -------
    Topology
        Agents labelled 1..n; ``assumption2(top).holds`` is true by construction.

    Raises
    ------
    InputError
        For an unknown family or a parameter out of range.

    Examples
    --------
    >>> import ntc_design as nd
    >>> from ntc_design.model.generate import random_network
    >>> top = random_network(100, d=3, seed=0)
    >>> top.n, top.dim, nd.assumption2(top).holds
    (100, 3, True)
    """
    _check_parameters(n, d, seed, family, p_negative, v1_fraction, extra, k, chord_scale)
    n, d = int(n), int(d)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))

    u, v = _base_edges(family, n, rng, extra, k)
    n_v1 = max(1, int(round(v1_fraction * n)))
    v1 = np.sort(rng.choice(n, size=n_v1, replace=False))
    in_v1 = np.zeros(n, dtype=bool)
    in_v1[v1] = True

    parent, depth = _forest(u, v, n, v1, in_v1, rng)

    # tree edges parent -> child (weights set in step 5)
    child = np.flatnonzero(parent >= 0)
    tree_from, tree_to = parent[child], child
    cu, cv, ch_from, ch_to, an_from, an_to, clash_to, clash_from = _chords_and_v1_edges(
        u, v, n, v1, tree_from, tree_to, rng
    )

    neg_ch, w_ch, w_an, sgn_tree, r_tree = _draw_weights(
        rng, cu.size, an_to.size, tree_to.size, d, p_negative, chord_scale
    )

    _clashes_antagonistic(
        n, d, rng, clash_to, clash_from, tree_to, tree_from, ch_to, ch_from, sgn_tree, neg_ch, w_ch
    )

    w_tree = _tree_weights(
        n, d, depth, tree_from, tree_to, ch_from, ch_to, w_ch, an_from, an_to, w_an, r_tree
    )

    rows = np.concatenate([tree_to, ch_to, an_to])
    cols = np.concatenate([tree_from, ch_from, an_from])
    sg = np.concatenate([sgn_tree, np.where(neg_ch, -1.0, 1.0), -np.ones(an_to.size)])
    wts = sg[:, None, None] * np.concatenate([w_tree, w_ch, w_an])
    order_e = np.lexsort((cols, rows))
    return Topology.from_arrays(
        tuple(range(1, n + 1)),
        d,
        rows[order_e],
        cols[order_e],
        wts[order_e],
        name=name or f"{family}-{n}-{d}-{seed}",
    )


def _draw_weights(rng, n_chords: int, n_anta: int, n_tree: int, d: int, p_negative, chord_scale):
    """The random signs and weights, drawn in this order (the seed fixes them all): chord
    signs, chord weights (PD or PSD), V1's antagonistic weights, tree signs, tree surplus."""
    neg_ch = rng.random(n_chords) < p_negative
    w_ch = np.where(
        (rng.random(n_chords) < 0.5)[:, None, None],
        _random_pd(rng, n_chords, d, chord_scale),
        _random_psd(rng, n_chords, d, chord_scale),
    )
    w_an = _random_pd(rng, n_anta, d)
    sgn_tree = np.where(rng.random(n_tree) < p_negative, -1.0, 1.0)
    r_tree = _random_pd(rng, n_tree, d)
    return neg_ch, w_ch, w_an, sgn_tree, r_tree


def _check_parameters(n, d, seed, family, p_negative, v1_fraction, extra, k, chord_scale) -> None:
    """:func:`random_network`'s parameters, each refused with its name."""
    require_positive("n", n, integer=True)
    require_positive("d", d, integer=True)
    if n < 2:
        raise InputError("a network needs at least 2 agents", field="n")
    if family not in FAMILIES:
        raise InputError(f"unknown {family!r} (known: {', '.join(FAMILIES)})", field="family")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"must be a non-negative integer, got {seed!r}", field="seed")
    if not 0.0 <= p_negative <= 1.0:
        raise InputError(f"must be in [0, 1], got {p_negative}", field="p_negative")
    if not 0.0 < v1_fraction <= 1.0:
        raise InputError(f"must be in (0, 1], got {v1_fraction}", field="v1_fraction")
    if not (extra >= 0 and np.isfinite(extra)):
        raise InputError(f"must be a non-negative number, got {extra}", field="extra")
    require_positive("k", k, integer=True)
    require_positive("chord_scale", chord_scale)
    if n > MAX_AGENTS:
        raise InputError(
            f"{n} agents is more than every topology reader accepts ({MAX_AGENTS})", field="n"
        )
    if d > MAX_DIM:
        raise InputError(f"{d} is more than every topology reader accepts ({MAX_DIM})", field="d")
    edges, need = generation_size(n, d, family, extra, k)
    if edges > MAX_EDGES:
        raise InputError(
            f"about {edges:.3g} edges, more than every topology reader accepts ({MAX_EDGES}); "
            "lower n, k or extra",
            field="n",
        )
    avail = available_memory()
    if need > 0.5 * avail:
        raise InputError(
            f"generating needs about {format_bytes(need)} of memory, more than 50 % of the "
            f"{format_bytes(avail)} available; lower n or d",
            field="n",
        )


def generation_size(n: int, d: int, family: str, extra: float, k: int) -> tuple[float, float]:
    """Edges and peak bytes :func:`random_network` will need, from its parameters alone
    (an upper estimate: every base edge may be directed both ways; the weights, their
    eigen-decompositions and NetworkX's objects for the small-world and scale-free
    families).

    Parameters
    ----------
    n, d : int
        Agents and state dimension.
    family : str
        One of :data:`FAMILIES`.
    extra : float
        Chords per agent (``random``).
    k : int
        Neighbours per agent (``ring``, ``small-world``, ``scale-free``).

    Returns
    -------
    tuple of float
        (edges, bytes).
    """
    base = {
        "random": (n - 1) + extra * n,
        "grid": 2.0 * n,
    }.get(family, n * max(1, k // 2))
    edges = 2.0 * float(base)
    per_edge = 8.0 * d * d * 6 + 64.0 + (600.0 if family in ("small-world", "scale-free") else 0)
    return edges, edges * per_edge + 200.0 * n


def _forest(u, v, n, v1, in_v1, rng) -> tuple[np.ndarray, np.ndarray]:
    """(parent, depth): a BFS forest from V1 over the base graph (a virtual root joined
    to V1); agents the base graph leaves unreached (disconnected families) hang on a
    random V1 agent."""
    n_v1 = v1.size
    und = sparse.coo_matrix((np.ones(u.size, dtype=np.int8), (u, v)), shape=(n + 1, n + 1)).tocsr()
    und = und + und.T
    root = sparse.csr_matrix(
        (np.ones(n_v1, dtype=np.int8), (np.full(n_v1, n), v1)), shape=(n + 1, n + 1)
    )
    g = (und + root).tocsr()
    g.sort_indices()
    order, pred = csgraph.breadth_first_order(g, n, directed=True, return_predecessors=True)
    parent = pred[:n].astype(np.int64)
    parent[in_v1] = -1
    lost = np.flatnonzero((parent < 0) & ~in_v1)
    parent[lost] = v1[rng.integers(0, n_v1, lost.size)]
    depth = np.zeros(n, dtype=np.int64)
    for i in order[1:]:
        if parent[i] >= 0:
            depth[i] = depth[parent[i]] + 1
    for i in lost:  # their parents are V1 agents (depth 0)
        depth[i] = 1
    return parent, depth


def _chords_and_v1_edges(u, v, n, v1, tree_from, tree_to, rng) -> tuple[np.ndarray, ...]:
    """The base edges not in the tree (chords, random orientation) and the V1 agents'
    antagonistic in-edges from a random other agent; a V1 agent whose draw collided with
    an existing edge is returned apart (clash_to, clash_from)."""
    n_v1 = v1.size
    # chords: base edges not in the tree, random orientation
    tkey = set((np.minimum(tree_from, tree_to) * n + np.maximum(tree_from, tree_to)).tolist())
    ckey = u * n + v
    chord = np.array([x not in tkey for x in ckey.tolist()], dtype=bool)
    cu, cv = u[chord], v[chord]
    flip = rng.random(cu.size) < 0.5
    ch_from, ch_to = np.where(flip, cv, cu), np.where(flip, cu, cv)
    # V1 antagonistic in-edges from a random other agent (not an existing edge)
    src = (v1 + 1 + rng.integers(0, n - 1, n_v1)) % n
    used = set((tree_to * n + tree_from).tolist()) | set((ch_to * n + ch_from).tolist())
    ok = np.array([x not in used for x in (v1 * n + src).tolist()], dtype=bool)
    an_from, an_to = src[ok], v1[ok]
    # a V1 agent whose draw collided gets its ND weight on the colliding edge instead
    clash_to, clash_from = v1[~ok], src[~ok]
    return cu, cv, ch_from, ch_to, an_from, an_to, clash_to, clash_from


def _clashes_antagonistic(
    n, d, rng, clash_to, clash_from, tree_to, tree_from, ch_to, ch_from, sgn_tree, neg_ch, w_ch
) -> None:
    """A V1 agent whose antagonistic in-edge collided with an existing edge gets that edge
    made ND instead (signs and chord weights updated in place)."""
    if clash_to.size:
        ck = clash_to * n + clash_from
        tpos = {x: m for m, x in enumerate((tree_to * n + tree_from).tolist())}
        cpos = {x: m for m, x in enumerate((ch_to * n + ch_from).tolist())}
        for x in ck.tolist():
            if x in tpos:
                sgn_tree[tpos[x]] = -1.0
            else:
                m = cpos[x]
                neg_ch[m] = True
                w_ch[m] = _random_pd(rng, 1, d)[0]


def _tree_weights(
    n, d, depth, tree_from, tree_to, ch_from, ch_to, w_ch, an_from, an_to, w_an, r_tree
) -> np.ndarray:
    """Tree weights, deepest level first: each large enough that its child is in-degree
    dominated (Σ_in|A| ≥ Σ_out|A|) with a random PD surplus."""
    mag_in_other = np.zeros((n, d, d))  # Σ |A_ij| over in-edges other than the tree edge
    out = np.zeros((n, d, d))  # Σ_{N'_i} |A_ji|
    np.add.at(mag_in_other, ch_to, w_ch)
    np.add.at(out, ch_from, w_ch)
    np.add.at(mag_in_other, an_to, w_an)
    np.add.at(out, an_from, w_an)
    w_tree = np.zeros((tree_to.size, d, d))
    tdepth = depth[tree_to]
    for lev in range(int(tdepth.max(initial=0)), 0, -1):
        at = np.flatnonzero(tdepth == lev)
        i = tree_to[at]
        need = out[i] - mag_in_other[i]
        lam, vec = np.linalg.eigh(0.5 * (need + need.transpose(0, 2, 1)))
        need_psd = (vec * np.maximum(lam, 0.0)[:, None, :]) @ vec.transpose(0, 2, 1)
        w = need_psd + r_tree[at]
        w = 0.5 * (w + w.transpose(0, 2, 1))
        w_tree[at] = w
        np.add.at(out, tree_from[at], w)
    return w_tree


def write_topology(top: Topology, path: str | Path) -> Path:
    """Write ``top``: ``.npz`` (compact edge list, :mod:`ntc_design.io.edgelist`) or
    ``.json``/``.yaml`` (the topology-file form), atomically.

    Parameters
    ----------
    top : Topology
        The topology.
    path : str or pathlib.Path
        The file; its suffix picks the format.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    InputError
        For an unknown file type, a missing or read-only folder, or a target that is
        not a regular file."""
    p = check_output_file(path, "out", TOPOLOGY_SUFFIXES)
    suf = p.suffix.lower()
    if suf == ".npz":
        ea = top.edge_arrays
        write_npz(p, top.labels, top.dim, ea.rows, ea.cols, ea.w, top.name)
        return p
    doc = top.to_dict()
    text = (
        json.dumps(doc, indent=1) + "\n"
        if suf == ".json"
        # libyaml's emitter where PyYAML has it: the same text, about 3x faster
        else yaml.dump(doc, Dumper=_SAFE_DUMPER, sort_keys=False, default_flow_style=None)
    )
    return write_atomic(p, text)
