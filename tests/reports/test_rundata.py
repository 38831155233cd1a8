"""Tests of :mod:`ntc_design.reports.rundata`."""

from tests.cli_helpers import assert_input_error


def test_report_missing_files_are_named(tmp_path, capsys, monkeypatch):
    assert_input_error(
        ["report", tmp_path / "nothing"],
        capsys,
        monkeypatch,
        "no such directory",
        "ntc simulate SCENARIO --out",
    )
    (tmp_path / "partial").mkdir()
    (tmp_path / "partial" / "summary.json").write_text("{}")
    assert_input_error(
        ["report", tmp_path / "partial"],
        capsys,
        monkeypatch,
        "missing ms_error.csv",
        "ntc simulate SCENARIO --out",
    )
    assert not (tmp_path / "partial" / "report.html").exists()
