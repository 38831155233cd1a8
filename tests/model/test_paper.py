"""Tests of :mod:`ntc_design.model.paper`."""

import importlib.resources
import tomllib
import zipfile
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from ntc_design.errors import InputError
from ntc_design.expr.symbolic import parse_expression, symbol
from ntc_design.model import Topology, paper
from ntc_design.numerics.linalg import Definiteness
from tests.conftest import EXAMPLES

A12_G1 = np.diag([1.0, 1.0, 2.0])

# The weights as printed in the paper's Section 5 (paper.tex), keyed (i, j) for A_ij: the
# edge j -> i. Typed from the text, not from ntc_design.model.paper.
PRINTED = {
    "G1": {
        (1, 2): A12_G1,
        (2, 1): -np.diag([1.0, 1, 0]),
        (6, 5): np.array([[7.0, 1, 1], [1, 6, 0], [1, 0, 5]]),
        (5, 2): np.array([[10.0, 1, 2], [1, 8, 1], [2, 1, 12]]),
        (7, 6): np.diag([3.1, 3.1, 3.2]),
        (2, 6): -np.diag([0.0, 0, 1]),
        (3, 6): -0.1 * A12_G1,
        (4, 3): A12_G1,
    },
    "G2": {
        (1, 2): -np.array([[5.0, 2, 1], [2, 4, 1], [1, 1, 3]]),
        (4, 7): -np.diag([0.0, 1, 0]),
        (6, 5): np.array([[6.0, 1, -1], [1, 8, 2], [-1, 2, 6]]),
        (6, 7): np.diag([4.0, 3, 3]),
        (7, 6): np.array([[5.0, 1, 0], [1, 6, -1], [0, -1, 5]]),
        (4, 3): -np.array([[2.0, 0, 1], [0, 0, 0], [1, 0, 3]]),
        (5, 1): np.array([[6.0, 1, -1], [1, 8, 2], [-1, 2, 6]]),  # A51 = A65
        (2, 6): -0.5 * np.eye(3),
        (3, 6): -0.5 * np.eye(3),
        (6, 2): -np.diag([0.0, 1, 0]),  # A62 = A47
    },
    "G3": {
        (3, 4): np.diag([1.0, 2, 0]),
        (3, 7): -np.array([[2.0, -1, 0], [-1, 2, 0], [0, 0, 1]]),
        (4, 3): np.array([[2.0, -1, 0], [-1, 3, 1], [0, 1, 4]]),
        (7, 5): np.diag([2.0, 3, 1]),
        (5, 2): np.array([[8.0, 2, 1], [2, 8, 1], [1, 1, 6]]),
        (2, 1): -np.array([[3.0, 1, -1], [1, 5, 2], [-1, 2, 5]]),
        (6, 3): -np.eye(3),
        (1, 5): -np.eye(3),
    },
}

# The class the paper writes beside each printed weight (≻, ⪰, ≺, ⪯).
PRINTED_CLASS = {
    "G1": {(1, 2): "PD", (2, 1): "NSD", (6, 5): "PD", (5, 2): "PD", (7, 6): "PD", (2, 6): "NSD"},
    "G2": {(1, 2): "ND", (4, 7): "NSD", (6, 5): "PD", (6, 7): "PD", (7, 6): "PD", (4, 3): "NSD"},
    "G3": {(3, 4): "PSD", (3, 7): "ND", (4, 3): "PD", (7, 5): "PD", (5, 2): "PD", (2, 1): "ND"},
}

BUILD = {"G1": paper.g1, "G2": paper.g2, "G3": paper.g3}


@pytest.mark.parametrize("name", ["G1", "G2", "G3"])
def test_topologies_have_the_printed_weights(name):
    top = BUILD[name]()
    assert isinstance(top, Topology)
    assert (top.n, top.dim, top.name) == (7, 3, name)
    assert top.labels == tuple(range(1, 8))
    got = {(top.labels[i], top.labels[j]): w for (i, j), w in top.weights.items()}
    assert set(got) == set(PRINTED[name])
    for key, w in PRINTED[name].items():
        np.testing.assert_array_equal(got[key], w, err_msg=f"{name} A{key}")


@pytest.mark.parametrize("name", ["G1", "G2", "G3"])
def test_weights_have_the_printed_classes(name):
    top = BUILD[name]()
    for (i, j), cls in PRINTED_CLASS[name].items():
        assert top.classes[(top.index(i), top.index(j))] is Definiteness(cls), (name, i, j)


def test_builders_return_fresh_objects():
    # each call builds anew: one caller's topology is not shared with another's
    assert paper.g1() is not paper.g1()
    assert paper.switching() is not paper.switching()


@pytest.mark.parametrize("name", ["G1", "G2", "G3"])
def test_stated_informed_agents_are_the_antagonised_ones(name):
    # Lemma 1 takes V_I = U: the agents with a negative in-edge
    top = BUILD[name]()
    assert sorted(top.labels[k] for k in top.antagonised) == paper.STATED[name]["informed"]


@pytest.mark.parametrize("name", ["G1", "G2", "G3"])
def test_stated_x0_is_one_plus_two_over_delta_times_theta(name):
    # x0 = (1 + 2/δ)·θ, printed to four decimals; exact rational arithmetic on the printed δ
    stated = paper.STATED[name]
    delta = Fraction(str(stated["delta"]))
    k1 = 1 + 2 / delta
    for x, th in zip(stated["x0"], paper.THETA, strict=True):
        exact = k1 * Fraction(th)
        assert abs(Fraction(str(x)) - exact) <= Fraction(1, 2 * 10**4), (name, x, float(exact))


def test_g1_delta_is_c_plus_the_margin():
    g = paper.STATED["G1"]
    assert Fraction(str(g["delta"])) - Fraction(str(g["C"])) == Fraction(1, 10)
    assert g["V1"] == g["informed"] == [2, 3]


def test_simulation_settings_are_the_papers():
    assert paper.THETA == [1.0, 2.0, -1.0]
    assert (paper.SIGMA, paper.F_SCALE, paper.DT, paper.PATHS) == (0.4, 0.3, 1e-3, 1000)
    assert paper.DWELL == 0.02
    assert paper.PATTERN == ("G2", "G2", "G1", "G3", "G3")


@pytest.mark.parametrize(
    "text, expected",
    [
        (paper.GAIN, "1/(1+t)"),
        (paper.GAIN_VANISHING, "1/(1+t)^2"),
        (paper.GAIN_ENERGY, "1/(1+t)^(1/3)"),
    ],
)
def test_gains_are_the_papers(text, expected):
    t = symbol("t")
    diff = parse_expression(text, "gain") - parse_expression(expected, "ref")
    assert sp.simplify(diff) == 0
    assert parse_expression(text, "gain").free_symbols == {t}


def test_gains_have_the_integrability_the_paper_names():
    # c = 1/(1+t): ∫c = ∞, ∫c² < ∞; (1+t)^-2: ∫c < ∞ (vanishing); (1+t)^-1/3: ∫c² = ∞
    t = symbol("t")

    def integral(text, power):
        return sp.integrate(parse_expression(text, "gain") ** power, (t, 0, sp.oo))

    assert integral(paper.GAIN, 1) == sp.oo and integral(paper.GAIN, 2) == 1
    assert integral(paper.GAIN_VANISHING, 1) == 1
    assert integral(paper.GAIN_ENERGY, 2) == sp.oo


def test_switching_follows_the_papers_pattern():
    sw = paper.switching()
    assert set(sw.modes) == {"G1", "G2", "G3"}
    assert sw.schedule == tuple((m, 0.02) for m in ("G2", "G2", "G1", "G3", "G3"))
    assert sw.period == pytest.approx(0.1, abs=1e-15)
    # G2 on [t_5l, t_5l+2), G1 on [t_5l+2, t_5l+3), G3 on [t_5l+3, t_5(l+1))
    for t, mode in [(0.01, "G2"), (0.03, "G2"), (0.05, "G1"), (0.07, "G3"), (0.09, "G3")]:
        for lap in (0, 3):
            assert sw.mode_at(t + 0.1 * lap) == mode, (t, lap)
    for name, build in BUILD.items():
        np.testing.assert_array_equal(sw.modes[name].laplacian(), build().laplacian())


# -- example_path ------------------------------------------------------------------------


def test_example_path_root_and_subfolder():
    root = paper.example_path()
    assert root.is_dir() and (root / "g1.yaml").is_file()
    sc = paper.example_path("scenarios")
    assert sc.is_dir() and sc.parent.resolve() == root.resolve()


def test_example_path_names_the_known_examples_when_missing():
    with pytest.raises(
        InputError, match=r"^example_path: no example 'nope\.yaml' \(there are "
    ) as exc:
        paper.example_path("nope.yaml")
    msg = str(exc.value)
    for f in sorted(EXAMPLES.glob("*.yaml")):
        assert f.name in msg
    assert "\n" not in msg


def test_example_path_refuses_a_sibling_that_shares_the_prefix(tmp_path, monkeypatch):
    # ../examples2/x is outside although its text starts like the folder's
    root = tmp_path / "examples"
    root.mkdir()
    (root / "g1.yaml").write_text("dim: 1\n")
    (tmp_path / "examples2").mkdir()
    (tmp_path / "examples2" / "x.yaml").write_text("dim: 1\n")
    monkeypatch.setattr(paper, "_examples_root", lambda: root)
    with pytest.raises(InputError, match="outside the bundled examples"):
        paper.example_path("../examples2/x.yaml")
    assert paper.example_path("g1.yaml") == (root / "g1.yaml").resolve()


def test_examples_root_prefers_the_installed_package_data(monkeypatch, tmp_path):
    # a wheel ships the examples in the package's folder, ntc_design/examples: found there,
    # through the regular package (not the namespace package ntc_design.examples, whose
    # MultiplexedPath's text is no path), before the checkout
    (tmp_path / "examples").mkdir()
    (tmp_path / "examples" / "g1.yaml").write_text("dim: 1\n")
    asked = []
    monkeypatch.setattr(importlib.resources, "files", lambda name: asked.append(name) or tmp_path)
    assert paper._examples_root() == tmp_path / "examples"
    assert asked == ["ntc_design"]
    assert paper.example_path("g1.yaml") == (tmp_path / "examples" / "g1.yaml").resolve()
    # package data without the examples in it: the checkout's folder
    (tmp_path / "examples" / "g1.yaml").unlink()
    assert paper._examples_root().resolve() == EXAMPLES.resolve()


def test_examples_of_a_zipped_package_are_copied_out_once(monkeypatch, tmp_path):
    # a package imported from a zip: its examples are no files; they are copied out
    archive = tmp_path / "pkg.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("ntc_design/examples/g1.yaml", "dim: 1\n")
        z.writestr("ntc_design/examples/scenarios/s.yaml", "name: s\n")
    monkeypatch.setattr(
        importlib.resources, "files", lambda name: zipfile.Path(archive, "ntc_design/")
    )
    monkeypatch.setattr(paper, "_EXTRACTED", [])
    root = paper._examples_root()
    assert (root / "g1.yaml").read_text() == "dim: 1\n"
    assert (root / "scenarios" / "s.yaml").read_text() == "name: s\n"
    assert paper._examples_root() == root  # once per process
    assert paper.example_files() == ["g1.yaml", "scenarios/s.yaml"]


def test_examples_root_falls_back_to_the_checkout(monkeypatch):
    def missing(_name):
        raise ModuleNotFoundError("ntc_design")

    monkeypatch.setattr(importlib.resources, "files", missing)
    assert paper._examples_root().resolve() == EXAMPLES.resolve()


def test_examples_root_refuses_when_nothing_is_installed(monkeypatch, tmp_path):
    def missing(_name):
        raise ModuleNotFoundError("ntc_design")

    monkeypatch.setattr(importlib.resources, "files", missing)
    # no examples beside the package either: the module file is placed in an empty folder
    monkeypatch.setattr(paper, "__file__", str(tmp_path / "pkg" / "paper.py"))
    with pytest.raises(InputError, match="^example_path: the bundled examples are not installed"):
        paper.example_path("g1.yaml")


def test_example_files_are_what_the_wheel_ships():
    # pyproject.toml's package data for ntc_design.examples is the same list
    data = tomllib.loads((EXAMPLES.parent / "pyproject.toml").read_text())
    shipped = data["tool"]["setuptools"]["package-data"]["ntc_design.examples"]
    assert tuple(shipped) == paper.EXAMPLE_FILES
    names = paper.example_files()
    assert "g1.yaml" in names and "scenarios/g1_fixed.yaml" in names
    assert not [n for n in names if n.startswith("figures/")]
    assert len(names) == 15


def test_copy_examples_into_a_new_folder(tmp_path):
    written = paper.copy_examples(tmp_path / "new" / "mine")
    names = paper.example_files()
    assert [p.relative_to(tmp_path / "new" / "mine").as_posix() for p in written] == names
    for name in names:
        assert (tmp_path / "new" / "mine" / name).read_bytes() == (EXAMPLES / name).read_bytes()
    (tmp_path / "empty").mkdir()
    assert len(paper.copy_examples(tmp_path / "empty")) == len(names)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda p: (p.mkdir(), (p / "x.txt").write_text("mine")), "the folder is not empty"),
        (lambda p: p.write_text("a file"), "exists and is not a folder"),
    ],
    ids=["non-empty folder", "a file"],
)
def test_copy_examples_refuses_what_it_would_overwrite(tmp_path, make, needle):
    dest = tmp_path / "dest"
    make(dest)
    before = sorted(tmp_path.rglob("*"))
    with pytest.raises(InputError, match=f"^{dest}: {needle}"):
        paper.copy_examples(dest)
    assert sorted(tmp_path.rglob("*")) == before
