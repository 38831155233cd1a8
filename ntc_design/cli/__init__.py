"""The ``ntc`` command line: :func:`run` is the program, :func:`main` runs it on a list of
arguments (what the tests call)."""

from .program import main, run

__all__ = ["main", "run"]
