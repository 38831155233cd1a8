"""A simulation run as ``ntc report`` reads it (summary.json, ms_error.csv, paths.npz),
each file bounded and checked against the others once, with one-line errors naming the
file and field."""

from __future__ import annotations

import csv
import io
import json
import shlex
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, format_bytes, one_line, require_number, require_positive
from ..gain.conditions import parse_gain
from ..gain.schedule import ScheduleGain, schedule_from_document
from ..io.files import parse_topology
from ..model import SwitchingTopology, Topology
from ..present.rows import counted
from ..simulate.budget import MEMORY_FRACTION, available_memory

REQUIRED = ("summary.json", "ms_error.csv", "paths.npz")


@dataclass
class RunData:
    """A simulation run as ``ntc report`` reads it: summary.json, the curves table and the
    paths, checked against each other once by :func:`load_run`."""

    path: Path
    summary: dict
    t: np.ndarray
    table: dict[str, np.ndarray]
    npz: dict[str, np.ndarray]

    @property
    def labels(self) -> list[str]:
        """The agent labels, as text."""
        return [str(a) for a in self.npz["labels"]]

    @property
    def gain(self) -> str | ScheduleGain:
        """The run's gain: its expression, or the schedule it recorded (checked by
        :func:`load_run`)."""
        g = self.summary["parameters"]["gain"]
        return schedule_from_document(g, "parameters.gain") if isinstance(g, dict) else g

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
        return np.asarray(self.summary["parameters"]["theta"], dtype=float)

    def topology(self) -> Topology | SwitchingTopology:
        """The run's topology (or switching set), rebuilt from summary.json.

        Returns
        -------
        Topology or SwitchingTopology

        Raises
        ------
        InputError
            A malformed topology or schedule, or a run over a time-varying topology.
        """
        where = f"{self.path}/summary.json"
        tops = {}
        for k, v in self.summary["topologies"].items():
            if not isinstance(v, dict):
                raise InputError(
                    f"{where}: topologies.{k}: expected a topology; {_rerun(self.path)}"
                )
            tops[k] = Topology.from_data(parse_topology(v, f"{where}: topologies.{k}"))
        sched = self.summary["parameters"].get("schedule")
        if sched is not None:  # a switching run: [{mode, duration}, ...] over the topologies
            ok = isinstance(sched, list) and all(
                isinstance(s, dict)
                and isinstance(s.get("mode"), str)
                and isinstance(s.get("duration"), (int, float))
                and not isinstance(s.get("duration"), bool)
                for s in sched
            )
            if not ok:
                raise InputError(
                    f"{where}: parameters.schedule: expected a list of {{mode, duration}}; "
                    f"{_rerun(self.path)}"
                )
            return SwitchingTopology(
                tops,
                tuple((s["mode"], float(s["duration"])) for s in sched),
                source=f"{where}: parameters",
            )
        if len(tops) != 1:
            raise InputError(
                f"{self.path}: a run over a topology given as functions of t has no single topology to certify"
            )
        return next(iter(tops.values()))

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


MAX_TEXT_BYTES = 256 * 2**20  # summary.json / ms_error.csv larger than this are refused
#: A report draws every agent (topology figure, per-agent curves and tables): refused above.
NPZ_KEYS = ("t", "paths", "labels", "theta")


def _rerun(d: Path) -> str:
    return f"re-run: ntc simulate SCENARIO --out {d}"


def _read_text(path: Path, d: Path) -> str:
    try:
        if path.stat().st_size > MAX_TEXT_BYTES:
            raise InputError(f"{path}: larger than {MAX_TEXT_BYTES // 2**20} MiB; {_rerun(d)}")
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: unreadable ({exc.__class__.__name__}); {_rerun(d)}") from None


def _read_npz(path: Path, d: Path) -> dict[str, np.ndarray]:
    """paths.npz, refusing a corrupt, empty or oversized (decompression bomb) archive."""
    try:
        with zipfile.ZipFile(path) as zf:
            size = sum(i.file_size for i in zf.infolist())
        limit = MEMORY_FRACTION * available_memory()
        if size > limit:
            raise InputError(
                f"{path}: unpacks to {format_bytes(size)}, more than {format_bytes(limit)}; {_rerun(d)}"
            )
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in NPZ_KEYS if k not in z.files]
            if missing:
                raise InputError(f"{path}: missing array {missing[0]!r}; {_rerun(d)}")
            npz = {k: z[k] for k in z.files}
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - BadZipFile, EOFError, zlib.error, ValueError...
        raise InputError(
            f"{path}: not a readable .npz archive ({exc.__class__.__name__}); {_rerun(d)}"
        ) from None
    if npz["paths"].ndim != 3 or npz["t"].ndim != 1 or npz["labels"].ndim != 1:
        raise InputError(f"{path}: arrays of the wrong shape; {_rerun(d)}")
    if npz["labels"].dtype.kind not in "UO" and npz["labels"].size:
        raise InputError(f"{path}: labels are not text; {_rerun(d)}")
    for k in ("t", "paths", "theta"):
        if npz[k].dtype.kind not in "fiu":
            raise InputError(f"{path}: array {k!r} is not numeric; {_rerun(d)}")
    return npz


def load_run(directory: str | Path) -> RunData:
    """Read a simulation output directory; name what is missing or malformed and how to
    make it again.

    Parameters
    ----------
    directory : str or Path
        A folder written by ``ntc simulate --out``.

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
        raise InputError(f"{d}: no such directory; make it with: ntc simulate SCENARIO --out {d}")
    for name in REQUIRED:
        if not (d / name).is_file():
            raise InputError(f"{d}: missing {name}; make it with: ntc simulate SCENARIO --out {d}")
    try:
        summary = json.loads(_read_text(d / "summary.json", d))
    except (json.JSONDecodeError, RecursionError, ValueError) as exc:
        raise InputError(
            f"{d}/summary.json: not valid JSON ({exc.__class__.__name__}); {_rerun(d)}"
        ) from None
    if not isinstance(summary, dict):
        raise InputError(f"{d}/summary.json: expected a mapping; {_rerun(d)}")
    for key in ("parameters", "topologies"):
        if not isinstance(summary.get(key), dict) or not summary[key]:
            raise InputError(f"{d}/summary.json: missing field '{key}'; {_rerun(d)}")
    for key in ("theta", "margin", "gain"):
        if key not in summary["parameters"]:
            raise InputError(f"{d}/summary.json: missing field 'parameters.{key}'; {_rerun(d)}")
    rows = list(csv.reader(io.StringIO(_read_text(d / "ms_error.csv", d))))
    if len(rows) < 2:
        raise InputError(f"{d}/ms_error.csv: no data rows; {_rerun(d)}")
    header = rows[0]
    if not header or header[0] != "t" or len(set(header)) != len(header):
        raise InputError(
            f"{d}/ms_error.csv: the header must start with 't' (unique columns); {_rerun(d)}"
        )
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(
                f"{d}/ms_error.csv: line {k} has {len(r)} values, the header {len(header)}; {_rerun(d)}"
            )
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:]])
    except ValueError:
        raise InputError(f"{d}/ms_error.csv: a value is not a number; {_rerun(d)}") from None
    if not np.all(np.isfinite(data[:, 0])) or np.any(np.diff(data[:, 0]) <= 0):
        raise InputError(f"{d}/ms_error.csv: times are not finite and increasing; {_rerun(d)}")
    npz = _read_npz(d / "paths.npz", d)
    if npz["t"].shape[0] != data.shape[0]:
        raise InputError(
            f"{d}: paths.npz has {npz['t'].shape[0]} save times, ms_error.csv {data.shape[0]} "
            f"(files from different runs?); {_rerun(d)}"
        )
    table = {h: data[:, k] for k, h in enumerate(header)}
    run = RunData(d, summary, table["t"], table, npz)
    _check_run(run)
    return run


def _check_run(run: RunData) -> None:
    """The fields of summary.json and paths.npz that the report reads, checked against each
    other before anything is written (certificate, figures, report.html): a damaged run, or
    files from different runs, is one line naming the file and the field rather than a
    TypeError or a failed reshape halfway through the figures."""
    d = run.path
    where = f"{d}/summary.json"

    def bad(field: str, what: str, file: str = where) -> InputError:
        return InputError(f"{file}: {field}: {what}; {_rerun(d)}")

    p = run.summary["parameters"]
    theta = p["theta"]
    if not isinstance(theta, list) or not theta:
        raise bad("parameters.theta", "expected a list of numbers")
    try:
        for k, v in enumerate(theta):
            require_number(f"parameters.theta[{k}]", v)
        require_positive("parameters.margin", p["margin"])
    except InputError as exc:
        raise InputError(f"{where}: {exc}; {_rerun(d)}") from None
    if isinstance(p["gain"], dict):  # a tabulated schedule, checked whole
        try:
            schedule_from_document(p["gain"], "parameters.gain")
        except InputError as exc:
            raise InputError(f"{where}: {exc}; {_rerun(d)}") from None
    elif not isinstance(p["gain"], str):
        raise bad("parameters.gain", "expected an expression in t (text) or a schedule")
    else:
        try:
            parse_gain(p["gain"])
        except InputError as exc:  # "gain: ..." from the parser
            raise InputError(f"{where}: parameters.{exc}; {_rerun(d)}") from None
    for key in ("noise", "time_varying"):
        if p.get(key) is not None and not isinstance(p[key], dict):
            raise bad(f"parameters.{key}", "expected a mapping")
    for key in ("run", "sample_paths"):
        if not isinstance(run.summary.get(key, {}), dict):
            raise bad(key, "expected a mapping")
    if not isinstance(run.summary.get("scenario", ""), str):
        raise bad("scenario", "expected a file name")
    sp_ = run.summary.get("sample_paths", {})
    if sp_.get("stored"):
        window = sp_.get("late_window")
        numbers = [sp_.get(k) for k in SPREAD_KEYS] + (window if isinstance(window, list) else [])
        if not (isinstance(window, list) and len(window) == 2) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in numbers
        ):
            raise bad("sample_paths", f"expected numbers {', '.join(SPREAD_KEYS)}, late_window")
    top = run.topology()
    labels = [str(a) for a in top.labels]
    npz_file = f"{d}/paths.npz"
    if run.labels != labels:
        raise bad(
            "labels",
            f"{counted(len(run.labels), 'agent')} {_few(run.labels)}, summary.json's topology has "
            f"{len(labels)} {_few(labels)} (files from different runs?)",
            npz_file,
        )
    if len(theta) != top.dim:
        raise bad("parameters.theta", f"{len(theta)} numbers, the topology has d = {top.dim}")
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


__all__ = ["RunData", "load_run"]
