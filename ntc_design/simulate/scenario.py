"""Scenario files -> (topology, :class:`SimulationSpec`), and the outputs of a run
(summary.json, ms_error.csv, paths.npz), written all-or-nothing into an output folder."""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import InputError, blame
from ..io.files import ScenarioData, jsonable, parse_scenario
from ..io.outputs import check_output_folder, json_text, output_folder
from ..model import SwitchingTopology, TimeVaryingTopology, Topology
from ..model.load import load
from .prepare import AnyTopology, edge_count
from .result import TIDY_COLUMNS, tidy_columns
from .spec import SimulationSpec

OUTPUT_FILES = ("summary.json", "ms_error.csv", "ms_error_long.csv", "paths.npz")
#: Above this many agents paths.npz keeps the sample paths of :data:`PATH_AGENTS` agents
#: (those with the largest final error: what a large network's report draws), and
#: ms_error_long.csv is left out above :data:`LONG_ROWS` rows (ms_error.csv holds the
#: same numbers; ``SimulationResult.to_pandas()`` gives the tidy form in Python).
PATHS_ALL_AGENTS_MAX = 20
PATH_AGENTS = 8
LONG_ROWS = 10**6
# what an earlier run's folder may hold besides its outputs (ntc report writes these)
REPLACEABLE = (
    *OUTPUT_FILES,
    "robust.csv",
    "report.html",
    "figures",
    "certificate.json",
    "paths_fine.npz",
)


def load_scenario(
    path: str | Path,
    overrides: dict | None = None,
    data: ScenarioData | None = None,
    flags: Mapping[str, str] | None = None,
) -> tuple[AnyTopology, SimulationSpec, ScenarioData]:
    """Read a scenario file: (topology, spec, the scenario as read).

    Parameters
    ----------
    path : str or Path
        The scenario file (YAML or JSON).
    overrides : dict, optional
        Top-level scenario keys that replace the file's (``paths``, ``T``, ``dt``,
        ``seed``, ``method``, ...), checked exactly as the file's own.
    data : ScenarioData, optional
        The file as :func:`ntc_design.io.files.parse_scenario` already read it (not read again).
    flags : mapping of str to str, optional
        The command line's name for each override it gave (its flag): an error about an
        override names it, not the file.

    Returns
    -------
    (Topology or SwitchingTopology, SimulationSpec, ScenarioData)
        The topology it names, the checked spec and the scenario as read.

    Raises
    ------
    InputError
        ``FILE: FIELD: what is wrong``, or ``--FLAG: what is wrong`` for an override.
    """
    sc = data if data is not None else parse_scenario(path)
    given = overrides or {}
    doc = {**sc.document, **given}
    try:  # unprefixed, to say whether the file or a flag gave the field
        spec = SimulationSpec._from_document(doc, sc.source)
    except InputError as exc:
        # a flag for a field of an override's block too (digital.period, given by its flag)
        named = {k: v for k, v in (flags or {}).items() if k.split(".", 1)[0] in given}
        raise blame(exc, sc.source, named, values=given) from None
    top = load(sc.topology)
    return top, spec, sc


def check_output(out_dir: str | Path) -> Path:
    """Refuse, before a run, an output folder that cannot receive its outputs.

    Parameters
    ----------
    out_dir : str or Path
        The output folder asked for.

    Returns
    -------
    Path
        The folder (it may not exist yet).

    Raises
    ------
    InputError
        A file by that name, a folder holding other files than an earlier run's
        outputs, or a folder that cannot be written.
    """
    return check_output_folder(out_dir, REPLACEABLE)


def ms_error_table(res) -> tuple[list[str], np.ndarray]:
    """The mean-square errors as a wide table (what ``ms_error.csv`` holds).

    Parameters
    ----------
    res : SimulationResult
        The result.

    Returns
    -------
    (list of str, numpy.ndarray)
        Column names t, mc_a, mc_a_lo, mc_a_hi, exact_a (a = agent label; only the
        methods that ran) and the table, one row per save time.
    """
    cols = ["t"]
    data = [res.save_times]
    for k, a in enumerate(res.labels):
        if res.mc is not None:
            cols += [f"mc_{a}", f"mc_{a}_lo", f"mc_{a}_hi"]
            data += [res.mc.mean[:, k], res.mc.lo[:, k], res.mc.hi[:, k]]
        if res.exact is not None:
            cols.append(f"exact_{a}")
            data.append(res.exact.ms_error[:, k])
    return cols, np.column_stack(data)


def write_outputs(
    res, out_dir: str | Path, extra: dict | None = None, files: dict[str, str] | None = None
) -> list[Path]:
    """Write summary.json, ms_error.csv (wide), ms_error_long.csv (tidy) and paths.npz into
    ``out_dir``, all or nothing (see :func:`ntc_design.io.outputs.output_folder`).

    Parameters
    ----------
    res : SimulationResult
        The result.
    out_dir : str or Path
        The output folder (created, or an earlier run's replaced).
    extra : dict, optional
        Added to the summary.
    files : dict of str to str, optional
        More text files to write into the folder (name -> text), e.g. ``robust.csv``.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    InputError
        When the folder cannot be written (``--out: ...``).
    """
    out = Path(out_dir)
    summary = res.summary()
    if extra:
        summary.update(extra)
    cols, table = ms_error_table(res)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(cols)
    for row in table:
        w.writerow([repr(float(v)) for v in row])
    agents, paths = stored_paths(res)
    long_form = res.save_times.size * len(res.labels) <= LONG_ROWS
    summary["files"] = {
        "path_agents": None if agents is None else [str(res.labels[i]) for i in agents],
        "ms_error_long": long_form,
    }
    with output_folder(out, REPLACEABLE) as tmp:
        (tmp / "summary.json").write_text(json_text(jsonable(summary)), encoding="utf-8")
        (tmp / "ms_error.csv").write_text(buf.getvalue(), encoding="utf-8")
        if long_form:
            # the same numbers in tidy long form (t, agent, mc, lo, hi, exact), as to_pandas()
            (tmp / "ms_error_long.csv").write_text(tidy_csv(res), encoding="utf-8")
        arrays: dict[str, np.ndarray] = {
            "t": res.save_times,
            "paths": paths,
            "mean_state": res.mc.mean_state if res.mc is not None else np.zeros((0, 0)),
            "exact_mean": (res.exact.mean + np.tile(res.theta, len(res.labels)))
            if res.exact is not None
            else np.zeros((0, 0)),
            "labels": np.array([str(a) for a in res.labels]),
            "theta": res.theta,
        }
        if agents is not None:
            arrays["path_agents"] = agents
        np.savez_compressed(tmp / "paths.npz", **arrays)  # type: ignore[arg-type]
        for name, text in (files or {}).items():
            (tmp / name).write_text(text, encoding="utf-8")
    written = [out / name for name in OUTPUT_FILES if long_form or name != "ms_error_long.csv"]
    return written + [out / name for name in files or {}]


def tidy_csv(res) -> str:
    """The tidy table as CSV text, as ``simulation_frame(res).to_csv(index=False)`` writes
    it (shortest round-trip floats, NaN as an empty field) without importing pandas.

    Parameters
    ----------
    res : SimulationResult
        The result.

    Returns
    -------
    str
        The header :data:`TIDY_COLUMNS` and one line per (save time, agent).
    """
    cols = tidy_columns(res)
    text = {k: [_csv_float(v) for v in cols[k].tolist()] for k in TIDY_COLUMNS if k != "agent"}
    text["agent"] = [str(v) for v in cols["agent"]]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(TIDY_COLUMNS)
    w.writerows(zip(*(text[k] for k in TIDY_COLUMNS), strict=True))
    return buf.getvalue()


def _csv_float(v: float) -> str:
    return "" if v != v else repr(v)


def stored_paths(res) -> tuple[np.ndarray | None, np.ndarray]:
    """The sample paths paths.npz keeps: every agent's up to :data:`PATHS_ALL_AGENTS_MAX`
    agents, else those of the :data:`PATH_AGENTS` agents with the largest final error
    (their 0-based indices, ascending, and the paths, (paths, saves, agents·d)).

    Parameters
    ----------
    res : SimulationResult
        The result.

    Returns
    -------
    (numpy.ndarray or None, numpy.ndarray)
        The agents (None: all of them) and their paths.
    """
    if res.mc is None:
        return None, np.zeros((0, res.save_times.size, 0))
    n, paths = len(res.labels), res.mc.paths
    if n <= PATHS_ALL_AGENTS_MAX or paths.size == 0:
        return None, paths
    final = res.exact.ms_error[-1] if res.exact is not None else res.mc.mean[-1]
    agents = np.sort(np.argsort(-np.asarray(final), kind="stable")[:PATH_AGENTS])
    d = paths.shape[2] // n
    cols = (agents[:, None] * d + np.arange(d)).ravel()
    return agents.astype(np.int64), paths[:, :, cols]


def result_output_bytes(res, topology) -> float:
    """:func:`output_bytes` of a finished run, said before :func:`write_outputs` writes it.

    Parameters
    ----------
    res : SimulationResult
        The result.
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The run's topology (summary.json holds its edges).

    Returns
    -------
    float
        Bytes.
    """

    known = (Topology, SwitchingTopology, TimeVaryingTopology)
    structure = topology if isinstance(topology, known) else topology.structure  # A(t) as text
    n, nd = len(res.labels), res.theta.size * len(res.labels)
    stored = res.mc.paths.shape[0] if res.mc is not None else 0
    return output_bytes(
        n, nd // n, res.save_times.size, stored, res.mc is not None, res.exact is not None,
        edge_count(structure),
    )  # fmt: skip


def output_bytes(
    n: int, d: int, saves: int, stored: int, mc: bool, exact: bool, edges: int = 0
) -> float:
    """About how many bytes a run's folder will take (text at ~20 bytes a number,
    arrays at 8), from its size alone, to say before the run starts.

    Parameters
    ----------
    n, d : int
        Agents and dimension.
    saves : int
        Save times.
    stored : int
        Stored sample paths.
    mc, exact : bool
        Which methods run.
    edges : int, optional
        Edges of the topology (summary.json holds it, for the report).

    Returns
    -------
    float
        Bytes.
    """
    per_agent = 3 * mc + exact
    wide = 20.0 * saves * n * per_agent
    long_rows = saves * n
    long = 40.0 * long_rows if long_rows <= LONG_ROWS else 0.0
    agents = n if n <= PATHS_ALL_AGENTS_MAX else min(n, PATH_AGENTS)
    arrays = 8.0 * saves * d * (stored * agents * mc + n * (mc + exact))
    return wide + long + arrays + 22.0 * edges * d * d


__all__ = [
    "OUTPUT_FILES",
    "check_output",
    "load_scenario",
    "ms_error_table",
    "output_bytes",
    "result_output_bytes",
    "stored_paths",
    "write_outputs",
]
