"""The registry of certificate kinds: ``kind`` field -> :class:`CertificateKind`.

Issuing takes the first kind that accepts a design; verifying looks the kind up by name.
A new kind is one module beside this one and one line here (CONTRIBUTING.md)."""

from __future__ import annotations

from .base import CertificateKind
from .digital import DigitalKind, DigitalSwitchingKind
from .digital_loss import DigitalLossKind
from .hurwitz import HurwitzKind
from .hurwitz_scale import HurwitzScaleKind
from .robust import RobustKind
from .switching import SwitchingKind
from .switching_scale import SwitchingScaleKind
from .time_varying import TimeVaryingKind

#: Every kind, by the name its certificates carry (the order is the issuing order).
KINDS: dict[str, CertificateKind] = {
    k.name: k
    for k in (
        HurwitzKind(),
        HurwitzScaleKind(),
        SwitchingKind(),
        SwitchingScaleKind(),
        TimeVaryingKind(),
        RobustKind(),
        DigitalLossKind(),
        DigitalKind(),
        DigitalSwitchingKind(),
    )
}


def kind_for(design: object) -> CertificateKind:
    """The kind that certifies ``design`` (the first in :data:`KINDS` that accepts it).

    Parameters
    ----------
    design : ProtocolDesign, SwitchingDesign or TimeVaryingDesign
        A Lemma 1 design.

    Returns
    -------
    CertificateKind

    Raises
    ------
    TypeError
        No kind accepts it (not a design).
    """
    for kind in KINDS.values():
        if kind.accepts(design):
            return kind
    raise TypeError(f"no certificate kind accepts a {type(design).__name__}")


__all__ = ["KINDS", "kind_for"]
