"""A simulation run as ``ntc report`` reads it (summary.json, ms_error.csv, paths.npz),
each file bounded and checked against the others once, with one-line errors naming the
file and field."""

from __future__ import annotations

import csv
import io
import json
import shlex
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import (
    InputError,
    format_bytes,
    one_line,
    require_int,
    require_number,
    require_positive,
)
from ..gain.schedule import ScheduleGain
from ..io.files import parse_topology
from ..model import SwitchingTopology, Topology
from ..present.rows import counted
from ..protocol.digital import Digital
from ..protocol.loss import require_loss, require_policy
from ..simulate.budget import MEMORY_FRACTION, available_memory
from ..simulate.digital import DigitalRun
from ..simulate.spec import SimulationSpec

REQUIRED = ("summary.json", "ms_error.csv", "paths.npz")


@dataclass
class RunData:
    """A simulation run as ``ntc report`` reads it: summary.json (as read, and through its
    types: :class:`RunSummary`), the curves table and the paths, checked against each other
    once by :func:`load_run`."""

    path: Path
    summary: dict
    t: np.ndarray
    table: dict[str, np.ndarray]
    npz: dict[str, np.ndarray]
    record: RunSummary
    #: The sampled protocol reported instead of the run's own (the period option of ``ntc report``).
    asked: Digital | None = field(default=None)

    @property
    def labels(self) -> list[str]:
        """The agent labels, as text."""
        return [str(a) for a in self.npz["labels"]]

    @property
    def spec(self) -> SimulationSpec:
        """The run's spec, read back from its recorded parameters."""
        return self.record.spec

    @property
    def digital(self) -> Digital | None:
        """The sampled protocol the report shows: the one asked for, else the run's own
        (None: a continuous run)."""
        return self.asked if self.asked is not None else self.record.spec.digital

    @property
    def gain(self) -> str | ScheduleGain:
        """The run's gain: its expression, or the schedule it recorded."""
        g = self.record.spec.gain
        assert isinstance(g, (str, ScheduleGain))  # a document's gain is never a callable
        return g

    def design_spec(self) -> SimulationSpec:
        """The spec of the run's design alone (θ, ΔC, δ, the gain, the noise and x(0), the
        other options at their defaults): what the report's exact curves re-run.

        Returns
        -------
        SimulationSpec
        """
        s = self.record.spec
        return SimulationSpec(
            theta=s.theta,
            margin=s.margin,
            delta=s.delta,
            gain=s.gain,
            noise=s.noise,
            initial=s.initial,
        )

    @property
    def path_agents(self) -> np.ndarray:
        """The 0-based agents whose sample paths paths.npz holds (all of them, or on a large
        network the few with the largest final error)."""
        agents = self.npz.get("path_agents")
        return np.arange(len(self.labels)) if agents is None else agents

    @property
    def rerun(self) -> str:
        """The command that makes this run and its report again: the command line the run
        recorded (its overrides included: ``--paths 200`` stays 200), else the scenario."""
        cmd = self.summary.get("command")
        if not isinstance(cmd, str) or not cmd.strip():
            scen = self.summary.get("scenario", "SCENARIO")
            cmd = shlex.join(["ntc", "simulate", str(scen), "--out", str(self.path)])
        return f"{one_line(cmd)} && {shlex.join(['ntc', 'report', str(self.path)])}"

    @property
    def theta(self) -> np.ndarray:
        """The target θ of the run."""
        return self.record.spec.theta

    def topology(self) -> Topology | SwitchingTopology:
        """The run's topology (or switching set), read from summary.json by
        :class:`RunSummary` (a run over a time-varying topology is refused there).

        Returns
        -------
        Topology or SwitchingTopology
        """
        return self.record.topology

    def ms(self, kind: str) -> np.ndarray | None:
        """The per-agent E‖x_i − θ‖² curves of one kind.

        Parameters
        ----------
        kind : str
            ``mc``, ``lo``, ``hi`` or ``exact``: the column prefix in ms_error.csv.

        Returns
        -------
        numpy.ndarray or None
            Shape (save times, N); None when the run has no such curves.
        """
        cols = [f"{kind}_{a}" for a in self.labels]
        if not all(c in self.table for c in cols):
            return None
        return np.column_stack([self.table[c] for c in cols])


#: The recorded parameters that the run's spec reads back; the others are what the run
#: resolved (``modes``, ``schedule``, the count of ``save_times``, A(t)'s ``time_varying``).
SPEC_KEYS = (
    "theta",
    "margin",
    "delta",
    "gain",
    "noise",
    "initial",
    "T",
    "dt",
    "stepping",
    "ds",
    "scheme",
    "method",
    "resample",
    "digital",
    "paths",
    "seed",
    "block_size",
    "store_paths",
    "workers",
    "rng",
    "device",
    "save_every",
)


def _unrecorded_f(x: np.ndarray) -> np.ndarray:
    """A run's callable f (recorded as ``"callable"``): not linear, and never evaluated."""
    raise InputError(
        "the run's f was a Python callable, which summary.json does not hold", field="noise.f"
    )


@dataclass(frozen=True, eq=False)
class RunSummary:
    """summary.json read back through its types: the run's :class:`SimulationSpec` (its
    recorded parameters, checked by :meth:`SimulationSpec.from_document`), its topology or
    switching set, and the blocks a report reads.

    Attributes
    ----------
    spec : SimulationSpec
        θ, ΔC, δ, the gain, the noise (a callable f as a stand-in that is not linear),
        x(0), T, the stepping, the method, the Monte Carlo options and the digital protocol.
    topology : Topology or SwitchingTopology
        The run's network (a switching set with its schedule).
    scenario : str or None
        The scenario file the run was made from.
    sample_paths : dict
        The spread of the sample paths (numbers under :data:`SPREAD_KEYS` and
        ``late_window`` when ``stored``).
    digital : DigitalRun or None
        A digital run's figures (period, delay, K, the partial step, the peak, the loss).
    """

    spec: SimulationSpec
    topology: Topology | SwitchingTopology
    scenario: str | None
    sample_paths: dict
    digital: DigitalRun | None

    @classmethod
    def from_document(cls, doc: Any, source: str | None = None) -> RunSummary:
        """Read a parsed summary.json.

        Parameters
        ----------
        doc : Any
            The document as parsed.
        source : str, optional
            The file name that prefixes error messages.

        Returns
        -------
        RunSummary

        Raises
        ------
        InputError
            ``SOURCE: FIELD: what is wrong``.
        """
        try:
            return cls._read(doc)
        except InputError as exc:
            if source:
                raise InputError(f"{exc}", field=source) from None
            raise

    @classmethod
    def _read(cls, doc: Any) -> RunSummary:
        if not isinstance(doc, Mapping):
            raise InputError("expected a mapping")
        for key in ("parameters", "topologies"):
            if not isinstance(doc.get(key), Mapping) or not doc[key]:
                raise InputError(f"missing field '{key}' (a mapping)", field=key)
        p = doc["parameters"]
        for key in ("theta", "margin", "gain"):
            if key not in p:
                raise InputError(f"missing field 'parameters.{key}'", field=f"parameters.{key}")
        for key in ("noise", "time_varying"):
            if p.get(key) is not None and not isinstance(p[key], Mapping):
                raise InputError("expected a mapping", field=f"parameters.{key}")
        for key in ("run", "sample_paths"):
            if not isinstance(doc.get(key, {}), Mapping):
                raise InputError("expected a mapping", field=key)
        scenario = doc.get("scenario")
        if scenario is not None and not isinstance(scenario, str):
            raise InputError("expected a file name", field="scenario")
        sp_ = dict(doc.get("sample_paths", {}))
        if sp_.get("stored"):
            window = sp_.get("late_window")
            numbers = [sp_.get(k) for k in SPREAD_KEYS] + (
                window if isinstance(window, list) else []
            )
            if not (isinstance(window, list) and len(window) == 2) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in numbers
            ):
                raise InputError(
                    f"expected numbers {', '.join(SPREAD_KEYS)}, late_window", field="sample_paths"
                )
        try:
            spec = SimulationSpec.from_document(_spec_document(p))
        except InputError as exc:
            field = f"parameters.{exc.field}" if exc.field else "parameters"
            raise InputError(*exc.parts, field=field, value=exc.value, option=exc.option) from None
        if isinstance(p.get("noise"), Mapping) and p["noise"].get("f") == "callable":
            spec = spec.replace(noise=replace(spec.noise, f=_unrecorded_f))
        top = _topology(doc["topologies"], p)
        if spec.theta.size != top.dim:
            raise InputError(
                f"{spec.theta.size} numbers, the topology has d = {top.dim}",
                field="parameters.theta",
            )
        return cls(spec, top, scenario, sp_, _digital_run(doc.get("digital")))


def _spec_document(p: Mapping[str, Any]) -> dict[str, Any]:
    """The recorded parameters as a scenario document: the noise's per-edge σ back from
    ``{"a->b": σ}`` to ``[{from, to, sigma}]``, a callable f left out (the caller puts
    :func:`_unrecorded_f` in its place)."""
    doc = {k: p[k] for k in SPEC_KEYS if p.get(k) is not None}
    noise = doc.get("noise")
    if isinstance(noise, Mapping):
        noise = dict(noise)
        edges = noise.get("sigma_edges")
        if isinstance(edges, Mapping):
            pairs = [(str(k).partition("->"), v) for k, v in edges.items()]
            if any(not arrow for (_, arrow, _), _ in pairs):
                raise InputError("expected keys 'FROM->TO'", field="noise.sigma_edges")
            noise["sigma_edges"] = [{"from": a, "to": b, "sigma": v} for (a, _, b), v in pairs]
        if noise.get("f") == "callable":  # read as the default, then replaced (_read)
            noise.pop("f")
        doc["noise"] = noise
    if "save_every" not in doc and isinstance(p.get("T"), (int, float)):
        doc["save_every"] = p["T"]  # the run saved at listed times: only their count is kept
    return doc


def _topology(tops_doc: Mapping[str, Any], p: Mapping[str, Any]) -> Topology | SwitchingTopology:
    """The run's topology or switching set from ``topologies`` and ``parameters.schedule``."""
    tops = {}
    for k, v in tops_doc.items():
        if not isinstance(v, dict):
            raise InputError("expected a topology", field=f"topologies.{k}")
        tops[k] = Topology.from_data(parse_topology(v, f"topologies.{k}"))
    sched = p.get("schedule")
    if sched is not None:  # a switching run: [{mode, duration}, ...] over the topologies
        ok = isinstance(sched, list) and all(
            isinstance(s, dict)
            and isinstance(s.get("mode"), str)
            and isinstance(s.get("duration"), (int, float))
            and not isinstance(s.get("duration"), bool)
            for s in sched
        )
        if not ok:
            raise InputError("expected a list of {mode, duration}", field="parameters.schedule")
        return SwitchingTopology(
            tops,
            tuple((s["mode"], float(s["duration"])) for s in sched),
            source="parameters",
        )
    if len(tops) != 1:
        raise InputError(
            "a run over a topology given as functions of t has no single topology to certify",
            field="topologies",
        )
    return next(iter(tops.values()))


def _digital_run(doc: Any) -> DigitalRun | None:
    """A digital run's ``digital`` block (what :meth:`DigitalRun.to_dict` wrote)."""
    if doc is None:
        return None
    if not isinstance(doc, Mapping):
        raise InputError("expected a mapping", field="digital")
    for key in ("period", "delay", "steps"):
        if key not in doc:
            raise InputError("missing", field=f"digital.{key}")
    # the exact figures may be ±inf or NaN on a diverging run (written as such): numbers
    optional = {
        key: _optional_number(f"digital.{key}", doc.get(key))
        for key in ("ms_error_peak", "peak_time", "continuous_final_ms_error")
    }
    loss = doc.get("loss")
    if loss is not None:
        if not isinstance(loss, Mapping):
            raise InputError("expected {policy, p, offset}", field="digital.loss")
        require_policy("digital.loss.policy", loss.get("policy"))
        require_loss("digital.loss.p", loss.get("p"))
        _optional_number("digital.loss.offset", loss.get("offset"))
        loss = dict(loss)
    require_positive("digital.period", doc["period"])
    return DigitalRun(
        period=float(doc["period"]),
        delay=require_int("digital.delay", doc["delay"], minimum=0),
        steps=require_int("digital.steps", doc["steps"], minimum=1),
        partial_step=require_number(
            "digital.partial_step", doc.get("partial_step", 0.0), minimum=0.0
        ),
        loss=loss,
        **optional,
    )


def _optional_number(name: str, value: Any) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a number, got {type(value).__name__}", field=name)
    return float(value)


MAX_TEXT_BYTES = 256 * 2**20  # summary.json / ms_error.csv larger than this are refused
#: A report draws every agent (topology figure, per-agent curves and tables): refused above.
NPZ_KEYS = ("t", "paths", "labels", "theta")


def _rerun(d: Path) -> str:
    return f"re-run: ntc simulate SCENARIO --out {d}"


def _read_text(path: Path, d: Path) -> str:
    try:
        if path.stat().st_size > MAX_TEXT_BYTES:
            raise InputError(
                f"larger than {MAX_TEXT_BYTES // 2**20} MiB; {_rerun(d)}", field=str(path)
            )
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(
            f"unreadable ({exc.__class__.__name__}); {_rerun(d)}", field=str(path)
        ) from None


def _read_npz(path: Path, d: Path) -> dict[str, np.ndarray]:
    """paths.npz, refusing a corrupt, empty or oversized (decompression bomb) archive."""
    try:
        with zipfile.ZipFile(path) as zf:
            size = sum(i.file_size for i in zf.infolist())
        limit = MEMORY_FRACTION * available_memory()
        if size > limit:
            raise InputError(
                f"unpacks to {format_bytes(size)}, more than {format_bytes(limit)}; {_rerun(d)}",
                field=str(path),
            )
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in NPZ_KEYS if k not in z.files]
            if missing:
                raise InputError(f"missing array {missing[0]!r}; {_rerun(d)}", field=str(path))
            npz = {k: z[k] for k in z.files}
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - BadZipFile, EOFError, zlib.error, ValueError...
        raise InputError(
            f"not a readable .npz archive ({exc.__class__.__name__}); {_rerun(d)}", field=str(path)
        ) from None
    if npz["paths"].ndim != 3 or npz["t"].ndim != 1 or npz["labels"].ndim != 1:
        raise InputError(f"arrays of the wrong shape; {_rerun(d)}", field=str(path))
    if npz["labels"].dtype.kind not in "UO" and npz["labels"].size:
        raise InputError(f"labels are not text; {_rerun(d)}", field=str(path))
    for k in ("t", "paths", "theta"):
        if npz[k].dtype.kind not in "fiu":
            raise InputError(f"array {k!r} is not numeric; {_rerun(d)}", field=str(path))
    return npz


def load_run(directory: str | Path) -> RunData:
    """Read a simulation output directory; name what is missing or malformed and how to
    make it again.

    Parameters
    ----------
    directory : str or Path
        A folder written by ``ntc simulate``.

    Returns
    -------
    RunData

    Raises
    ------
    InputError
        One line naming the file and what is wrong.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InputError(
            f"no such directory; make it with: ntc simulate SCENARIO --out {d}", field=str(d)
        )
    for name in REQUIRED:
        if not (d / name).is_file():
            raise InputError(
                f"missing {name}; make it with: ntc simulate SCENARIO --out {d}", field=str(d)
            )
    try:
        summary = json.loads(_read_text(d / "summary.json", d))
    except (json.JSONDecodeError, RecursionError, ValueError) as exc:
        raise InputError(
            f"not valid JSON ({exc.__class__.__name__}); {_rerun(d)}", field=f"{d}/summary.json"
        ) from None
    rows = list(csv.reader(io.StringIO(_read_text(d / "ms_error.csv", d))))
    if len(rows) < 2:
        raise InputError(f"no data rows; {_rerun(d)}", field=f"{d}/ms_error.csv")
    header = rows[0]
    if not header or header[0] != "t" or len(set(header)) != len(header):
        raise InputError(
            f"the header must start with 't' (unique columns); {_rerun(d)}",
            field=f"{d}/ms_error.csv",
        )
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(
                f"line {k} has {len(r)} values, the header {len(header)}; {_rerun(d)}",
                field=f"{d}/ms_error.csv",
            )
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:]])
    except ValueError:
        raise InputError(
            f"a value is not a number; {_rerun(d)}", field=f"{d}/ms_error.csv"
        ) from None
    if not np.all(np.isfinite(data[:, 0])) or np.any(np.diff(data[:, 0]) <= 0):
        raise InputError(
            f"times are not finite and increasing; {_rerun(d)}", field=f"{d}/ms_error.csv"
        )
    npz = _read_npz(d / "paths.npz", d)
    if npz["t"].shape[0] != data.shape[0]:
        raise InputError(
            f"paths.npz has {npz['t'].shape[0]} save times, ms_error.csv {data.shape[0]} "
            f"(files from different runs?); {_rerun(d)}",
            field=str(d),
        )
    try:
        record = RunSummary.from_document(summary, f"{d}/summary.json")
    except InputError as exc:
        more = f"; {_rerun(d)}"
        raise InputError(
            *exc.parts, more, field=exc.field, value=exc.value, option=exc.option
        ) from None
    table = {h: data[:, k] for k, h in enumerate(header)}
    run = RunData(d, summary, table["t"], table, npz, record)
    _check_files(run)
    return run


def _check_files(run: RunData) -> None:
    """paths.npz and ms_error.csv against the checked summary (:class:`RunSummary`): files
    from different runs, or a damaged archive, are one line naming the file and the field
    rather than a TypeError or a failed reshape halfway through the figures."""
    d = run.path

    def bad(field: str, what: str, file: str) -> InputError:
        return InputError(f"{what}; {_rerun(d)}", field=f"{file}: {field}")

    top = run.record.topology
    labels = [str(a) for a in top.labels]
    npz_file = f"{d}/paths.npz"
    if run.labels != labels:
        raise bad(
            "labels",
            f"{counted(len(run.labels), 'agent')} {_few(run.labels)}, summary.json's topology has "
            f"{len(labels)} {_few(labels)} (files from different runs?)",
            npz_file,
        )
    if np.asarray(run.npz["theta"]).shape != (top.dim,):
        raise bad(
            "theta", f"shape {np.asarray(run.npz['theta']).shape}, expected ({top.dim},)", npz_file
        )
    paths = run.npz["paths"]
    agents = run.npz.get("path_agents")
    if agents is not None and (
        agents.ndim != 1
        or agents.dtype.kind not in "iu"
        or (agents.size and (agents.min() < 0 or agents.max() >= top.n))
        or np.any(np.diff(agents) <= 0)
    ):
        raise bad("path_agents", f"expected increasing agent indices in 0..{top.n - 1}", npz_file)
    width = top.n * top.dim if agents is None else agents.size * top.dim
    if paths.size and paths.shape[1:] != (run.t.size, width):
        raise bad(
            "paths",
            f"shape {paths.shape}, expected (paths, {run.t.size} save times, "
            + (
                f"N·d = {width})"
                if agents is None
                else f"{agents.size} stored agents × d = {width})"
            ),
            npz_file,
        )
    if run.ms("mc") is None and run.ms("exact") is None:
        raise bad(
            "header",
            f"no mc_<agent> or exact_<agent> column for every agent {_few(labels)}",
            f"{d}/ms_error.csv",
        )
    if run.ms("mc") is not None and not all(
        f"mc_{a}_{b}" in run.table for a in labels for b in ("lo", "hi")
    ):
        raise bad("header", "an mc_<agent> column without its _lo and _hi", f"{d}/ms_error.csv")


SPREAD_KEYS = (
    "late_fluctuation_mean",
    "late_fluctuation_max",
    "final_error_norm_mean",
)


def _few(labels: list[str]) -> str:
    shown = ", ".join(labels[:4]) + (", …" if len(labels) > 4 else "")
    return f"[{shown}]"


__all__ = ["RunData", "RunSummary", "load_run"]
