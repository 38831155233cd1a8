"""Tests of :mod:`ntc_design.io.edgelist`."""

import numpy as np
import pytest

from ntc_design.model.generate import random_network
from tests.cli_helpers import assert_input_error


@pytest.mark.hostile
def test_bad_npz_gives_one_line(tmp_path, capsys, monkeypatch):
    top = random_network(10, 2, seed=1)
    ea = top.edge_arrays
    good = {
        "format": np.array("ntc-design/edge-list"),
        "dim": np.array(2),
        "labels": np.arange(1, 11),
        "from": ea.cols,
        "to": ea.rows,
        "weights": ea.w,
    }
    cases = [
        ({"to": ea.rows + 100}, "to[0]"),
        ({"weights": ea.w[:, :1]}, "weights"),
        ({"from": ea.cols.astype(float)}, "from"),
        ({"extra": np.zeros(2)}, "unknown array"),
        ({"labels": np.array([1] * 10)}, "unique"),
        ({"format": np.array("x")}, "format"),
    ]
    for k, (change, needle) in enumerate(cases):
        p = tmp_path / f"bad{k}.npz"
        np.savez(p, **(good | change))
        assert_input_error(["check", p], capsys, monkeypatch, str(p), needle)
    dup = tmp_path / "dup.npz"
    np.savez(
        dup,
        **(
            good
            | {
                "from": np.r_[ea.cols, ea.cols[:1]],
                "to": np.r_[ea.rows, ea.rows[:1]],
                "weights": np.r_[ea.w, ea.w[:1]],
            }
        ),
    )
    assert_input_error(["check", dup], capsys, monkeypatch, "duplicated edge")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"PK\x03\x04 not really")
    assert_input_error(["check", junk], capsys, monkeypatch, "not a readable")
    asym = tmp_path / "asym.npz"
    w = ea.w.copy()
    w[3, 0, 1] += 1.0
    np.savez(asym, **(good | {"weights": w}))
    assert_input_error(["check", asym], capsys, monkeypatch, "not symmetric")


NFC_E, NFD_E = "\u00e9", "e\u0301"  # "é" as one code point and as e + combining accent


def _label_files(tmp_path, first: str, second: str):
    """The same two-agent network with labels ``first`` and ``second`` (edge first ->
    second) in each format that carries labels: YAML, CSV, .npz and .mat."""
    import json

    from scipy.io import savemat

    from ntc_design.io.edgelist import write_npz

    yml = tmp_path / "net.yaml"  # JSON is YAML: the labels exactly as written
    yml.write_text(
        json.dumps(
            {
                "dim": 1,
                "agents": [first, second],
                "edges": [{"from": first, "to": second, "weight": [[-1]]}],
            }
        ),
        encoding="utf-8",
    )
    csv = tmp_path / "net.csv"
    csv.write_text(f"from,to,a11\n{first},x,-1\nx,{second},1\n", encoding="utf-8")
    npz = tmp_path / "net.npz"
    write_npz(npz, [first, second], 1, np.array([1]), np.array([0]), -np.ones((1, 1, 1)))
    mat = tmp_path / "net.mat"
    labels = np.array([first, second], dtype=object)
    savemat(mat, {"A": np.array([[0.0, 0], [-1, 0]]), "dim": 1.0, "labels": labels})
    return {"yaml": yml, "csv": csv, "npz": npz, "mat": mat}


@pytest.mark.hostile
@pytest.mark.parametrize(
    "fmt, first, second, needles",
    [
        (fmt, NFC_E, NFD_E, ["U+00E9", "U+0065 U+0301", "differ only by Unicode form"])
        for fmt in ("yaml", "csv", "npz", "mat")
    ]
    + [
        (fmt, "a", "a ", ["'a'", "'a '", "differ only by surrounding spaces"])
        for fmt in ("yaml", "npz", "mat")  # CSV fields are stripped: "a " is the agent a
    ]
    + [
        (fmt, "b", " a", ["label ' a' has surrounding spaces", "write it as 'a'"])
        for fmt in ("yaml", "npz", "mat")
    ],
    ids=lambda v: v if isinstance(v, str) and v.isascii() and v.strip() == v else None,
)
def test_look_alike_labels_are_refused(fmt, first, second, needles, tmp_path, capsys, monkeypatch):
    f = _label_files(tmp_path, first, second)[fmt]
    assert_input_error(["check", f], capsys, monkeypatch, str(f), *needles)


@pytest.mark.hostile
def test_a_lone_surrogate_label_is_refused(tmp_path, capsys, monkeypatch):
    # JSON's "\ud800" reads as a lone surrogate: no character, it reached ntc export's C
    # emitter as an internal error (UnicodeEncodeError, exit 1)
    import json

    f = tmp_path / "net.yaml"
    net = {
        "dim": 1,
        "agents": ["\ud800a", "b"],
        "edges": [{"from": "b", "to": "\ud800a", "weight": -1}],
    }
    f.write_text(json.dumps(net))  # ASCII: the surrogate as the escape \ud800
    assert_input_error(["check", f], capsys, monkeypatch, str(f), "lone surrogate")


@pytest.mark.parametrize("fmt", ["yaml", "csv", "npz", "mat"])
def test_labels_are_kept_in_nfc(fmt, tmp_path):
    import ntc_design as nd

    top = nd.load(_label_files(tmp_path, NFD_E, "z")[fmt])
    assert NFC_E in top.labels and NFD_E not in top.labels  # one agent, spelled in NFC


def test_yaml_edges_find_an_nfc_label_written_in_nfd(tmp_path):
    import ntc_design as nd

    f = tmp_path / "net.yaml"
    f.write_text(
        f'{{"dim": 1, "agents": ["{NFC_E}", "z"], '
        f'"edges": [{{"from": "{NFD_E}", "to": "z", "weight": [[-1]]}}]}}',
        encoding="utf-8",
    )
    top = nd.load(f)
    assert top.labels == (NFC_E, "z") and len(top.edges) == 1
