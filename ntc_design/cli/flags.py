"""Each ``ntc`` command's flags as the library's fields: one map per command, field ->
flag. The library names its parameters and the scenario's fields (``digital.period``,
``max_gain``), never a flag; an error about a field a flag gave names the flag, and
advice in a message (:class:`~ntc_design.errors.Option`) is written as flags
(:func:`ntc_design.errors.blame`). Nothing here imports the library's layers."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping

from ..errors import InputError, blame

#: The digital protocol's fields and their flags (the scenario's ``digital:`` block).
_DIGITAL = {
    "digital": "--period",
    "digital.period": "--period",
    "digital.delay": "--delay",
    "digital.loss": "--loss",
    "digital.policy": "--loss-policy",
}
#: The same as the parameters of the library's functions (``period=``, ``policy=``).
_SAMPLED = {"period": "--period", "delay": "--delay", "loss": "--loss", "policy": "--loss-policy"}

#: Command -> field -> flag: every flag of every command is some field's (the field the
#: library names in its messages), and every field here is a flag of its command.
FLAGS: dict[str, dict[str, str]] = {
    "check": {"full": "--full", "json": "--json"},
    "design": {
        "theta": "--theta",
        "margin": "--margin",
        "thresholds": "--thresholds",
        "out": "--out",
        "json": "--json",
    },
    "generate": {
        "out": "--out",
        "n": "--agents",
        "d": "--dim",
        "seed": "--seed",
        "family": "--family",
        "p_negative": "--p-negative",
        "json": "--json",
    },
    "gain": {"json": "--json"},
    "certify": {
        "theta": "--theta",
        "margin": "--margin",
        "gain": "--gain",
        "out": "--out",
        "noise_sigma": "--noise-sigma",
        "noise_f": "--noise-f",
        "rate_method": "--rate-method",
        **_DIGITAL,
        **_SAMPLED,
        "deadline": "--deadline",
        "json": "--json",
    },
    "verify": {"topology": "--topology", "theta": "--theta", "json": "--json"},
    "robust": {
        "theta": "--theta",
        "radius": "--radius",
        "margin": "--margin",
        "out": "--out",
        "json": "--json",
    },
    "export": {
        "out": "--out",
        "lang": "--lang",
        **_SAMPLED,
        "gain": "--gain",
        "sigma": "--noise-sigma",
        "f": "--noise-f",
        "agent": "--agent",
        "json": "--json",
    },
    "examples": {"copy": "--copy", "json": "--json"},
    "simulate": {
        "out": "--out",
        "workers": "--workers",
        "paths": "--paths",
        "T": "--horizon",
        "dt": "--dt",
        "seed": "--seed",
        "method": "--method",
        "rng": "--rng",
        "device": "--device",
        **_DIGITAL,
        **_SAMPLED,
        "scheduler": "--scheduler",
        "json": "--json",
    },
    "tune": {
        "horizon": "--horizon",
        "schedule": "--schedule",
        "family": "--schedule",
        "require": "--require",
        "tune_delta": "--tune-delta",
        "eps": "--eps",
        "method": "--method",
        "max_evaluations": "--evaluations",
        "max_gain": "--max-gain",
        "max_peak": "--max-peak",
        "check_paths": "--check-paths",
        "out": "--out",
        **_DIGITAL,
        **_SAMPLED,
        "tolerance": "--tolerance",
        "json": "--json",
    },
    "sweep": {"out": "--out", "scheduler": "--scheduler", "workers": "--workers", "json": "--json"},
    "report": {"interactive": "--interactive", **_DIGITAL, **_SAMPLED, "json": "--json"},
    "reproduce": {
        "out": "--out",
        "T": "--horizon",
        "paths": "--paths",
        "dt": "--dt",
        "ds": "--dt",
        "stepping": "--stepping",
        "workers": "--workers",
        "seed": "--seed",
        "interactive": "--interactive",
        "json": "--json",
    },
}

#: Command -> a deprecated spelling -> the flag it stands for (hidden from the help).
DEPRECATED: dict[str, dict[str, str]] = {
    "generate": {"--n": "--agents", "--d": "--dim"},
    "export": {"--sigma": "--noise-sigma", "--f": "--noise-f"},
    "tune": {"--family": "--schedule"},
}


def flags_of(
    command: str, given: Mapping[str, object] | None = None, /, **typed: str
) -> dict[str, str]:
    """A command's map, narrowed to the fields whose flags were given.

    Parameters
    ----------
    command : str
        The command (``simulate``).
    given : mapping of str to object, optional
        Field -> the value its flag gave (None: not given); None: every field.
    **typed : str
        Field -> the spelling the user typed, where it is not the map's (a deprecated one).

    Returns
    -------
    dict of str to str
        Field -> flag.
    """
    flags = {**FLAGS[command], **typed}
    if given is None:
        return flags
    return {k: f for k, f in flags.items() if k in given and given[k] is not None}


@contextlib.contextmanager
def flags_named(command: str, *fields: str, **typed: str) -> Iterator[None]:
    """Errors of the library about a field a flag gave name the flag: ``theta: x0
    overflows`` from :func:`ntc_design.design` is ``--theta: x0 overflows`` (the user
    typed --theta, not a field called theta); the advice it gives is written as flags.

    Parameters
    ----------
    command : str
        The command whose map applies.
    *fields : str
        The fields whose flags were given (none: every field of the map).
    **typed : str
        Field -> the spelling the user typed (a deprecated one).

    Yields
    ------
    None

    Raises
    ------
    InputError
        The error inside, its field renamed to the flag.
    """
    flags = flags_of(command, **typed)
    named = {k: flags[k] for k in fields} if fields else flags
    try:
        yield
    except InputError as exc:
        raise blame(exc, None, named, advice=flags) from None


def digital_flags(
    period: object = None, delay: object = None, loss: object = None, policy: object = None
) -> dict[str, str]:
    """The digital block's fields whose flags were given (``--period``, ``--delay``,
    ``--loss``, ``--loss-policy``; None: not given).

    Parameters
    ----------
    period, delay, loss, policy : object
        The flags' values.

    Returns
    -------
    dict of str to str
        Field (``digital.period``) -> flag.
    """
    values = {"period": period, "delay": delay, "loss": loss, "policy": policy}
    return {f"digital.{k}": _SAMPLED[k] for k, v in values.items() if v is not None}


__all__ = ["digital_flags", "DEPRECATED", "FLAGS", "flags_named", "flags_of"]
