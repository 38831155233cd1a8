"""The paper's Section 5 as reference data: topologies G1, G2, G3, the switching example,
the simulation settings and the numbers the paper states (for `ntc reproduce paper`).
``examples/*.yaml`` hold the same topologies as files; a test checks they agree."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import InputError
from .model import SwitchingTopology, Topology

THETA = [1.0, 2.0, -1.0]
SIGMA = 0.4
F_SCALE = 0.3
DT = 1e-3
PATHS = 1000
GAIN = "1/(1+t)"
GAIN_VANISHING = "(1+t)^-2"  # ∫c < ∞: the cumulative effect vanishes
GAIN_ENERGY = "(1+t)^(-1/3)"  # ∫c² = ∞: the noise energy is infinite
DWELL = 0.02
PATTERN = ("G2", "G2", "G1", "G3", "G3")

_A12_G1 = np.diag([1.0, 1.0, 2.0])


def g1() -> Topology:
    """G1 of Niu & Wu, Sec. 5.1 (the fixed-topology example, 7 agents, d = 3).

    Returns
    -------
    Topology
        G1.
    """
    return Topology.from_edges(
        7,
        3,
        [
            (2, 1, _A12_G1),
            (1, 2, -np.diag([1.0, 1.0, 0.0])),
            (5, 6, np.array([[7.0, 1, 1], [1, 6, 0], [1, 0, 5]])),
            (2, 5, np.array([[10.0, 1, 2], [1, 8, 1], [2, 1, 12]])),
            (6, 7, np.diag([3.1, 3.1, 3.2])),
            (6, 2, -np.diag([0.0, 0.0, 1.0])),
            (6, 3, -0.1 * _A12_G1),
            (3, 4, _A12_G1),
        ],
        name="G1",
    )


def g2() -> Topology:
    """G2 of Niu & Wu, Sec. 5.2 (weights as in eq. (22)).

    Returns
    -------
    Topology
        G2.
    """
    a65 = np.array([[6.0, 1, -1], [1, 8, 2], [-1, 2, 6]])
    a47 = -np.diag([0.0, 1.0, 0.0])
    return Topology.from_edges(
        7,
        3,
        [
            (2, 1, -np.array([[5.0, 2, 1], [2, 4, 1], [1, 1, 3]])),
            (7, 4, a47),
            (5, 6, a65),
            (7, 6, np.diag([4.0, 3.0, 3.0])),
            (6, 7, np.array([[5.0, 1, 0], [1, 6, -1], [0, -1, 5]])),
            (3, 4, -np.array([[2.0, 0, 1], [0, 0, 0], [1, 0, 3]])),
            (1, 5, a65),
            (6, 2, -0.5 * np.eye(3)),
            (6, 3, -0.5 * np.eye(3)),
            (2, 6, a47),
        ],
        name="G2",
    )


def g3() -> Topology:
    """G3 of Niu & Wu, Sec. 5.2 (weights as in eq. (23)).

    Returns
    -------
    Topology
        G3.
    """
    return Topology.from_edges(
        7,
        3,
        [
            (4, 3, np.diag([1.0, 2.0, 0.0])),
            (7, 3, -np.array([[2.0, -1, 0], [-1, 2, 0], [0, 0, 1]])),
            (3, 4, np.array([[2.0, -1, 0], [-1, 3, 1], [0, 1, 4]])),
            (5, 7, np.diag([2.0, 3.0, 1.0])),
            (2, 5, np.array([[8.0, 2, 1], [2, 8, 1], [1, 1, 6]])),
            (1, 2, -np.array([[3.0, 1, -1], [1, 5, 2], [-1, 2, 5]])),
            (3, 6, -np.eye(3)),
            (5, 1, -np.eye(3)),
        ],
        name="G3",
    )


def switching() -> SwitchingTopology:
    """The switching example of Niu & Wu, Sec. 5.2: G1, G2, G3 in the paper's pattern,
    each for the same dwell time.

    Returns
    -------
    SwitchingTopology
        The modes and the periodic schedule.
    """
    return SwitchingTopology(
        {"G1": g1(), "G2": g2(), "G3": g3()}, tuple((m, DWELL) for m in PATTERN)
    )


# What the paper states (Section 5).
STATED = {
    "G1": {
        "C": 7.1440,
        "delta": 7.2440,
        "x0": [1.2761, 2.5522, -1.2761],
        "informed": [2, 3],
        "V1": [2, 3],
    },
    "G2": {"delta": 7.0495, "x0": [1.2837, 2.5674, -1.2837], "informed": [1, 2, 3, 4, 6]},
    "G3": {"delta": 3.1000, "x0": [1.6452, 3.2903, -1.6452], "informed": [1, 2, 3, 6]},
}


def example_path(name: str = "") -> Path:
    """A bundled example file (the checkout's ``examples/``, shipped in the wheel as
    ``ntc_design.examples``): where it is however the package was installed, so a script
    or a downloaded notebook runs outside a checkout.

    Parameters
    ----------
    name : str, optional
        A file inside the examples, e.g. ``"g1.yaml"`` or ``"scenarios/g1_fixed.yaml"``;
        empty: the folder itself.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        No such example, or a name that leaves the examples folder.

    Examples
    --------
    >>> import ntc_design as nd
    >>> nd.load(nd.example_path("g1.yaml")).n
    7
    """
    root = _examples_root()
    target = (root / name).resolve()
    if root.resolve() not in (target, *target.parents):
        raise InputError(f"example_path: {name!r} is outside the bundled examples")
    if not target.exists():
        known = sorted(p.name for p in root.glob("*.yaml"))
        raise InputError(f"example_path: no example {name!r} (there are {', '.join(known)}, …)")
    return target


def _examples_root() -> Path:
    try:  # an installed wheel: the package data
        from importlib.resources import files

        root = Path(str(files("ntc_design.examples")))
        if (root / "g1.yaml").is_file():
            return root
    except (ModuleNotFoundError, TypeError):
        pass
    checkout = Path(__file__).resolve().parent.parent / "examples"  # a checkout (editable)
    if (checkout / "g1.yaml").is_file():
        return checkout
    raise InputError("example_path: the bundled examples are not installed with this package")
