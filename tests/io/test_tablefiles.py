"""Tests of :mod:`ntc_design.io.tablefiles`."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.io import savemat

import ntc_design as nd
from ntc_design.certify import certify, topology_hash
from ntc_design.io.tablefiles import write_csv_edges
from tests.cli_helpers import assert_input_error
from tests.conftest import EXAMPLES


def test_csv_and_mat_carry_the_radii(tmp_path):
    from scipy.io import savemat

    (tmp_path / "t.csv").write_text("from,to,a11,uncertainty\n2,1,-1,0.02\n3,2,2,\n")
    assert nd.load(tmp_path / "t.csv").uncertainty == {(1, 0): 0.02}
    a = np.zeros((3, 3))
    a[0, 1], a[1, 2] = -1.0, 2.0
    u = np.zeros((3, 3))
    u[0, 1] = 0.03
    savemat(tmp_path / "m.mat", {"A": a, "dim": 1, "uncertainty": u})
    assert nd.load(tmp_path / "m.mat").uncertainty == {(0, 1): 0.03}


@pytest.mark.hostile
def test_mat_uncertainty_on_a_missing_edge_is_refused(tmp_path):
    from scipy.io import savemat

    a = np.zeros((3, 3))
    a[0, 1] = -1.0
    u = np.zeros((3, 3))
    u[2, 0] = 0.1
    savemat(tmp_path / "m.mat", {"A": a, "dim": 1, "uncertainty": u})
    with pytest.raises(nd.InputError, match=r"uncertainty\(3, 1\): uncertainty on a missing edge"):
        nd.load(tmp_path / "m.mat")


HEADER = "from,to,a11,a12,a13,a21,a22,a23,a31,a32,a33\n"


@pytest.mark.parametrize("name", ["g1.csv", "g1.mat"])
def test_g1_as_csv_or_mat_is_the_yaml_network(name, g1, theta):
    top = nd.load(EXAMPLES / name)
    assert topology_hash(top) == topology_hash(g1)  # same labels, order, edges, weights
    a, b = nd.design(top, theta, 0.1), nd.design(g1, theta, 0.1)
    assert a.delta == b.delta and np.array_equal(a.x0, b.x0)
    assert np.array_equal(a.grounded_laplacian(), b.grounded_laplacian())
    ca, cb = certify(top, theta, gain="1/(1+t)"), certify(g1, theta, gain="1/(1+t)")
    (sa,) = ca.certificate["subject"]["modes"].values()
    (sb,) = cb.certificate["subject"]["modes"].values()

    def strip(m):  # all but the name: a CSV or MATLAB file has none
        return {**m, "topology": {k: v for k, v in m["topology"].items() if k != "name"}}

    assert strip(sa) == strip(sb)
    assert [c["kind"] for c in ca.certificate["claims"]] == [
        c["kind"] for c in cb.certificate["claims"]
    ]
    assert ca.certificate["results"]["eig_bound"] == cb.certificate["results"]["eig_bound"]
    assert ca.verification.valid and [t.guaranteed for t in ca.theorems] == [True, True]


def test_csv_round_trip_of_a_random_network(tmp_path):
    from ntc_design.model.generate import random_network

    top = random_network(200, 2, seed=4)
    ea = top.edge_arrays
    write_csv_edges(tmp_path / "r.csv", top.labels, top.dim, ea.rows, ea.cols, ea.w)
    back = nd.load(tmp_path / "r.csv")
    assert sorted(back.labels) == sorted(top.labels)
    for (i, j), w in top.weights.items():  # every weight back exactly, by label
        k = (back.index(top.labels[i]), back.index(top.labels[j]))
        assert np.array_equal(back.weights[k], w)
    assert len(back.weights) == len(top.weights)


CSV_BAD = [
    (HEADER + "1,2,1,0,0,0,1,0,0,0\n", ["row 2", "a33", "empty"]),  # a short row
    (HEADER + "1,2,1,0,0,0,1,0,0,0,1,9\n", ["row 2", "12 fields", "11"]),  # a long one
    (HEADER + "1,2,1,0,0,0,1,0,0,0,1\n2,1,nan,0,0,0,1,0,0,0,1\n", ["row 3", "a11", "finite"]),
    (HEADER + "1,2,1,0,0,0,x,0,0,0,1\n", ["row 2", "a22", "'x'"]),
    (HEADER + "1,2,1,0,0,0,1,0,0,0,1\n1,2,1,0,0,0,1,0,0,0,1\n", ["row 3", "1->2", "twice"]),
    ("source,target,w\n1,2,1\n", ["row 1", "from, to"]),
    ("from,to,a11,a12\n1,2,1,0\n", ["row 1", "d²"]),
    (HEADER + ",2,1,0,0,0,1,0,0,0,1\n", ["row 2", "'from' is empty"]),
    (HEADER + "1,2,1e999,0,0,0,1,0,0,0,1\n", ["row 2", "a11", "finite"]),
]


@pytest.mark.hostile
@pytest.mark.parametrize("text, needles", CSV_BAD)
def test_hostile_csv_is_one_line(text, needles, tmp_path, capsys, monkeypatch):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    assert_input_error(["check", f], capsys, monkeypatch, str(f), *needles)


def _mat(path, **variables):
    savemat(path, variables)
    return path


@pytest.mark.hostile
@pytest.mark.parametrize(
    "variables, needles",
    [
        ({"dim": 3.0}, ["A: missing"]),
        ({"A": np.eye(6)}, ["dim: missing"]),
        ({"A": np.zeros((6, 6)), "dim": 4.0}, ["A:", "square", "dim = 4"]),
        ({"A": np.full((6, 6), np.nan), "dim": 3.0}, ["A(1, 1)", "finite"]),
        ({"A": np.eye(6), "dim": 3.0}, ["diagonal block (1, 1)", "self-loop"]),
        ({"A": {"x": 1.0}, "dim": 3.0}, ["A:", "struct"]),  # a struct where a matrix belongs
        ({"A": np.array([["a", "b"]], dtype=object), "dim": 1.0}, ["A:", "numeric"]),
        ({"A": np.zeros((6, 6)), "dim": 2.5}, ["dim", "integer"]),
        (
            {"A": sp.csr_matrix((2 * 10**6 + 2, 2 * 10**6 + 2)), "dim": 1.0},
            ["A:", "agents", "at most"],
        ),
        (
            {"A": np.zeros((4, 4)), "dim": 2.0, "labels": np.array(["a", "a"], dtype=object)},
            ["labels", "unique"],
        ),
        (
            {"A": np.zeros((4, 4)), "dim": 2.0, "labels": np.array([1.0, 2.0])},
            ["labels", "strings"],
        ),
    ],
    ids=[
        "no-A",
        "no-dim",
        "size",
        "nan",
        "self-loop",
        "struct",
        "objects",
        "dim",
        "huge",
        "dup-labels",
        "num-labels",
    ],
)
def test_hostile_mat_is_one_line(variables, needles, tmp_path, capsys, monkeypatch):
    f = _mat(tmp_path / "bad.mat", **variables)
    assert_input_error(["check", f], capsys, monkeypatch, str(f), *needles)


@pytest.mark.hostile
def test_not_a_mat_file_is_one_line(tmp_path, capsys, monkeypatch):
    f = tmp_path / "x.mat"
    f.write_bytes(b"MATLAB 5.0 MAT-file" + b"\x00" * 200)
    assert_input_error(["check", f], capsys, monkeypatch, str(f), "not a readable MATLAB file")
