"""Parameter sweeps: a base scenario, a grid or a list of points, each point designed,
certified and simulated, on this machine or on a Dask cluster.

A sweep file::

    base: scenarios/g1_fixed.yaml     # a scenario file, relative to this file
    grid:                             # the Cartesian product of the lists ...
      noise.sigma: [0.1, 0.4]         # a dotted key reaches into the scenario
      margin: [0.1, 1.0]
      seed: [0, 1]
    # points: [{margin: 0.1, seed: 3}, {margin: 2.0}]   # ... or an explicit list

Every point is identified by a hash of its resolved parameters (the scenario with the
overrides applied and the topology document inlined), and its result is written
atomically to ``DIR/points/<hash>.npz`` and then ``DIR/points/<hash>.json`` as soon as it
arrives; the tables (``results.csv``, ``results.parquet``, ``curves.parquet``) are rebuilt
from those files. Re-running the same sweep into the same DIR computes only the points
without a result file. A point that fails inside (a bad parameter, a divergence) is a
result like any other, a row carrying its error; a point the cluster gave up on (its
workers kept dying) gets a row with the error but no file, so the next run retries it.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError
from .files import jsonable, parse_switching, parse_topology, read_document, text_field
from .outputs import atomic_path, write_atomic
from .simulate.spec import SCENARIO_KEYS

FORMAT = 1
MAX_POINTS = 10_000  # points in one sweep
MAX_VALUES = 1_000  # values of one grid key
SWEEP_KEYS = {"name", "description", "base", "grid", "points"}
# keys a sweep may set: the scenario's own (the engine, not the sweep, decides the workers),
# and the fields inside noise and initial
TOP_KEYS = set(SCENARIO_KEYS) - {"name", "description", "workers"}
NESTED_KEYS = {"noise": {"sigma", "f", "sigma_edges"}, "initial": {"uniform", "seed"}}
# simulate()'s defaults, for the path-step estimate of a point
DEFAULTS = {"T": 10.0, "dt": 1e-3, "paths": 1000}
_CERT_CACHE: dict[str, tuple] = {}  # per process: points differing only in noise/seed/T share one
_CERT_CACHE_SIZE = 64


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


@dataclass
class PointResult:
    """One point's row (see :data:`ROW_FIELDS`) and its mean-square curves (save times ×
    agents; ``mc``/``lo``/``hi``/``exact`` None where not computed)."""

    point: str
    params: dict
    row: dict
    t: np.ndarray
    labels: list[str]
    mc: np.ndarray | None = None
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    exact: np.ndarray | None = None


ROW_FIELDS = (
    "point",
    "delta",
    "certified",
    "ms_guaranteed",
    "as_guaranteed",
    "certificate_digest",
    "ms_final_mc",
    "ms_final_exact",
    "T",
    "paths",
    "path_steps",
    "wall_seconds",
    "worker",
    "error",
)


@dataclass
class SweepProgress:
    """Where a running sweep is: points done (reused ones included) and path-steps (an
    estimate until each point reports its own total)."""

    points_total: int
    points_done: int = 0
    failed: int = 0
    reused: int = 0
    path_steps_total: int = 0
    path_steps_done: int = 0
    started: float = field(default_factory=time.monotonic)

    @property
    def elapsed(self) -> float:
        """Seconds since the sweep started."""
        return time.monotonic() - self.started

    def line(self) -> str:
        """The progress as one line.

        Returns
        -------
        str
            Points done (failed, reused), path-steps and seconds.
        """
        return (
            f"sweep: {self.points_done}/{self.points_total} points ({self.failed} failed, "
            f"{self.reused} reused), {self.path_steps_done:.3g}/{self.path_steps_total:.3g} "
            f"path-steps, {self.elapsed:.0f} s"
        )


@dataclass(frozen=True)
class SweepOutcome:
    """What a finished sweep did: its folder, points computed, reused and failed, the
    files written and the seconds taken."""

    out_dir: Path
    points: int
    computed: int
    reused: int
    failed: int
    files: tuple[Path, ...]
    seconds: float


# -- the sweep file --------------------------------------------------------------------


def _err(src: Path, fieldname: str, msg: str) -> InputError:
    return InputError(f"{src}: {fieldname}: {msg}")


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
    from .simulate.scenario import load_scenario

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
    from .model import SwitchingTopology, Topology

    if "modes" in doc or "schedule" in doc:
        return SwitchingTopology.from_data(parse_switching(doc, source))
    return Topology.from_data(parse_topology(doc, source))


def _certify_key(topology_doc: dict, spec) -> str:
    """What a point's certificate depends on: the topology, θ, the margin and the gain."""
    gain = spec.gain if isinstance(spec.gain, str) else None
    return json.dumps(
        jsonable([topology_doc, spec.theta, spec.margin, gain]), sort_keys=True, default=repr
    )


def _certify_row(top, spec) -> tuple:
    """(δ, certificate valid, MS verdict, a.s. verdict, digest) of one certification."""
    from .certify import certify
    from .design import SwitchingDesign

    gain = spec.gain if isinstance(spec.gain, str) else None
    res = certify(top, spec.theta, spec.margin, gain)
    des = res.design
    delta = (
        max(d.delta for d in des.modes.values()) if isinstance(des, SwitchingDesign) else des.delta
    )
    verdict = {th.theorem: th.guaranteed for th in res.theorems}
    return (
        float(delta),
        bool(res.verification.valid),
        verdict.get(1, verdict.get(3)),
        verdict.get(2, verdict.get(4)),
        res.certificate["digest"],
    )


def _certify_cached(top, topology_doc: dict, spec) -> tuple:
    """:func:`_certify_row`, cached per process (points that differ only in noise, seed or
    T share one certificate)."""
    key = _certify_key(topology_doc, spec)
    if key not in _CERT_CACHE:
        row = _certify_row(top, spec)
        if len(_CERT_CACHE) >= _CERT_CACHE_SIZE:
            _CERT_CACHE.pop(next(iter(_CERT_CACHE)))
        _CERT_CACHE[key] = row
    return _CERT_CACHE[key]


def _certify_any(task: PointTask, topology_doc=None, progress=None, remote=False) -> tuple:
    """One certification as a cluster task (the first point of its key stands for all)."""
    from .simulate import SimulationSpec

    del progress, remote  # a certification reports no path-steps
    doc = topology_doc if topology_doc is not None else task.topology_doc
    spec = SimulationSpec.from_document(task.scenario)
    return _certify_cached(topology_from_document(doc), doc, spec)


def run_point(
    task: PointTask,
    progress: Callable[[int, int], None] | None = None,
    remote: bool = False,
    workers: int | None = None,
    certificate: tuple | None = None,
) -> PointResult:
    """Design, certify and simulate one point. Errors inside the point (a bad parameter, a
    divergence, a failed design) become the row's ``error``; nothing is raised.

    Parameters
    ----------
    task
        The point, by value.
    progress
        Called with (path-steps done, total) during the Monte Carlo run.
    remote
        True inside a cluster task: the Monte Carlo runs in this process with one BLAS
        thread (the cluster's workers are the parallelism).
    workers
        Local processes for the Monte Carlo when not remote (None: the scenario's).
    certificate
        The point's certification row when it was computed as a task of its own (the
        sweep certifies each distinct topology, θ, margin and gain once on a cluster).

    Returns
    -------
    PointResult
    """
    from threadpoolctl import threadpool_limits

    from .simulate import SimulationDiverged, SimulationSpec, simulate

    t0 = time.perf_counter()
    row: dict[str, Any] = {k: None for k in ROW_FIELDS}
    row.update(point=task.point, worker=_worker_name(remote))
    res = None
    try:
        # the same checks as a scenario file: every field named in a one-line error
        spec = SimulationSpec.from_document(task.scenario)
        top = topology_from_document(task.topology_doc)
        if remote or workers is not None:
            spec = spec.replace(mc=replace(spec.mc, workers=1 if remote else workers))
        row["T"], row["paths"] = spec.T, spec.mc.paths
        (
            row["delta"],
            row["certified"],
            row["ms_guaranteed"],
            row["as_guaranteed"],
            row["certificate_digest"],
        ) = certificate or _certify_cached(top, task.topology_doc, spec)
        with threadpool_limits(limits=1 if remote else None):
            try:
                res = simulate(top, spec, progress=progress)
            except SimulationDiverged as exc:
                res, row["error"] = exc.result, str(exc)
        row["path_steps"] = res.stats.path_steps
        if res.mc is not None and row["error"] is None:
            row["ms_final_mc"] = float(res.mc.mean[-1].sum())
        if res.exact is not None and row["error"] is None:
            row["ms_final_exact"] = float(res.exact.ms_error[-1].sum())
    except InputError as exc:
        row["error"] = str(exc)
    except Exception as exc:  # noqa: BLE001 - any failure of one point is that point's row
        row["error"] = f"{exc.__class__.__name__}: {exc}".splitlines()[0]
    row["wall_seconds"] = time.perf_counter() - t0
    if res is None:
        return PointResult(task.point, task.params, row, np.zeros(0), [])
    mc, ex = res.mc, res.exact
    return PointResult(
        task.point,
        task.params,
        row,
        np.asarray(res.save_times, dtype=float),
        [str(a) for a in res.labels],
        None if mc is None else mc.mean,
        None if mc is None else mc.lo,
        None if mc is None else mc.hi,
        None if ex is None else ex.ms_error,
    )


def _worker_name(remote: bool) -> str:
    if remote:
        try:
            from distributed import get_worker

            return get_worker().address
        except ValueError:
            pass
    return f"local:{socket.gethostname()}"


# -- point files -----------------------------------------------------------------------


def save_point(out_dir: Path, res: PointResult) -> Path:
    """Store one point: ``points/<hash>.npz`` (curves), then ``points/<hash>.json`` (row).

    A point counts as done once its JSON file exists, and each file appears whole or not
    at all.

    Parameters
    ----------
    out_dir : pathlib.Path
        The sweep's folder.
    res : PointResult
        The point's result.

    Returns
    -------
    pathlib.Path
        The JSON file.
    """
    pdir = out_dir / "points"
    pdir.mkdir(parents=True, exist_ok=True)
    arrays = {"t": res.t, "labels": np.array(res.labels, dtype=str)}
    for k in ("mc", "lo", "hi", "exact"):
        v = getattr(res, k)
        if v is not None:
            arrays[k] = v
    with atomic_path(pdir / f"{res.point}.npz") as tmp:
        np.savez_compressed(tmp, **arrays)
    doc = {"format": FORMAT, "point": res.point, "params": res.params, "row": res.row}
    path = pdir / f"{res.point}.json"
    write_atomic(path, json.dumps(jsonable(doc), indent=1) + "\n")
    return path


def load_point(out_dir: Path, point: str) -> PointResult | None:
    """The stored result of a point.

    Parameters
    ----------
    out_dir : pathlib.Path
        The sweep's folder.
    point : str
        The point's hash.

    Returns
    -------
    PointResult or None
        None when missing or unreadable (compute it again).
    """
    pdir = out_dir / "points"
    try:
        doc = json.loads((pdir / f"{point}.json").read_text(encoding="utf-8"))
        with np.load(pdir / f"{point}.npz") as z:
            arr = {k: z[k] for k in z.files}
    except (OSError, ValueError, KeyError, EOFError):
        return None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("point") != point:
        return None
    row = {k: doc["row"].get(k) for k in ROW_FIELDS}
    return PointResult(
        point,
        doc.get("params", {}),
        row,
        arr["t"],
        [str(a) for a in arr["labels"]],
        arr.get("mc"),
        arr.get("lo"),
        arr.get("hi"),
        arr.get("exact"),
    )


# -- tables ----------------------------------------------------------------------------


def _cell(v: Any) -> Any:
    """A swept value as a table cell: numbers and strings as they are, anything else as
    JSON text."""
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return json.dumps(jsonable(v))


def write_tables(sweep: Sweep, out_dir: Path, results: dict[str, PointResult]) -> list[Path]:
    """``results.csv``, ``results.parquet`` (one row per point, in sweep order: the swept
    keys as named in the file, then :data:`ROW_FIELDS`) and ``curves.parquet`` (long form:
    point, t, agent, mc, lo, hi, exact), each written atomically.

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    out_dir : pathlib.Path
        Its folder.
    results : dict of str to PointResult
        The points' results by hash (a missing point gets an error row).

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    import pandas as pd

    rows, curves = [], []
    for task in sweep.tasks():
        res = results.get(task.point)
        row = {k: None for k in ROW_FIELDS}
        if res is None:
            row.update(point=task.point, error="not computed")
        else:
            row.update(res.row)
            s, n = res.t.size, len(res.labels)
            if s and n:
                nan = np.full((s, n), np.nan)

                def col(a, nan=nan):
                    return (a if a is not None else nan).reshape(-1)

                curves.append(
                    pd.DataFrame(
                        {
                            "point": task.point,
                            "t": np.repeat(res.t, n),
                            "agent": np.tile(np.array(res.labels, dtype=object), s),
                            "mc": col(res.mc),
                            "lo": col(res.lo),
                            "hi": col(res.hi),
                            "exact": col(res.exact),
                        }
                    )
                )
        row.update({k: _cell(task.params.get(k)) for k in sweep.keys})
        rows.append(row)
    # a swept key named like a row field (T, paths) is that column, shown once
    table = pd.DataFrame(
        rows, columns=[*sweep.keys, *(f for f in ROW_FIELDS if f not in sweep.keys)]
    )
    for k in sweep.keys:  # one type per column (Parquet): mixed columns become text
        kinds = {type(v) for v in table[k] if v is not None}
        if len(kinds) > 1 and not kinds <= {int, float}:
            table[k] = [None if v is None else str(v) for v in table[k]]
    for k in ("delta", "ms_final_mc", "ms_final_exact", "T", "wall_seconds"):
        if k not in sweep.keys:
            table[k] = pd.to_numeric(table[k], errors="coerce").astype(float)
    for k in ("certified", "ms_guaranteed", "as_guaranteed"):
        table[k] = table[k].astype("boolean")
    for k in ("paths", "path_steps"):
        if k not in sweep.keys:
            table[k] = pd.to_numeric(table[k], errors="coerce").astype("Int64")
    cols = ["point", "t", "agent", "mc", "lo", "hi", "exact"]
    long = pd.concat(curves, ignore_index=True) if curves else pd.DataFrame(columns=cols)
    long["t"] = long["t"].astype(float)
    for k in ("mc", "lo", "hi", "exact"):
        long[k] = long[k].astype(float)
    written = []
    for name, write in (
        ("results.csv", lambda p: table.to_csv(p, index=False)),
        ("results.parquet", lambda p: table.to_parquet(p, index=False)),
        ("curves.parquet", lambda p: long.to_parquet(p, index=False)),
    ):
        with atomic_path(out_dir / name) as tmp:
            write(tmp)
        written.append(out_dir / name)
    return written


def _write_manifest(sweep: Sweep, out_dir: Path) -> Path:
    doc = {
        "format": FORMAT,
        "kind": "sweep",
        "name": sweep.name,
        "source": str(sweep.source),
        "base": str(sweep.base),
        "keys": list(sweep.keys),
        "points": [{"point": t.point, "params": t.params} for t in sweep.tasks()],
    }
    path = out_dir / "sweep.json"
    write_atomic(path, json.dumps(jsonable(doc), indent=1) + "\n")
    return path


# -- the driver ------------------------------------------------------------------------


def run_sweep(
    sweep: str | Path | Sweep,
    out_dir: str | Path,
    *,
    scheduler: str | None = None,
    engine=None,
    workers: int | None = None,
    progress: Callable[[SweepProgress], None] | None = None,
) -> SweepOutcome:
    """Run every point of a sweep not already in ``out_dir`` and rebuild the tables.

    Parameters
    ----------
    sweep
        A sweep file or a :class:`Sweep` from :func:`load_sweep`.
    out_dir
        The output directory (created; points already there are reused).
    scheduler
        The address of a Dask scheduler (``tcp://host:port``): points become tasks on its
        workers. None: the points run here one after the other, each on ``workers`` local
        processes (the scenario's, or 2).
    engine
        An engine (:mod:`ntc_design.distributed`) to use instead of ``scheduler``.
    workers
        Local processes per point (without a scheduler).
    progress
        Called with a :class:`SweepProgress` whenever points or path-steps advance.

    Returns
    -------
    SweepOutcome

    Raises
    ------
    InputError
        A malformed sweep file or an unreachable scheduler (before anything is written).
    """
    from .distributed import LocalEngine, engine_for

    sw = sweep if isinstance(sweep, Sweep) else load_sweep(sweep)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out: {out} exists and is not a directory")
    own = engine is None
    eng = engine_for(scheduler, workers) if own else engine
    t0 = time.monotonic()
    try:
        out.mkdir(parents=True, exist_ok=True)
        _write_manifest(sw, out)
        tasks = sw.tasks()
        results: dict[str, PointResult] = {}
        todo = []
        for t in tasks:
            got = load_point(out, t.point)
            if got is None:
                todo.append(t)
            else:
                results[t.point] = got
        state = SweepProgress(len(tasks), reused=len(results), points_done=len(results))
        total = {t.point: t.path_steps_estimate for t in tasks}
        done = {p: total[p] for p in results}
        state.failed = sum(1 for r in results.values() if r.row.get("error"))

        def report() -> None:
            state.path_steps_total = sum(total.values())
            state.path_steps_done = sum(done.values())
            if progress is not None:
                progress(state)

        def tick(point: str, d: int, n: int) -> None:
            total[point], done[point] = n, d
            report()

        report()
        if todo:
            items = [(t.point, (t, None, workers)) for t in todo]
            if not isinstance(eng, LocalEngine):
                # Tasks carry their topology by value: a scattered copy can be lost with a
                # killed worker once Dask's memory manager has dropped the other replicas
                # (7 points cancelled in the killed-worker test).
                certs = _cluster_certificates(eng, todo)
                items = [(t.point, (t, None, None, certs.get(t.point))) for t in todo]
            for point, res, exc in eng.map_unordered(_run_any, items, progress=tick):
                if exc is not None:  # the cluster gave up: a row now, a retry next run
                    task = next(t for t in todo if t.point == point)
                    row = {k: None for k in ROW_FIELDS}
                    row.update(
                        point=point, error=f"not computed: {exc.__class__.__name__}: {exc}"[:500]
                    )
                    results[point] = PointResult(point, task.params, row, np.zeros(0), [])
                else:
                    save_point(out, res)
                    results[point] = res
                if results[point].row.get("error"):
                    state.failed += 1
                state.points_done += 1
                done[point] = total[point]
                report()
        files = write_tables(sw, out, results)
    finally:
        if own:
            eng.close()
    return SweepOutcome(
        out,
        len(sw.points),
        len(sw.points) - state.reused,
        state.reused,
        state.failed,
        (out / "sweep.json", *files),
        time.monotonic() - t0,
    )


def _cluster_certificates(eng, todo: list[PointTask]) -> dict:
    """Certify each distinct (topology, θ, margin, gain) once, as tasks of their own, so
    that two workers never repeat a certification; point -> certification row. A key
    whose task fails (or whose scenario is malformed) is left to its points."""
    from .simulate import SimulationSpec

    first: dict[str, str] = {}
    key_of: dict[str, str] = {}
    by_point = {t.point: t for t in todo}
    for t in todo:
        try:
            spec = SimulationSpec.from_document(t.scenario)
        except InputError:
            continue
        key = _certify_key(t.topology_doc, spec)
        key_of[t.point] = key
        first.setdefault(key, t.point)
    rows = {}
    for point, row, exc in eng.map_unordered(
        _certify_any, [(p, (by_point[p],)) for p in first.values()]
    ):
        if exc is None:
            rows[point] = row
    by_key = {k: rows[p] for k, p in first.items() if p in rows}
    return {p: by_key[k] for p, k in key_of.items() if k in by_key}


def _run_any(
    task: PointTask,
    topology_doc=None,
    workers=None,
    certificate=None,
    progress=None,
    remote=False,
) -> PointResult:
    """run_point, with the topology document passed separately when it was scattered."""
    if topology_doc is not None:
        task = PointTask(task.point, task.params, task.scenario, topology_doc)
    return run_point(task, progress, remote, workers, certificate)
