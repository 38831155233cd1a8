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
