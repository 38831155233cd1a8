"""Topologies made elsewhere: CSV edge lists and MATLAB block matrices.

**CSV** (``.csv``): a header row ``from, to, a11, a12, …, add`` (the d² entries of A_ij row
by row, d from the number of columns), then one edge per row. An edge from j to i carries
A_ij, as in the YAML files. Labels are integers or strings; the agents are the labels in
the order they first appear. Read by NumPy's C reader, bounded like every file (size, rows,
numbers); an error names the row (the header is row 1).

**MATLAB** (``.mat``, read by :func:`scipy.io.loadmat`): a variable ``A``, the
(N·d) × (N·d) block matrix (dense or sparse) whose block (i, j) is A_ij, a scalar ``dim``
and optionally ``labels`` (a cell array of strings). A non-zero block (i, j) with i ≠ j is
the edge j → i; a diagonal block must be zero (no self-loops). :func:`write_mat` writes
arrays for MATLAB (what ``ProtocolDesign.to_mat`` uses).
"""

from __future__ import annotations

import csv
import math
import os
import re
import stat
import struct
import warnings
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sparse

from ..errors import NUMBER_TEXT, InputError, Option, format_bytes
from ..numerics.memory import available_memory
from .edgelist import (
    MAX_AGENTS,
    MAX_DIM,
    MAX_EDGES,
    EdgeListData,
    check_label_spellings,
    label_from_text,
)
from .outputs import atomic_path

MAX_CSV_BYTES = 2 * 2**30  # a 10⁶-agent edge list with d = 3 is about 120 MB
MAX_MAT_BYTES = 2 * 2**30  # the file (what its variables need is bounded by the memory)
CSV_MAX_DIM = 100  # 10⁴ weight columns; larger weights belong in .npz or .mat
MAX_HEADER_CHARS = 2**20


def _bounded(p: Path, limit: float) -> Path:
    """The file, refused in one line when it cannot be read, is not a regular file (a
    folder, ``/dev/zero``, a FIFO: no end, or no size to bound) or is larger than
    ``limit``."""
    try:
        st = os.stat(p)
    except OSError as exc:
        raise InputError(
            f"cannot read ({exc.strerror or exc.__class__.__name__})", field=str(p)
        ) from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError("is a folder, expected a topology file", field=str(p))
    if not stat.S_ISREG(st.st_mode):
        raise InputError("not a regular file (a device, pipe or socket)", field=str(p))
    if st.st_size > limit:
        raise InputError(
            f"{st.st_size / 2**30:.1f} GiB; at most {limit / 2**30:.0f} GiB", field=str(p)
        )
    return p


#: What loadmat makes of each MATLAB class, bytes per element (4: char, as numpy's UCS-4;
#: 6 to 15: double, single, int8, uint8, int16, uint16, int32, uint32, int64, uint64).
_MAT_ITEM_BYTES = {4: 4, 6: 8, 7: 4, 8: 1, 9: 1, 10: 2, 11: 2, 12: 4, 13: 4, 14: 8, 15: 8}
_MAT_CLASSES = {1: "cell", 2: "struct", 3: "object", 4: "char", 5: "sparse", 6: "double"}
#: The variables read_mat loads (loadmat skips the others without inflating them).
_MAT_VARIABLES = ("A", "dim", "labels", "uncertainty")
#: A variable's tags, flags, dimensions and name come first: this much inflated output is
#: enough to read them (a name is at most 63 characters, MATLAB's limit; dimensions few).
_MAT_HEAD = 4096


def _mat_subelement(buf: bytes, pos: int, order: str) -> tuple[int, bytes, int] | None:
    """(type, data, next position) of the MATLAB 5 data element at ``pos`` (the small
    format packs type and size in one word), or None past the end of ``buf``."""
    if pos + 8 > len(buf):
        return None
    word, nbytes = struct.unpack(order + "II", buf[pos : pos + 8])
    if word >> 16:  # small data element: 2-byte size, 2-byte type, up to 4 bytes of data
        size = word >> 16
        return word & 0xFFFF, buf[pos + 4 : pos + 4 + size], pos + 8
    end = pos + 8 + nbytes
    if end > len(buf):
        return None
    return word, buf[pos + 8 : end], end + (-nbytes % 8)


def _mat_header(head: bytes, order: str) -> tuple[str, int, int, tuple[int, ...], int] | None:
    """(name, class, nzmax, dimensions, declared element bytes) of a variable from the
    first bytes of its miMATRIX element, or None when they are not there."""
    if len(head) < 8:
        return None
    kind, total = struct.unpack(order + "II", head[:8])
    if kind != 14:
        return None
    flags = _mat_subelement(head, 8, order)
    dims = flags and _mat_subelement(head, flags[2], order)
    name = dims and _mat_subelement(head, dims[2], order)
    if not (flags and dims and name) or len(flags[1]) < 8:
        return None
    word, nzmax = struct.unpack(order + "II", flags[1][:8])
    count = len(dims[1]) // 4
    shape = struct.unpack(order + f"{count}i", dims[1][: 4 * count])
    return name[1].decode("latin-1"), word & 0xFF | (word & 0x800) << 8, nzmax, shape, total


def _mat_memory(cls: int, nzmax: int, shape: tuple[int, ...], total: int) -> float:
    """The bytes loadmat allocates for a variable, from its declared class and sizes (the
    stored data may be of a smaller type: a double matrix of zeros is stored as bytes)."""
    complex_ = 2 if cls & 0x80000 else 1
    cls &= 0xFF
    if cls == 5:  # sparse: values and row indices per non-zero, a pointer per column
        cols = shape[1] if len(shape) > 1 else 1
        return float(nzmax) * (8 * complex_ + 8) + (max(cols, 0) + 1) * 8.0
    if cls in _MAT_ITEM_BYTES:
        return float(math.prod(max(x, 0) for x in shape)) * _MAT_ITEM_BYTES[cls] * complex_
    # a cell, struct or object: a numpy object per element, about 3x its stored header
    return 3.0 * total


def _mat_inflated_bytes(p: Path, limit: float) -> None:
    """Refuse a MATLAB 5 file whose variables, as loaded, need more than ``limit`` bytes by
    their declared classes and dimensions (a 1.7 MB file of zeros can declare a 1.8 GB
    matrix), read from each variable's header before its data is inflated; a variable that
    inflates past its declared size, or declares more than its class and dimensions
    hold, is refused as corrupt. Only the variables :func:`read_mat` loads count; the
    others are skipped as loadmat skips them."""
    with open(p, "rb") as fh:
        head = fh.read(128)
        if len(head) < 128 or head[126:128] not in (b"IM", b"MI"):
            return  # not MATLAB 5 (v4 is never compressed; loadmat refuses the rest)
        order = "<" if head[126:128] == b"IM" else ">"
        need = 0.0
        while tag := fh.read(8):
            if len(tag) < 8:
                return
            kind, nbytes = struct.unpack(order + "II", tag)
            if kind not in (14, 15):  # not a top-level variable: loadmat refuses the file
                return
            start = fh.tell()
            z = zlib.decompressobj() if kind == 15 else None
            out = bytearray(tag if z is None else b"")
            left = nbytes
            while len(out) < _MAT_HEAD and left > 0:  # the header: a bounded prefix
                data = fh.read(min(left, 2**16))
                if not data:
                    break
                left -= len(data)
                if z is None:
                    out += data
                    continue
                try:
                    out += z.decompress(data, _MAT_HEAD)
                    while z.unconsumed_tail and len(out) < _MAT_HEAD:
                        out += z.decompress(z.unconsumed_tail, _MAT_HEAD)
                except zlib.error as exc:
                    raise InputError(
                        f"not a readable MATLAB file (a compressed variable: {exc})", field=str(p)
                    ) from None
                if z.unconsumed_tail:
                    break  # the header is in: the rest is data
            info = _mat_header(bytes(out), order)
            if info is None and len(out) >= _MAT_HEAD:  # loadmat would read on: refuse
                raise InputError(
                    f"not a readable MATLAB file (a variable's header is longer than "
                    f"{_MAT_HEAD} bytes)",
                    field=str(p),
                )
            if info is not None and info[0] in _MAT_VARIABLES:
                name, cls, nzmax, shape, total = info
                mem = _mat_memory(cls, nzmax, shape, total)
                if cls & 0xFF in _MAT_ITEM_BYTES or cls & 0xFF == 5:
                    if total > mem + _MAT_HEAD:
                        raise InputError(
                            f"declares {format_bytes(total)} of data for a "
                            f"{'×'.join(map(str, shape))} array of {format_bytes(mem)} "
                            "(a corrupt MATLAB file)",
                            field=f"{p}: {name}",
                        )
                need += mem
                if need > limit:
                    what = _MAT_CLASSES.get(cls & 0xFF, "numeric")
                    raise InputError(
                        f"a {'×'.join(map(str, shape))} {what} array needs "
                        f"{format_bytes(mem)} once loaded (from a "
                        f"{format_bytes(os.path.getsize(p))} file), more than the "
                        f"{format_bytes(limit)} allowed here (a sixth of the memory available: "
                        "free, within ulimit -v, or NTC_AVAILABLE_MEMORY); store a large "
                        "network as a sparse A or as .npz",
                        field=f"{p}: {name}",
                    )
                if z is not None:  # inflate the rest, counting: never past what it declares
                    got = len(out)
                    while not z.eof:
                        data = z.unconsumed_tail or fh.read(min(left, 2**20))
                        if not z.unconsumed_tail:
                            left -= len(data)
                        if not data:
                            break
                        try:
                            got += len(z.decompress(data, 2**20))
                        except zlib.error as exc:
                            raise InputError(
                                f"not a readable MATLAB file (a compressed variable: {exc})",
                                field=str(p),
                            ) from None
                        if got > total + 8:
                            raise InputError(
                                f"inflates past the {format_bytes(total)} it "
                                "declares (a corrupt MATLAB file)",
                                field=f"{p}: {name}",
                            )
            fh.seek(start + nbytes + (-nbytes % 8 if kind == 14 else 0))


def _labels_in_order(
    src: np.ndarray, dst: np.ndarray, where: Path
) -> tuple[tuple, np.ndarray, np.ndarray]:
    """Labels in order of first appearance (row by row, from before to) and the 0-based
    index of each end."""
    both = np.empty(2 * src.size, dtype=object)
    both[0::2], both[1::2] = src, dst
    uniq, first, inv = np.unique(both.astype(str), return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # position of each label by first appearance
    rank = np.empty(order.size, dtype=np.int64)
    rank[order] = np.arange(order.size)
    idx = rank[inv]
    texts = check_label_spellings([str(u) for u in uniq], f"{where}: from/to")
    labels = tuple(label_from_text(texts[k]) for k in order)
    return labels, idx[1::2], idx[0::2]


def _rows_and_fields(p: Path) -> tuple[np.ndarray, np.ndarray]:
    """(line number, fields) of every non-blank line after the header: commas counted in
    the bytes, vectorised; a file with quotes (a label holding a comma) by the csv module.
    A NUL byte is refused, naming its row (the C reader would end a field at it: ``1\\0``
    would read as 1)."""
    data = np.fromfile(p, dtype=np.uint8)
    nul = np.flatnonzero(data == 0)
    if nul.size:
        row = int(np.count_nonzero(data[: nul[0]] == ord("\n"))) + 1
        raise InputError(f"row {row}: a NUL byte", field=str(p))
    if np.any(data == ord('"')):
        with open(p, encoding="utf-8", errors="replace", newline="") as fh:
            got = [(k, len(row)) for k, row in enumerate(csv.reader(fh), 1) if row and k > 1]
        arr = np.array(got, dtype=np.int64).reshape(-1, 2)
        return arr[:, 0], arr[:, 1]
    ends = np.flatnonzero(data == ord("\n"))
    if data.size and data[-1] != ord("\n"):
        ends = np.append(ends, data.size)  # a last line without its newline
    starts = np.concatenate([[0], ends[:-1] + 1])
    # commas per line: each comma's line by its position among the line ends
    commas = np.flatnonzero(data == ord(","))
    fields = np.bincount(np.searchsorted(ends, commas), minlength=ends.size) + 1
    keep = np.ones(ends.size, dtype=bool)
    for k in np.flatnonzero(fields == 1).tolist():  # no comma: blank, or a wrong row
        if np.any(data[starts[k] : ends[k]] > ord(" ")):
            break  # a wrong row is reported; what follows it does not matter
        keep[k] = False  # a blank line is skipped, as by the reader
    line = np.arange(1, ends.size + 1)
    keep[0] = False  # the header
    return line[keep], fields[keep]


def _csv_columns(p: Path, cols: list[int], dtype, rows: int) -> np.ndarray:
    """Columns of the data rows by NumPy's C reader (quotes honoured, no comments)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "no data": a header-only file
        out = np.loadtxt(
            p, delimiter=",", skiprows=1, usecols=cols, dtype=dtype, ndmin=2, comments=None,
            quotechar='"', encoding="utf-8", max_rows=rows,
        )  # fmt: skip
    return out.reshape(-1, len(cols))


#: Optional columns after the weights, in either order: an edge's radius and its loss.
CSV_EXTRA_COLUMNS = ("uncertainty", "loss")


def _trailing(header: list[str]) -> list[str]:
    """The optional columns (:data:`CSV_EXTRA_COLUMNS`) at the end of the header."""
    out: list[str] = []
    for name in reversed(header[2:]):
        if name in CSV_EXTRA_COLUMNS and name not in out:
            out.insert(0, name)
        else:
            break
    return out


def _csv_header(p: Path) -> tuple[list[str], list[str], int]:
    """(header, the weight columns, d) from row 1, refused unless it is from, to, a11 … add."""
    with open(p, encoding="utf-8", errors="replace") as fh:
        line = fh.readline(MAX_HEADER_CHARS + 1)
    if len(line) > MAX_HEADER_CHARS:
        raise InputError(
            f"row 1: the header is longer than {MAX_HEADER_CHARS} characters "
            f"(at most d = {CSV_MAX_DIM} in a CSV file; use .npz or .mat for larger weights)",
            field=str(p),
        )
    header = [h.strip() for h in line.rstrip("\n\r").split(",")]
    if len(header) < 3 or header[:2] != ["from", "to"]:
        raise InputError(
            "row 1: the header must start with from, to (then a11 … add)", field=str(p)
        )
    k = len(header) - 2 - len(_trailing(header))
    d = int(round(k**0.5))
    if d * d != k:
        raise InputError(
            f"row 1: {k} weight columns; d² columns are needed (d = 1, 2, 3, …)", field=str(p)
        )
    if d > CSV_MAX_DIM:
        raise InputError(
            f"row 1: d = {d}; a CSV file holds at most d = {CSV_MAX_DIM} "
            "(use .npz or .mat for larger weights)",
            field=str(p),
        )
    want = [f"a{r}{c}" if d < 10 else f"a{r}_{c}" for r in range(1, d + 1) for c in range(1, d + 1)]
    if header[2 : 2 + k] != want:
        raise InputError(
            f"row 1: weight columns must be {', '.join(want[:4])}{' …' if k > 4 else ''}",
            field=str(p),
        )
    return header, want, d


def read_csv_edges(path: str | Path) -> EdgeListData:
    """Read a CSV edge list (see the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.csv`` file.

    Returns
    -------
    EdgeListData
        Labels in order of first appearance, d and the edge arrays.

    Raises
    ------
    InputError
        An unreadable or oversized file, a wrong header, a ragged row, a value that is not a
        finite number, more rows or agents than the limits, an edge listed twice; the
        message names the row.
    """
    p = _bounded(Path(path), MAX_CSV_BYTES)
    header, want, d = _csv_header(p)
    k = d * d
    lines, fields = _rows_and_fields(p)
    e = lines.size
    if e > MAX_EDGES:
        raise InputError(f"more than {MAX_EDGES} rows", field=str(p))
    wrong = np.flatnonzero(fields != len(header))
    if wrong.size:
        r = int(wrong[0])
        short = " (a short row)" if fields[r] < len(header) else ""
        raise InputError(
            f"row {lines[r]}: {fields[r]} fields, the header has {len(header)}{short}", field=str(p)
        )
    extra = _trailing(header)
    at = {name: len(header) - len(extra) + m for m, name in enumerate(extra)}
    try:
        text = _csv_columns(p, [0, 1] + list(at.values()), str, e)
        # numbers by the C reader: ASCII numerals only, no underscores
        w = _csv_columns(p, list(range(2, 2 + k)), np.float64, e).ravel()
    except (UnicodeDecodeError, ValueError, OSError) as exc:
        m = re.search(
            r"could not convert string '(.*)' to float64 at row (\d+), column (\d+)", str(exc)
        )
        if m is None:
            raise InputError(
                f"not a readable CSV table ({exc.__class__.__name__})", field=str(p)
            ) from None
        r, c, got = int(m.group(2)), int(m.group(3)) - 3, m.group(1).strip()
        what = f"= {got[:30]!r} is not a finite number" if got else "is empty (a short row?)"
        raise InputError(f"row {lines[r]}: {want[c]} {what}", field=str(p)) from None
    src, dst = text[:, 0], text[:, 1]
    for name, col in (("from", src), ("to", dst)):
        empty = np.flatnonzero(np.char.str_len(np.char.strip(col)) == 0)
        if empty.size:
            raise InputError(f"row {lines[empty[0]]}: '{name}' is empty", field=str(p))
    bad = np.flatnonzero(~np.isfinite(w))
    if bad.size:
        r, c = divmod(int(bad[0]), k)
        got = float(w[bad[0]])  # inf, nan: not NumPy's repr (np.float64(inf))
        raise InputError(
            f"row {lines[r]}: {want[c]} = {got!r} is not a finite number", field=str(p)
        )
    labels, rows, cols = _labels_in_order(np.char.strip(src), np.char.strip(dst), p)
    if len(labels) > MAX_AGENTS:
        raise InputError(f"{len(labels)} agents; at most {MAX_AGENTS}", field=str(p))
    key = rows.astype(np.int64) * len(labels) + cols
    order = np.argsort(key, kind="stable")
    dup = np.flatnonzero(np.diff(key[order]) == 0)
    if dup.size:
        r = int(order[dup[0] + 1])
        raise InputError(f"row {lines[r]}: edge {src[r]}->{dst[r]} is listed twice", field=str(p))
    place = {name: 2 + m for m, name in enumerate(extra)}
    unc = (
        _csv_uncertainty(text[:, place["uncertainty"]], lines, p)
        if "uncertainty" in place
        else None
    )
    lost = _csv_loss(text[:, place["loss"]], lines, p) if "loss" in place else None
    return EdgeListData(p.stem, d, labels, rows, cols, w.reshape(e, d, d), str(p), unc, lost)


def _csv_loss(column: np.ndarray, lines: np.ndarray, p: Path) -> np.ndarray:
    """The optional ``loss`` column: per row a message loss in [0, 1), or empty (none)."""
    vals = np.char.strip(column.astype(str))
    out = np.full(vals.size, np.nan)
    for r in np.flatnonzero(np.char.str_len(vals) > 0).tolist():
        text = str(vals[r])
        v = float(text) if NUMBER_TEXT.fullmatch(text) else math.nan  # ASCII numerals only
        if not (math.isfinite(v) and 0 <= v < 1):
            raise InputError(
                f"row {lines[r]}: loss = {text[:30]!r}: a loss probability must be a "
                "number in [0, 1) (or empty)",
                field=str(p),
            )
        out[r] = v
    return out


def _csv_uncertainty(column: np.ndarray, lines: np.ndarray, p: Path) -> np.ndarray:
    """The optional ``uncertainty`` column: per row a radius in [0, 1), or empty (none)."""
    vals = np.char.strip(column.astype(str))
    out = np.full(vals.size, np.nan)
    for r in np.flatnonzero(np.char.str_len(vals) > 0).tolist():
        text = str(vals[r])
        v = float(text) if NUMBER_TEXT.fullmatch(text) else math.nan  # ASCII numerals only
        if not (math.isfinite(v) and 0 <= v < 1):
            raise InputError(
                f"row {lines[r]}: uncertainty = {str(vals[r])[:30]!r}: the radius must be a "
                "number in [0, 1) (or empty)",
                field=str(p),
            )
        out[r] = v
    return out


def write_csv_edges(path: str | Path, labels, dim: int, rows, cols, w) -> None:
    """Write an edge list as CSV (the format :func:`read_csv_edges` reads), atomically.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    labels : sequence
        The agent labels.
    dim : int
        d.
    rows, cols : numpy.ndarray
        0-based target and source of each edge.
    w : numpy.ndarray
        The weights, (E, d, d).
    """
    lab = np.array([str(x) for x in labels], dtype=object)
    # rows ordered so that the agents first appear in label order where the edges allow it
    # (the reader numbers agents by first appearance)
    rows, cols, w = np.asarray(rows), np.asarray(cols), np.asarray(w, dtype=float)
    order = np.lexsort((np.minimum(rows, cols), cols > rows, np.maximum(rows, cols)))
    rows, cols, w = rows[order], cols[order], w[order]
    cols_w = [
        f"a{r}{c}" if dim < 10 else f"a{r}_{c}"
        for r in range(1, dim + 1)
        for c in range(1, dim + 1)
    ]
    flat = w.reshape(len(rows), dim * dim).tolist()
    with atomic_path(Path(path)) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["from", "to", *cols_w])
        # repr: the shortest text that reads back as the same double
        out.writerows(
            [f, t, *map(repr, ws)] for f, t, ws in zip(lab[cols], lab[rows], flat, strict=True)
        )


def _mat_labels(raw: Any, n: int, p: Path) -> tuple:
    if raw is None:
        return tuple(range(1, n + 1))
    arr = np.asarray(raw)
    if arr.dtype == object:
        items = [np.asarray(x).ravel() for x in arr.ravel()]
        if not all(x.dtype.kind == "U" and x.size == 1 for x in items):
            raise InputError("expected a cell array of strings", field=f"{p}: labels")
        out = [str(x[0]) for x in items]
    elif arr.dtype.kind == "U":
        out = [str(x).strip() for x in arr.ravel()]
    else:
        raise InputError(f"expected a cell array of strings, got {arr.dtype}", field=f"{p}: labels")
    if len(out) != n:
        raise InputError(f"{len(out)} labels for {n} agents", field=f"{p}: labels")
    if len(set(out)) != n:
        raise InputError("agent labels must be unique", field=f"{p}: labels")
    return tuple(label_from_text(x) for x in check_label_spellings(out, f"{p}: labels"))


def _scalar_text(a: np.ndarray) -> str:
    return (
        repr(a.ravel()[0].item()) if a.size == 1 and a.dtype.kind in "fiu" else f"shape {a.shape}"
    )


def read_mat(path: str | Path) -> EdgeListData:
    """Read a MATLAB block matrix (see the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mat`` file (MATLAB 5 to 7.2).

    Returns
    -------
    EdgeListData
        Labels, d and the edges (non-zero off-diagonal blocks).

    Raises
    ------
    InputError
        An unreadable or oversized file, a missing or wrongly typed ``A``/``dim``/``labels``
        (a struct or an object array where a matrix belongs), a size that d does not divide,
        a non-finite entry, or a non-zero diagonal block.
    """
    from scipy.io import loadmat

    p = _bounded(Path(path), MAX_MAT_BYTES)
    # loadmat holds the variables, then A is copied to triplets: a third of the memory
    # share every size check allows, by what the variables declare (not by a fixed cap)
    _mat_inflated_bytes(p, available_memory() / 6)
    try:
        doc = loadmat(p, variable_names=["A", "dim", "labels", "uncertainty"], mat_dtype=False)
    except Exception as exc:  # noqa: BLE001 - whatever a malformed file raises inside scipy
        raise InputError(
            f"not a readable MATLAB file ({exc.__class__.__name__})", field=str(p)
        ) from None
    for key in ("A", "dim"):
        if key not in doc:
            raise InputError("missing", field=f"{p}: {key}")
    a = doc["A"]
    if not sparse.issparse(a):
        a = np.asarray(a)
        if a.dtype.kind not in "fiub" or a.dtype.names is not None:
            raise InputError(
                f"expected a numeric matrix, got {'a struct' if a.dtype.names else a.dtype}",
                field=f"{p}: A",
            )
    dim_a = np.asarray(doc["dim"])
    if (
        dim_a.dtype.kind not in "fiu"
        or dim_a.size != 1
        or not np.isfinite(dim_a.ravel()[0])
        or float(dim_a.ravel()[0]) != int(dim_a.ravel()[0])
    ):
        raise InputError(f"expected one integer, got {_scalar_text(dim_a)}", field=f"{p}: dim")
    d = int(dim_a.ravel()[0])
    if not 1 <= d <= MAX_DIM:
        raise InputError(f"must be in 1..{MAX_DIM}, got {d}", field=f"{p}: dim")
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] % d:
        raise InputError(
            f"expected a square (N·d)×(N·d) matrix, got shape {a.shape} with dim = {d}",
            field=f"{p}: A",
        )
    n = a.shape[0] // d
    if not 1 <= n <= MAX_AGENTS:
        raise InputError(f"{n} agents; at most {MAX_AGENTS}", field=f"{p}: A")
    coo = sparse.coo_matrix(a, dtype=float)
    if not np.all(np.isfinite(coo.data)):
        k = int(np.flatnonzero(~np.isfinite(coo.data))[0])
        raise InputError(
            f"A({coo.row[k] + 1}, {coo.col[k] + 1}): not a finite number", field=str(p)
        )
    nz = coo.data != 0
    bi, bj = coo.row[nz] // d, coo.col[nz] // d
    self_loop = np.flatnonzero(bi == bj)
    if self_loop.size:
        i = int(bi[self_loop[0]])
        raise InputError(
            f"diagonal block ({i + 1}, {i + 1}) is not zero (a self-loop)", field=f"{p}: A"
        )
    labels = _mat_labels(doc.get("labels"), n, p)
    pairs = np.unique(bi.astype(np.int64) * n + bj)
    if pairs.size > MAX_EDGES:
        raise InputError(f"more than {MAX_EDGES} edges", field=f"{p}: A")
    rows, cols = pairs // n, pairs % n
    w = np.zeros((pairs.size, d, d))
    at = np.searchsorted(pairs, bi.astype(np.int64) * n + bj)  # each entry's edge
    np.add.at(w, (at, coo.row[nz] % d, coo.col[nz] % d), coo.data[nz])
    unc = _mat_uncertainty(doc.get("uncertainty"), n, rows, cols, p)
    return EdgeListData(p.stem, d, labels, rows, cols, w, str(p), unc)


def _mat_uncertainty(u, n: int, rows, cols, p: Path) -> np.ndarray | None:
    """The ``uncertainty`` variable: an N×N matrix whose (i, j) entry is edge j -> i's
    radius ρ (0: none given); a value where there is no edge is refused, and so is NaN
    (as in YAML and CSV: it used to read as none given, the common radius in its place)."""
    if u is None:
        return None
    a = np.asarray(u.toarray() if hasattr(u, "toarray") else u)
    if a.dtype.kind not in "fiu" or a.shape != (n, n):
        raise InputError(
            f"expected a numeric {n}×{n} matrix (one radius per edge)", field=f"{p}: uncertainty"
        )
    a = a.astype(float)
    nan = np.argwhere(np.isnan(a))
    if nan.size:
        i, j = (int(x) + 1 for x in nan[0])
        raise InputError(
            f"uncertainty({i}, {j}): NaN is not a radius (0 for none given, then "
            f"{Option('radius')} applies)",
            field=str(p),
        )
    has = a != 0
    edge = np.zeros((n, n), dtype=bool)
    edge[rows, cols] = True
    stray = np.argwhere(has & ~edge)
    if stray.size:
        i, j = (int(x) + 1 for x in stray[0])
        raise InputError(f"uncertainty({i}, {j}): uncertainty on a missing edge", field=str(p))
    vals = a[rows, cols]
    bad = np.flatnonzero(has[rows, cols] & ~((vals >= 0) & (vals < 1)))
    if bad.size:
        k = int(bad[0])
        raise InputError(
            f"uncertainty({rows[k] + 1}, {cols[k] + 1}): the radius must be in [0, 1), "
            f"got {vals[k]:g}",
            field=str(p),
        )
    return np.where(has[rows, cols], vals, np.nan)  # NaN here: none given, for the caller


def write_mat(path: str | Path, arrays: dict[str, Any]) -> None:
    """Write variables to a MATLAB file, atomically (nothing half-written).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mat`` file.
    arrays : dict
        Variable name to array (sparse matrices stay sparse; lists of strings become cell
        arrays).
    """
    from scipy.io import savemat

    with atomic_path(Path(path)) as tmp, open(tmp, "wb") as fh:
        savemat(fh, arrays, do_compression=True, oned_as="column")


__all__ = ["read_csv_edges", "read_mat", "write_csv_edges", "write_mat"]
