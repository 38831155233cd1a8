"""Readers of certificate fields: each value read from a file is type- and range-checked
and a malformed one raises one ``InputError`` line naming the field."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from .format import MAX_SCHEDULE


def need(doc: dict, key: str, typ: type | tuple, where: str) -> Any:
    """A required field of the given JSON type (a bool is not a number).

    Parameters
    ----------
    doc : dict
        The object holding it.
    key : str
        The field.
    typ : type or tuple of type
        The accepted types.
    where : str
        The object, for messages.

    Returns
    -------
    Any
        The value.

    Raises
    ------
    InputError
        Missing, not an object, or of the wrong type.
    """
    if not isinstance(doc, dict):
        raise InputError("expected an object", field=where)
    if key not in doc:
        raise InputError(f"missing field '{key}'", field=where)
    v = doc[key]
    if isinstance(v, bool) and bool not in (typ if isinstance(typ, tuple) else (typ,)):
        raise InputError(f"field '{key}' has the wrong type (bool)", field=where)
    if not isinstance(v, typ):
        raise InputError(f"field '{key}' has the wrong type ({type(v).__name__})", field=where)
    return v


def number(x: Any, where: str) -> float:
    """A finite JSON number as a float.

    Parameters
    ----------
    x : Any
        The value.
    where : str
        The field, for messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a number, too large for a double, or not finite.
    """
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise InputError(f"expected a number, got {type(x).__name__}", field=where)
    try:
        v = float(x)
    except OverflowError:
        raise InputError("number too large", field=where) from None
    if not math.isfinite(v):
        raise InputError("must be finite", field=where)
    return v


def vector(x: Any, n: int, where: str) -> np.ndarray:
    """A list of n finite numbers.

    Parameters
    ----------
    x : Any
        The value.
    n : int
        Its length.
    where : str
        The field, for messages.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    InputError
        Not a list of n numbers.
    """
    if not isinstance(x, list) or len(x) != n:
        raise InputError(f"expected a list of {n} numbers", field=where)
    return np.array([number(v, where) for v in x], dtype=float)


def matrix(x: Any, n: int, where: str) -> np.ndarray:
    """An n×n matrix of finite numbers (shape checked before anything is allocated).

    Parameters
    ----------
    x : Any
        The field's value.
    n : int
        The size.
    where : str
        The field, for messages.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    InputError
        Not an n×n matrix of finite numbers.
    """
    if (
        not isinstance(x, list)
        or len(x) != n
        or any(not isinstance(r, list) or len(r) != n for r in x)
    ):
        raise InputError(f"expected a {n}x{n} matrix", field=where)
    for r in x:
        for v in r:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise InputError("non-numeric entry", field=where)
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError("non-numeric or too large entry", field=where) from None
    if not np.all(np.isfinite(a)):
        raise InputError("non-finite entry", field=where)
    return a


def finite_number(x: Any) -> float | None:
    """A JSON number as a finite float, else None (a bool, a string, NaN, or an integer
    beyond any double).

    Parameters
    ----------
    x : Any
        A value read from a certificate.

    Returns
    -------
    float or None
    """
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    try:
        xf = float(x)
    except OverflowError:
        return None
    return xf if math.isfinite(xf) else None


def parse_schedule(subject: dict, where: str) -> tuple[tuple[str, float], ...]:
    """A switching subject's schedule: 1 to ``MAX_SCHEDULE`` entries ``{mode, duration}``
    with positive finite durations.

    Parameters
    ----------
    subject : dict
        The certificate's subject.
    where : str
        Its name, for messages.

    Returns
    -------
    tuple of (str, float)

    Raises
    ------
    InputError
        A malformed schedule.
    """
    sched = need(subject, "schedule", list, where)
    if not sched or len(sched) > MAX_SCHEDULE:
        raise InputError(f"expected 1 to {MAX_SCHEDULE} entries", field=f"{where}.schedule")
    out = []
    for k, item in enumerate(sched):
        w = f"{where}.schedule[{k}]"
        if not isinstance(item, dict) or set(item) != {"mode", "duration"}:
            raise InputError("expected {mode, duration}", field=w)
        if not isinstance(item["mode"], str):
            raise InputError("expected a mode name", field=f"{w}.mode")
        t = number(item["duration"], f"{w}.duration")
        if not 0 < t < 1e300:
            raise InputError("must be positive and finite", field=f"{w}.duration")
        out.append((item["mode"], t))
    return tuple(out)


__all__ = [
    "finite_number",
    "matrix",
    "need",
    "number",
    "parse_schedule",
    "vector",
]
