"""Reading topology and switching files (YAML or JSON) into plain, validated data.

This is the lowest layer: it knows the file formats and checks their structure (labels,
shapes, numbers, self-loops, duplicates), and returns plain data. Whether a weight is
symmetric and of one sign is the model's business (``ntc_design.model``).

Topology file::

    name: G1                  # optional
    dim: 3
    agents: 7                 # or a list of labels
    matrices:                 # optional named weights, reusable below
      A12: [[1, 0, 0], [0, 1, 0], [0, 0, 2]]
    edges:                    # an edge from j to i carries A_ij
      - {from: 2, to: 1, weight: [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}
      - {from: 1, to: 2, weight: {diag: [-1, -1, 0]}}
      - {from: 6, to: 2, weight: {identity: -0.5}}
      - {from: 6, to: 3, weight: {matrix: A12, scale: -0.1}}

Switching file::

    modes: {G1: g1.yaml, G2: {dim: 3, agents: 7, edges: [...]}}
    schedule: [{mode: G2, duration: 0.04}, {mode: G1, duration: 0.02}]
"""

from __future__ import annotations

import difflib
import math
from collections import Counter
from collections.abc import Iterator
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from itertools import chain
from pathlib import Path
from typing import Any
from unicodedata import normalize

import numpy as np

from ..errors import InputError, require_radius
from .documents import read_document, type_name
from .edgelist import MAX_AGENTS, MAX_DIM, EdgeListData, check_label_spellings, read_npz
from .tablefiles import read_csv_edges, read_mat

Label = int | str


@dataclass(frozen=True)
class EdgeData:
    """One directed edge j -> i with its weight A_ij (as written, not yet classified)."""

    source: Label  # j
    target: Label  # i
    weight: np.ndarray
    field: str  # e.g. "edge 2->1", for error messages
    uncertainty: float | None = None  # this edge's relative radius ρ_e, when given
    loss: float | None = None  # this edge's message loss p_e (the digital protocol), when given


@dataclass(frozen=True)
class TopologyData:
    """A topology file as read: name, dimension d, agent labels and edges (validated
    field by field; the network checks are :class:`ntc_design.model.Topology`'s)."""

    name: str | None
    dim: int
    labels: tuple[Label, ...]
    edges: tuple[EdgeData, ...]
    source: str | None
    uncertainty: float | None = None  # the file-wide default radius, when given


@dataclass(frozen=True)
class SwitchingData:
    """A switching file as read: each mode's topology and the periodic schedule as
    (mode, duration) pairs."""

    modes: dict[str, Any]  # TopologyData, or EdgeListData for an .npz mode file
    schedule: tuple[tuple[str, float], ...]
    source: str | None


def jsonable(x: Any) -> Any:
    """A value JSON can hold.

    Parameters
    ----------
    x : Any
        A value built of NumPy arrays and scalars, floats, mappings and sequences.

    Returns
    -------
    Any
        The same value with NumPy scalars and arrays as Python objects, non-finite floats
        as ``None`` (JSON has no NaN) and mapping keys as strings.
    """
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    return x


def field_error(source: str | None, field: str, msg: str) -> InputError:
    """The one-line error naming the file and the field."""
    return InputError(msg, field=f"{source}: {field}" if source else field)


def _close(key: Any, known: Any) -> str:
    """``; did you mean 'weight'?`` for a key one or two typos from a known one."""
    if not isinstance(key, str):
        return ""
    match = difflib.get_close_matches(key, sorted(known), n=1, cutoff=0.7)
    return f"; did you mean {match[0]!r}?" if match else ""


def _show(x: Any, n: int = 40) -> str:
    """A value for a one-line message: repr, newlines escaped, at most ``n`` characters."""
    if isinstance(x, int) and x.bit_length() >= 200:
        return f"<an integer of {len(str(x)) if x.bit_length() < 14_000 else 'over 4000'} digits>"
    r = repr(x)
    return r if len(r) <= n else r[: n - 1] + "…"


def _q(key: Any) -> str:
    """A label or key as it appears in a field name: plain if short and printable."""
    if type(key) is int and key.bit_length() < 100:  # the common case: at most 31 digits
        return str(key)
    s = str(key) if not isinstance(key, int) or key.bit_length() < 200 else _show(key)
    return s if s.isprintable() and len(s) <= 40 and s.strip() == s else _show(s)


def text_field(doc: dict[str, Any], key: str, source: str | None = None) -> str | None:
    """An optional free-text field (``name``, ``description``) of a scenario or sweep file.

    Parameters
    ----------
    doc : dict
        The document.
    key : str
        The field.
    source : str, optional
        The file, for messages.

    Returns
    -------
    str or None
        The text, None when absent or null.

    Raises
    ------
    InputError
        Anything else (a list, a number): refused, not used as its repr.
    """
    v = doc.get(key)
    if v is None or isinstance(v, str):
        return v
    raise field_error(source, key, f"expected text, got {type_name(v)} {_show(v)}")


def _number(x: Any, source: str | None, field: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise field_error(source, field, f"expected a number, got {_show(x)}")
    try:
        v = float(x)
    except OverflowError:
        raise field_error(source, field, f"number {_show(x)} is too large") from None
    if not math.isfinite(v):
        raise field_error(source, field, f"entry is {_show(x)}; numbers must be finite")
    return v


_NUMBERS = {int, float}
_LIST = {list}
_PLAIN = {int, float, bool, type(None)}  # scalars that are not text


def _square(rows: Any, dim: int, source: str | None, field: str) -> np.ndarray:
    if (  # the common case, every check in C: dim lists of dim ints and floats (no bool)
        type(rows) is list
        and len(rows) == dim
        and set(map(type, rows)) == _LIST
        and set(map(len, rows)) == {dim}
        and set(map(type, chain.from_iterable(rows))) <= _NUMBERS
    ):
        try:  # float(v) for each entry; a huge or non-finite one is named below
            a = np.array(rows, dtype=float)
        except OverflowError:
            a = None
        if a is not None and np.isfinite(a).all():
            return a
    if not isinstance(rows, list) or not all(isinstance(r, list) for r in rows):
        raise field_error(source, field, f"expected a {dim}x{dim} list of rows")
    if len(rows) != dim or any(len(r) != dim for r in rows):
        cols = sorted({len(r) for r in rows})
        shape = f"{len(rows)}x{'/'.join(str(c) for c in cols[:4]) or 0}"
        raise field_error(source, field, f"expected a {dim}x{dim} matrix, got {shape}")
    return np.array([[_number(v, source, field) for v in r] for r in rows], dtype=float)


def parse_weight(
    spec: Any,
    dim: int,
    source: str | None,
    field: str,
    named: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """A d×d edge weight from its file form.

    Parameters
    ----------
    spec : Any
        Rows, ``{diag: [...]}``, ``{identity: s}``, ``{matrix: NAME, scale: s}`` or a plain
        number ``s`` (meaning ``s·I``).
    dim : int
        The weight's size d.
    source : str or None
        The file it came from, for messages.
    field : str
        The field it came from, for messages.
    named : dict of str to numpy.ndarray, optional
        The file's named matrices, for the ``matrix`` form.

    Returns
    -------
    numpy.ndarray
        The d×d weight (not symmetrised: the model checks symmetry).

    Raises
    ------
    InputError
        A non-numeric entry, a wrong shape, an unknown name or form.
    """
    if isinstance(spec, list):
        return _square(spec, dim, source, field)
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return _number(spec, source, field) * np.eye(dim)
    if isinstance(spec, dict):
        keys = set(spec)
        if keys == {"diag"}:
            diag = spec["diag"]
            if not isinstance(diag, list) or len(diag) != dim:
                raise field_error(source, field, f"diag must list {dim} numbers")
            return np.diag([_number(v, source, field) for v in diag])
        if keys == {"identity"}:
            return _number(spec["identity"], source, field) * np.eye(dim)
        if "matrix" in keys and keys <= {"matrix", "scale"}:
            name = spec["matrix"]
            if not named or not isinstance(name, str) or name not in named:
                known = ", ".join(_q(k) for k in sorted(named or {})[:10]) or "none defined"
                raise field_error(source, field, f"unknown matrix {_show(name)} (known: {known})")
            return _number(spec.get("scale", 1.0), source, field) * named[name]
        raise field_error(
            source,
            field,
            f"unknown weight form {sorted(keys, key=str)}; use rows, {{diag: [...]}}, "
            "{identity: s}, {matrix: NAME, scale: s} or a number",
        )
    raise field_error(source, field, f"expected a matrix, got {type_name(spec)}")


def parse_labels(agents: Any, source: str | None) -> tuple[Label, ...]:
    """The agent labels of ``agents``: a count (labels 1..N) or a list of distinct labels."""
    if isinstance(agents, int) and not isinstance(agents, bool):
        if agents < 1:
            raise field_error(source, "agents", f"need at least one agent, got {_show(agents)}")
        if agents > MAX_AGENTS:
            raise field_error(source, "agents", f"{_show(agents)} agents; at most {MAX_AGENTS}")
        return tuple(range(1, agents + 1))
    if isinstance(agents, list) and agents:
        if len(agents) > MAX_AGENTS:
            raise field_error(source, "agents", f"{len(agents)} labels; at most {MAX_AGENTS}")
        labels: list[Label] = []
        for a in agents:
            if isinstance(a, bool) or not isinstance(a, (int, str)):
                raise field_error(source, "agents", f"label {_show(a)} is not a name or a number")
            if isinstance(a, int) and a.bit_length() > 63:
                raise field_error(source, "agents", f"label {_show(a)} is too large")
            labels.append(a)
        counts = Counter(str(a) for a in labels)
        dup = sorted(k for k, c in counts.items() if c > 1)
        if dup:
            raise field_error(
                source, "agents", f"duplicated label(s) {', '.join(_q(k) for k in dup[:5])}"
            )
        return check_label_spellings(labels, f"{source or 'topology'}: agents")
    raise field_error(source, "agents", "expected a positive count or a non-empty list of labels")


def _weights_at_once(edges_doc: Any, dim: int) -> list[np.ndarray] | None:
    """Every edge's weight, when all are written as dim rows of dim finite numbers (no
    bool), converted in one call; None otherwise (each is then read by ``parse_weight``,
    which names the bad entry)."""
    if type(edges_doc) is not list or set(map(type, edges_doc)) != {dict}:
        return None
    ws = [e.get("weight") for e in edges_doc]
    rows = list(chain.from_iterable(ws)) if set(map(type, ws)) == _LIST else None
    if (
        rows is None
        or set(map(len, ws)) != {dim}
        or set(map(type, rows)) != _LIST
        or set(map(len, rows)) != {dim}
        or not set(map(type, chain.from_iterable(rows))) <= _NUMBERS
    ):
        return None
    try:
        a = np.array(ws, dtype=float)  # float(v) of every entry
    except OverflowError:
        return None
    return [w.copy() for w in a] if np.isfinite(a).all() else None


TOPOLOGY_KEYS = {"name", "description", "dim", "agents", "matrices", "edges", "uncertainty"}
EDGE_KEYS = {"from", "to", "weight"}
EDGE_OPTIONAL = {"uncertainty", "loss"}


def parse_uncertainty(value: Any, source: str | None, field: str) -> float:
    """A relative radius ρ of a weight's Loewner interval: a number in [0, 1).

    Parameters
    ----------
    value : Any
        The value as read.
    source : str or None
        The file, for messages.
    field : str
        The field, for messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a finite number in [0, 1).
    """
    return require_radius(value, f"{source}: {field}" if source else field)


def parse_edge_loss(value: Any, source: str | None, field: str) -> float:
    """An edge's message loss probability p_e (the digital protocol): a finite number in
    [0, 1).

    Parameters
    ----------
    value : Any
        The value as read.
    source : str or None
        The file, for messages.
    field : str
        The field, for messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a finite number in [0, 1).
    """
    where = f"{source}: {field}" if source else field
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a loss probability in [0, 1), got {_show(value)}", field=where)
    v = float(value)
    if not (math.isfinite(v) and 0.0 <= v < 1.0):
        raise InputError(f"a loss probability must be finite and in [0, 1), got {v!r}", field=where)
    return v


def edge_entries(
    edges_doc: list, by_key: dict[str, Label], source: str | None, optional: AbstractSet[str]
) -> Iterator[tuple[int, dict, str, Label, Label]]:
    """The edges of an ``edges`` list as every topology format checks them, once: each a
    mapping of ``from``, ``to``, ``weight`` (and the ``optional`` keys), its ends known
    labels (compared in NFC), no self-loop, no edge twice.

    Parameters
    ----------
    edges_doc : list
        The document's ``edges``.
    by_key : dict of str to label
        The agents by their text (NFC).
    source : str or None
        The file, for messages.
    optional : set of str
        The keys an edge may carry besides from, to and weight.

    Yields
    ------
    tuple of (int, dict, str, label, label)
        The index, the mapping, its name in messages (``edge a->b``), from and to.

    Raises
    ------
    InputError
        The first edge that is not one, naming it.
    """
    seen: set[tuple[str, str]] = set()
    for k, e in enumerate(edges_doc):
        if not isinstance(e, dict):
            raise field_error(source, f"edges[{k}]", "expected a mapping {from, to, weight}")
        if e.keys() - optional != EDGE_KEYS:
            # an unknown key first: a misspelt 'wieght' is the cause of the missing 'weight'
            extra = sorted(set(e) - EDGE_KEYS - optional, key=str)
            if extra:
                raise field_error(
                    source,
                    f"edges[{k}]",
                    f"unknown field {_show(extra[0])}{_close(extra[0], EDGE_KEYS)}",
                )
            missing = sorted(EDGE_KEYS - set(e))
            raise field_error(source, f"edges[{k}]", f"missing {', '.join(missing)}")
        for end in ("from", "to"):
            lab = e[end]
            if isinstance(lab, bool) or not isinstance(lab, (int, str)):
                raise field_error(
                    source, f"edges[{k}].{end}", f"expected an agent label, got {_show(lab)}"
                )
        field = f"edge {_q(e['from'])}->{_q(e['to'])}"
        j, i = (
            normalize("NFC", str(e["from"])),
            normalize("NFC", str(e["to"])),
        )  # the labels are kept in NFC
        for end, lab in (("from", j), ("to", i)):
            if lab not in by_key:
                raise field_error(source, field, f"unknown agent label {_show(lab)} in '{end}'")
        if i == j:
            raise field_error(source, field, "self-loop (an agent cannot listen to itself)")
        if (j, i) in seen:
            raise field_error(source, field, "duplicated edge")
        seen.add((j, i))
        yield k, e, field, by_key[j], by_key[i]


def parse_topology(doc: dict[str, Any], source: str | None = None) -> TopologyData:
    """Validate a topology mapping (see the module docstring for the form).

    Parameters
    ----------
    doc : dict
        The mapping as read from a file.
    source : str, optional
        The file it came from, for messages.

    Returns
    -------
    TopologyData
        Labels, dimension and edges with their d×d weights.

    Raises
    ------
    InputError
        An unknown or missing field, a bad label, edge or weight.
    """
    unknown = sorted(set(doc) - TOPOLOGY_KEYS, key=str)
    if unknown:
        raise field_error(
            source,
            _q(unknown[0]),
            f"unknown field{_close(unknown[0], TOPOLOGY_KEYS)} (allowed: {', '.join(sorted(TOPOLOGY_KEYS))})",
        )
    for key in ("dim", "agents", "edges"):
        if key not in doc:
            raise field_error(source, key, "missing")
    dim = doc["dim"]
    if isinstance(dim, bool) or not isinstance(dim, int) or dim < 1:
        raise field_error(source, "dim", f"expected a positive integer, got {_show(dim)}")
    if dim > MAX_DIM:
        raise field_error(source, "dim", f"{_show(dim)} is larger than the limit {MAX_DIM}")
    labels = parse_labels(doc["agents"], source)
    by_key = {str(a): a for a in labels}
    named: dict[str, np.ndarray] = {}
    mats = doc.get("matrices") or {}
    if not isinstance(mats, dict):
        raise field_error(source, "matrices", "expected a mapping of name -> matrix")
    for name, spec in mats.items():
        named[str(name)] = parse_weight(spec, dim, source, f"matrices.{_q(name)}")
    edges_doc = doc["edges"]
    if not isinstance(edges_doc, list):
        raise field_error(source, "edges", "expected a list of {from, to, weight}")
    edges: list[EdgeData] = []
    batch = _weights_at_once(edges_doc, dim)
    for k, e, field, j, i in edge_entries(edges_doc, by_key, source, EDGE_OPTIONAL):
        w = batch[k] if batch is not None else parse_weight(e["weight"], dim, source, field, named)
        unc = e.get("uncertainty")
        rho = None if unc is None else parse_uncertainty(unc, source, f"{field}: uncertainty")
        lost = e.get("loss")
        p_e = None if lost is None else parse_edge_loss(lost, source, f"{field}: loss")
        edges.append(EdgeData(j, i, w, field, rho, p_e))
    name = doc.get("name")
    default = doc.get("uncertainty")
    return TopologyData(
        name=str(name) if name is not None else None,
        dim=dim,
        labels=labels,
        edges=tuple(edges),
        source=source,
        uncertainty=None if default is None else parse_uncertainty(default, source, "uncertainty"),
    )


_EDGE_READERS = {".npz": read_npz, ".csv": read_csv_edges, ".mat": read_mat}


def parse_switching(doc: dict[str, Any], source: str | None = None) -> SwitchingData:
    """Validate a switching mapping: named modes and a periodic schedule.

    Parameters
    ----------
    doc : dict
        The mapping as read from a file; a mode is a topology file (relative to
        ``source``) or an inline topology.
    source : str, optional
        The file it came from, for messages and for locating mode files.

    Returns
    -------
    SwitchingData
        The modes' topologies and the schedule as (mode, duration) pairs.

    Raises
    ------
    InputError
        An unknown field, an unreadable or invalid mode, a malformed schedule entry.
    """
    unknown = sorted(set(doc) - {"name", "description", "modes", "schedule"}, key=str)
    if unknown:
        raise field_error(source, _q(unknown[0]), "unknown field (allowed: modes, schedule, name)")
    modes_doc = doc.get("modes")
    if not isinstance(modes_doc, dict) or not modes_doc:
        raise field_error(source, "modes", "expected a non-empty mapping name -> file or topology")
    base = Path(source).parent if source else Path(".")
    modes: dict[str, TopologyData | EdgeListData] = {}
    for name, spec in modes_doc.items():
        if isinstance(spec, str):
            path = base / spec
            try:
                reader = _EDGE_READERS.get(Path(spec).suffix.lower())
                if reader is not None:  # an .npz/.csv edge list or a MATLAB block matrix
                    modes[str(name)] = reader(path)
                    continue
                mode_doc = read_document(path)
            except InputError as exc:  # say which switching file and mode named it
                raise field_error(source, f"modes.{_q(name)}", str(exc)) from None
            modes[str(name)] = parse_topology(mode_doc, str(path))
        elif isinstance(spec, dict):
            inner = f"{source}: modes.{_q(name)}" if source else f"modes.{_q(name)}"
            modes[str(name)] = parse_topology(spec, inner)
        else:
            raise field_error(
                source, f"modes.{_q(name)}", "expected a file path or an inline topology"
            )
    sched = doc.get("schedule")
    if not isinstance(sched, list) or not sched:
        raise field_error(source, "schedule", "expected a non-empty list of {mode, duration}")
    schedule: list[tuple[str, float]] = []
    for k, item in enumerate(sched):
        field = f"schedule[{k}]"
        if not isinstance(item, dict) or set(item) != {"mode", "duration"}:
            raise field_error(source, field, "expected {mode: NAME, duration: T}")
        mode = str(item["mode"])
        # mode names and positive durations are checked by the model (SwitchingTopology)
        dur = _number(item["duration"], source, f"{field}.duration")
        schedule.append((mode, dur))
    return SwitchingData(modes=modes, schedule=tuple(schedule), source=source)


def has_text(x: Any) -> bool:
    """Whether a weight specification contains a string (an expression of t)."""
    if isinstance(x, str):
        return True
    if isinstance(x, dict):
        return any(has_text(v) for k, v in x.items() if k != "matrix")
    if isinstance(x, list):
        if all(type(r) is list for r in x):  # rows: their entries' types at once, in C
            if set(map(type, chain.from_iterable(x))) <= _PLAIN:
                return False
        return any(has_text(v) for v in x)
    return False


def is_time_varying(doc: dict[str, Any]) -> bool:
    """Whether a topology mapping is time-varying (:mod:`ntc_design.io.tvfiles`).

    Parameters
    ----------
    doc : dict
        A topology mapping as read.

    Returns
    -------
    bool
        True when it declares ``period``/``constant_after`` or a weight holds an
        expression (a string).
    """
    if {"period", "constant_after"} & set(doc):
        return True
    edges = doc.get("edges")
    return isinstance(edges, list) and any(
        isinstance(e, dict) and has_text(e.get("weight")) for e in edges
    )


@dataclass(frozen=True)
class ScenarioData:
    """A simulation scenario as read: its source, the topology file it names and the
    document itself (the simulation keys are checked by
    ``ntc_design.simulate.spec.SimulationSpec.from_document``)."""

    source: str
    topology: Path
    document: dict[str, Any]


def parse_scenario(path: str | Path) -> ScenarioData:
    """Read a scenario file and locate the topology file it names.

    The simulation keys are checked by the simulation layer, not here.

    Parameters
    ----------
    path : str or pathlib.Path
        A YAML or JSON scenario with a ``topology`` field (relative to the scenario).

    Returns
    -------
    ScenarioData
        The source, the topology file's path and the document.

    Raises
    ------
    InputError
        The file cannot be read, its ``name`` or ``description`` is not text, or its
        ``topology`` is missing or names no file.
    """
    doc = read_document(path)
    src = str(path)
    for key in ("name", "description"):
        text_field(doc, key, src)
    if "topology" not in doc:
        if "edges" in doc or "agents" in doc or "modes" in doc:
            raise InputError(
                f"this is a topology file; simulate and tune need a scenario whose "
                f"'topology:' names it, e.g. a YAML file with 'topology: {Path(src).name}', "
                "'theta: [1, 2, -1]', 'gain: 1/(1+t)', 'T: 10' "
                "(see examples/scenarios/g1_fixed.yaml)",
                field=src,
            )
        raise field_error(src, "topology", "missing (the topology file this scenario runs on)")
    topo = doc["topology"]
    if not isinstance(topo, str) or not topo or "\x00" in topo:
        raise field_error(src, "topology", "expected a file path")
    tpath = Path(src).parent / topo
    if not tpath.is_file():
        raise field_error(src, "topology", f"no such file {str(tpath)!r}")
    return ScenarioData(src, tpath, doc)


__all__ = [
    "EdgeData",
    "edge_entries",
    "ScenarioData",
    "SwitchingData",
    "TopologyData",
    "jsonable",
    "parse_scenario",
    "parse_switching",
    "parse_topology",
    "parse_weight",
    "text_field",
]
