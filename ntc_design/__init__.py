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

from .design import AssumptionWarning, ProtocolDesign, SwitchingDesign, assumption2, design
from .errors import InputError
from .generate import random_network
from .loader import load
from .model import SwitchingTopology, TimeVaryingTopology, Topology
from .paper import example_path

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
    "example_path",
    "load",
    "random_network",
]
