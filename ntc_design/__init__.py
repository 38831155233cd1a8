"""ntc-design: certify, design and validate non-trivial consensus protocols on directed
signed matrix-weighted networks with compound measurement noise."""

from .design import AssumptionWarning, ProtocolDesign, SwitchingDesign, assumption2, design
from .errors import InputError
from .generate import random_network
from .model import SwitchingTopology, TimeVaryingTopology, Topology, load

__version__ = "0.1.0"

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
    "load",
    "random_network",
]
