"""The one error type a user sees for bad input."""


class InputError(ValueError):
    """Bad input: a file, matrix, label or parameter that is wrong.

    The message is one line that names the file and the edge or field and says what is
    wrong; the CLI prints it and exits with code 2.
    """


def where(source: str | None, field: str) -> str:
    """Prefix naming the file (if any) and the field an error concerns."""
    return f"{source}: {field}" if source else field
