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

    def strip(m):  # all but the name (a CSV or MATLAB file has none); each file's edge order
        top = {k: v for k, v in m["topology"].items() if k != "name"}
        top["edges"] = sorted(top["edges"], key=lambda e: (str(e["from"]), str(e["to"])))
        return {**m, "topology": top}

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
    (HEADER + "1,2,1,0,0,0,1,0,0,0\n", ["row 2: 10 fields, the header has 11", "short"]),
    # issue 41 item 9 (c): a short row whose missing field is the optional radius
    (
        HEADER[:-1] + ",uncertainty\n1,2,1,0,0,0,1,0,0,0,1,0.1\n2,3,1,0,0,0,1,0,0,0,1\n",
        ["row 3: 11 fields, the header has 12 (a short row)"],
    ),
    ("from,to,a11\n1,2,-1\n\n2,3\n", ["row 4: 2 fields, the header has 3"]),
    # issue 41 items 9 (d), 14 (b): numbers in ASCII numerals, no underscores
    ("from,to,a11\n1,2,\u0663\n", ["row 2", "a11 = '\u0663' is not a finite number"]),
    ("from,to,a11\n1,2,\uff13\n", ["row 2", "a11 = '\uff13' is not a finite number"]),
    ("from,to,a11\n1,2,0_5\n", ["row 2", "a11 = '0_5' is not a finite number"]),
    (
        "from,to,a11,uncertainty\n1,2,-1,\u0660.\u0661\n",
        ["row 2", "uncertainty = '\u0660.\u0661'", "[0, 1)"],
    ),
    ("from,to,a11,uncertainty\n1,2,-1,0_1\n", ["row 2", "uncertainty = '0_1'"]),
    ("from,to,a11,uncertainty\n1,2,-1,\uff10.\uff11\n", ["row 2", "uncertainty = "]),
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
    f.write_text(text, encoding="utf-8")
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
        (
            {
                "A": np.array([[0.0, -1.0], [0.0, 0.0]]),
                "dim": 1.0,
                "uncertainty": np.array([[0.0, np.nan], [0.0, 0.0]]),
            },
            ["uncertainty(1, 2)", "NaN is not a radius"],
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
        "nan-radius",
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


def _mat_variable(name: str, cls: int, shape, data: bytes, declared: int | None = None) -> bytes:
    """One compressed MATLAB 5 variable (miCOMPRESSED around miMATRIX) of class ``cls``
    and dimensions ``shape`` holding ``data`` as miUINT8; ``declared`` overrides the
    miMATRIX size (a lying header)."""
    import struct
    import zlib

    def element(kind: int, payload: bytes) -> bytes:
        return struct.pack("<II", kind, len(payload)) + payload + b"\0" * (-len(payload) % 8)

    body = (
        element(6, struct.pack("<II", cls, 0))  # array flags: the class, nzmax 0
        + element(5, struct.pack(f"<{len(shape)}i", *shape))
        + element(1, name.encode())
        + element(2, data)
    )
    size = len(body) if declared is None else declared
    packed = zlib.compress(struct.pack("<II", 14, size) + body)
    return struct.pack("<II", 15, len(packed)) + packed


def _mat_file(path, *variables: bytes):
    import struct

    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    path.write_bytes(head + b"".join(variables))
    return path


@pytest.mark.hostile
@pytest.mark.parametrize(
    "variables, memory, needles",
    [
        # the file: a double A declared 15000×15000 (1.8 GB loaded) from a tiny file
        (
            [_mat_variable("A", 6, (15000, 15000), b"\0" * 4096)],
            "6G",
            ["A: a 15000×15000 double array needs 1.7 GiB once loaded", "the 1.0 GiB allowed"],
        ),
        # the bound follows the memory: 7.6 MiB of doubles past a sixth of 30M
        (
            [_mat_variable("A", 6, (1000, 1000), b"\0" * 64)],
            "30M",
            ["A: a 1000×1000 double array needs 7.6 MiB", "the 5.0 MiB allowed"],
        ),
        # two variables read_mat loads: their sum counts (4 MiB + 4 MiB past 7 MiB)
        (
            [
                _mat_variable("A", 6, (724, 724), b"\0" * 64),
                _mat_variable("uncertainty", 6, (724, 724), b"\0" * 64),
            ],
            "42M",
            ["uncertainty: a 724×724 double array needs 4.0 MiB", "the 7.0 MiB allowed"],
        ),
        # a header that declares more data than its class and shape hold
        (
            [_mat_variable("A", 6, (2, 2), b"\0" * 64, declared=50_000)],
            "6G",
            ["A: declares 48.8 KiB of data for a 2×2 array of 32 B", "corrupt"],
        ),
        # data that inflates past what the header declares
        (
            [_mat_variable("A", 8, (10_000, 10_000), b"\0" * 200_000, declared=100)],
            "6G",
            ["A: inflates past the 100 B it declares", "corrupt"],
        ),
    ],
    ids=["bomb-1.8GB", "by-memory", "summed", "declares-more", "inflates-more"],
)
def test_hostile_mat_sizes_refused_before_loading(
    variables, memory, needles, tmp_path, capsys, monkeypatch
):
    import scipy.io

    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", memory)

    def no_load(*args, **kwargs):  # refused before loadmat allocates anything
        raise AssertionError("loadmat called")

    monkeypatch.setattr(scipy.io, "loadmat", no_load)
    f = _mat_file(tmp_path / "bomb.mat", *variables)
    assert f.stat().st_size < 10_000
    assert_input_error(["check", f], capsys, monkeypatch, str(f), *needles)


def test_mat_bound_counts_declared_sizes_not_a_fixed_cap(tmp_path, monkeypatch):
    from ntc_design.io.tablefiles import _mat_inflated_bytes

    # 1000×1000 doubles: 7.6 MiB loaded; a skipped variable (not one read_mat loads) is free
    f = _mat_file(
        tmp_path / "m.mat",
        _mat_variable("A", 6, (1000, 1000), b"\0" * 64),
        _mat_variable("other", 6, (10**5, 10**5), b"\0" * 64),
    )
    _mat_inflated_bytes(f, 8 * 2**20)  # fits: no error
    with pytest.raises(nd.InputError, match=r"needs 7\.6 MiB once loaded"):
        _mat_inflated_bytes(f, 7 * 2**20)


def test_csv_blank_lines_and_empty_radii_are_not_short_rows(tmp_path):
    f = tmp_path / "ok.csv"
    f.write_text("from,to,a11,uncertainty\n1,2,-0.5,\n\n2,3,0.5,0.125\n", encoding="utf-8")
    top = nd.load(f)
    assert top.labels == (1, 2, 3) and top.uncertainty == {(2, 1): 0.125}


@pytest.mark.hostile
def test_a_mat_inflating_past_the_process_limit_is_refused(tmp_path, capsys, monkeypatch):
    # 2.3 GB declared by a small file: the machine's 64 GiB would hold it, a 4 GiB ulimit -v
    # (RLIMIT_AS) would not: the cap is a sixth of what the process may still map
    import resource

    import scipy.io

    from ntc_design.io.tablefiles import read_mat
    from ntc_design.numerics import memory

    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", "64G")
    f = _mat_file(tmp_path / "big.mat", _mat_variable("A", 6, (17_000, 17_000), b"\0" * 4096))
    assert f.stat().st_size < 10_000

    def loaded(*args, **kwargs):
        raise RuntimeError("loadmat reached")

    monkeypatch.setattr(scipy.io, "loadmat", loaded)
    with pytest.raises(nd.InputError, match=r"\(RuntimeError\)$"):  # 2.2 GiB < 64 GiB / 6: read
        read_mat(f)
    soft = int(memory._address_space_used() + 4 * 2**30)
    monkeypatch.setattr(resource, "getrlimit", lambda which: (soft, resource.RLIM_INFINITY))
    line = assert_input_error(
        ["check", f], capsys, monkeypatch, "A: a 17000×17000 double array needs 2.2 GiB",
        "ulimit -v",
    )  # fmt: skip
    import re

    allowed = float(re.search(r"more than the ([0-9.]+) MiB allowed", line).group(1))
    assert (
        600 < allowed <= round(4 * 1024 / 6, 1)
    )  # a sixth of the 4 GiB left, less what was mapped since


@pytest.mark.hostile
@pytest.mark.parametrize("value, shown", [("inf", "inf"), ("-inf", "-inf"), ("nan", "nan")])
def test_a_csv_weight_that_is_not_finite_is_shown_as_written(
    tmp_path, capsys, monkeypatch, value, shown
):
    p = tmp_path / "w.csv"
    p.write_text(f"from,to,a11\n1,2,{value}\n2,1,-1\n", encoding="utf-8")
    line = assert_input_error(["check", p], capsys, monkeypatch, f"a11 = {shown} is not a finite")
    assert "np." not in line and "float64" not in line


def test_csv_carries_the_losses_beside_the_radii(tmp_path):
    (tmp_path / "t.csv").write_text("from,to,a11,loss\n2,1,-1,0.2\n3,2,2,\n")
    assert nd.load(tmp_path / "t.csv").loss == {(1, 0): 0.2}
    (tmp_path / "u.csv").write_text("from,to,a11,uncertainty,loss\n2,1,-1,0.02,\n3,2,2,,0.4\n")
    top = nd.load(tmp_path / "u.csv")
    assert top.uncertainty == {(1, 0): 0.02} and top.loss == {
        (0, 2): 0.4
    }  # labels by first appearance: 2, 1, 3
    (tmp_path / "v.csv").write_text("from,to,a11,loss,uncertainty\n2,1,-1,0.1,0.03\n")
    top = nd.load(tmp_path / "v.csv")
    assert top.uncertainty == {(1, 0): 0.03} and top.loss == {(1, 0): 0.1}


@pytest.mark.hostile
@pytest.mark.parametrize("bad", ["1", "-0.1", "nan", "often"])
def test_a_bad_csv_loss_names_the_row(tmp_path, bad):
    (tmp_path / "t.csv").write_text(f"from,to,a11,loss\n2,1,-1,{bad}\n")
    with pytest.raises(nd.InputError, match=r"t\.csv: row 2: loss = .*a loss probability"):
        nd.load(tmp_path / "t.csv")
