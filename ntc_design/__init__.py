"""ntc-design: certify, design and validate non-trivial consensus protocols on directed
signed matrix-weighted networks with compound measurement noise.

Equation, definition, lemma, theorem and section numbers in the docstrings are the printed
ones of the paper below ("Niu & Wu, eq. (8)"). Assumptions 1, 2, 3 are its Assumptions 3.1,
3.2 and 4.1 (numbered within sections in print).

References
----------
T. Niu, X. Wu, "Non-trivial consensus on directed signed matrix-weighted networks with
compound measurement noises and time-varying topologies", submitted to Information Sciences.
Its Lemma 1 (the protocol design) comes from the authors' earlier, noise-free paper,
T. Niu, B. Mao, X. Wu, T. Huang, arXiv:2602.11822.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING

__version__ = "0.1.0"

# Re-exports, loaded on first use (PEP 562): `import ntc_design` costs a few milliseconds,
# and a command loads SciPy, SymPy and the layers only when it needs them.
_EXPORTS = {
    "AssumptionWarning": "errors",
    "InputError": "errors",
    "ProtocolDesign": "design",
    "SwitchingDesign": "design",
    "SwitchingTopology": "model",
    "TimeVaryingTopology": "model",
    "Topology": "model",
    "assumption2": "design",
    "example_path": "paper",
    "load": "loader",
    "random_network": "generate",
}

if TYPE_CHECKING:
    from .design import ProtocolDesign, SwitchingDesign, assumption2, design
    from .errors import AssumptionWarning, InputError
    from .generate import random_network
    from .loader import load
    from .model import SwitchingTopology, TimeVaryingTopology, Topology
    from .paper import example_path

__all__ = [
    "AssumptionWarning",
    "InputError",
    "ProtocolDesign",
    "SwitchingDesign",
    "SwitchingTopology",
    "TimeVaryingTopology",
    "Topology",
    "assumption2",
    "design",
    "example_path",
    "load",
    "random_network",
]


class _Package(types.ModuleType):
    """The package module: ``ntc_design.design`` is Lemma 1's :func:`~ntc_design.design.design`
    (as it always was), although the subpackage of the same name binds itself here when
    it is first imported."""

    @property
    def design(self):
        override = self.__dict__.get("_design_override")
        if override is not None:
            return override
        from .design.lemma1 import design

        return design

    @design.setter
    def design(self, value) -> None:
        # the import system binds the subpackage here when it is first imported: kept
        # aside; anything else (a test's patch) replaces the function until deleted
        if isinstance(value, types.ModuleType) and value.__name__ == f"{__name__}.design":
            return
        self.__dict__["_design_override"] = value

    @design.deleter
    def design(self) -> None:
        self.__dict__.pop("_design_override", None)


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value  # once: later lookups are plain attribute reads
        return value
    raise AttributeError(f"module 'ntc_design' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
