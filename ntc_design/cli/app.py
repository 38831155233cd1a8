"""The ``ntc`` program's shared ground: the typer app every command registers on, the
option types several commands share, and the helpers they use (the command line as typed,
JSON output, comma-separated vectors). Nothing here imports the library's layers."""

from __future__ import annotations

import contextlib
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer

from .. import __version__
from ..errors import INT_TEXT, NUMBER_TEXT, InputError, blame, number_from_text, number_rule
from .flags import digital_flags

if TYPE_CHECKING:  # the annotation only: NumPy loads when a command asks for the protocol
    from ..protocol.digital import Digital

# Everything else loads in the command that needs it: `ntc --help` and a mistyped option
# answer without importing NumPy, SciPy, SymPy or the library's layers.


def _flag_type(original):
    """A flag (``--json``, ``--help``, ``--tune-delta``) takes no value: its help line
    shows no type (this typer prints ``<bool>`` for it)."""

    def display_type_rich(self, ctx):
        if getattr(self, "is_flag", False) and not getattr(self, "count", False):
            return None
        return original(self, ctx)

    return display_type_rich


def _usage_name(self) -> str:
    """An argument in the usage line as click writes it, ``FILE`` (``[FILE]`` when
    optional), not this typer's ``{file}`` (which reads as a placeholder to fill in)."""
    name = self.metavar if self.metavar is not None else self.name.upper()
    name = name if self.required else f"[{name}]"
    return name + ("..." if self.nargs != 1 else "")


def _error_hint(self, ctx: object = None) -> str:
    """``Missing argument 'FILE'``: the argument named as the usage line names it."""
    return f"'{self.metavar or self.name.upper()}'"


with contextlib.suppress(AttributeError):  # another typer: its own rendering stays
    typer.core.TyperOption.display_type_rich = _flag_type(  # type: ignore[method-assign]
        typer.core.TyperOption.display_type_rich
    )
if hasattr(typer.core.TyperArgument, "_usage_display_name"):  # typer >= 0.2x braces it
    typer.core.TyperArgument._usage_display_name = _usage_name  # type: ignore[method-assign]
    typer.core.TyperArgument.get_error_hint = _error_hint  # type: ignore[method-assign]


def _ascii_numbers(original):
    """Every number flag (``--radius``, ``--seed``, …) read in ASCII numerals only: typer
    parses them by pydantic, which reads ``0_05`` as 5.0 (Python's number syntax)."""

    def build(number_class, **kwargs):
        adapter = original(number_class, **kwargs)
        pattern = INT_TEXT if number_class is int else NUMBER_TEXT
        if kwargs.get("min") is not None or kwargs.get("max") is not None or kwargs.get("clamp"):
            return adapter  # not used by ntc's flags: typer's own bounds stay as they are
        from pydantic import BeforeValidator, TypeAdapter

        def check(value):
            if isinstance(value, str) and not pattern.fullmatch(value):
                rule = number_rule(value)
                if number_class is int:  # '1.5' to --delay: an integer is what is missing
                    rule = rule if "_" in value or not value.isascii() else "(digits 0-9)"
                    raise ValueError(f"{value[:40]!r} is not an integer {rule}")
                raise ValueError(f"{value[:40]!r} is not a number {rule}")
            return value

        checked: Any = Annotated[number_class, BeforeValidator(check)]  # a runtime type
        return TypeAdapter(checked)

    return build


with contextlib.suppress(AttributeError, ImportError):  # another typer: its own parsing
    import typer._adapters as _adapters

    _adapters._build_number_adapter = _ascii_numbers(_adapters._build_number_adapter)

app = typer.Typer(
    add_completion=True,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
    rich_markup_mode="markdown",  # paragraphs of a docstring reflow to the terminal
    help="Certify, design and validate non-trivial consensus protocols on signed "
    "matrix-weighted networks with compound measurement noise.",
)


def _version(value: bool) -> None:
    if value:
        print(f"ntc {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="Print the version.", metavar=""
        ),
    ] = False,
) -> None:
    """Certify, design and validate non-trivial consensus protocols on signed
    matrix-weighted networks with compound measurement noise."""


FileArg = Annotated[
    Path,
    typer.Argument(
        help="A topology, switching or time-varying topology file (YAML or JSON), an edge "
        "list (.csv, .npz) or a MATLAB block matrix (.mat)."
    ),
]
# a flag takes no value: no metavar (click would print <bool>)
JsonOpt = Annotated[bool, typer.Option("--json", help="Machine-readable JSON output.", metavar="")]
SchedulerOpt = Annotated[
    str | None,
    typer.Option(
        help="Run on a Dask cluster: the scheduler's address, e.g. tcp://10.0.0.5:8786 "
        "(start one with `dask scheduler` and `dask worker ADDRESS`). Default: this machine."
    ),
]


def parse_vector(text: str, field: str) -> list[float]:
    """``"1,2,-1"`` -> ``[1.0, 2.0, -1.0]``; one clear error otherwise."""
    parts = [x for x in text.replace(" ", "").strip("[]").split(",") if x != ""]
    if not all(NUMBER_TEXT.fullmatch(x) for x in parts):
        bad = next(x for x in parts if not NUMBER_TEXT.fullmatch(x))
        raise InputError(
            f"expected comma-separated numbers, got {text!r} ({bad[:40]!r} is not a "
            f"number {number_rule(bad)})",
            field=field,
        )
    vals = [number_from_text(x, field) for x in parts]
    if not vals:
        raise InputError(f"expected comma-separated numbers, got {text!r}", field=field)
    return vals


PeriodOpt = Annotated[
    float | None,
    typer.Option(
        "--period",
        help="The digital protocol's sampling period h: agents sample every h and hold their "
        "input (overrides the scenario's digital block).",
    ),
]
DelayOpt = Annotated[
    int | None,
    typer.Option(
        "--delay",
        help="The digital protocol's measurement delay D, in samples (with --period or the "
        "scenario's digital block; default 0).",
    ),
]

LossOpt = Annotated[
    float | None,
    typer.Option(
        "--loss",
        help="The probability p in [0, 1) that a message is lost, on every edge at every "
        "step (the digital protocol; overrides the scenario's digital.loss).",
    ),
]
LossPolicyOpt = Annotated[
    str | None,
    typer.Option(
        "--loss-policy",
        help="What an agent does with a lost message: skip (leave the term out), rescale "
        "(divide the received terms by 1 − p) or hold (reuse the last one received).",
    ),
]


def digital_option(
    period: float | None,
    delay: int | None,
    given: object = None,
    horizon: object = None,
    loss: float | None = None,
    policy: str | None = None,
) -> Digital | None:
    """The sampled protocol from ``--period`` and ``--delay`` over a scenario's own
    ``digital`` block (``given``), checked with the flags named in errors: the one
    :class:`~ntc_design.protocol.digital.Digital` the command passes on.

    Parameters
    ----------
    period : float or None
        ``--period``.
    delay : int or None
        ``--delay``.
    given : mapping or None
        The scenario's ``digital`` block, if any.
    horizon : float, optional
        T, for a command whose run does not check h <= T itself (a period longer than it
        is refused, naming ``--period``); a simulation's spec checks it.
    loss : float or None, optional
        ``--loss``.
    policy : str or None, optional
        ``--loss-policy``.

    Returns
    -------
    Digital or None
        None when no flag asks for one.

    Raises
    ------
    InputError
        A bad flag value (naming the flag), or ``--delay`` without a period.
    """
    from ..protocol.digital import Digital
    from ..protocol.loss import require_loss, require_policy

    if loss is not None:
        require_loss("--loss", loss)
    checked = require_policy("--loss-policy", policy) if policy is not None else None
    if period is None and delay is None and loss is None and policy is None:
        return None
    base = dict(given) if isinstance(given, dict) else {}
    if period is None and "period" not in base:
        flag = "--delay" if delay is not None else "--loss" if loss is not None else "--loss-policy"
        raise InputError("needs --period (or a digital block in the scenario)", field=flag)
    try:
        dg = Digital(
            period if period is not None else base["period"],
            delay if delay is not None else base.get("delay", 0),
            loss if loss is not None else base.get("loss", 0.0),
            checked if checked is not None else base.get("policy", "skip"),
        )
        if isinstance(horizon, (int, float)) and not isinstance(horizon, bool) and horizon > 0:
            dg.steps(float(horizon))
    except InputError as exc:
        raise blame(exc, None, digital_flags(period, delay)) from None
    return dg


_V = TypeVar("_V")  # a flag's value type


def renamed_flag(
    old: str,
    old_value: _V | None,
    new: str,
    new_value: _V | None,
    check: Callable[[str, Any], object] | None = None,
) -> tuple[str, _V | None]:
    """A flag given under its deprecated spelling (``--sigma`` for ``--noise-sigma``): its
    value, checked, then a note on stderr; both spellings at once are refused.

    Parameters
    ----------
    old, new : str
        The deprecated and the current spelling.
    old_value, new_value : object
        Their values (None: not given).
    check : callable, optional
        ``check(flag, value)`` raises :class:`InputError` for a bad value (named as typed),
        before the note: a refusal stays one line.

    Returns
    -------
    (str, object)
        The spelling the user typed (errors name it) and the value.

    Raises
    ------
    InputError
        Both spellings given, or what ``check`` raises.
    """
    flag, value = (new, new_value) if old_value is None else (old, old_value)
    if old_value is not None and new_value is not None:
        raise InputError(f"the old spelling of {new}; give {new} only", field=old)
    if check is not None and value is not None:
        check(flag, value)
    if flag == old:
        print(f"note: {old} is deprecated; it is {new}", file=sys.stderr)
    return flag, value


def require_file(path: Path | None, hint: str = "") -> None:
    """A file the command reads, refused at once when it does not exist (before the
    library's layers are imported: seconds on a loaded machine); a folder or a device is
    left to the reader, which says what it is.

    Parameters
    ----------
    path : Path or None
        The file (None: not given).
    hint : str, optional
        Added to the message (``; expected a certificate ...``).

    Raises
    ------
    InputError
        ``PATH: no such file``.
    """
    if path is None:
        return
    try:
        missing = not path.exists()  # a dangling link is missing too
    except (OSError, ValueError):  # a name the reader refuses in its own words
        return
    if missing:
        raise InputError(f"no such file{hint}", field=str(path))


def check_theta_length(file: Path, theta: list[float]) -> None:
    """A ``--theta`` of the wrong length refused before the library loads, where the file
    states d: a YAML or JSON topology (up to 1 MiB, read twice at most) with a top-level
    ``dim``. Anything else is left to the library, which checks it after reading.

    Parameters
    ----------
    file : Path
        The topology file.
    theta : list of float
        ``--theta``.

    Raises
    ------
    InputError
        ``--theta: expected d numbers (the state dimension d), got n``.
    """
    from ..io.documents import read_document  # YAML and NumPy only

    try:
        small = file.suffix.lower() in (".yaml", ".yml", ".json") and file.stat().st_size < 2**20
        dim = read_document(file).get("dim") if small else None
    except (InputError, OSError, ValueError):  # the library says it when it reads the file
        return
    if type(dim) is int and dim > 0 and len(theta) != dim:
        raise InputError(
            f"expected {dim} numbers (the state dimension d), got {len(theta)}", field="--theta"
        )


def check_digital_flags(period: float | None, delay: int | None) -> None:
    """``--period`` and ``--delay`` on their own (h > 0 and finite, D an integer in range),
    before any file or library layer is read.

    Parameters
    ----------
    period : float or None
        ``--period``.
    delay : int or None
        ``--delay``.

    Raises
    ------
    InputError
        Naming the flag.
    """
    if period is None and delay is None:
        return
    from ..protocol.digital import Digital  # NumPy only

    try:
        Digital(period if period is not None else 1.0, delay if delay is not None else 0)
    except InputError as exc:
        raise blame(exc, None, digital_flags(period, delay)) from None


ARGS: list[str] = []  # this invocation's arguments (set by main)


def command_line() -> str:
    """This invocation as a shell command (``ntc`` and its arguments, quoted), whether
    ``main`` read them from ``sys.argv`` or was given them."""
    import shlex

    return shlex.join(["ntc", *ARGS])


def json_text(obj) -> str:
    from ..io.files import jsonable

    return json.dumps(jsonable(obj), indent=2, ensure_ascii=False)
