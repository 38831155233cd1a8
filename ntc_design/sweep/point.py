"""One point of a sweep: certified once per (topology, θ, margin, gain), simulated, and
summarised as a typed row (:class:`PointRow`) with its mean-square curves."""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from ..certify import certify
from ..errors import InputError, optional_module
from ..io.files import jsonable
from ..protocol import ProtocolDesign, SwitchingDesign
from ..simulate import SimulationDiverged, SimulationSpec, simulate
from .spec import PointTask, topology_from_document


@dataclass(frozen=True)
class CertificationRow:
    """What a point's certification contributes to its row.

    Attributes
    ----------
    delta : float
        δ of the design (the largest over the modes of a switching set).
    certified : bool
        Whether the certificate verified.
    ms_guaranteed, as_guaranteed : bool or None
        The mean-square and almost-sure theorem verdicts (None when not assessed).
    digest : str
        The certificate's digest.
    """

    delta: float
    certified: bool
    ms_guaranteed: bool | None
    as_guaranteed: bool | None
    digest: str


@dataclass(frozen=True)
class PointRow:
    """One point's row of ``results.csv`` (the fields of :data:`ROW_FIELDS`, in order).

    Attributes
    ----------
    point : str
        The point's hash.
    delta, certified, ms_guaranteed, as_guaranteed, certificate_digest
        From its certification (:class:`CertificationRow`).
    ms_final_mc, ms_final_exact : float or None
        E Σ_i‖x_i(T) − θ‖² by Monte Carlo and by the exact moments.
    T, paths, path_steps
        The horizon, the Monte Carlo paths, steps × paths.
    wall_seconds : float or None
        The point's wall time.
    worker : str or None
        Where it ran.
    error : str or None
        Why the point failed, None when it did not.
    """

    point: str
    delta: float | None = None
    certified: bool | None = None
    ms_guaranteed: bool | None = None
    as_guaranteed: bool | None = None
    certificate_digest: str | None = None
    ms_final_mc: float | None = None
    ms_final_exact: float | None = None
    T: float | None = None
    paths: int | None = None
    path_steps: int | None = None
    wall_seconds: float | None = None
    worker: str | None = None
    error: str | None = None

    def to_dict(self) -> dict:
        """The row as a mapping in :data:`ROW_FIELDS` order.

        Returns
        -------
        dict
        """
        return asdict(self)

    @classmethod
    def from_dict(cls, doc: dict) -> PointRow:
        """A row read back from a point file (unknown keys ignored, missing ones None).

        Parameters
        ----------
        doc : dict
            The stored row.

        Returns
        -------
        PointRow
        """
        return cls(**{f.name: doc.get(f.name) for f in fields(cls)})  # type: ignore[arg-type]


#: The columns a point contributes to ``results.csv``, in order.
ROW_FIELDS = tuple(f.name for f in fields(PointRow))


@dataclass(frozen=True, eq=False)
class PointResult:
    """One point's row (:class:`PointRow`) and its mean-square curves (save times ×
    agents; ``mc``/``lo``/``hi``/``exact`` None where not computed)."""

    point: str
    params: dict
    row: PointRow
    t: np.ndarray
    labels: list[str]
    mc: np.ndarray | None = None
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    exact: np.ndarray | None = None


_CERT_CACHE: dict[
    str, CertificationRow
] = {}  # per process: points differing only in noise/seed/T share one
_CERT_CACHE_SIZE = 64


def certify_key(topology_doc: dict, spec: SimulationSpec) -> str:
    """What a point's certificate depends on: the topology, θ, the margin and the gain.

    Parameters
    ----------
    topology_doc : dict
        The inlined topology document.
    spec : SimulationSpec
        The point's scenario.

    Returns
    -------
    str
        Canonical JSON of those four.
    """
    gain = spec.gain if isinstance(spec.gain, str) else None
    return json.dumps(
        jsonable([topology_doc, spec.theta, spec.margin, gain]), sort_keys=True, default=repr
    )


def _certification(top, spec: SimulationSpec) -> CertificationRow:
    gain = spec.gain if isinstance(spec.gain, str) else None
    res = certify(top, spec.theta, spec.margin, gain)
    des = res.design
    if isinstance(des, SwitchingDesign):
        delta = max(d.delta for d in des.modes.values())
    elif isinstance(des, ProtocolDesign):
        delta = des.delta
    else:  # topology_from_document never gives A(t)
        raise InputError("a topology given as functions of t cannot be swept", field="sweep")
    verdict = {th.theorem: th.guaranteed for th in res.theorems}
    return CertificationRow(
        delta=float(delta),
        certified=bool(res.verification.valid),
        ms_guaranteed=verdict.get(1, verdict.get(3)),
        as_guaranteed=verdict.get(2, verdict.get(4)),
        digest=res.certificate["digest"],
    )


def _certify_cached(top, topology_doc: dict, spec: SimulationSpec) -> CertificationRow:
    """The certification, cached per process (points that differ only in noise, seed or
    T share one certificate)."""
    key = certify_key(topology_doc, spec)
    if key not in _CERT_CACHE:
        row = _certification(top, spec)
        if len(_CERT_CACHE) >= _CERT_CACHE_SIZE:
            _CERT_CACHE.pop(next(iter(_CERT_CACHE)))
        _CERT_CACHE[key] = row
    return _CERT_CACHE[key]


def certify_task(
    task: PointTask, topology_doc: dict | None = None, progress=None, remote: bool = False
) -> CertificationRow:
    """One certification as a cluster task (the first point of its key stands for all).

    Parameters
    ----------
    task : PointTask
        A point with this certification's key.
    topology_doc : dict, optional
        The topology document when it was shipped apart from the task.
    progress, remote
        Accepted for the engine's calling convention; a certification reports no
        path-steps.

    Returns
    -------
    CertificationRow

    Raises
    ------
    InputError
        The point's scenario or topology is malformed.
    """
    del progress, remote
    doc = topology_doc if topology_doc is not None else task.topology_doc
    spec = SimulationSpec.from_document(task.scenario)
    return _certify_cached(topology_from_document(doc), doc, spec)


def run_point(
    task: PointTask,
    progress: Callable[[int, int], None] | None = None,
    remote: bool = False,
    workers: int | None = None,
    certificate: CertificationRow | None = None,
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
        The point's certification when it was computed as a task of its own (the
        sweep certifies each distinct topology, θ, margin and gain once on a cluster).

    Returns
    -------
    PointResult
    """
    t0 = time.perf_counter()
    row: dict[str, Any] = {"point": task.point, "worker": _worker_name(remote)}
    res = None
    try:
        # the same checks as a scenario file: every field named in a one-line error
        spec = SimulationSpec.from_document(task.scenario)
        top = topology_from_document(task.topology_doc)
        if remote:
            spec = spec.replace(mc=replace(spec.mc, workers=1))
        elif workers is not None:
            spec = spec.replace(mc=replace(spec.mc, workers=workers))
        row["T"], row["paths"] = spec.T, spec.mc.paths
        cert = certificate or _certify_cached(top, task.topology_doc, spec)
        row.update(
            delta=cert.delta,
            certified=cert.certified,
            ms_guaranteed=cert.ms_guaranteed,
            as_guaranteed=cert.as_guaranteed,
            certificate_digest=cert.digest,
        )
        with threadpool_limits(limits=1 if remote else None):
            try:
                res = simulate(top, spec, progress=progress)
            except SimulationDiverged as exc:
                res, row["error"] = exc.result, str(exc)
        row["path_steps"] = res.stats.path_steps
        if res.mc is not None and row.get("error") is None:
            row["ms_final_mc"] = float(res.mc.mean[-1].sum())
        if res.exact is not None and row.get("error") is None:
            row["ms_final_exact"] = float(res.exact.ms_error[-1].sum())
    except InputError as exc:
        row["error"] = str(exc)
    except Exception as exc:  # noqa: BLE001 - any failure of one point is that point's row
        row["error"] = f"{exc.__class__.__name__}: {exc}".splitlines()[0]
    row["wall_seconds"] = time.perf_counter() - t0
    if res is None:
        return PointResult(task.point, task.params, PointRow(**row), np.zeros(0), [])
    mc, ex = res.mc, res.exact
    return PointResult(
        task.point,
        task.params,
        PointRow(**row),
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
            return (
                optional_module("distributed", "cluster", "a sweep on a cluster")
                .get_worker()
                .address
            )
        except ValueError:
            pass
    return f"local:{socket.gethostname()}"
