"""Run the ``ntc`` CLI in-process and capture its exit code and output."""

import re
import sys

import pytest

from ntc_design.cli import main


def run_cli(args, capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["ntc", *map(str, args)])
    code = 0
    try:
        main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def assert_input_error(args, capsys, monkeypatch, *needles):
    code, out, err = run_cli(args, capsys, monkeypatch)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, (code, out, err)
    assert len(lines) == 1, err
    assert "Traceback" not in err
    if "--json" in map(str, args):  # the same error as JSON on stdout, for scripts
        import json

        assert json.loads(out) == {"ok": False, "error": lines[0][7:], "exit_code": 2}
    else:
        assert out == ""
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


__all__ = ["assert_input_error", "pytest", "run_cli"]


# a slow machine makes a command print its heartbeat (reports.terminal.Progress) on stderr
_PROGRESS = re.compile(r"^ntc \w+: \[\d+ s\] ")


def without_progress(err: str) -> str:
    """stderr without the heartbeat lines a run prints every 5 s (how many depends on the
    machine's speed, not on the command's outcome)."""
    return "\n".join(ln for ln in err.splitlines() if not _PROGRESS.match(ln))
