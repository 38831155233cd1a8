"""Robust certification: Lemma 1's protocol when every weight is known only within a
relative Loewner interval (the set and the bounds: :mod:`.search`).

Modules, each importing only those listed before it: :mod:`.problem` (the data types),
:mod:`.are` (the Riccati search), :mod:`.lmi` (the S-procedure LMIs), :mod:`.offset` (the
offset's reduced S-procedure), :mod:`.realise` (hill-climbed realisations), :mod:`.report`
(the brackets as a table), :mod:`.scale` (sparse bounds for large networks) and
:mod:`.search` (:func:`robust`, the brackets at a radius).
"""

from .problem import (
    CHANNEL_FLOOR,
    Bracket,
    Realisation,
    UncertainEdges,
    channel_bound,
    pivot_columns,
    radius_phrase,
    radius_text,
    realised_topology,
    uncertain_edges,
    whitening_basis,
)
from .realise import abscissa
from .report import RobustDesign, RobustReport
from .search import (
    DEFAULT_RADIUS,
    ROBUST_MAX_ND,
    check_radius,
    check_robust_work,
    robust,
    robust_seconds,
    robust_sweep,
)

__all__ = [
    "CHANNEL_FLOOR",
    "DEFAULT_RADIUS",
    "ROBUST_MAX_ND",
    "Bracket",
    "Realisation",
    "RobustDesign",
    "RobustReport",
    "UncertainEdges",
    "abscissa",
    "channel_bound",
    "check_radius",
    "check_robust_work",
    "pivot_columns",
    "radius_phrase",
    "radius_text",
    "realised_topology",
    "robust",
    "robust_seconds",
    "robust_sweep",
    "uncertain_edges",
    "whitening_basis",
]
