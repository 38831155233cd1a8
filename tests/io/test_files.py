"""Tests of :mod:`ntc_design.io.files`."""

import json
import os
import stat

import pytest

import ntc_design as nd
from ntc_design.certify.format import topology_hash
from ntc_design.errors import InputError
from ntc_design.io import files
from ntc_design.model.generate import write_topology
from ntc_design.model.load import load
from tests.cli_helpers import assert_input_error, run_cli
from tests.support.switching_scale import _refresh


def test_a_misspelt_key_is_named_with_its_close_match(tmp_path, capsys, monkeypatch):
    f = tmp_path / "t.yaml"
    f.write_text("dim: 1\nagents: 2\nedges:\n  - {from: 1, to: 2, wieght: 1}\n")
    line = assert_input_error(["check", f], capsys, monkeypatch, "edges[0]", "'wieght'")
    assert "did you mean 'weight'" in line and "missing" not in line
    f.write_text("dim: 1\nagent: 2\nedges: []\n")
    assert_input_error(["check", f], capsys, monkeypatch, "did you mean 'agents'")


def test_labels_from_list_and_json_file(tmp_path):
    doc = {
        "dim": 1,
        "agents": ["a", "b", "c"],
        "edges": [
            {"from": "a", "to": "b", "weight": [[-2]]},
            {"from": "b", "to": "c", "weight": 1},
        ],
    }
    p = tmp_path / "t.json"
    p.write_text(json.dumps(doc))
    top = nd.load(p)
    assert top.labels == ("a", "b", "c")
    des = nd.design(top, [3.0]).to_dict()
    assert des["informed"] == ["b"] and des["V1"] == ["b"]
    assert des["assumption_holds"] is False  # agent a can be reached by no path
    assert [v["agent"] for v in des["violations"]] == ["a"]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "name, content, needle",
    [
        ("zero.yaml", "dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[0]], uncertainty: 0.1}\n", "edge 2->1: uncertainty on a zero weight"),
        ("big.yaml", "dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], uncertainty: 1.5}\n", "edge 2->1: uncertainty: the radius must be"),
        ("text.yaml", "dim: 1\nagents: [1, 2]\nuncertainty: lots\nedges:\n  - {from: 2, to: 1, weight: [[1]]}\n", "uncertainty: expected a number"),
        ("neg.csv", "from,to,a11,uncertainty\n2,1,-1,-0.1\n", "row 2: uncertainty"),
        ("nan.csv", "from,to,a11,uncertainty\n2,1,-1,nan\n", "row 2: uncertainty"),
        # a 400-digit integer: float() of it raised OverflowError, an internal error
        ("huge.yaml", "dim: 1\nagents: [1, 2]\nuncertainty: " + "9" * 400 + "\nedges:\n  - {from: 2, to: 1, weight: [[1]]}\n", "uncertainty: an integer of 400 digits is beyond the float range"),
        ("huge_edge.yaml", "dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], uncertainty: -" + "9" * 400 + "}\n", "edge 2->1: uncertainty: an integer of 400 digits"),
    ],
)  # fmt: skip
def test_a_bad_uncertainty_is_one_line_exit_2(tmp_path, name, content, needle, capsys, monkeypatch):
    p = tmp_path / name
    p.write_text(content)
    assert_input_error(["check", p], capsys, monkeypatch, needle, str(p))


def test_npz_modes_in_a_switching_file(tmp_path, big_switching, capsys, monkeypatch):
    for k, t in big_switching.modes.items():
        write_topology(t, tmp_path / f"{k}.npz")
    f = tmp_path / "big_switching.yaml"
    f.write_text(
        "modes: {A: A.npz, B: B.npz}\nschedule: [{mode: A, duration: 0.1}, {mode: B, duration: 0.2}]\n"
    )
    got = load(f)
    for k, t in big_switching.modes.items():
        assert topology_hash(got.modes[k]) == topology_hash(t)
    out = tmp_path / "c.json"
    code, text, err = run_cli(
        ["certify", f, "--theta", "1,-2,0.5", "--out", out, "--gain", "1/(1+t)"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    assert (
        "proven lower bound ℓ: λ_min > ℓ" in text and "Theorem 3 (mean square): guaranteed" in text
    )
    mode = stat.S_IMODE(os.stat(out).st_mode)
    umask = os.umask(0)
    os.umask(umask)
    assert mode == 0o666 & ~umask  # a file to share, not a private temporary file
    code, text, err = run_cli(
        ["verify", out, "--topology", f, "--theta", "1,-2,0.5"], capsys, monkeypatch
    )
    assert code == 0, err
    assert "kind: switching-scale" in text and "VALID" in text
    doc = json.loads(out.read_text())
    doc["proofs"]["A"]["lower"] *= 1.5
    out.write_text(json.dumps(_refresh(doc)))
    code, _, err = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 1 and "L_B(A) + L_B(A)ᵀ ≻ 0" in err
    (tmp_path / "B.npz").write_bytes(b"not a zip")
    assert_input_error(["check", f], capsys, monkeypatch, "big_switching.yaml", "modes.B", "B.npz")


def test_a_missing_npz_mode_says_so(tmp_path, capsys, monkeypatch):
    f = tmp_path / "big_switching.yaml"
    f.write_text("modes: {A: nope.npz}\nschedule: [{mode: A, duration: 1}]\n")
    assert_input_error(["check", f], capsys, monkeypatch, "modes.A", "nope.npz: no such file")


@pytest.mark.parametrize(
    "rows,expect",
    [
        ([[1, 2], [2, 5.5]], [[1.0, 2.0], [2.0, 5.5]]),
        ([[2**53 + 1, 0], [0, 1]], [[float(2**53 + 1), 0.0], [0.0, 1.0]]),
        ([[True, 0], [0, 1]], "expected a number, got True"),
        ([[10**400, 0], [0, 1]], "is too large"),
        ([[float("inf"), 0], [0, 1]], "numbers must be finite"),
        ([[1, "t"], [0, 1]], "expected a number, got 't'"),
    ],
)
def test_weight_rows_read_in_c_give_the_same_values_and_errors(rows, expect):
    """The rows of numbers are converted at once; anything else gets the entry's message."""
    if isinstance(expect, str):
        with pytest.raises(InputError, match=expect.replace("(", r"\(")):
            files.parse_weight(rows, 2, "f.yaml", "edge 1->2")
    else:
        w = files.parse_weight(rows, 2, "f.yaml", "edge 1->2")
        assert w.dtype == float and w.tolist() == expect


@pytest.mark.parametrize(
    "weight,expect",
    [
        ([[1, 2.5], [None, True]], False),
        ([[1, "t"], [0, 1]], True),
        ([[1, [2, "t"]]], True),
        ([[1, {"diag": [1]}]], False),
        ({"matrix": "A", "scale": "2*t"}, True),
        ([], False),
    ],
)
def test_has_text(weight, expect):
    assert files.has_text(weight) is expect


@pytest.mark.parametrize(
    "edge,message",
    [
        ({"from": 1, "to": 2}, "f.yaml: edges[0]: missing weight"),
        ({"to": 2}, "f.yaml: edges[0]: missing from, weight"),
        (
            {"from": 1, "to": 2, "wieght": 1},
            "f.yaml: edges[0]: unknown field 'wieght'; did you mean 'weight'?",
        ),
        ({"from": 1, "to": 2, "weight": 1, "x": 0}, "f.yaml: edges[0]: unknown field 'x'"),
    ],
)
def test_edge_field_messages(edge, message):
    doc = {"dim": 1, "agents": 2, "edges": [edge]}
    with pytest.raises(InputError) as err:
        files.parse_topology(doc, "f.yaml")
    assert str(err.value) == message


@pytest.mark.parametrize(
    "weights,message",
    [
        ([[[1, 0], [0, 1]], [[2, 0.5], [0.5, 2]]], None),
        ([[[1, 0], [0, 1]], [[True, 0], [0, 1]]], "f.yaml: edge 2->3: expected a number, got True"),
        ([[[1, 0], [0, 1]], [[1, 0], [0]]], "f.yaml: edge 2->3: expected a 2x2 matrix, got 2x1/2"),
        ([[[1, 0], [0, 1]], [[10**400, 0], [0, 1]]], "is too large"),
        ([[[1, 0], [0, 1]], 2.5], None),
    ],
)
def test_weights_read_at_once_or_one_by_one(weights, message):
    """All-rows weights are converted in one call; the same arrays and messages as one by one."""
    doc = {"dim": 2, "agents": 3, "edges": [{"from": 1, "to": 2, "weight": weights[0]}]}
    doc["edges"].append({"from": 2, "to": 3, "weight": weights[1]})
    if message is not None:
        with pytest.raises(InputError, match=message.replace("(", r"\(")):
            files.parse_topology(doc, "f.yaml")
        return
    got = [e.weight for e in files.parse_topology(doc, "f.yaml").edges]
    one = [files.parse_weight(w, 2, "f.yaml", "w") for w in weights]
    assert all(
        a.dtype == b.dtype and a.shape == b.shape and (a == b).all()
        for a, b in zip(got, one, strict=True)
    )
    assert got[0].base is None  # each weight owns its numbers


def test_an_edge_carries_its_loss(tmp_path):
    p = tmp_path / "t.yaml"
    p.write_text(
        "dim: 1\nagents: [1, 2, 3]\nedges:\n  - {from: 2, to: 1, weight: [[-1]], loss: 0.25}\n"
        "  - {from: 3, to: 2, weight: [[2]]}\n"
    )
    top = load(p)
    assert top.loss == {(0, 1): 0.25}
    assert "loss" not in json.dumps(top.to_dict())


@pytest.mark.hostile
@pytest.mark.parametrize(
    "content, needle",
    [
        ("dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], loss: 1.0}\n", "edge 2->1: loss: a loss probability must be finite and in [0, 1)"),
        ("dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], loss: .nan}\n", "edge 2->1: loss: a loss probability"),
        ("dim: 1\nagents: [1, 2]\nedges:\n  - {from: 2, to: 1, weight: [[1]], loss: high}\n", "edge 2->1: loss: expected a loss probability"),
    ],
)  # fmt: skip
def test_a_bad_edge_loss_is_one_line_exit_2(tmp_path, content, needle, capsys, monkeypatch):
    p = tmp_path / "t.yaml"
    p.write_text(content)
    assert_input_error(["check", p], capsys, monkeypatch, needle, str(p))
