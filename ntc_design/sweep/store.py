"""A sweep's folder: one file pair per point (written atomically as it arrives), the
manifest, and the tables rebuilt from the point files."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..files import jsonable
from ..outputs import atomic_path, write_atomic
from .point import ROW_FIELDS, PointResult, PointRow
from .spec import FORMAT, Sweep


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
    arrays: dict[str, Any] = {"t": res.t, "labels": np.array(res.labels, dtype=str)}
    for k in ("mc", "lo", "hi", "exact"):
        v = getattr(res, k)
        if v is not None:
            arrays[k] = v
    with atomic_path(pdir / f"{res.point}.npz") as tmp:
        np.savez_compressed(tmp, **arrays)
    doc = {"format": FORMAT, "point": res.point, "params": res.params, "row": res.row.to_dict()}
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
    row = PointRow.from_dict(doc["row"]) if isinstance(doc.get("row"), dict) else None
    if row is None:
        return None
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
    rows, curves = [], []
    for task in sweep.tasks():
        res = results.get(task.point)
        row: dict[str, Any] = {k: None for k in ROW_FIELDS}
        if res is None:
            row.update(point=task.point, error="not computed")
        else:
            row.update(res.row.to_dict())
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


def write_manifest(sweep: Sweep, out_dir: Path) -> Path:
    """``sweep.json``: the sweep's name, source, base, swept keys and points.

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    out_dir : pathlib.Path
        Its folder.

    Returns
    -------
    pathlib.Path
        The file written.
    """
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
