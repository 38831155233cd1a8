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
from typing import TYPE_CHECKING

__version__ = "0.1.0"

# Re-exports, loaded on first use (PEP 562): `import ntc_design` costs a few milliseconds,
# and a command loads SciPy, SymPy and the layers only when it needs them.
_EXPORTS = {
    "AssumptionWarning": "errors",
    "InputError": "errors",
    "ProtocolDesign": "protocol",
    "SwitchingDesign": "protocol",
    "SwitchingTopology": "model",
    "TimeVaryingTopology": "model",
    "Topology": "model",
    "assumption2": "protocol",
    "design": "protocol",
    "example_path": "model.paper",
    "load": "model.load",
    "random_network": "model.generate",
}

if TYPE_CHECKING:
    from .errors import AssumptionWarning, InputError
    from .model import SwitchingTopology, TimeVaryingTopology, Topology
    from .model.generate import random_network
    from .model.load import load
    from .model.paper import example_path
    from .protocol import ProtocolDesign, SwitchingDesign, assumption2, design

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


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value  # once: later lookups are plain attribute reads
        return value
    raise AttributeError(f"module 'ntc_design' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
