"""ntc-design: certify, design and validate non-trivial consensus protocols on directed
signed matrix-weighted networks with compound measurement noise."""

from .design import ProtocolDesign, SwitchingDesign, assumption2, design
from .errors import InputError
from .model import SwitchingTopology, TimeVaryingTopology, Topology, load

__version__ = "0.1.0"

__all__ = [
    "InputError",
    "ProtocolDesign",
    "SwitchingDesign",
    "SwitchingTopology",
    "TimeVaryingTopology",
    "Topology",
    "assumption2",
    "design",
    "load",
]
