"""The one error type a user sees for bad input, and the small checks that raise it."""

from __future__ import annotations

import importlib
import math
import numbers
import os
import re
import sys
import types
import warnings
from collections.abc import Mapping

from .fields import Option, flag_value, options_written_as


class InputError(ValueError):
    """Bad input: a file, matrix, label or parameter that is wrong.

    The message is one line that names the file and the edge or field and says what is
    wrong; the CLI prints it and exits with code 2. The field is data (:attr:`field`):
    the library names its parameters and fields, the command line maps them to its flags
    (:func:`blame`).

    Parameters
    ----------
    *parts : str or Option
        The message: text, and the parameters it names (:class:`Option`, written by each
        reader in its own words).
    field : str, optional
        The field or parameter that is wrong (``digital.period``, a file's name); ``str()``
        is ``field: message``. Never written into the message's text: the command line
        names the field by its flag (:func:`blame`).
    value : object, optional
        The field's value the message is about (``schedule="optimal": ...``).
    option : bool, optional
        The field is a parameter of the call (not a document's field): each reader names
        it in its words, the command line by its flag (:func:`options_written_as`).

    Attributes
    ----------
    field : str or None
        The field the error is about.
    value : object
        Its value the message is about (None: the field alone).
    option : bool
        The field is a parameter of the call.
    parts : tuple of str or Option
        The message without the field.
    """

    def __init__(
        self,
        *parts: str | Option,
        field: str | None = None,
        value: object = None,
        option: bool = False,
    ) -> None:
        self.field = field
        self.value = value
        self.option = option
        self.parts = parts
        super().__init__(self.text())

    @property
    def message(self) -> str:
        """The message without the field, in the library's words."""
        return "".join(str(p) for p in self.parts)

    def text(self, flags: Mapping[str, str] | None = None, name: str | None = None) -> str:
        """The one line, the parameters it names written as flags where ``flags`` has them.

        Parameters
        ----------
        flags : mapping of str to str, optional
            Field -> flag (a command's map).
        name : str, optional
            What to call the field (default :attr:`field`, as its flag where ``flags`` has
            it); ``""``: the message alone.

        Returns
        -------
        str
        """
        flags = flags or {}
        body = "".join(
            p.as_flag(flags[p.field]) if isinstance(p, Option) and p.field in flags else str(p)
            for p in self.parts
        )
        if name is None and self.field is not None:
            head = Option(self.field, self.value)
            if self.field in flags:
                name = head.as_flag(flags[self.field])
            else:  # a parameter of the call: the reader's words for it (its flag)
                name = str(head) if self.option else head.words()
        return f"{name}: {body}" if name else body

    def __reduce__(self):  # across processes, with its field and parts
        return (_rebuild_error, (type(self), self.parts, self.field, self.value, self.option))


def _rebuild_error(
    cls: type, parts: tuple, field: str | None, value: object, option: bool
) -> InputError:
    return cls(*parts, field=field, value=value, option=option)


def quote(label) -> str:
    """A label as it may appear inside a one-line message.

    Parameters
    ----------
    label : int or str
        An agent or mode label.

    Returns
    -------
    str
        An integer as written, anything else repr-quoted (so a label holding a newline
        cannot split or forge an error line).
    """
    if isinstance(label, numbers.Integral) and not isinstance(label, bool):
        return str(int(label))
    return repr(str(label))


def one_line(text: str) -> str:
    """``text`` with every control character escaped, printable on one line.

    Parameters
    ----------
    text : str
        Any text (converted with ``str``).

    Returns
    -------
    str
        The text with non-printable characters as ``unicode_escape`` sequences.
    """
    return "".join(
        ch if ch.isprintable() or ch == " " else ch.encode("unicode_escape").decode("ascii")
        for ch in str(text)
    )


def _show(value) -> str:
    # a NumPy scalar as the number it is (inf, 3), not its repr (np.float64(inf))
    if type(value).__module__ == "numpy" and isinstance(value, numbers.Real):
        value = int(value) if isinstance(value, numbers.Integral) else float(value)
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        digits = len(str(abs(int(value))))
        if digits > 40:  # a 400-digit integer: its size, not its digits
            return f"an integer of {digits} digits"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


#: A number as text: ASCII digits only, no underscores (Python's float() and int(), and
#: pydantic for typed flags, read "0_05" as 5.0 and "٣" as 3).
NUMBER_TEXT = re.compile(
    r"\s*[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf(?:inity)?|nan)\s*",
    re.IGNORECASE | re.ASCII,
)
INT_TEXT = re.compile(r"\s*[+-]?[0-9]+\s*", re.ASCII)


def number_from_text(text: str, name: str) -> float:
    """A number written as text (a flag's value, a table cell), in ASCII numerals only.

    Parameters
    ----------
    text : str
        The text.
    name : str
        The flag or field named in the message.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Anything but an optional sign, ASCII digits, a decimal point and an exponent
        (or inf, nan): ``0_05``, ``٣``, ``３`` are refused, not read as 5, 3, 3.
    """
    if not NUMBER_TEXT.fullmatch(text):
        raise InputError(f"{text[:40]!r} is not a number {number_rule(text)}", field=name)
    return float(text)


def number_rule(text: str) -> str:
    """Why a text is not a number, for a message: what it holds that is not allowed.

    Parameters
    ----------
    text : str
        The text refused.

    Returns
    -------
    str
    """
    if "_" in text:
        return "(write it without underscores: ASCII digits, a point, an exponent)"
    if not text.isascii():
        return "(write it in ASCII digits 0-9)"
    return "(ASCII digits, a point, an exponent)"


def real_float(name: str, value) -> float:
    """A real number as a float, an integer beyond the float range refused (``float`` of
    a 400-digit integer raises OverflowError; a document may hold one).

    Parameters
    ----------
    name : str
        The field named in the message.
    value : numbers.Real
        The number (not a bool; the caller checks the type).

    Returns
    -------
    float

    Raises
    ------
    InputError
        An integer too large for a float (magnitude above about 1.8e308).
    """
    try:
        return float(value)
    except OverflowError:
        raise InputError(
            f"{_show(value)} is beyond the float range (about 1.8e308)", field=name
        ) from None


def require_theta(theta, dim: int):
    """θ as d finite numbers, not all zero (the target of non-trivial consensus).

    Parameters
    ----------
    theta : sequence of float or numpy.ndarray
        The target state.
    dim : int
        The state dimension d.

    Returns
    -------
    numpy.ndarray
        θ, shape (d,).

    Raises
    ------
    InputError
        Not d finite numbers, or θ = 0.
    """
    import numpy as np

    try:
        th = np.asarray(theta, dtype=float).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"expected {dim} numbers, got {theta!r}", field="theta") from None
    if th.size != dim:
        raise InputError(
            f"expected {dim} numbers (the state dimension d), got {th.size}", field="theta"
        )
    if not np.all(np.isfinite(th)):
        raise InputError("entries must be finite", field="theta")
    if not np.any(th):
        raise InputError("must be non-zero (the target of non-trivial consensus)", field="theta")
    return th


def require_x0(theta, k1) -> None:
    """Refuse a θ whose Lemma 1 state x0 = k1·θ overflows (k1 = 1 + 2/δ > 1: a θ near the
    float range passes :func:`require_theta`, then x0 is infinite and only a certificate
    check far downstream named it, as ``subject.modes.G1.x0``).

    Parameters
    ----------
    theta : numpy.ndarray
        θ (finite).
    k1 : float or numpy.ndarray
        k1, one value or one per instant.

    Raises
    ------
    InputError
        ``theta: ...``, saying the largest |θ_i| that fits.
    """
    import numpy as np

    th, k = np.abs(np.asarray(theta, dtype=float)), float(np.max(k1))
    with np.errstate(over="ignore"):
        if np.all(np.isfinite(th * k)):
            return
    top = float(np.max(th))
    raise InputError(
        f"x0 = k1·θ overflows: |θ| up to {top:.4g} times k1 = 1 + 2/δ = {k:.6g} is "
        f"beyond the float range (about 1.8e308); every |θ_i| must be below "
        f"{np.finfo(float).max / k:.4g}",
        field="theta",
    )


def require_positive(name: str, value, integer: bool = False) -> None:
    """Raise InputError unless ``value`` is a finite positive number (an integer if asked).

    Parameters
    ----------
    name : str
        The field named in the message.
    value : object
        The value to check.
    integer : bool
        Also require an integer (a float such as ``2.0`` is refused).

    Raises
    ------
    InputError
        When the value is not a finite positive number (integer).
    """
    if integer:
        require_int(name, value, minimum=1)
        return
    bad = (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or not math.isfinite(real_float(name, value))
        or value <= 0
    )
    if bad:
        raise InputError(f"must be a positive number, got {_show(value)}", field=name)


def require_int(name: str, value, minimum: int = 0, maximum: int | None = None) -> int:
    """``value`` as an int if it is an integer (not a bool, not a float) in
    [minimum, maximum].

    Parameters
    ----------
    name : str
        The field named in the message.
    value : object
        The value to check.
    minimum, maximum : int
        Inclusive bounds (``maximum`` None: unbounded).

    Returns
    -------
    int

    Raises
    ------
    InputError
        When the value is not an integer in range.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        kind = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise InputError(f"must be {kind}, got {_show(value)}", field=name)
    v = int(value)
    if v < minimum:
        kind = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise InputError(f"must be {kind}, got {v}", field=name)
    if maximum is not None and v > maximum:
        raise InputError(f"must be at most {maximum}, got {_show(v)}", field=name)
    return v


def require_number(
    name: str, value, minimum: float | None = None, bound: float | None = None
) -> float:
    """``value`` as a finite float (not a bool), at least ``minimum`` and at most
    ``bound`` in magnitude if given.

    Parameters
    ----------
    name : str
        The field named in the message.
    value : object
        The value to check.
    minimum : float, optional
        Inclusive lower bound.
    bound : float, optional
        Largest magnitude allowed (|value| <= bound).

    Returns
    -------
    float

    Raises
    ------
    InputError
        When the value is not a finite number at least ``minimum`` (and within ``bound``).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"expected a number, got {_show(value)}", field=name)
    v = real_float(name, value)
    if not math.isfinite(v):
        raise InputError(f"must be finite, got {_show(value)}", field=name)
    if minimum is not None and v < minimum:
        raise InputError(f"must be >= {minimum:g}, got {_show(value)}", field=name)
    if bound is not None and abs(v) > bound:
        raise InputError(f"must be at most {bound:g} in magnitude, got {_show(value)}", field=name)
    return v


def blame(
    exc: InputError,
    source: object,
    flags: Mapping[str, str] | None = None,
    fields: Mapping[str, str] | None = None,
    values: Mapping[str, object] | None = None,
    advice: Mapping[str, str] | None = None,
) -> InputError:
    """Who an error of a run is about: the flag that gave its field (``--paths: ...``),
    or else the file (``SOURCE: FIELD: ...``).

    Parameters
    ----------
    exc : InputError
        The error, its field as data (:attr:`InputError.field`: a field of the scenario,
        or a parameter of the run); an error about a flag already (``--x``) is kept.
    source : object
        The file the other fields come from (its name prefixes their errors); None: no
        file (the fields are the program's own).
    flags : mapping of str to str, optional
        Field -> the flag that gave its value (only the fields a flag gave).
    fields : mapping of str to str, optional
        Field -> the file's name for it, for a parameter the file gave (``horizon`` -> ``T``
        when ``--horizon`` defaulted to the scenario's T).
    values : mapping of str to object, optional
        Field -> the value its flag gave: an error about the file's own field that arose
        with flags given says them (``(with`` and the flags as typed), as they took part.
    advice : mapping of str to str, optional
        Field -> flag for every flag of the command: the parameters the message advises
        (:class:`Option`) are written as flags (default: ``flags``).

    Returns
    -------
    InputError
        The error to raise, one line, naming the flag or the file.
    """
    flags = flags or {}
    field = exc.field
    if field is not None and field.startswith("--"):
        return exc
    # advice names a parameter (the command's flag for it), or a file's field where a flag
    # gave that field
    options = {**{k: f for k, f in (advice or {}).items() if k not in _documents(exc)}, **flags}
    head = field.split(".", 1)[0].split("[", 1)[0] if field is not None else None
    # a flag for that very field (digital.delay), else for its block (digital)
    key = field if field in flags else head if head in flags else None
    if field is not None and key is not None:
        flag = Option(f"{flags[key]}{field[len(key) :]}", exc.value)
        return InputError(exc.text(options, ""), field=flag.as_flag(flag.field))
    name = ""
    if field is not None:  # a parameter of the call in the reader's words, a field as is
        name = str(Option(field, exc.value)) if exc.option else Option(field, exc.value).words()
    if field is not None and head is not None and fields and head in fields:
        name = f"{fields[head]}{field[len(head) :]}"
    body = exc.text(options, "")
    given = [f"{flags[k]} {flag_value(v)}" for k, v in (values or {}).items() if k in flags]
    with_flags = f" (with {', '.join(dict.fromkeys(given))})" if given else ""
    if source is None:
        return InputError(body + with_flags, field=name or None)
    text = f"{name}: {body}" if name else body
    return InputError(text + with_flags, field=str(source))


def _documents(exc: InputError) -> set[str]:
    """The document fields an error's advice names (written as flags only where given)."""
    return {p.field for p in exc.parts if isinstance(p, Option) and p.document}


class AssumptionWarning(UserWarning):
    """Assumption 2 fails for a topology being designed: Lemma 1 does not apply and the
    design must be certified before it is trusted (also flagged by
    ``ProtocolDesign.assumption_holds``). Defined here, with the errors, so that the
    command line can filter it without importing the design layer."""


def format_bytes(n: float) -> str:
    """A byte count in binary units, e.g. ``1.5e9`` -> ``'1.4 GiB'``.

    Parameters
    ----------
    n : float
        Number of bytes.

    Returns
    -------
    str
        The count in B, KiB, ..., PiB with one decimal (none for bytes).
    """
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} PiB"  # pragma: no cover


def format_seconds(s: float) -> str:
    """A duration for people: ``'45 s'``, ``'12 min'``, ``'3.2 h'``, ``'4.1 days'``.

    Parameters
    ----------
    s : float
        Seconds.

    Returns
    -------
    str
    """
    if not math.isfinite(s):
        return "forever"
    if s < 90:
        return f"{s:.0f} s"
    if s < 5400:
        return f"{s / 60:.0f} min"
    if s < 2 * 86400:
        return f"{s / 3600:.1f} h"
    return f"{s / 86400:.1f} days"


#: The shortest horizon T accepted: the time grids compare instants to 1e-14 (relative
#: above 1) and sample c(t) from 1e-6 on, so a T below this leaves no step to take (and a
#: subnormal T halves to 0).
MIN_HORIZON = 1e-9


def require_horizon(name: str, value) -> float:
    """A horizon T: a finite number of at least :data:`MIN_HORIZON`.

    Parameters
    ----------
    name : str
        The field or flag named in the message (``T``, ``--horizon``).
    value : object
        The value given.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a finite number, or below :data:`MIN_HORIZON`.
    """
    require_number(name, value)  # a non-finite one said as such first
    require_positive(name, value)
    t = real_float(name, value)
    if t < MIN_HORIZON:
        raise InputError(
            f"{_show(value)} is shorter than the shortest horizon {MIN_HORIZON:g} (the "
            "time grids resolve instants to about 1e-14)",
            field=name,
        )
    return t


#: The largest seed accepted (numpy's SeedSequence takes any non-negative int).
MAX_SEED = 2**128


def require_radius(value, name: str = "radius", below_one: bool = True) -> float:
    """A relative radius ρ of a weight's Loewner interval (1−ρ)|A| ⪯ |A'| ⪯ (1+ρ)|A|:
    a finite number >= 0, and below 1 where asked (at 1 a weight may vanish).

    Parameters
    ----------
    value : object
        The value given.
    name : str, optional
        The field named in the message (the file first, where there is one).
    below_one : bool, optional
        Refuse ρ >= 1.

    Returns
    -------
    float

    Raises
    ------
    InputError
        One line naming the field.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"expected a number, got {_show(value)}", field=name)
    r = real_float(name, value)
    if not (math.isfinite(r) and r >= 0 and (r < 1 or not below_one)):
        limit = " and below 1 (at 1 a weight may vanish)" if below_one else ""
        raise InputError(
            f"the radius must be a finite number >= 0{limit}, got {_show(value)}", field=name
        )
    return r


#: The optional extras (pyproject.toml) and what each brings: the core install certifies,
#: designs, simulates, tunes, bounds robustly and reports without them.
EXTRAS = {
    "tables": "pandas and PyArrow (sweep tables, data frames)",
    "cluster": "Dask distributed (sweeps and Monte Carlo on a cluster)",
    "interop": "networkx and python-control (graphs and state-space models in and out)",
}


def optional_module(name: str, extra: str, what: str) -> types.ModuleType:
    """An optional dependency, imported; one line naming the extra that brings it when it
    is not installed.

    Parameters
    ----------
    name : str
        The module (``pandas``, ``distributed``).
    extra : str
        The extra of :data:`EXTRAS` that installs it.
    what : str
        What needs it (``ntc sweep``), the start of the message.

    Returns
    -------
    types.ModuleType

    Raises
    ------
    InputError
        It is not installed (exit code 2 at the command line).

    Examples
    --------
    >>> optional_module("math", "tables", "a test").sqrt(4.0)
    2.0
    """
    try:
        return importlib.import_module(name)
    except ImportError:
        top = name.split(".", 1)[0]
        raise InputError(
            f"{what} needs {top}, which the core install leaves out: "
            f'pip install "ntc-design[{extra}]"'
        ) from None


__all__ = [
    "LONG_WORK_SECONDS",
    "check_work",
    "EXTRAS",
    "INT_TEXT",
    "optional_module",
    "MAX_SEED",
    "NUMBER_TEXT",
    "MIN_HORIZON",
    "AssumptionWarning",
    "blame",
    "require_theta",
    "InputError",
    "format_bytes",
    "format_seconds",
    "interrupt_seen",
    "note_interrupt",
    "number_from_text",
    "number_rule",
    "Option",
    "options_written_as",
    "one_line",
    "quote",
    "real_float",
    "require_horizon",
    "require_int",
    "require_number",
    "require_positive",
    "require_radius",
    "require_x0",
]


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))


def warn_user(message: str, category: type[Warning]) -> None:
    """Warn, attributing the warning to the first caller outside this package (the user's
    call, however deep inside the toolkit the condition was found).

    Parameters
    ----------
    message : str
        The warning.
    category : type of Warning
        Its class.
    """
    level = 2  # warnings.warn's level of warn_user's caller
    frame: types.FrameType | None = sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)


#: Work estimated longer than this says so before it starts (one warning line).
LONG_WORK_SECONDS = 60.0


def check_work(
    seconds: float,
    what: str,
    limit: float,
    instead: str,
    field: str | None = None,
    option: bool = False,
) -> None:
    """Refuse work estimated past ``limit`` in one line; past :data:`LONG_WORK_SECONDS`,
    say the estimate before it starts.

    Parameters
    ----------
    seconds : float
        The estimate.
    what : str
        What the work is and how long it takes, the message's start (``tuning for T = 1e4
        takes roughly 2 h``).
    limit : float
        The longest work accepted, in seconds.
    instead : str
        What to do instead, said when it is refused.
    field : str, optional
        The field or parameter whose value asks for the work (``horizon``): the error's
        field, and the warning's start.
    option : bool, optional
        ``field`` is a parameter of the call (written as its flag at the command line).

    Raises
    ------
    InputError
        The estimate is above ``limit`` (or not a number).

    Examples
    --------
    >>> check_work(5.0, "a test of roughly 5 s", 3600.0, "a smaller one", field="test")
    """
    if not seconds <= limit:
        raise InputError(
            f"{what}, more than the limit of {format_seconds(limit)}; {instead}",
            field=field,
            option=option,
        )
    if seconds > LONG_WORK_SECONDS:
        head = "" if field is None else f"{Option(field) if option else field}: "
        warn_user(f"{head}{what}; Ctrl-C stops cleanly", UserWarning)


# -- interrupts that Python may lose ---------------------------------------------------------
#
# A KeyboardInterrupt raised while a finaliser (__del__, a weakref callback) runs is
# printed as "Exception ignored" and dropped: Ctrl-C at such an instant would be lost. The
# CLI's SIGINT handler also notes the signal here, and long loops check the note.

_SIGINT_SEEN: list[bool] = []


def note_interrupt(signum: int = 2, frame: object = None) -> None:
    """A SIGINT handler: note the signal, then raise KeyboardInterrupt as Python's own does.

    Parameters
    ----------
    signum : int
        The signal.
    frame : frame, optional
        The interrupted frame.

    Raises
    ------
    KeyboardInterrupt
        Always.
    """
    _SIGINT_SEEN.append(True)
    raise KeyboardInterrupt


def interrupt_seen() -> bool:
    """Whether :func:`note_interrupt` ran in this process (its exception may have been lost).

    Returns
    -------
    bool
    """
    return bool(_SIGINT_SEEN)
