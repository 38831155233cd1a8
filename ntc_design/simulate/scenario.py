"""Scenario files -> (topology, :class:`SimulationSpec`), and the outputs of a run
(summary.json, ms_error.csv, paths.npz), written all-or-nothing into an output folder."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from ..files import ScenarioData, jsonable, parse_scenario
from ..loader import load
from ..outputs import check_output_folder, json_text, output_folder
from .driver import AnyTopology
from .result import simulation_frame
from .spec import SimulationSpec

OUTPUT_FILES = ("summary.json", "ms_error.csv", "ms_error_long.csv", "paths.npz")
# what an earlier run's folder may hold besides its outputs (ntc report writes these)
REPLACEABLE = (*OUTPUT_FILES, "report.html", "figures", "certificate.json", "paths_fine.npz")


def load_scenario(
    path: str | Path, overrides: dict | None = None
) -> tuple[AnyTopology, SimulationSpec, ScenarioData]:
    """Read a scenario file: (topology, spec, the scenario as read).

    Parameters
    ----------
    path : str or Path
        The scenario file (YAML or JSON).
    overrides : dict, optional
        Top-level scenario keys that replace the file's (``paths``, ``T``, ``dt``,
        ``seed``, ``method``, ...), checked exactly as the file's own.

    Returns
    -------
    (Topology or SwitchingTopology, SimulationSpec, ScenarioData)
        The topology it names, the checked spec and the scenario as read.

    Raises
    ------
    InputError
        ``FILE: FIELD: what is wrong``.
    """
    sc = parse_scenario(path)
    doc = {**sc.document, **(overrides or {})}
    spec = SimulationSpec.from_document(doc, sc.source)
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


def write_outputs(res, out_dir: str | Path, extra: dict | None = None) -> list[Path]:
    """Write summary.json, ms_error.csv (wide), ms_error_long.csv (tidy) and paths.npz into
    ``out_dir``, all or nothing (see :func:`ntc_design.outputs.output_folder`).

    Parameters
    ----------
    res : SimulationResult
        The result.
    out_dir : str or Path
        The output folder (created, or an earlier run's replaced).
    extra : dict, optional
        Added to the summary.

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
    with output_folder(out, REPLACEABLE) as tmp:
        (tmp / "summary.json").write_text(
            json_text(jsonable(summary)), encoding="utf-8"
        )
        (tmp / "ms_error.csv").write_text(buf.getvalue(), encoding="utf-8")
        # the same numbers in tidy long form (t, agent, mc, lo, hi, exact), as to_pandas()
        (tmp / "ms_error_long.csv").write_text(
            simulation_frame(res).to_csv(index=False), encoding="utf-8"
        )
        np.savez_compressed(
            tmp / "paths.npz",
            t=res.save_times,
            paths=res.mc.paths if res.mc is not None else np.zeros((0, res.save_times.size, 0)),
            mean_state=res.mc.mean_state if res.mc is not None else np.zeros((0, 0)),
            exact_mean=(res.exact.mean + np.tile(res.theta, len(res.labels)))
            if res.exact is not None
            else np.zeros((0, 0)),
            labels=np.array([str(a) for a in res.labels]),
            theta=res.theta,
        )
    return [out / name for name in OUTPUT_FILES]


__all__ = ["OUTPUT_FILES", "check_output", "load_scenario", "ms_error_table", "write_outputs"]
