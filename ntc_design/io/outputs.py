"""Writing outputs so that a reader never sees half of them.

- :func:`write_atomic` writes one file: a temporary file beside the target, flushed and
  synced, then renamed over it (a rename is atomic on POSIX). :func:`atomic_path` is the
  same for writers that want a file name (NumPy, pandas, Parquet). Both remove their
  temporary file whatever fails (a folder in the target's place, a full disk, Ctrl-C), so
  no ``.tmp`` is ever left behind; every file the package writes whole goes through them.
- :func:`output_folder` makes a folder all-or-nothing: everything is written into a
  temporary folder beside the target, which replaces the target only when the block
  finishes without an exception (Ctrl-C included). An interrupted run leaves the old
  folder as it was (or no folder) and no stray temporary files.
- :func:`check_output_folder` refuses, before any work, a target that is an existing
  file, a folder that holds files other than the outputs being replaced, or a place
  that cannot be written.

Errors are :class:`~ntc_design.errors.InputError`: one line naming the option (``out``: the parameter, as
the command line's flag at the command line) and the path.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from ..errors import InputError, one_line


def _oserror(option: str, path: Path, exc: OSError) -> InputError:
    why = exc.strerror or exc.__class__.__name__
    return InputError(f"cannot write {one_line(str(path))!r} ({why})", field=option, option=True)


def check_output_file(
    path: str | Path, option: str = "out", suffixes: tuple[str, ...] = ()
) -> Path:
    """Refuse, before any work, a file target that cannot be written as a regular file: a
    folder, an existing device, FIFO or socket (``/dev/full``, a named pipe: the rename
    that writes the file would replace the node), a missing or read-only folder, or a
    suffix other than ``suffixes``.

    Parameters
    ----------
    path : str or Path
        The file to be written.
    option : str
        Named in the message.
    suffixes : tuple of str
        The suffixes accepted (lower case, with the dot); empty: any.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        ``path`` is a folder or not a regular file, its folder is missing or not
        writable, or its suffix is not one of ``suffixes``.
    """
    p = Path(path)
    shown = repr(one_line(str(p)))
    if suffixes and p.suffix.lower() not in suffixes:
        listed = (
            ", ".join(suffixes[:-1]) + " or " + suffixes[-1] if len(suffixes) > 1 else suffixes[0]
        )
        raise InputError(f"{shown}: expected a {listed} file", field=option, option=True)
    if p.is_dir():
        raise InputError(f"{shown} is a folder, expected a file name", field=option, option=True)
    if os.path.lexists(p) and not p.is_file():
        raise InputError(
            f"{shown} exists and is not a regular file (a device, pipe, socket or "
            "broken link); choose a file name",
            field=option,
            option=True,
        )
    parent = p.parent
    if not parent.is_dir():
        raise InputError(
            f"the folder {one_line(str(parent))!r} does not exist", field=option, option=True
        )
    _probe(parent, option)
    return p


def _probe(folder: Path, option: str) -> None:
    """Refuse a folder nothing can be created in, by creating (and removing) an empty
    temporary folder there: permission bits do not say it for root, a read-only mount or
    /proc, and a long run must not find out only at its end."""
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(
            f"the folder {one_line(str(folder))!r} is not writable", field=option, option=True
        )
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".ntc-probe.", dir=folder))
    except OSError as exc:
        why = exc.strerror or exc.__class__.__name__
        raise InputError(
            f"cannot write in the folder {one_line(str(folder))!r} ({why})",
            field=option,
            option=True,
        ) from None


@contextlib.contextmanager
def atomic_path(path: str | Path, option: str = "out") -> Iterator[Path]:
    """A temporary file beside ``path`` to write (its name ends like ``path``'s, so NumPy
    adds no second ``.npz``); when the block finishes it is synced and renamed over
    ``path``, and on any failure, the rename's included, it is removed.

    Parameters
    ----------
    path : str or Path
        The file to write.
    option : str
        Named in an error message.

    Yields
    ------
    Path
        The temporary file (empty) to write to.

    Raises
    ------
    InputError
        ``path`` is a folder, or its folder is missing or cannot be written.
    """
    p = check_output_file(path, option)
    try:
        fd, name = tempfile.mkstemp(prefix=f".{p.name}.", suffix=f".tmp{p.suffix}", dir=p.parent)
    except OSError as exc:
        raise _oserror(option, p, exc) from None
    tmp = Path(name)
    try:
        try:
            os.fchmod(fd, 0o666 & ~_umask())  # mkstemp makes 0600: a shared file, not a secret
        finally:
            os.close(fd)
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, p)
    except OSError as exc:
        raise _oserror(option, p, exc) from None
    finally:  # after a successful rename there is nothing left to remove
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def write_atomic(path: str | Path, data: str | bytes, option: str = "out") -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` through a temporary file and a rename
    (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
        The file to write.
    data : str or bytes
        Its whole content (text is written as UTF-8).
    option : str
        Named in an error message.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        When the folder is missing or not writable, or the path is a folder.
    """
    raw = data.encode("utf-8") if isinstance(data, str) else data
    with atomic_path(path, option) as tmp:
        tmp.write_bytes(raw)
    return Path(path)


def check_output_folder(
    path: str | Path, replaceable: Iterable[str] | None = (), option: str = "out"
) -> Path:
    """Check, before any work, that ``path`` can become an output folder.

    Parameters
    ----------
    path : str or Path
        The output folder asked for.
    replaceable : iterable of str or None
        Names an existing folder may hold (the outputs of an earlier run, which will be
        replaced). Anything else in it is the user's: the folder is refused. None: the
        folder's content is not checked (the caller writes single files into it).
    option : str
        Named in error messages.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        When ``path`` is a file, holds other files, or its parent is missing or not
        writable.
    """
    p = Path(path)
    shown = repr(one_line(str(p)))
    if os.path.lexists(p) and not p.is_dir():
        what = "an existing file" if p.is_file() else "not a folder (a device, pipe or link)"
        raise InputError(f"{shown} is {what}, expected a folder", field=option, option=True)
    parent = p.resolve().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent  # missing folders are made
    if not parent.is_dir():
        raise InputError(
            f"{one_line(str(parent))!r} in {shown} is a file, not a folder",
            field=option,
            option=True,
        )
    _probe(parent, option)
    if p.is_dir() and replaceable is not None:
        allowed = set(replaceable)
        try:
            other = sorted(x.name for x in p.iterdir() if x.name not in allowed)
        except OSError as exc:
            raise _oserror(option, p, exc) from None
        if other:
            raise InputError(
                f"{shown} exists and holds other files ({one_line(other[0])!r}"
                + (f" and {len(other) - 1} more" if len(other) > 1 else "")
                + "); choose a new folder",
                field=option,
                option=True,
            )
    return p


@contextlib.contextmanager
def output_folder(
    path: str | Path, replaceable: Iterable[str] = (), option: str = "out"
) -> Iterator[Path]:
    """All-or-nothing output folder: yields a temporary folder beside ``path``; on
    success it replaces ``path`` (an earlier folder is moved aside, then removed); on any
    exception it is removed and ``path`` is left as it was.

    Parameters
    ----------
    path : str or Path
        The folder to create or replace.
    replaceable : iterable of str
        See :func:`check_output_folder`.
    option : str
        Named in error messages.

    Yields
    ------
    Path
        The temporary folder to write into.

    Raises
    ------
    InputError
        See :func:`check_output_folder`; also when a write fails (read-only, disk full).
    """
    target = check_output_folder(path, replaceable, option)
    parent = target.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise _oserror(option, target, exc) from None
    try:
        try:
            yield tmp
        except OSError as exc:
            raise _oserror(option, target, exc) from None
        os.chmod(tmp, 0o777 & ~_umask())
        old = None
        try:
            if target.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=parent))
                os.rmdir(old)
                os.rename(target, old)
            try:
                os.rename(tmp, target)
            except BaseException:
                if old is not None:
                    os.rename(old, target)
                    old = None
                raise
        except OSError as exc:
            raise _oserror(option, target, exc) from None
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


__all__ = [
    "atomic_path",
    "exit_process",
    "check_output_file",
    "check_output_folder",
    "json_text",
    "output_folder",
    "write_atomic",
]


#: A top-level value whose compact JSON is longer than this (characters) is written on one
#: line by :func:`json_text`.
JSON_INDENT_MAX_CHARS = 200_000


def json_text(doc: dict) -> str:
    """``doc`` as JSON text for people: one top-level key per line, each value indented
    (as ``json.dumps(doc, indent=1)``) unless its compact form is longer than
    ``JSON_INDENT_MAX_CHARS``, then on one line. ``json``'s indenting encoder is pure
    Python; its compact one is C: a 10⁵-agent run's 72 MB summary took 3.4 s, 1.4 s so.

    Parameters
    ----------
    doc : dict
        A JSON-ready mapping (see :func:`ntc_design.io.files.jsonable`).

    Returns
    -------
    str
        The text, with a final newline.

    Examples
    --------
    >>> print(json_text({"a": [1, 2], "b": {"c": None}}), end="")
    {
     "a": [
      1,
      2
     ],
     "b": {
      "c": null
     }
    }
    """
    parts = []
    for key, value in doc.items():
        text = json.dumps(value, ensure_ascii=False)
        if len(text) <= JSON_INDENT_MAX_CHARS:
            text = json.dumps(value, indent=1, ensure_ascii=False).replace("\n", "\n ")
        parts.append(f" {json.dumps(str(key), ensure_ascii=False)}: {text}")
    return "{\n" + ",\n".join(parts) + "\n}\n" if parts else "{}\n"


def exit_process(code: str | int | None) -> None:
    """End the process with ``code`` without the interpreter's teardown of its modules
    (about 0.3 s once Numba and SciPy are loaded): the exit handlers run and the streams
    are flushed first. A flush that fails is the command's failure (1 for a closed pipe,
    2 and one line otherwise). With another thread or a child process alive, under a
    profiler or tracer (which write at exit), or for a code that is not a number, the
    ordinary exit is taken.

    Parameters
    ----------
    code : int, str or None
        The exit code (``sys.exit``'s argument).
    """
    import atexit
    import multiprocessing as mp
    import sys
    import threading

    if (
        not isinstance(code, int)
        or sys.getprofile() is not None  # a profiler (python -m cProfile) writes at exit
        or sys.gettrace() is not None  # so does a coverage tracer
        or threading.active_count() > 1
        or mp.active_children()
    ):
        sys.exit(code)
    try:
        atexit._run_exitfuncs()
    except KeyboardInterrupt:
        code = 130
    # what is still buffered is written now: a failure is the command's failure, as main()
    # reports one during the command (1 for a closed pipe, 2 and one line otherwise)
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:  # started with the stream closed
            continue
        try:
            stream.flush()
        except BrokenPipeError:
            code = code or 1
        except (OSError, ValueError) as exc:
            code = code or 2
            if name == "stdout" and sys.stderr is not None:
                try:
                    print(f"error: standard output: {exc.__class__.__name__}: {exc}",
                          file=sys.stderr, flush=True)  # fmt: skip
                except (OSError, ValueError):
                    pass
    os._exit(code)
