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

Modules: :mod:`.spec` (the file and its points), :mod:`.point` (one point and its typed
row), :mod:`.store` (point files and tables), :mod:`.run` (the driver).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

# loaded on first use (PEP 562): the Monte Carlo engines (:mod:`.engines`) are used by
# ntc simulate without the sweep's tables, certification and cluster client
_EXPORTS = {
    "ROW_FIELDS": "point",
    "CertificationRow": "point",
    "PointResult": "point",
    "PointRow": "point",
    "certify_key": "point",
    "certify_task": "point",
    "run_point": "point",
    "SweepOutcome": "run",
    "SweepProgress": "run",
    "run_sweep": "run",
    "FORMAT": "spec",
    "MAX_POINTS": "spec",
    "MAX_VALUES": "spec",
    "PointTask": "spec",
    "Sweep": "spec",
    "load_sweep": "spec",
    "point_hash": "spec",
    "topology_from_document": "spec",
    "load_point": "store",
    "save_point": "store",
    "write_manifest": "store",
    "write_tables": "store",
}

if TYPE_CHECKING:
    from .point import (
        ROW_FIELDS,
        CertificationRow,
        PointResult,
        PointRow,
        certify_key,
        certify_task,
        run_point,
    )
    from .run import SweepOutcome, SweepProgress, run_sweep
    from .spec import (
        FORMAT,
        MAX_POINTS,
        MAX_VALUES,
        PointTask,
        Sweep,
        load_sweep,
        point_hash,
        topology_from_document,
    )
    from .store import load_point, save_point, write_manifest, write_tables

__all__ = [
    "FORMAT",
    "MAX_POINTS",
    "MAX_VALUES",
    "ROW_FIELDS",
    "CertificationRow",
    "PointResult",
    "PointRow",
    "PointTask",
    "Sweep",
    "SweepOutcome",
    "SweepProgress",
    "certify_key",
    "certify_task",
    "load_point",
    "load_sweep",
    "point_hash",
    "run_point",
    "run_sweep",
    "save_point",
    "topology_from_document",
    "write_manifest",
    "write_tables",
]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
