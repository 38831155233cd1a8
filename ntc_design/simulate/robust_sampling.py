"""The scenario's ``robust:`` option: weight realisations simulated besides the nominal
network (:func:`ntc_design.sweep.robust.robust_study` runs them)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import MAX_SEED, InputError, require_int, require_radius

MAX_REALISATIONS = 1000


@dataclass(frozen=True)
class RobustSampling:
    """Weight realisations to simulate besides the nominal network (scenario key
    ``robust: {realizations: K, radius: ρ, seed: S}``): K draws from the Loewner set of
    :mod:`ntc_design.certify.robust.search` (every edge's radius is its file's ``uncertainty:``,
    else ``radius``), each run with the nominal protocol."""

    realizations: int = 10
    radius: float = 0.05
    seed: int = 0

    def __post_init__(self) -> None:
        require_int("robust.realizations", self.realizations, minimum=1, maximum=MAX_REALISATIONS)
        r = require_radius(self.radius, "robust.radius")
        require_int("robust.seed", self.seed, minimum=0, maximum=MAX_SEED)
        object.__setattr__(self, "realizations", int(self.realizations))
        object.__setattr__(self, "radius", float(r))
        object.__setattr__(self, "seed", int(self.seed))

    @classmethod
    def from_document(cls, doc: Any) -> RobustSampling:
        """From the scenario's ``robust`` mapping.

        Parameters
        ----------
        doc : Any
            ``{realizations, radius, seed}`` (each optional).

        Returns
        -------
        RobustSampling

        Raises
        ------
        InputError
            Not a mapping, an unknown key or a bad value.
        """
        if not isinstance(doc, Mapping):
            raise InputError(
                f"expected {{realizations, radius, seed}}, got {doc!r}", field="robust"
            )
        unknown = sorted(str(k) for k in set(doc) - {"realizations", "radius", "seed"})
        if unknown:
            raise InputError(
                "unknown field (known: realizations, radius, seed)", field=f"robust.{unknown[0]}"
            )
        return cls(**dict(doc))


__all__ = ["MAX_REALISATIONS", "RobustSampling"]
