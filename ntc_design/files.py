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

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import InputError

Label = int | str


@dataclass(frozen=True)
class EdgeData:
    """One directed edge j -> i with its weight A_ij (as written, not yet classified)."""

    source: Label  # j
    target: Label  # i
    weight: np.ndarray
    field: str  # e.g. "edge 2->1", for error messages


@dataclass(frozen=True)
class TopologyData:
    name: str | None
    dim: int
    labels: tuple[Label, ...]
    edges: tuple[EdgeData, ...]
    source: str | None


@dataclass(frozen=True)
class SwitchingData:
    modes: dict[str, TopologyData]
    schedule: tuple[tuple[str, float], ...]
    source: str | None


def jsonable(x: Any) -> Any:
    """A value JSON can hold: NumPy scalars and arrays to Python, non-finite floats to
    null (JSON has no NaN), mapping keys to strings."""
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


def read_document(path: str | Path) -> dict[str, Any]:
    """Read a YAML or JSON mapping from ``path`` (JSON by the ``.json`` suffix)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: cannot read the file ({exc.__class__.__name__})") from None
    if not text.strip():
        raise InputError(f"{p}: the file is empty")
    try:
        if p.suffix.lower() == ".json":
            doc = json.loads(text)
        else:
            doc = yaml.safe_load(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{p}: not valid JSON (line {exc.lineno}: {exc.msg})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f"line {mark.line + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or "malformed YAML"
        raise InputError(f"{p}: not valid YAML ({line}{problem})") from None
    if not isinstance(doc, dict):
        raise InputError(f"{p}: expected a mapping at the top level, got {_kind(doc)}")
    return doc


def _kind(x: Any) -> str:
    return "nothing" if x is None else type(x).__name__


def _err(source: str | None, field: str, msg: str) -> InputError:
    return InputError(f"{source}: {field}: {msg}" if source else f"{field}: {msg}")


def _number(x: Any, source: str | None, field: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise _err(source, field, f"expected a number, got {x!r}")
    v = float(x)
    if not math.isfinite(v):
        raise _err(source, field, f"entry is {x!r}; weights must be finite")
    return v


def _square(rows: Any, dim: int, source: str | None, field: str) -> np.ndarray:
    if not isinstance(rows, list) or not all(isinstance(r, list) for r in rows):
        raise _err(source, field, f"expected a {dim}x{dim} list of rows")
    if len(rows) != dim or any(len(r) != dim for r in rows):
        shape = f"{len(rows)}x{'/'.join(str(len(r)) for r in rows) or 0}"
        raise _err(source, field, f"expected a {dim}x{dim} matrix, got {shape}")
    return np.array([[_number(v, source, field) for v in r] for r in rows], dtype=float)


def parse_weight(
    spec: Any,
    dim: int,
    source: str | None,
    field: str,
    named: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """A d×d weight from its file form: rows, ``{diag: [...]}``, ``{identity: s}``,
    ``{matrix: NAME, scale: s}`` or a plain number ``s`` (meaning ``s·I``)."""
    if isinstance(spec, list):
        return _square(spec, dim, source, field)
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return _number(spec, source, field) * np.eye(dim)
    if isinstance(spec, dict):
        keys = set(spec)
        if keys == {"diag"}:
            diag = spec["diag"]
            if not isinstance(diag, list) or len(diag) != dim:
                raise _err(source, field, f"diag must list {dim} numbers")
            return np.diag([_number(v, source, field) for v in diag])
        if keys == {"identity"}:
            return _number(spec["identity"], source, field) * np.eye(dim)
        if "matrix" in keys and keys <= {"matrix", "scale"}:
            name = spec["matrix"]
            if not named or not isinstance(name, str) or name not in named:
                known = ", ".join(sorted(named or {})) or "none defined"
                raise _err(source, field, f"unknown matrix {name!r} (known: {known})")
            return _number(spec.get("scale", 1.0), source, field) * named[name]
        raise _err(
            source,
            field,
            f"unknown weight form {sorted(keys)}; use rows, {{diag: [...]}}, "
            "{identity: s}, {matrix: NAME, scale: s} or a number",
        )
    raise _err(source, field, f"expected a matrix, got {_kind(spec)}")


def _labels(agents: Any, source: str | None) -> tuple[Label, ...]:
    if isinstance(agents, int) and not isinstance(agents, bool):
        if agents < 1:
            raise _err(source, "agents", f"need at least one agent, got {agents}")
        return tuple(range(1, agents + 1))
    if isinstance(agents, list) and agents:
        labels: list[Label] = []
        for a in agents:
            if isinstance(a, bool) or not isinstance(a, (int, str)):
                raise _err(source, "agents", f"label {a!r} is not a name or a number")
            labels.append(a)
        keys = [str(a) for a in labels]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise _err(source, "agents", f"duplicated label(s) {', '.join(dup)}")
        return tuple(labels)
    raise _err(source, "agents", "expected a positive count or a non-empty list of labels")


TOPOLOGY_KEYS = {"name", "description", "dim", "agents", "matrices", "edges"}
EDGE_KEYS = {"from", "to", "weight"}


def parse_topology(doc: dict[str, Any], source: str | None = None) -> TopologyData:
    """Validate a topology mapping (see the module docstring for the form)."""
    unknown = sorted(set(doc) - TOPOLOGY_KEYS)
    if unknown:
        raise _err(
            source, unknown[0], f"unknown field (allowed: {', '.join(sorted(TOPOLOGY_KEYS))})"
        )
    for key in ("dim", "agents", "edges"):
        if key not in doc:
            raise _err(source, key, "missing")
    dim = doc["dim"]
    if isinstance(dim, bool) or not isinstance(dim, int) or dim < 1:
        raise _err(source, "dim", f"expected a positive integer, got {dim!r}")
    labels = _labels(doc["agents"], source)
    by_key = {str(a): a for a in labels}
    named: dict[str, np.ndarray] = {}
    mats = doc.get("matrices") or {}
    if not isinstance(mats, dict):
        raise _err(source, "matrices", "expected a mapping of name -> matrix")
    for name, spec in mats.items():
        named[str(name)] = parse_weight(spec, dim, source, f"matrices.{name}")
    edges_doc = doc["edges"]
    if not isinstance(edges_doc, list):
        raise _err(source, "edges", "expected a list of {from, to, weight}")
    edges: list[EdgeData] = []
    seen: set[tuple[str, str]] = set()
    for k, e in enumerate(edges_doc):
        if not isinstance(e, dict):
            raise _err(source, f"edges[{k}]", "expected a mapping {from, to, weight}")
        missing = sorted(EDGE_KEYS - set(e))
        if missing:
            raise _err(source, f"edges[{k}]", f"missing {', '.join(missing)}")
        extra = sorted(set(e) - EDGE_KEYS)
        if extra:
            raise _err(source, f"edges[{k}]", f"unknown field {extra[0]!r}")
        j, i = str(e["from"]), str(e["to"])
        field = f"edge {j}->{i}"
        for end, lab in (("from", j), ("to", i)):
            if lab not in by_key:
                raise _err(source, field, f"unknown agent label {lab!r} in '{end}'")
        if i == j:
            raise _err(source, field, "self-loop (an agent cannot listen to itself)")
        if (j, i) in seen:
            raise _err(source, field, "duplicated edge")
        seen.add((j, i))
        w = parse_weight(e["weight"], dim, source, field, named)
        edges.append(EdgeData(by_key[j], by_key[i], w, field))
    name = doc.get("name")
    return TopologyData(
        name=str(name) if name is not None else None,
        dim=dim,
        labels=labels,
        edges=tuple(edges),
        source=source,
    )


def parse_switching(doc: dict[str, Any], source: str | None = None) -> SwitchingData:
    """Validate a switching mapping: named modes and a periodic schedule."""
    unknown = sorted(set(doc) - {"name", "description", "modes", "schedule"})
    if unknown:
        raise _err(source, unknown[0], "unknown field (allowed: modes, schedule, name)")
    modes_doc = doc.get("modes")
    if not isinstance(modes_doc, dict) or not modes_doc:
        raise _err(source, "modes", "expected a non-empty mapping name -> file or topology")
    base = Path(source).parent if source else Path(".")
    modes: dict[str, TopologyData] = {}
    for name, spec in modes_doc.items():
        if isinstance(spec, str):
            path = base / spec
            modes[str(name)] = parse_topology(read_document(path), str(path))
        elif isinstance(spec, dict):
            inner = f"{source}: modes.{name}" if source else f"modes.{name}"
            modes[str(name)] = parse_topology(spec, inner)
        else:
            raise _err(source, f"modes.{name}", "expected a file path or an inline topology")
    sched = doc.get("schedule")
    if not isinstance(sched, list) or not sched:
        raise _err(source, "schedule", "expected a non-empty list of {mode, duration}")
    schedule: list[tuple[str, float]] = []
    for k, item in enumerate(sched):
        field = f"schedule[{k}]"
        if not isinstance(item, dict) or set(item) != {"mode", "duration"}:
            raise _err(source, field, "expected {mode: NAME, duration: T}")
        mode = str(item["mode"])
        # mode names and positive durations are checked by the model (SwitchingTopology)
        dur = _number(item["duration"], source, f"{field}.duration")
        schedule.append((mode, dur))
    return SwitchingData(modes=modes, schedule=tuple(schedule), source=source)


def parse_file(path: str | Path):
    """Read a topology or a switching file; which one is told by its fields. A ``.npz``
    file is a compact edge list (:mod:`ntc_design.edgelist`)."""
    if str(path).lower().endswith(".npz"):
        from .edgelist import read_npz

        return read_npz(path)
    doc = read_document(path)
    src = str(path)
    if "modes" in doc or "schedule" in doc:
        return parse_switching(doc, src)
    return parse_topology(doc, src)


SCENARIO_KEYS = {
    "name",
    "description",
    "topology",
    "theta",
    "margin",
    "gain",
    "noise",
    "initial",
    "T",
    "dt",
    "paths",
    "seed",
    "save_every",
    "save_times",
    "method",
    "stepping",
    "ds",
    "workers",
    "block_size",
    "store_paths",
    "resample",
}


@dataclass(frozen=True)
class ScenarioData:
    """A simulation scenario as written (values checked by the simulation layer)."""

    source: str
    topology: Path
    values: dict[str, Any]
    initial: Any
    noise: dict[str, Any]


def parse_scenario(path: str | Path) -> ScenarioData:
    """Read a scenario file::

    topology: g1.yaml            # a topology or switching file, relative to this file
    theta: [1, 2, -1]
    margin: 0.1
    gain: "1/(1+t)"
    noise: {sigma: 0.4, f: 0.3}  # f: a scalar s (f(x) = s x) or a d×d matrix;
                                 # sigma_edges: [{from: 2, to: 1, sigma: 0.1}]
    initial: {uniform: [-3, 3], seed: 1}   # or a list of N states (each d numbers)
    T: 10
    dt: 0.001
    paths: 1000
    seed: 0
    save_every: 0.1              # or save_times: [0, 0.5, 1, ...]
    method: both                 # mc | exact | both
    stepping: uniform            # or intrinsic (with ds)
    """
    doc = read_document(path)
    src = str(path)
    unknown = sorted(set(doc) - SCENARIO_KEYS)
    if unknown:
        raise _err(
            src, unknown[0], "unknown field (allowed: " + ", ".join(sorted(SCENARIO_KEYS)) + ")"
        )
    for key in ("topology", "theta"):
        if key not in doc:
            raise _err(src, key, "missing")
    topo = doc["topology"]
    if not isinstance(topo, str):
        raise _err(src, "topology", "expected a file path")
    tpath = Path(src).parent / topo
    if not tpath.is_file():
        raise _err(src, "topology", f"no such file {tpath}")
    noise = doc.get("noise", {}) or {}
    if not isinstance(noise, dict) or set(noise) - {"sigma", "f", "sigma_edges"}:
        raise _err(src, "noise", "expected {sigma, f, sigma_edges}")
    if "sigma" in noise:
        s = _number(noise["sigma"], src, "noise.sigma")
        if s < 0:
            raise _err(src, "noise.sigma", f"must be >= 0, got {noise['sigma']!r}")
    if "f" in noise and not isinstance(noise["f"], (int, float, list)):
        raise _err(src, "noise.f", "expected a number or a d×d matrix")
    edges = noise.get("sigma_edges", []) or []
    if not isinstance(edges, list) or any(
        not isinstance(e, dict) or set(e) != {"from", "to", "sigma"} for e in edges
    ):
        raise _err(src, "noise.sigma_edges", "expected a list of {from, to, sigma}")
    values = {k: v for k, v in doc.items() if k not in ("topology", "noise", "initial")}
    for key in ("T", "dt", "margin", "save_every", "ds", "resample"):
        if key in values:
            _number(values[key], src, key)
    for key in ("paths", "seed", "workers", "block_size", "store_paths"):
        if key in values and (isinstance(values[key], bool) or not isinstance(values[key], int)):
            raise _err(src, key, f"expected an integer, got {values[key]!r}")
    return ScenarioData(src, tpath, values, doc.get("initial"), noise)
