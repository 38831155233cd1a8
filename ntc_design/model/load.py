"""``load``: any topology file as its model object (the one place that knows every kind of
topology: fixed, switching, time-varying)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..io.edgelist import EdgeListData
from ..io.files import SwitchingData, TopologyData
from ..io.readers import parse_file
from . import SwitchingTopology, Topology

if TYPE_CHECKING:
    from .timevarying import ExpressionTopology


def load(path: str | Path) -> Topology | SwitchingTopology | ExpressionTopology:
    """Load a topology file, a switching file or a time-varying topology file (YAML or
    JSON), an edge list (``.csv`` or the compact ``.npz``, :mod:`ntc_design.io.edgelist`) or a
    MATLAB block matrix (``.mat``, :mod:`ntc_design.io.tablefiles`).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    Topology or SwitchingTopology or ExpressionTopology
        A time-varying file gives an :class:`~ntc_design.model.timevarying.ExpressionTopology`,
        or the fixed :class:`Topology` when every weight is a constant expression.

    Raises
    ------
    InputError
        The file cannot be read or is not a valid topology (one line naming the file and
        the field or edge).

    Examples
    --------
    >>> import ntc_design as nd
    >>> nd.load("examples/g1.yaml")
    Topology('G1', N=7, d=3, 8 edges (3 antagonistic), U={2, 3})
    """
    data = parse_file(path)
    if isinstance(data, EdgeListData):
        return Topology.from_data(data)
    if isinstance(data, SwitchingData):
        return SwitchingTopology.from_data(data)
    if isinstance(data, TopologyData):
        return Topology.from_data(data)
    from .timevarying import ExpressionTopology

    tv = ExpressionTopology.from_data(data)
    return tv.fixed() if tv.constant else tv


__all__ = ["load"]
