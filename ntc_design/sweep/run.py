"""Running a sweep: every point not already stored, here or on a Dask cluster, with
progress, then the tables."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..simulate import SimulationSpec
from .engines import LocalEngine, engine_for
from .point import PointResult, PointRow, certify_key, certify_task, run_point
from .spec import PointTask, Sweep, load_sweep
from .store import load_point, save_point, tables_module, write_manifest, write_tables


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
        An engine (:mod:`ntc_design.sweep.engines`) to use instead of ``scheduler``.
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
        A malformed sweep file, an unreachable scheduler or the ``tables`` extra missing
        (before anything is written).
    """
    tables_module()  # pandas and PyArrow write the tables at the end: checked first
    sw = sweep if isinstance(sweep, Sweep) else load_sweep(sweep)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out} exists and is not a directory", field="out", option=True)
    own = engine is None
    eng = engine_for(scheduler, workers) if own else engine
    t0 = time.monotonic()
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_manifest(sw, out)
        tasks = sw.tasks()
        results: dict[str, PointResult] = {}
        for t in tasks:
            got = load_point(out, t.point)
            if got is not None:
                results[t.point] = got
        todo = [t for t in tasks if t.point not in results]
        tracker = _Tracker(tasks, results, progress)
        if todo:
            _run_points(eng, todo, workers, out, results, tracker)
        files = write_tables(sw, out, results)
    finally:
        if own:
            eng.close()
    state = tracker.state
    return SweepOutcome(
        out,
        len(sw.points),
        len(sw.points) - state.reused,
        state.reused,
        state.failed,
        (out / "sweep.json", *files),
        time.monotonic() - t0,
    )


class _Tracker:
    """The sweep's progress: points done and path-steps (estimates until each point
    reports its own total), told to the caller's callback."""

    def __init__(self, tasks: list[PointTask], reused: dict[str, PointResult], progress):
        self.state = SweepProgress(len(tasks), reused=len(reused), points_done=len(reused))
        self.state.failed = sum(1 for r in reused.values() if r.row.error)
        self.total = {t.point: t.path_steps_estimate for t in tasks}
        self.done = {p: self.total[p] for p in reused}
        self.progress = progress
        self.report()

    def report(self) -> None:
        self.state.path_steps_total = sum(self.total.values())
        self.state.path_steps_done = sum(self.done.values())
        if self.progress is not None:
            self.progress(self.state)

    def tick(self, point: str, d: int, n: int) -> None:
        self.total[point], self.done[point] = n, d
        self.report()

    def finished(self, point: str, failed: bool) -> None:
        self.state.failed += int(failed)
        self.state.points_done += 1
        self.done[point] = self.total[point]
        self.report()


def _run_points(
    eng,
    todo: list[PointTask],
    workers: int | None,
    out: Path,
    results: dict[str, PointResult],
    tracker: _Tracker,
) -> None:
    """Run the points not stored yet; store each as it arrives."""
    items: list[tuple[str, tuple]] = [(t.point, (t, None, workers)) for t in todo]
    if not isinstance(eng, LocalEngine):
        # Tasks carry their topology by value: a scattered copy can be lost with a
        # killed worker once Dask's memory manager has dropped the other replicas
        # (7 points cancelled in the killed-worker test).
        certs = _cluster_certificates(eng, todo)
        items = [(t.point, (t, None, None, certs.get(t.point))) for t in todo]
    for point, res, exc in eng.map_unordered(_run_any, items, progress=tracker.tick):
        if exc is not None:  # the cluster gave up: a row now, a retry next run
            task = next(t for t in todo if t.point == point)
            row = PointRow(
                point=point, error=f"not computed: {exc.__class__.__name__}: {exc}"[:500]
            )
            results[point] = PointResult(point, task.params, row, np.zeros(0), [])
        else:
            save_point(out, res)
            results[point] = res
        tracker.finished(point, bool(results[point].row.error))


def _cluster_certificates(eng, todo: list[PointTask]) -> dict:
    """Certify each distinct (topology, θ, margin, gain) once, as tasks of their own, so
    that two workers never repeat a certification; point -> certification row. A key
    whose task fails (or whose scenario is malformed) is left to its points."""
    first: dict[str, str] = {}
    key_of: dict[str, str] = {}
    by_point = {t.point: t for t in todo}
    for t in todo:
        try:
            spec = SimulationSpec.from_document(t.scenario)
        except InputError:
            continue
        key = certify_key(t.topology_doc, spec)
        key_of[t.point] = key
        first.setdefault(key, t.point)
    rows = {}
    for point, row, exc in eng.map_unordered(
        certify_task, [(p, (by_point[p],)) for p in first.values()]
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
