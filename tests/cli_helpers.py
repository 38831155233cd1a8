"""Run the ``ntc`` CLI in-process and capture its exit code and output."""

import re
import sys

import pytest
import typer.main

from ntc_design.cli import main

_BUILT: dict[int, tuple] = {}  # id(Typer app) -> (app, its click command)
_build = typer.main.get_command


def _built_command(typer_instance):
    """typer's click command for the app, built once per process: typer rebuilds it from the
    functions' signatures on every call (~0.1 s, 90 % of a refused command's time), and the
    result depends only on the registered commands, which no test changes."""
    key = id(typer_instance)
    if key not in _BUILT:
        _BUILT[key] = (typer_instance, _build(typer_instance))
    return _BUILT[key][1]


def run_cli(args, capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["ntc", *map(str, args)])
    monkeypatch.setattr(typer.main, "get_command", _built_command)
    code = 0
    try:
        main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


# Lines whose presence depends on the machine, not on the input: the progress heartbeat
# ("ntc simulate: [5 s] simulating …", after 5 s of a run: a loaded machine gets there before
# a refusal that a quiet one reaches sooner) and the note of a first run that compiles the
# kernels (a cold Numba cache). Tests of what a command says leave them out; a test that a
# refusal comes before any of them (the GPU check) looks at every line.
MACHINE_LINE = re.compile(r"^(ntc \w+: \[\d+ s\] |note: compiling the simulation kernels once)")


def said_lines(err: str) -> list[str]:
    """The non-empty lines of ``err`` but the progress heartbeat and the compile note."""
    return [ln for ln in err.splitlines() if ln.strip() and not MACHINE_LINE.match(ln)]


def assert_input_error(args, capsys, monkeypatch, *needles):
    code, out, err = run_cli(args, capsys, monkeypatch)
    lines = said_lines(err)
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


def without_progress(err: str) -> str:
    """stderr without the heartbeat lines a run prints every 5 s (how many depends on the
    machine's speed, not on the command's outcome) and the first run's compile note."""
    return "\n".join(ln for ln in err.splitlines() if not MACHINE_LINE.match(ln))


__all__ = [
    "MACHINE_LINE", "assert_input_error", "pytest", "run_cli", "said_lines", "without_progress",
]  # fmt: skip
