"""Parameters named as data in the library's messages: an :class:`Option` is a field of
the library (``schedule``, ``max_gain``) that each reader writes in its own words, the
Python caller as a keyword (``schedule="power"``), the command line as its flag
(``--schedule power``) while :func:`options_written_as` holds its command's map."""

from __future__ import annotations

import contextlib
import contextvars
import types
from collections.abc import Iterator, Mapping
from dataclasses import dataclass


@dataclass(frozen=True)
class Option:
    """A parameter named inside a message, as data: the library's name for it (and the
    value advised), which each reader writes in its own words.

    ``str()`` gives the library's words (``schedule="power"``, or ``device: cpu`` for a
    document's field), or the flag while :func:`options_written_as` holds a map that has
    the field (``--schedule power``: ``ntc`` holds its command's map while it runs one);
    :meth:`ntc_design.errors.InputError.text` and :func:`ntc_design.errors.blame` write an
    error's options with a map they are given.

    Attributes
    ----------
    field : str
        The parameter or field (``schedule``, ``digital.period``).
    value : object, optional
        The value advised (None: the parameter itself is named).
    document : bool, optional
        A field of a document: written ``field: value`` rather than ``field=value``.
    quoted : bool, optional
        A text value is quoted in the library's words (``schedule="power"``); False: a
        number already written as text (``max_gain=50.0000``).
    alias : str, optional
        The library's words where they are not the field's name (``to_dict()`` for the
        JSON output).
    """

    field: str
    value: object = None
    document: bool = False
    quoted: bool = True
    alias: str | None = None

    def __str__(self) -> str:
        flag = None if self.document else _OPTION_WORDS.get().get(self.field)
        return self.as_flag(flag) if flag is not None else self.words()

    def words(self) -> str:
        """The option in the library's words, whoever reads it.

        Returns
        -------
        str
            ``schedule="power"``, ``max_gain``, ``device: cpu`` (a document's field).
        """
        if self.alias is not None:
            return self.alias
        if self.value is None:
            return self.field
        if self.document:
            return f"{self.field}: {flag_value(self.value)}"
        text = isinstance(self.value, str) and self.quoted
        shown = f'"{self.value}"' if text else flag_value(self.value)
        return f"{self.field}={shown}"

    def as_flag(self, flag: str) -> str:
        """The option as typed at the command line.

        Parameters
        ----------
        flag : str
            The flag that gives the field (``--schedule``).

        Returns
        -------
        str
            ``--schedule power`` (the flag alone where no value is advised).
        """
        return flag if self.value is None else f"{flag} {flag_value(self.value)}"


#: Field -> flag while the command line runs a command (:func:`options_written_as`): the
#: options a message or a table's note names are written as its flags.
_OPTION_WORDS: contextvars.ContextVar[Mapping[str, str]] = contextvars.ContextVar(
    "option_words", default=types.MappingProxyType({})
)


@contextlib.contextmanager
def options_written_as(flags: Mapping[str, str]) -> Iterator[None]:
    """Within this block, every :class:`Option` the library writes (in a message, a note,
    a table's row) is written as the flag that gives its field: the command line's words.

    Parameters
    ----------
    flags : mapping of str to str
        Field -> flag (a command's map).

    Yields
    ------
    None
    """
    token = _OPTION_WORDS.set(dict(flags))
    try:
        yield
    finally:
        _OPTION_WORDS.reset(token)


def flag_value(value: object) -> str:
    """A value as typed after its flag (a number in its short form).

    Parameters
    ----------
    value : object
        The value (a float, a mapping of the digital block's fields, anything).

    Returns
    -------
    str
        ``1e+12``, ``period 0.1, delay 1``, or ``str(value)``.
    """
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, Mapping):  # the digital block (period, delay)
        return ", ".join(
            f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}" for k, v in value.items()
        )
    return str(value)


__all__ = ["Option", "flag_value", "options_written_as"]
