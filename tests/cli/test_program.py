"""Tests of :mod:`ntc_design.cli.program`: every error one line, with --json too."""

import json

import pytest

from tests.cli_helpers import run_cli


@pytest.mark.hostile
@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
@pytest.mark.parametrize(
    "exc, code, message",
    [
        (
            ValueError("too many values to unpack (expected 1)"),
            1,
            "internal error (ValueError: too many values to unpack (expected 1)); re-run with "
            "NTC_DEBUG=1 for the traceback",
        ),
        (
            MemoryError(),
            2,
            "out of memory: the input asks for more memory than the machine has",
        ),
        (PermissionError(13, "Permission denied", "x.json"), 2, "'x.json': Permission denied"),
        (KeyboardInterrupt(), 130, "interrupted"),
    ],
    ids=["internal", "memory", "os", "interrupt"],
)
def test_every_error_exit_is_one_line_and_json_under_json(
    exc, code, message, as_json, capsys, monkeypatch, tmp_path
):
    import ntc_design.certify

    def fails(*_args, **_kwargs):
        raise exc

    monkeypatch.setattr(ntc_design.certify, "verify_file", fails)
    monkeypatch.delenv("NTC_DEBUG", raising=False)
    (tmp_path / "c.json").write_text("{}")  # a missing one is refused before verify_file
    args = ["verify", tmp_path / "c.json", *(["--json"] if as_json else [])]
    got, out, err = run_cli(args, capsys, monkeypatch)
    assert (got, err) == (code, f"error: {message}\n")
    if as_json:  # a script reading stdout gets JSON for every error exit
        assert json.loads(out) == {"ok": False, "error": message, "exit_code": code}
    else:
        assert out == ""
