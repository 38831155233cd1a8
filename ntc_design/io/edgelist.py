"""A compact file format for big networks: a NumPy ``.npz`` edge list.

A topology file in YAML/JSON spends a dict per edge; a 100,000-edge network reads in
seconds. The ``.npz`` form holds plain arrays (read with ``allow_pickle=False``: nothing
in the file can execute code)::

    format   "ntc-design/edge-list" (a 0-d string array)
    version  1
    dim      d
    labels   (N,) int64 or unicode agent labels
    from     (E,) int64: index of the sending agent j (0-based, into labels)
    to       (E,) int64: index of the receiving agent i
    weights  (E, d, d) float64: A_ij, the weight of the edge j -> i
    name     optional 0-d string

Write one with ``ntc generate`` (to an ``.npz`` file) or :func:`write_npz`; every command
that reads a topology file accepts it. Sizes are bounded (:data:`MAX_AGENTS`,
:data:`MAX_EDGES`, :data:`MAX_DIM`); a wrong array gives one line naming the file and
the array.
"""

from __future__ import annotations

import re
import unicodedata
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .outputs import atomic_path

FORMAT = "ntc-design/edge-list"
VERSION = 1

#: Size limits shared by every topology file (``files`` reads them from here).
MAX_DIM = 1000  # size of one weight matrix (d x d)
MAX_AGENTS = 10**6
MAX_EDGES = 50_000_000
#: Declared uncompressed size of all arrays (zip headers; zipfile checks them on read).
MAX_NPZ_BYTES = 2 * 2**30
KEYS = {"format", "version", "dim", "labels", "from", "to", "weights", "name"}


_CANONICAL_INT = re.compile(r"0|-?[1-9][0-9]{0,17}")  # ASCII, no sign +, no leading zero
_NUMBER_LIKE = re.compile(r"\s*[+-]?\d+\s*")  # \d: any script's digits, as int() reads


def label_from_text(text: str) -> int | str:
    """An agent label read from text (a CSV cell, a MATLAB string): an integer when the
    text is one in canonical ASCII form (``7``, ``-3``, ``0``), else the text as written
    (``"01"``, ``"+1"``, ``"١"`` stay strings: no two spellings become one number).

    Parameters
    ----------
    text : str
        The label as written.

    Returns
    -------
    int or str
    """
    return int(text) if _CANONICAL_INT.fullmatch(text) else text


def _spelled(t: str) -> str:
    """A label for a message: as written, with its code points when they are not ASCII
    (``'é' (U+0065 U+0301)``: two labels that print alike read apart)."""
    if t.isascii():
        return repr(t)
    return f"{t!r} ({' '.join(f'U+{ord(c):04X}' for c in t[:12])})"


def check_label_spellings(texts, what: str) -> tuple:
    """The agent labels as every reader keeps them: text in Unicode NFC (``"e\\u0301"``
    is ``"é"``), after refusing labels that look the same but are different agents: a
    label with surrounding spaces (``"a "`` beside ``"a"``), two labels equal in NFC, and
    two spellings of one number (``1`` and ``01``, ``+1``, ``-0``/``0``, ``١``: read as
    integers they would be the same agent; as written they are two). A user who meant
    two agents renames one; either way it is bad input. The one check of every reader
    (YAML, time-varying YAML, CSV, ``.npz``, ``.mat``).

    Parameters
    ----------
    texts : iterable of int or str
        The distinct labels as written (integers pass as they are).
    what : str
        The file and field, for the message.

    Returns
    -------
    tuple
        The labels in the given order, text in NFC.

    Raises
    ------
    InputError
        Naming both labels (or the one with surrounding spaces).
    """
    out = []
    forms: dict[str, str] = {}  # NFC, spaces stripped -> the label as written
    seen: dict[int, str] = {}
    for t in texts:
        if not isinstance(t, str):
            out.append(t)
            continue
        if not t.isascii() and any("\ud800" <= c <= "\udfff" for c in t):
            # a lone surrogate (JSON's "\ud800") is no character: it cannot be printed,
            # written to a file or emitted as code
            raise InputError(f"label {t!r} holds a lone surrogate (not a character)", field=what)
        n = t if t.isascii() else unicodedata.normalize("NFC", t)
        key = n.strip()
        if key in forms and forms[key] != t:
            how = "surrounding spaces" if forms[key].strip() == t.strip() else "Unicode form"
            raise InputError(
                f"labels {_spelled(forms[key])} and {_spelled(t)} differ only by "
                f"{how}: they look like one agent; write each agent's label one way",
                field=what,
            )
        forms[key] = t
        if key != n:
            raise InputError(
                f"label {t!r} has surrounding spaces (write it as {key!r})", field=what
            )
        out.append(n)
        if len(t) > 40 or not _NUMBER_LIKE.fullmatch(t):
            continue
        try:
            v = int(t)
        except ValueError:
            continue
        if v in seen and seen[v] != t:
            raise InputError(
                f"labels {seen[v]!r} and {t!r} are two spellings of the number {v}; "
                "write each agent's label one way (or use names that are not numbers)",
                field=what,
            )
        seen.setdefault(v, t)
    return tuple(out)


@dataclass(frozen=True)
class EdgeListData:
    """A topology as arrays: edge k is ``cols[k] -> rows[k]`` with weight ``w[k]``."""

    name: str | None
    dim: int
    labels: tuple
    rows: np.ndarray
    cols: np.ndarray
    w: np.ndarray
    source: str | None
    uncertainty: np.ndarray | None = None  # per edge ρ_e (NaN: none), from a CSV column or MAT
    loss: np.ndarray | None = None  # per edge p_e (NaN: none), from a CSV column


def read_npz(path: str | Path) -> EdgeListData:
    """Read and check an edge-list ``.npz`` file (structure only; symmetry and sign of
    the weights are the model's business).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.npz`` file.

    Returns
    -------
    EdgeListData
        Labels, d and the edge arrays.

    Raises
    ------
    InputError
        An unreadable file, arrays too large, an unknown or missing array, or arrays of
        the wrong type, shape or range.
    """
    src = str(path)

    def bad(field: str, msg: str) -> InputError:
        return InputError(f"{msg}", field=f"{src}: {field}")

    if not Path(path).is_file():
        raise InputError("no such file", field=src)
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError):
        raise InputError("not a readable .npz edge list", field=src) from None
    with z:
        total = sum(i.file_size for i in z.zip.infolist())
        if total > MAX_NPZ_BYTES:
            raise InputError(
                f"arrays take {total / 2**30:.1f} GiB uncompressed; at most "
                f"{MAX_NPZ_BYTES / 2**30:.0f} GiB",
                field=src,
            )
        keys = set(z.files)
        unknown = keys - KEYS
        if unknown:
            raise bad(sorted(unknown)[0], "unknown array")
        for k in ("format", "dim", "labels", "from", "to", "weights"):
            if k not in keys:
                raise bad(k, "missing array")
        try:
            arrs = {k: z[k] for k in sorted(keys)}  # each member read once
            for k, a in arrs.items():  # a member that is not a .npy array reads back as bytes
                if not isinstance(a, np.ndarray):
                    raise bad(k, "not a .npy array")
            fmt = arrs["format"]
            if fmt.shape != () or str(fmt) != FORMAT:
                raise bad("format", f"must be {FORMAT!r}")
            if "version" in keys and int(arrs["version"]) != VERSION:
                raise bad("version", f"unsupported version (this reader knows {VERSION})")
            dim_a = arrs["dim"]
            if dim_a.shape != () or dim_a.dtype.kind not in "iu":
                raise bad("dim", "must be one integer")
            dim = int(dim_a)
            if not 1 <= dim <= MAX_DIM:
                raise bad("dim", f"must be in 1..{MAX_DIM}, got {dim}")
            labels_a = arrs["labels"]
            if labels_a.ndim != 1 or labels_a.dtype.kind not in "iuU":
                raise bad("labels", "must be a 1-d array of integers or strings")
            n = labels_a.shape[0]
            if not 1 <= n <= MAX_AGENTS:
                raise bad("labels", f"needs 1..{MAX_AGENTS} agents, got {n}")
            labels = tuple(labels_a.tolist())
            if len({str(x) for x in labels}) != n:
                raise bad("labels", "agent labels must be unique")
            if labels_a.dtype.kind == "U":
                labels = check_label_spellings(labels, f"{src}: labels")
            cols, rows, w = arrs["from"], arrs["to"], arrs["weights"]
            name = None
            if "name" in keys:
                nm = arrs["name"]
                if nm.shape != () or nm.dtype.kind != "U":
                    raise bad("name", "must be one string")
                name = str(nm)
        except InputError:
            raise
        except (ValueError, TypeError, KeyError, zipfile.BadZipFile):
            raise InputError("not a readable .npz edge list", field=src) from None
    rows, cols = _check_edges(bad, rows, cols, w, n, dim, labels)
    return EdgeListData(name, dim, labels, rows, cols, np.asarray(w, dtype=float), src)


def _check_edges(bad, rows, cols, w, n: int, dim: int, labels) -> tuple[np.ndarray, np.ndarray]:
    """The edge arrays of an .npz edge list: shapes, types, agent indices in range, no
    edge twice; (rows, cols) as int64."""
    for k, a in (("from", cols), ("to", rows)):
        if a.ndim != 1 or a.dtype.kind not in "iu":
            raise bad(k, "must be a 1-d integer array")
    e = cols.shape[0]
    if rows.shape[0] != e:
        raise bad("to", f"has {rows.shape[0]} entries but 'from' has {e}")
    if e > MAX_EDGES:
        raise bad("from", f"at most {MAX_EDGES} edges, got {e}")
    if w.shape != (e, dim, dim) or w.dtype.kind != "f":
        raise bad("weights", f"must be a float array of shape ({e}, {dim}, {dim}), got {w.shape}")
    rows = rows.astype(np.int64)
    cols = cols.astype(np.int64)
    for k, a in (("from", cols), ("to", rows)):
        out = np.flatnonzero((a < 0) | (a >= n))
        if out.size:
            raise bad(f"{k}[{out[0]}]", f"agent index {a[out[0]]} out of range 0..{n - 1}")
    key = rows * n + cols
    order = np.argsort(key, kind="stable")
    dup = np.flatnonzero(np.diff(key[order]) == 0)
    if dup.size:
        k = order[dup[0] + 1]
        raise bad(f"edge {labels[cols[k]]}->{labels[rows[k]]}", "duplicated edge")
    return rows, cols


def write_npz(
    path: str | Path,
    labels,
    dim: int,
    rows: np.ndarray,
    cols: np.ndarray,
    w: np.ndarray,
    name: str | None = None,
) -> None:
    """Write an edge list as ``.npz``, atomically (nothing half-written).

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.
    labels : sequence of int or str
        The agent labels.
    dim : int
        The weight size d.
    rows, cols : numpy.ndarray
        0-based target and source of each edge (edge k is ``cols[k] -> rows[k]``).
    w : numpy.ndarray
        The weights, shape (E, d, d).
    name : str, optional
        The topology's name.
    """
    p = Path(path)
    lab = (
        np.array([str(x) for x in labels])
        if any(isinstance(x, str) for x in labels)
        else np.array(labels, dtype=np.int64)
    )
    arrays = {
        "format": np.array(FORMAT),
        "version": np.array(VERSION),
        "dim": np.array(int(dim)),
        "labels": lab,
        "from": np.asarray(cols, dtype=np.int64),
        "to": np.asarray(rows, dtype=np.int64),
        "weights": np.ascontiguousarray(w, dtype=float),
    }
    if name is not None:
        arrays["name"] = np.array(str(name))
    with atomic_path(p) as tmp:
        np.savez_compressed(tmp, **arrays)  # type: ignore[arg-type]  # numpy stub: **kwds typed as allow_pickle
