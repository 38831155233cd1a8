"""One dispatcher for topology files: a topology, a switching set, a time-varying
topology (YAML or JSON), an ``.npz`` or ``.csv`` edge list, or a ``.mat`` block matrix."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .documents import read_document
from .edgelist import read_npz
from .files import is_time_varying, parse_switching, parse_topology
from .tablefiles import read_csv_edges, read_mat


def parse_file(path: str | Path) -> Any:
    """Read a topology, a switching or a time-varying topology file.

    Which one is told by its fields: ``modes``/``schedule`` for switching, weights that are
    expressions of t for time-varying (:mod:`ntc_design.io.tvfiles`). A ``.npz`` file is a
    compact edge list (:mod:`ntc_design.io.edgelist`); ``.csv`` an edge list and ``.mat`` a
    MATLAB block matrix (:mod:`ntc_design.io.tablefiles`).

    Parameters
    ----------
    path : str or pathlib.Path
        A YAML or JSON file, an ``.npz`` or ``.csv`` edge list, or a ``.mat`` block matrix.

    Returns
    -------
    TopologyData or SwitchingData or TimeVaryingData or EdgeListData
        The validated file contents.

    Raises
    ------
    InputError
        The file cannot be read or is not a valid topology of any kind.
    """
    suffix = str(path).lower()
    if suffix.endswith(".npz"):
        return read_npz(path)
    if suffix.endswith(".csv"):
        return read_csv_edges(path)
    if suffix.endswith(".mat"):
        return read_mat(path)
    doc = read_document(path)
    src = str(path)
    if "modes" in doc or "schedule" in doc:
        return parse_switching(doc, src)
    if is_time_varying(doc):
        from .tvfiles import parse_time_varying

        return parse_time_varying(doc, src)
    return parse_topology(doc, src)


__all__ = ["parse_file"]
