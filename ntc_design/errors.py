"""The one error type a user sees for bad input."""


class InputError(ValueError):
    """Bad input: a file, matrix, label or parameter that is wrong.

    The message is one line that names the file and the edge or field and says what is
    wrong; the CLI prints it and exits with code 2.
    """


def require_positive(name: str, value, integer: bool = False) -> None:
    """Raise InputError unless ``value`` is a finite positive number (an integer if asked)."""
    import math

    bad = (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or value <= 0
    )
    if integer:
        bad = bad or not float(value).is_integer()
    if bad:
        kind = "a positive integer" if integer else "a positive number"
        raise InputError(f"{name}: must be {kind}, got {value!r}")
