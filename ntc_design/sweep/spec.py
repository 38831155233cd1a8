"""The sweep file: a base scenario and a grid or list of points, validated; one
:class:`PointTask` per point, identified by the hash of its resolved parameters."""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io.documents import read_document
from ..io.files import jsonable, parse_switching, parse_topology, text_field
from ..model import SwitchingTopology, Topology
from ..simulate.scenario import load_scenario
from ..simulate.spec import SCENARIO_KEYS

# 2: Monte Carlo draws its normals in the kernel by default (rng: xoshiro); points of
# format 1 (NumPy's PCG64) hash differently and are computed again, never mixed in
FORMAT = 2
MAX_POINTS = 10_000  # points in one sweep
MAX_VALUES = 1_000  # values of one grid key
SWEEP_KEYS = {"name", "description", "base", "grid", "points"}
# keys a sweep may set: the scenario's own (the engine, not the sweep, decides the workers),
# and the fields inside noise and initial
TOP_KEYS = set(SCENARIO_KEYS) - {"name", "description", "workers"}
NESTED_KEYS = {"noise": {"sigma", "f", "sigma_edges"}, "initial": {"uniform", "seed"}}
# simulate()'s defaults, for the path-step estimate of a point
DEFAULTS = {"T": 10.0, "dt": 1e-3, "paths": 1000}


@dataclass(frozen=True)
class Sweep:
    """A validated sweep file: the swept keys in file order and one override mapping per
    point (a listed point may leave keys out: they keep the base scenario's values)."""

    source: Path
    base: Path
    base_doc: dict
    topology_doc: dict
    keys: tuple[str, ...]
    points: tuple[dict, ...]
    name: str = ""

    def tasks(self) -> list[PointTask]:
        """One task per point, in sweep order.

        Returns
        -------
        list of PointTask
            Each with its resolved scenario and hash.
        """
        return [_task(self, p) for p in self.points]


@dataclass(frozen=True)
class PointTask:
    """What a worker needs for one point, by value: the resolved scenario (topology
    inlined as ``topology_doc``) and the swept values."""

    point: str
    params: dict
    scenario: dict
    topology_doc: dict

    @property
    def path_steps_estimate(self) -> int:
        """paths × T/dt from the scenario (0 when they are not numbers)."""
        v = {**DEFAULTS, **{k: self.scenario[k] for k in DEFAULTS if k in self.scenario}}
        try:
            return int(v["paths"]) * max(1, math.ceil(float(v["T"]) / float(v["dt"])))
        except (TypeError, ValueError, ZeroDivisionError, OverflowError):
            return 0


def _err(src: Path, fieldname: str, msg: str) -> InputError:
    return InputError(f"{msg}", field=f"{src}: {fieldname}")


def _check_key(src: Path, where: str, key: Any, base_doc: dict) -> str:
    if not isinstance(key, str) or not key:
        raise _err(src, where, f"expected a scenario field name, got {key!r}")
    head, dot, rest = key.partition(".")
    if head not in TOP_KEYS:
        raise _err(
            src,
            f"{where}.{key}",
            "not a scenario field (allowed: "
            + ", ".join(sorted(TOP_KEYS))
            + ", noise.sigma|f|sigma_edges, initial.uniform|seed)",
        )
    if dot:  # "noise." (nothing after the dot) is no field either, not all of noise
        if head not in NESTED_KEYS or rest not in NESTED_KEYS[head]:
            allowed = ", ".join(f"{h}.{k}" for h in NESTED_KEYS for k in sorted(NESTED_KEYS[h]))
            raise _err(
                src, f"{where}.{key}", f"no such field in a scenario (dotted keys: {allowed})"
            )
        if head == "initial" and not isinstance(base_doc.get("initial"), dict):
            raise _err(
                src,
                f"{where}.{key}",
                "the base scenario's initial is not a {uniform, seed} mapping",
            )
    return key


def _check_value(src: Path, where: str, value: Any) -> None:
    """Refuse an integer that the results table cannot hold (a 64-bit column; a
    400-digit integer is no float either), anywhere inside a swept value."""
    stack = [(where, value)]
    while stack:
        at, v = stack.pop()
        if isinstance(v, int) and not isinstance(v, bool) and not -(2**63) <= v < 2**63:
            digits = len(str(abs(v)))
            raise _err(
                src,
                at,
                f"an integer of {digits} digits is beyond the 64-bit integers of the results table",
            )
        if isinstance(v, dict):
            stack.extend((f"{at}.{k}", x) for k, x in v.items())
        elif isinstance(v, list):
            stack.extend((f"{at}[{i}]", x) for i, x in enumerate(v))


def _check_conflicts(src: Path, where: str, keys) -> None:
    ks = set(keys)
    for k in ks:
        if "." in k and k.split(".")[0] in ks:
            raise _err(src, f"{where}.{k}", f"conflicts with {k.split('.')[0]} set as a whole")


def _inline_topology(path: Path) -> dict:
    """The topology document with switching modes given as files read in, so it ships
    without the file system."""
    doc = read_document(path)
    modes = doc.get("modes")
    if isinstance(modes, dict):
        doc = {
            **doc,
            "modes": {
                k: read_document(path.parent / v) if isinstance(v, str) else v
                for k, v in modes.items()
            },
        }
    return doc


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep file (see the module docstring).

    Parameters
    ----------
    path
        The sweep file (YAML or JSON).

    Returns
    -------
    Sweep

    Raises
    ------
    InputError
        One line naming the file and field: an unknown key, a dotted key that is not a
        scenario field, an empty or over-long list, more than :data:`MAX_POINTS` points,
        duplicate points, or a base scenario that does not parse.
    """
    src = Path(path)
    doc = read_document(src)
    unknown = sorted(str(k) for k in set(doc) - SWEEP_KEYS)
    if unknown:
        raise _err(
            src, unknown[0], "unknown field (allowed: " + ", ".join(sorted(SWEEP_KEYS)) + ")"
        )
    for key in ("name", "description"):
        text_field(doc, key, str(src))
    if not isinstance(doc.get("base"), str) or not doc["base"]:
        raise _err(src, "base", "expected the path of a scenario file")
    base = src.parent / doc["base"]
    if not base.is_file():
        raise _err(src, "base", f"no such file {base}")
    _, _, sc = load_scenario(base)  # a broken base is the file's error, not every point's
    base_doc = read_document(base)
    if ("grid" in doc) == ("points" in doc):
        raise _err(src, "grid", "give exactly one of grid (a product of lists) or points (a list)")
    if "grid" in doc:
        grid = doc["grid"]
        if not isinstance(grid, dict) or not grid:
            raise _err(src, "grid", "expected a non-empty mapping field -> list of values")
        keys = tuple(_check_key(src, "grid", k, base_doc) for k in grid)
        _check_conflicts(src, "grid", keys)
        n = 1
        for k in keys:
            vals = grid[k]
            if not isinstance(vals, list) or not vals:
                raise _err(src, f"grid.{k}", "expected a non-empty list of values")
            if len(vals) > MAX_VALUES:
                raise _err(src, f"grid.{k}", f"{len(vals)} values; at most {MAX_VALUES}")
            _check_value(src, f"grid.{k}", vals)
            n *= len(vals)
        if n > MAX_POINTS:
            raise _err(src, "grid", f"{n} points; at most {MAX_POINTS} in one sweep")
        points = tuple(
            dict(zip(keys, combo, strict=True))
            for combo in itertools.product(*(grid[k] for k in keys))
        )
    else:
        pts = doc["points"]
        if not isinstance(pts, list) or not pts:
            raise _err(src, "points", "expected a non-empty list of {field: value} mappings")
        if len(pts) > MAX_POINTS:
            raise _err(src, "points", f"{len(pts)} points; at most {MAX_POINTS} in one sweep")
        seen: dict[str, None] = {}
        for i, p in enumerate(pts):
            if not isinstance(p, dict) or not p:
                raise _err(src, f"points[{i}]", "expected a non-empty {field: value} mapping")
            for k in p:
                seen[_check_key(src, f"points[{i}]", k, base_doc)] = None
                _check_value(src, f"points[{i}].{k}", p[k])
            _check_conflicts(src, f"points[{i}]", p)
        keys = tuple(seen)
        _check_conflicts(src, "points", keys)
        points = tuple(dict(p) for p in pts)
    topology_doc = _inline_topology(sc.topology)
    sweep = Sweep(src, base, base_doc, topology_doc, keys, points, str(doc.get("name") or src.stem))
    hashes: dict[str, int] = {}
    for i, t in enumerate(sweep.tasks()):
        if t.point in hashes:
            raise _err(
                src,
                "points" if "points" in doc else "grid",
                f"point {i} repeats point {hashes[t.point]} (same resolved parameters)",
            )
        hashes[t.point] = i
    return sweep


def _get(doc: dict, key: str) -> Any:
    head, _, rest = key.partition(".")
    v = doc.get(head)
    return v.get(rest) if rest and isinstance(v, dict) else (None if rest else v)


def _resolve(sweep: Sweep, overrides: dict) -> tuple[dict, dict]:
    """(scenario with the overrides, topology document)."""
    doc = copy.deepcopy(sweep.base_doc)
    top = sweep.topology_doc
    for key, value in overrides.items():
        head, _, rest = key.partition(".")
        if head == "topology":
            path = sweep.source.parent / str(value)
            if not path.is_file():
                raise _err(sweep.source, "topology", f"no such file {path}")
            top = _inline_topology(path)
        elif rest:
            sub = doc.get(head)
            doc[head] = {**(sub if isinstance(sub, dict) else {}), rest: copy.deepcopy(value)}
        else:
            doc[head] = copy.deepcopy(value)
    for k in ("name", "description", "workers", "topology"):
        doc.pop(k, None)
    return doc, top


def point_hash(scenario: dict, topology_doc: dict) -> str:
    """The identity of a point: it names the point's files and lets a re-run reuse them.

    Parameters
    ----------
    scenario : dict
        The resolved scenario.
    topology_doc : dict
        The inlined topology.

    Returns
    -------
    str
        16 hex digits of SHA-256 over both (canonical JSON).
    """
    body = {"format": FORMAT, "scenario": scenario, "topology": topology_doc}
    text = json.dumps(jsonable(body), sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _task(sweep: Sweep, overrides: dict) -> PointTask:
    scenario, top = _resolve(sweep, overrides)
    # the value each swept key has at this point (the base's where a listed point is silent)
    params = {k: overrides[k] if k in overrides else _get(sweep.base_doc, k) for k in sweep.keys}
    return PointTask(point_hash(scenario, top), params, scenario, top)


# -- one point (runs on a worker) ------------------------------------------------------


def topology_from_document(doc: dict, source: str = "topology"):
    """A topology from its (inlined) document.

    Parameters
    ----------
    doc : dict
        A topology or switching mapping.
    source : str, optional
        Its name, for messages.

    Returns
    -------
    Topology or SwitchingTopology
        The validated topology.

    Raises
    ------
    InputError
        The document is not a valid topology.
    """
    if "modes" in doc or "schedule" in doc:
        return SwitchingTopology.from_data(parse_switching(doc, source))
    return Topology.from_data(parse_topology(doc, source))
