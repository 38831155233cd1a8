"""The paper's Section 5 as reference data: topologies G1, G2, G3, the switching example,
the simulation settings and the numbers the paper states (for `ntc reproduce paper`).
``examples/*.yaml`` hold the same topologies as files; a test checks they agree."""

from __future__ import annotations

import importlib.resources
from importlib.resources.abc import Traversable
from pathlib import Path

import numpy as np

from ..errors import InputError
from . import SwitchingTopology, Topology

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
        raise InputError(f"{name!r} is outside the bundled examples", field="example_path")
    if not target.exists():
        known = sorted(p.name for p in root.glob("*.yaml"))
        raise InputError(
            f"no example {name!r} (there are {', '.join(known)}, …)", field="example_path"
        )
    return target


def _examples_root() -> Path:
    # An installed wheel holds the examples in the package's own folder, ntc_design/examples
    # (pyproject.toml maps examples/ there). They are found through the regular package
    # ntc_design: ``files("ntc_design.examples")`` would be a namespace package (examples/
    # has no __init__.py), a MultiplexedPath whose text is no path.
    try:
        bundled = importlib.resources.files("ntc_design").joinpath("examples")
    except (ModuleNotFoundError, TypeError):
        bundled = None
    if isinstance(bundled, Path) and (bundled / "g1.yaml").is_file():
        return bundled
    if bundled is not None and not isinstance(bundled, Path) and _has_examples(bundled):
        return _extracted(bundled)  # a zip or another loader: the files, copied out once
    checkout = Path(__file__).resolve().parents[2] / "examples"  # a checkout (editable)
    if (checkout / "g1.yaml").is_file():
        return checkout
    raise InputError(
        "the bundled examples are not installed with this package", field="example_path"
    )


def _has_examples(bundled: Traversable) -> bool:
    try:
        return bundled.joinpath("g1.yaml").is_file()
    except OSError:
        return False


_EXTRACTED: list[Path] = []


def _extracted(bundled: Traversable) -> Path:
    """The examples of a package that is not on the file system (a zip), copied into a
    temporary folder once per process (``importlib.resources.as_file`` copies one file,
    not a folder, before Python 3.12)."""
    if not _EXTRACTED:
        import atexit
        import shutil
        import tempfile

        root = Path(tempfile.mkdtemp(prefix="ntc-examples-"))
        atexit.register(shutil.rmtree, root, True)

        def copy(src: Traversable, dest: Path) -> None:
            for entry in src.iterdir():
                if entry.is_dir():
                    (dest / entry.name).mkdir()
                    copy(entry, dest / entry.name)
                elif entry.is_file():
                    (dest / entry.name).write_bytes(entry.read_bytes())

        copy(bundled, root)
        _EXTRACTED.append(root)
    return _EXTRACTED[0]


#: The example files a wheel ships (pyproject.toml's package data for ntc_design.examples;
#: a test keeps the two lists equal): a checkout's examples/figures are not among them.
EXAMPLE_FILES = ("*.yaml", "*.csv", "*.mat", "scenarios/*.yaml", "sweeps/*.yaml")


def example_files() -> list[str]:
    """The bundled examples' files, relative to their folder (``g1.yaml``,
    ``scenarios/g1_fixed.yaml``, ...), sorted: what a wheel ships
    (:data:`EXAMPLE_FILES`).

    Returns
    -------
    list of str

    Raises
    ------
    InputError
        The examples are not installed with this package.
    """
    root = _examples_root()
    return sorted({p.relative_to(root).as_posix() for g in EXAMPLE_FILES for p in root.glob(g)})


def copy_examples(dest: str | Path) -> list[Path]:
    """Copy the bundled examples into a new folder (for a user who installed the package
    without a checkout: ``ntc examples``, copied to a folder).

    Parameters
    ----------
    dest : str or pathlib.Path
        The folder to create; an existing one must be empty.

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    InputError
        ``dest`` is a file or a folder that is not empty, or the examples are not
        installed with this package.
    """
    import shutil

    dest = Path(dest)
    if dest.is_symlink() and not dest.exists():  # mkdir would say "File exists"
        raise InputError(
            f"a link to {str(dest.readlink())!r}, which does not exist (give a new or "
            "empty folder, or the folder the link should name)",
            field=str(dest),
        )
    if dest.exists() and not dest.is_dir():
        raise InputError("exists and is not a folder (give a new or empty folder)", field=str(dest))
    if dest.is_dir() and any(dest.iterdir()):
        raise InputError("the folder is not empty (give a new or empty folder)", field=str(dest))
    root = _examples_root()
    names = example_files()
    written = []
    for name in names:
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(root / name, target)
        written.append(target)
    return written
