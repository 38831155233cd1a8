"""The three brackets at one radius as every face shows them (:class:`RobustReport`), and
the design the robust certificate kind accepts (:class:`RobustDesign`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from ...present.rows import Table, fmt
from ...protocol import ProtocolDesign
from .problem import Bracket, radius_phrase, uncertain_edges


@dataclass(frozen=True)
class RobustReport:
    """The three brackets at one radius, with the matrices that prove the certified ends
    (``lmi``: P, τ for the decay and margin LMIs; γ, λ, Y for the offset)."""

    design: ProtocolDesign
    radius: float  # the largest ρ_e (ρ itself when every edge has the same)
    radii: tuple[float, ...]  # ρ_e per uncertain edge (UncertainEdges order)
    nominal_decay: float
    decay: Bracket
    offset: Bracket
    margin: Bracket
    proofs: dict = field(repr=False)
    seconds: float = 0.0

    def table(self, title: str | None = None) -> Table:
        """The three brackets as the table every face shows.

        Parameters
        ----------
        title : str, optional
            The table's title.

        Returns
        -------
        ntc_design.present.rows.Table
        """

        num = functools.partial(fmt, digits=6)  # None shows as "—"
        top = self.design.topology
        d, o, m = (_proven_by(b.method) for b in (self.decay, self.offset, self.margin))
        rows = [
            ("decay rate min Re λ(L_B(A'))", num(self.decay.lower), num(self.decay.upper),
             f"lower proven ({d}); upper attained by a realisation"),
            ("consensus offset ‖x* − 1⊗θ‖₂", num(self.offset.lower), num(self.offset.upper),
             f"upper proven ({o}); lower attained by a realisation"),
            ("margin radius ρ", num(self.margin.lower), num(self.margin.upper),
             f"lower proven ({m} at α = 0); upper: a destabilising realisation"),
        ]  # fmt: skip
        ed = uncertain_edges(top)
        antag = int(np.sum(ed.s < 0))
        notes: tuple[str, ...] = (
            f"nominal decay rate {self.nominal_decay:.6g}; the protocol (informed agents, B_i, "
            f"δ = {self.design.delta:.6g}, x0) is kept at its nominal design",
            f"only the {antag} antagonistic weight(s) move the consensus point "
            "(D_eᵀ(1⊗θ) = 0 on cooperative edges)",
        )
        if len(set(self.radii)) > 1:  # what each bracket is about, said where it differs
            notes += (
                "the decay and offset brackets hold for the per-edge radii; the margin radius "
                "is one ρ on every edge",
            )
        phrase = radius_phrase(self.radii, self.radius, ed.labels(top))
        return Table.build(
            title or f"{top.name or 'topology'}: robust brackets {phrase}",
            ("bracket", "lower", "upper", "which end is proven"),
            rows,
            notes,
        )

    def to_dict(self) -> dict:
        """The report in the ``--json`` form: radius, decay, offset and margin, each
        realisation as topology-file edges.

        Returns
        -------
        dict
        """
        top = self.design.topology
        ed = uncertain_edges(top)

        def real(b: Bracket) -> list[dict] | None:
            return None if b.realisation is None else b.realisation.edges(top, ed)

        uniform = len(set(self.radii)) <= 1
        return {
            "radius": self.radius if uniform else list(self.radii),
            "nominal_decay": self.nominal_decay,
            "decay": {
                "lower": self.decay.lower,
                "upper": self.decay.upper,
                "realization": real(self.decay),
                "method": self.decay.method,
            },
            "offset": {
                "lower": self.offset.lower,
                "upper": self.offset.upper,
                "realization": real(self.offset),
                "method": self.offset.method,
            },
            "margin": {
                "lower": self.margin.lower,
                "upper": self.margin.upper,
                "destabilizing": real(self.margin),
                "realization_radius": None
                if self.margin.realisation is None
                else self.margin.realisation.radius,
                "method": self.margin.method,
            },
        }


def _proven_by(method: str) -> str:
    """A short name for the method that proves a bracket's end (the table's last column)."""
    for key, name in (
        ("Riccati", "Riccati search"),
        ("comparison", "comparison bound"),
        ("dominance", "block dominance"),
        ("Finsler", "S-procedure"),
        ("eliminated", "S-procedure, reduced"),
    ):
        if key in method:
            return name
    return "LMI"


@dataclass(frozen=True)
class RobustDesign:
    """A nominal design whose weights are known within relative radii, with the brackets
    found for it: what the ``robust`` certificate kind accepts and issues from (as a
    :class:`ntc_design.protocol.digital.DigitalDesign` is for the digital kinds).

    Parameters
    ----------
    report : RobustReport
        The brackets (:func:`ntc_design.certify.robust.robust`); its ``design`` is the
        nominal protocol and its radii the set.
    """

    report: RobustReport

    @property
    def design(self) -> ProtocolDesign:
        """The nominal design."""
        return self.report.design


__all__ = ["RobustDesign", "RobustReport"]
