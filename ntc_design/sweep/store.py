"""A sweep's folder: one file pair per point (written atomically as it arrives), the
manifest, and the tables rebuilt from the point files."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import optional_module
from ..io.files import jsonable
from ..io.outputs import atomic_path, write_atomic
from .point import ROW_FIELDS, PointResult, PointRow
from .spec import FORMAT, Sweep

POINT_ARRAYS = ("t", "labels", "mc", "lo", "hi", "exact")
MAX_POINT_BYTES = 2**30  # a stored point larger than this is not one this package wrote


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
        jpath, npath = pdir / f"{point}.json", pdir / f"{point}.npz"
        if jpath.stat().st_size > MAX_POINT_BYTES or npath.stat().st_size > MAX_POINT_BYTES:
            return None
        doc = json.loads(jpath.read_text(encoding="utf-8"))
        with np.load(npath, allow_pickle=False) as z:
            if not set(z.files) <= set(POINT_ARRAYS) or not {"t", "labels"} <= set(z.files):
                return None
            if sum(i.file_size for i in z.zip.infolist()) > MAX_POINT_BYTES:
                return None  # the sizes zipfile enforces while inflating
            arr = {k: z[k] for k in z.files}
    # a damaged or foreign file (garbage, a zip bomb's member, JSON nested 10⁵ deep) is
    # a point to compute again, never an internal error
    except (OSError, ValueError, KeyError, EOFError, RecursionError, zipfile.BadZipFile):
        return None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("point") != point:
        return None
    row = PointRow.from_dict(doc["row"]) if isinstance(doc.get("row"), dict) else None
    params = doc.get("params", {})
    if row is None or not isinstance(params, dict) or not _arrays_agree(arr):
        return None
    return PointResult(
        point,
        params,
        row,
        arr["t"],
        [str(a) for a in arr["labels"]],
        arr.get("mc"),
        arr.get("lo"),
        arr.get("hi"),
        arr.get("exact"),
    )


def _arrays_agree(arr: dict[str, np.ndarray]) -> bool:
    """t is 1-d, finite and increasing; labels 1-d text; each curve (t, agents), real."""
    t, labels = arr["t"], arr["labels"]
    if t.ndim != 1 or t.dtype.kind != "f" or labels.ndim != 1 or labels.dtype.kind != "U":
        return False
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        return False
    shape = (t.size, labels.size)
    return all(
        arr[k].shape == shape and arr[k].dtype.kind == "f"
        for k in ("mc", "lo", "hi", "exact")
        if k in arr
    )


# -- tables ----------------------------------------------------------------------------


def _cell(v: Any) -> Any:
    """A swept value as a table cell: numbers and strings as they are, anything else as
    JSON text."""
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return json.dumps(jsonable(v))


def tables_module():
    """pandas, with PyArrow for its Parquet files: the ``tables`` extra, or one line
    naming it."""
    optional_module("pyarrow", "tables", "a sweep")
    return optional_module("pandas", "tables", "a sweep")


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

    Raises
    ------
    InputError
        pandas or PyArrow is not installed (the ``tables`` extra).
    """
    pd = tables_module()
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
