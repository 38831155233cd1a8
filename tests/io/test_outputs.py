"""Tests of :mod:`ntc_design.io.outputs`."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.io.outputs import atomic_path, output_folder, write_atomic
from ntc_design.model.paper import THETA
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import write_outputs

# ------------------------------------------------------------------- atomic outputs


def test_write_atomic_replaces_whole_file(tmp_path):
    p = tmp_path / "f.txt"
    write_atomic(p, "old")
    write_atomic(p, "new")
    assert p.read_text() == "new" and os.listdir(tmp_path) == ["f.txt"]
    with pytest.raises(InputError, match=r"^out: .* is a folder"):
        write_atomic(tmp_path, "x")


@pytest.mark.hostile
def test_atomic_writer_removes_its_temporary_file(tmp_path, monkeypatch):
    """The rename fails (a folder took the target's name after the check), the writer
    raises, Ctrl-C: each leaves only what was there, never a temporary file."""
    import ntc_design.io.outputs as outputs

    target = tmp_path / "report.html"
    target.mkdir()
    monkeypatch.setattr(outputs, "check_output_file", lambda p, option="out": Path(p))
    with pytest.raises(InputError, match=r"^report: cannot write .*report.html"):
        write_atomic(target, "x", option="report")
    assert os.listdir(tmp_path) == ["report.html"] and os.listdir(target) == []
    monkeypatch.undo()
    for exc in (RuntimeError, KeyboardInterrupt):
        with pytest.raises(exc), atomic_path(tmp_path / "a.npz") as tmp:
            np.savez_compressed(tmp, x=np.ones(3))
            raise exc
    assert os.listdir(tmp_path) == ["report.html"]
    with atomic_path(tmp_path / "a.npz") as tmp:  # NumPy adds no second .npz to the name
        np.savez_compressed(tmp, x=np.ones(3))
    assert sorted(os.listdir(tmp_path)) == ["a.npz", "report.html"]
    assert np.load(tmp_path / "a.npz")["x"].tolist() == [1.0, 1.0, 1.0]


def test_output_folder_is_all_or_nothing(tmp_path):
    target = tmp_path / "run"
    with output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("1")
        (tmp / "b.txt").write_text("1")
    with pytest.raises(KeyboardInterrupt), output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("2")
        raise KeyboardInterrupt
    assert (target / "a.txt").read_text() == "1" and (target / "b.txt").read_text() == "1"
    assert os.listdir(tmp_path) == ["run"]  # no temporary folder left
    with output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("3")
    assert os.listdir(target) == ["a.txt"] and os.listdir(tmp_path) == ["run"]


@pytest.mark.hostile
def test_output_folder_refuses_a_folder_with_other_files(tmp_path):
    (tmp_path / "precious.txt").write_text("keep")
    with pytest.raises(InputError, match=r"^out: .* holds other files \('precious.txt'"):
        with output_folder(tmp_path, ["summary.json"]):
            pass
    assert (tmp_path / "precious.txt").read_text() == "keep"


def test_permission_error_while_writing_is_one_line(g1, tmp_path, monkeypatch):
    res = simulate(g1, THETA, T=0.1, paths=4, save_every=0.05, workers=1)
    import ntc_design.io.outputs as outputs

    def denied(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(outputs.tempfile, "mkdtemp", denied)
    with pytest.raises(InputError, match=r"^out: cannot write .* \(Permission denied\)$"):
        write_outputs(res, tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_json_text_is_indented_json_with_long_values_on_one_line(monkeypatch):
    """summary.json at 10⁵ agents: long values go through json's C encoder on one line;
    short documents are byte for byte json.dumps(indent=1)."""

    from ntc_design.io import outputs

    small = {"a": [1, 2.5], "b": {"c": None, "d": []}, "e": {}, "f": "ü", "g": [{"x": 1}]}
    assert outputs.json_text(small) == json.dumps(small, indent=1, ensure_ascii=False) + "\n"
    assert outputs.json_text({}) == "{}\n"
    monkeypatch.setattr(outputs, "JSON_INDENT_MAX_CHARS", 12)
    text = outputs.json_text(small)
    assert json.loads(text) == small
    lines = text.splitlines()
    assert ' "b": {"c": null, "d": []},' in lines and ' "a": [' in lines  # 22 chars vs 8
