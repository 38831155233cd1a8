"""The certificate format: version and size limits, canonical JSON, digests, topology and
switching hashes, sealing and writing a certificate.

The digest is a SHA-256 checksum of the file's content. Anyone can recompute it: it
detects accidental damage, it does not authenticate anyone (it is not a signature).
"""

from __future__ import annotations

import hashlib
import json
import platform
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.outputs import write_atomic
from ..model import Topology
from ..numerics.linalg import MAGNITUDE_EXP

FORMAT = "ntc-design/certificate"


VERSION = 2


SUPPORTED_VERSIONS = (2,)


MAX_SIZE = 2000  # Nd of the largest certificate verify reads (its P alone is 32 MB)


MAX_MODES = 64


MAX_SCHEDULE = 10_000


MAX_CERT_BYTES = 256 * 2**20


#: The magnitude range of every nonzero number entering a proof (the model's weight range,
#: :data:`ntc_design.numerics.linalg.MAGNITUDE_EXP`).
NUMBER_EXP = MAGNITUDE_EXP


#: Reported floating-point results (eigenvalues, residuals) are recomputed and must agree
#: within RESULT_RTOL relative to the norm of the matrix they come from: eigenvalue
#: solvers differ in the last digits between machines.
RESULT_RTOL = 1e-8


DIGEST_NOTE = (
    "the digest is a SHA-256 checksum anyone can recompute: it detects accidental damage, "
    "it is not a signature; validity comes from the proofs, re-derived from the content"
)


def package_versions() -> dict[str, str]:
    """Versions of Python and of the packages a certificate depends on.

    Returns
    -------
    dict
        Package name -> version (``"not installed"`` when missing).
    """
    out = {"python": platform.python_version()}
    for pkg in (
        "ntc-design",
        "numpy",
        "scipy",
        "sympy",
        "cvxpy",
        "clarabel",
        "control",
        "python-flint",
    ):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def canonical(obj: Any) -> bytes:
    """The canonical JSON bytes that digests are taken of (sorted keys, no spaces).

    Parameters
    ----------
    obj : Any
        A JSON-compatible value.

    Returns
    -------
    bytes
    """
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode()


def document_hash(doc: Any) -> str:
    """``sha256:`` and the SHA-256 of a document's canonical JSON (the hash of a
    time-varying topology, whose weights are expressions).

    Parameters
    ----------
    doc : Any
        A JSON-ready document.

    Returns
    -------
    str
    """
    return "sha256:" + hashlib.sha256(canonical(doc)).hexdigest()


def digest(doc: dict) -> str:
    """SHA-256 of everything in a certificate but its ``digest`` field: a checksum
    anyone can recompute, not a signature.

    Parameters
    ----------
    doc : dict
        A certificate.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    return document_hash({k: v for k, v in doc.items() if k != "digest"})


#: Edges hashed per chunk by :func:`topology_hash` (its memory does not grow with E).
HASH_CHUNK = 20_000


def topology_hash(top: Topology) -> str:
    """A canonical hash of a topology: the same network gives the same hash whatever the
    file's layout (named matrices, ``diag``, edge order, its name).

    Hashed: the agent labels in order, d, and every edge with a nonzero weight as
    ``[from, to, weight]`` sorted by (to, from) index, each entry as the exact hex form of
    its double (``float.hex``; −0.0 is written as 0.0).

    Parameters
    ----------
    top : Topology
        A fixed topology.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    # the canonical JSON of {"dim", "edges", "labels"} written directly from the edge
    # arrays (one pass, no per-edge dict): the same bytes as json.dumps(..., sort_keys=True,
    # separators=(",", ":"), ensure_ascii=True) of the nested lists, and so the same hash
    ea = top.edge_arrays
    keep = np.any(ea.w != 0, axis=(1, 2))
    order = np.lexsort((ea.cols, ea.rows))
    order = order[keep[order]]
    d = top.dim
    lab = label_json(top.labels)
    fast = bool(np.all(np.isfinite(ea.w)))
    padded = np.array(lab, dtype="S").view(np.uint8).reshape(len(lab), -1) if fast and lab else None
    h = hashlib.sha256(f'{{"dim":{d},"edges":['.encode())
    for k0 in range(0, order.size, HASH_CHUNK):  # in chunks: memory stays small at any E
        part = order[k0 : k0 + HASH_CHUNK]
        if padded is not None:
            text = _edges_text_fast(padded, ea.cols[part], ea.rows[part], ea.w[part] + 0.0)
        else:
            text = _edges_text(lab, ea.cols[part], ea.rows[part], ea.w[part] + 0.0).encode()
        h.update((b"," if k0 else b"") + text)
    h.update(f'],"labels":[{",".join(lab)}]}}'.encode())
    return "sha256:" + h.hexdigest()


def label_json(labels) -> list[str]:
    """Each label as canonical JSON text (``json.dumps(x, ensure_ascii=True,
    sort_keys=True, separators=(",", ":"))``), with the C string encoder and ``repr`` for
    the common str and int labels (a million labels in well under a second).

    Parameters
    ----------
    labels : sequence
        Agent labels.

    Returns
    -------
    list of str
    """
    enc = json.encoder.encode_basestring_ascii

    def one(x) -> str:
        return json.dumps(x, ensure_ascii=True, sort_keys=True, separators=(",", ":"))

    return [enc(x) if type(x) is str else repr(x) if type(x) is int else one(x) for x in labels]


def _edges_text(lab, cols, rows, w) -> str:
    """``[from,to,weight]`` of some edges as canonical JSON, one float.hex per entry (the
    reference form, also used for non-finite weights)."""
    d = w.shape[1]
    hexes = [float.hex(x) for x in w.ravel().tolist()]
    rws = [",".join(f'"{x}"' for x in hexes[k : k + d]) for k in range(0, len(hexes), d)]
    mats = ["[[" + "],[".join(rws[k : k + d]) + "]]" for k in range(0, len(rws), d)]
    return ",".join(
        f"[{lab[j]},{lab[i]},{m}]"
        for j, i, m in zip(cols.tolist(), rows.tolist(), mats, strict=True)
    )


_HEX = np.frombuffer(b"0123456789abcdef", dtype=np.uint8)
_DIG = np.frombuffer(b"0123456789", dtype=np.uint8)


def _hex_fields(x: np.ndarray) -> np.ndarray:
    """``float.hex`` of finite doubles (−0.0 excluded) as fixed 24-byte fields, NUL where
    the text is shorter: sign, ``0x1.`` or ``0x0.``, the 13 mantissa digits (one for 0.0),
    ``p``, the exponent's sign and up to 4 digits."""
    bits = x.view(np.uint64)
    neg = (bits >> np.uint64(63)).astype(bool)
    ex = ((bits >> np.uint64(52)) & np.uint64(0x7FF)).astype(np.int64)
    man = bits & np.uint64((1 << 52) - 1)
    out = np.zeros((x.size, 24), dtype=np.uint8)
    out[:, 0] = np.where(neg, ord("-"), 0)
    out[:, 1], out[:, 2], out[:, 4] = ord("0"), ord("x"), ord(".")
    out[:, 3] = np.where(ex > 0, ord("1"), ord("0"))
    nib = (man[:, None] >> (np.uint64(4) * np.arange(12, -1, -1, dtype=np.uint64))) & np.uint64(15)
    nib = nib.astype(np.int64)
    # all 13 digits, but 0.0 is written 0x0.0p+0
    zero = (ex == 0) & (man == 0)
    out[:, 5:18] = np.where(zero[:, None] & (np.arange(13) > 0), 0, _HEX[nib])
    e = np.where(ex > 0, ex - 1023, np.where(man > 0, -1022, 0))
    out[:, 18] = ord("p")
    out[:, 19] = np.where(e < 0, ord("-"), ord("+"))
    a = np.abs(e)
    for k, p in enumerate((1000, 100, 10, 1)):
        dig = _DIG[(a // p) % 10]
        out[:, 20 + k] = np.where((a >= p) | (p == 1), dig, 0)
    return out


def _edges_text_fast(padded, cols, rows, w) -> bytes:
    """:func:`_edges_text` for finite weights, vectorised: fixed-width fields with NUL
    padding, joined and the NULs removed (labels' JSON never contains a NUL byte)."""
    k, d = w.shape[0], w.shape[1]
    if k == 0:
        return b""

    def lit(text: str) -> np.ndarray:
        return np.broadcast_to(np.frombuffer(text.encode(), dtype=np.uint8), (k, len(text)))

    hexes = _hex_fields(np.ascontiguousarray(w).ravel()).reshape(k, d, d, 24)
    parts = [lit(","), lit("["), padded[cols], lit(","), padded[rows], lit(",[")]
    for r in range(d):
        parts.append(lit("[" if r == 0 else ",["))
        for c in range(d):
            parts += [lit('"' if c == 0 else ',"'), hexes[:, r, c], lit('"')]
        parts.append(lit("]"))
    parts.append(lit("]]"))
    return np.concatenate(parts, axis=1).tobytes().replace(b"\x00", b"")[1:]


def switching_hash(mode_hashes: Mapping[str, str], schedule) -> str:
    """A canonical hash of a switching topology: the hash of every mode by name and the
    schedule as ``[mode, duration.hex()]`` pairs in order.

    Parameters
    ----------
    mode_hashes : mapping
        Mode name -> :func:`topology_hash` of its topology.
    schedule : sequence of (str, float)
        The periodic schedule.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    return document_hash(
        {
            "modes": dict(sorted(mode_hashes.items())),
            "schedule": [[m, float(t).hex()] for m, t in schedule],
        }
    )


def scheduled_modes(schedule) -> tuple[str, ...]:
    """The modes a schedule uses, in order of first use.

    Parameters
    ----------
    schedule : sequence of (str, float)
        (mode, duration) pairs.

    Returns
    -------
    tuple of str
    """
    return tuple(dict.fromkeys(m for m, _ in schedule))


def finish(doc: dict, method: str | None = None) -> dict:
    """Seal a certificate: the subject's digest, package versions, the verification
    method (when given) and the digest of everything.

    Parameters
    ----------
    doc : dict
        The certificate without its digests.
    method : str, optional
        ``verification_method``, for the kinds that state it.

    Returns
    -------
    dict
        ``doc``, completed.
    """
    doc["subject_digest"] = document_hash(doc["subject"])
    doc["versions"] = package_versions()
    if method is not None:
        doc["verification_method"] = method
    doc["digest"] = digest(doc)
    return doc


def write_certificate(doc: dict, path: str | Path, option: str = "out") -> None:
    """Write a certificate atomically (:func:`ntc_design.io.outputs.write_atomic`): a reader
    never sees a half-written file.

    Parameters
    ----------
    doc : dict
        The certificate, as made by :func:`hurwitz_certificate` or
        :func:`switching_certificate`.
    path : str or pathlib.Path
        The JSON file to write.
    option : str, optional
        The command or option named in an error (``report`` when a report writes it).

    Raises
    ------
    InputError
        When the folder cannot be written, the path is a folder, or the certificate holds
        non-finite numbers.
    """
    try:
        text = json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    except ValueError:  # JSON has no NaN/Inf: such numbers prove nothing anyway
        raise InputError(
            "the certificate holds non-finite numbers (nothing is proven); not written",
            field=str(path),
        ) from None
    write_atomic(path, text, option)


__all__ = [
    "DIGEST_NOTE",
    "FORMAT",
    "HASH_CHUNK",
    "MAX_CERT_BYTES",
    "MAX_MODES",
    "MAX_SCHEDULE",
    "MAX_SIZE",
    "NUMBER_EXP",
    "RESULT_RTOL",
    "SUPPORTED_VERSIONS",
    "VERSION",
    "canonical",
    "digest",
    "document_hash",
    "finish",
    "package_versions",
    "scheduled_modes",
    "switching_hash",
    "topology_hash",
    "write_certificate",
]
