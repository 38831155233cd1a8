"""The ``ntc`` program: the commands registered in ``ntc --help`` order (here, and only
here), and the entry point that turns every error into one line and an exit code (2: bad
input, 1: not proven or an internal error, 130: interrupted)."""

from __future__ import annotations

import json
import sys

import typer

from ..errors import (
    AssumptionWarning,
    InputError,
    interrupt_seen,
    note_interrupt,
    one_line,
    options_written_as,
)
from ..io.outputs import exit_process
from .app import ARGS, app
from .commands import (
    certify,
    check,
    design_cmd,
    examples,
    export_cmd,
    gain,
    generate,
    robust,
    verify,
)
from .flags import FLAGS
from .runs import report, reproduce, simulate, sweep, tune

# fmt: off
app.command(epilog="Example: ntc check examples/g1.yaml")(check)
app.command("design", epilog="Example: ntc design examples/g1.yaml --theta 1,2,-1")(design_cmd)
app.command(epilog="Example: ntc generate --agents 1000 --dim 3 --out runs/net.npz")(generate)
app.command(epilog="Example: ntc gain '1/(1+t)'")(gain)
app.command(epilog="Example: ntc certify examples/g1.yaml --theta 1,2,-1 --gain '1/(1+t)' --out runs/g1.json")(certify)
app.command(epilog="Example: ntc verify runs/g1.json --topology examples/g1.yaml --theta 1,2,-1")(verify)
app.command(epilog="Example: ntc robust examples/g1.yaml --theta 1,2,-1 --radius 0.05")(robust)
app.command("export", epilog="Example: ntc export examples/scenarios/g1_deadline.yaml --lang c --out runs/g1-c --period 0.1 --delay 1")(export_cmd)
app.command(epilog="Example: ntc examples --copy my-examples")(examples)
app.command(epilog="Example: ntc simulate examples/scenarios/g1_fixed.yaml --out runs/g1 --paths 200")(simulate)
app.command(epilog="Example: ntc tune examples/scenarios/g1_fixed.yaml --eps 1.5 --out runs/g1-tuned")(tune)
app.command(epilog="Example: ntc sweep examples/sweeps/g1_noise.yaml --out runs/g1_noise")(sweep)
app.command(epilog="Example: ntc report runs/g1")(report)
app.command(epilog="Example: ntc reproduce paper --out runs/paper")(reproduce)
# fmt: on


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line on stderr (``warning: ...``), without the source line."""
    print(f"warning: {one_line(str(message))}", file=sys.stderr)


def _argv(args: list[str]) -> list[str]:
    """A value that starts with a minus sign (``ntc gain "-1/(1+t)"``, ``--gain "-1"``)
    is a value, not an option. Option values are taken as they are by click; a positional
    one (a minus sign followed by a digit, ``(`` or ``.``) is moved after ``--`` at the end
    (every command has at most one such positional argument)."""
    args = _bare_deadline(args)
    if "--" in args:
        return list(args)
    rest: list[str] = []
    negative: list[str] = []
    for k, tok in enumerate(args):
        prev = args[k - 1] if k else ""
        looks_negative = len(tok) > 1 and tok[0] == "-" and (tok[1].isdigit() or tok[1] in "(.")
        takes_value = prev.startswith("-") and "=" not in prev and prev not in _FLAGS
        (negative if looks_negative and not takes_value else rest).append(tok)
    return rest + ["--", *negative] if negative else rest


_FLAGS = {"--json", "--help", "--version"}  # options that take no value


def _bare_deadline(args: list[str]) -> list[str]:
    """``--deadline`` takes an optional value (T): bare (last, or before an option or a
    file), it is given the empty value, which means the scenario's T."""
    out = list(args)
    for k in range(len(out) - 1, -1, -1):
        if out[k] != "--deadline":
            continue
        nxt = out[k + 1] if k + 1 < len(out) else None
        if nxt is None or not (nxt[:1].isdigit() or nxt[:1] in ".+-" and nxt[1:2].isdigit()):
            out.insert(k + 1, "")
    return out


def _error_exit(message: str, args: list[str], code: int = 2) -> int:
    """An error exit: ``error: ...`` on stderr, and with --json ``{"error": ...}`` on
    stdout too (a script reading stdout gets JSON for every error exit: bad input, memory,
    an unreadable file, an interrupt, an internal error). Returns ``code`` (2: bad
    input)."""
    print(f"error: {message}", file=sys.stderr)
    if "--json" in args[: args.index("--")] if "--" in args else "--json" in args:
        try:
            print(
                json.dumps({"ok": False, "error": message, "exit_code": code}, ensure_ascii=False)
            )
        except OSError:  # stdout itself is gone (a closed pipe): stderr has said it
            pass
    return code


def main(argv: list[str] | None = None) -> None:
    """Run the CLI: one line ``error: ...`` on stderr for every user error (exit 2), for
    an interrupt (exit 130); warnings as ``warning: ...`` lines.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).
    """
    import os
    import warnings

    try:  # typer >= 0.20 vendors click; its exceptions are what the commands raise
        from typer._click import exceptions as click
    except ImportError:  # pragma: no cover - older typer
        from click import exceptions as click  # type: ignore[no-redef]

    args = sys.argv[1:] if argv is None else list(argv)
    ARGS[:] = args
    # figures are written to files: no display, whatever the machine has (a GUI backend
    # would open windows or fail without one); set before matplotlib is ever imported
    os.environ.setdefault("MPLBACKEND", "Agg")
    warnings.showwarning = _warning_line
    warnings.simplefilter("ignore", RuntimeWarning)  # numerical trouble is checked, not warned
    warnings.simplefilter("once", AssumptionWarning)  # one line per network, not per mode
    code = 0
    try:
        try:
            # the options the library names (messages, notes, rows) as this command's flags
            command = next((a for a in args if not a.startswith("-")), "")
            with options_written_as(FLAGS.get(command, {})):
                rv = app(args=_argv(args), prog_name="ntc", standalone_mode=False)
        except click.NoArgsIsHelpError as exc:
            print(exc.format_message())
            code = 2
        else:
            code = rv if isinstance(rv, int) else 0
            if code == 0 and interrupt_seen():  # Ctrl-C came, its exception was lost
                code = 130
            if code == 130:  # typer turns KeyboardInterrupt into Exit(130)
                _error_exit("interrupted", args, 130)
    except InputError as exc:
        code = _error_exit(one_line(str(exc)), args)
    except click.UsageError as exc:
        where = f" (see: {exc.ctx.command_path} --help)" if exc.ctx is not None else ""
        code = _error_exit(f"{one_line(exc.format_message())}{where}", args)
    except click.ClickException as exc:  # e.g. an unreadable file argument
        code = _error_exit(one_line(exc.format_message()), args)
    except (KeyboardInterrupt, typer.Abort):
        code = _error_exit("interrupted", args, 130)
    except MemoryError:
        code = _error_exit(
            "out of memory: the input asks for more memory than the machine has", args
        )
    except BrokenPipeError:
        code = 1
    except OSError as exc:  # a file or folder the user named cannot be read or written
        where = f"{one_line(str(exc.filename))!r}: " if exc.filename else ""
        code = _error_exit(f"{where}{exc.strerror or exc.__class__.__name__}", args)
    except Exception as exc:  # a bug: one line, the traceback with NTC_DEBUG=1
        if os.environ.get("NTC_DEBUG"):
            raise
        code = _error_exit(
            f"internal error ({exc.__class__.__name__}: {one_line(str(exc))[:300]}); "
            "re-run with NTC_DEBUG=1 for the traceback",
            args,
            1,
        )
    sys.exit(code)


def run() -> None:
    """The ``ntc`` program: :func:`main`, then an exit that skips the interpreter's
    teardown of its modules (about 0.3 s once Numba and SciPy are loaded). The exit
    handlers still run and the streams are flushed first; with another thread or a child
    process still alive, or under a profiler or tracer, the ordinary exit is taken.
    """
    import signal

    # Ctrl-C raises KeyboardInterrupt as always, and is noted (errors.note_interrupt): one
    # raised inside a finaliser is dropped by Python, the note is not. An ignored SIGINT
    # (a background job) stays ignored, as Python leaves it.
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, note_interrupt)
    try:
        main()
        code: str | int | None = 0
    except SystemExit as exc:
        code = exc.code
    exit_process(code)
