"""The compact form of a scale certificate's subject: arrays packed as base64, and the
topology, δ, θ and informed agents of a mode read back and validated by the model."""

from __future__ import annotations

import base64
from typing import Any

import numpy as np

from ..errors import InputError
from ..model import Topology
from ..numerics.linalg import RANGE_TEXT, out_of_range
from ..protocol import ProtocolDesign, lemma1_delta
from .checks import Check
from .fields import need, number, vector

_DTYPES = {"f8": "<f8", "i8": "<i8", "u1": "<u1"}


def pack(a: np.ndarray, kind: str) -> dict:
    """An array as ``{"dtype", "shape", "base64"}`` (little-endian bytes, exact): a
    100,000-edge certificate stays compact and hashes fast.

    Parameters
    ----------
    a : numpy.ndarray
        The array.
    kind : {"f8", "i8", "u1"}
        The stored dtype.

    Returns
    -------
    dict
        ``dtype``, ``shape`` and the little-endian bytes in base64.
    """
    arr = np.ascontiguousarray(a, dtype=_DTYPES[kind])
    return {
        "dtype": kind,
        "shape": list(arr.shape),
        "base64": base64.b64encode(arr.tobytes()).decode("ascii"),
    }


def unpack(x: Any, where: str, kind: str, shape: tuple[int, ...]) -> np.ndarray:
    """Inverse of :func:`pack`, checking dtype, shape and length.

    Parameters
    ----------
    x : Any
        The packed form read from a certificate.
    where : str
        The field, for messages.
    kind : {"f8", "i8", "u1"}
        The dtype expected.
    shape : tuple of int
        The shape expected.

    Returns
    -------
    numpy.ndarray
        The array.

    Raises
    ------
    InputError
        Not a packed array, or the wrong dtype, shape, base64 or length.
    """
    if not isinstance(x, dict) or set(x) != {"dtype", "shape", "base64"}:
        raise InputError("expected a packed array {dtype, shape, base64}", field=where)
    if x["dtype"] != kind or x["shape"] != list(shape):
        raise InputError(f"expected dtype {kind} and shape {list(shape)}", field=where)
    if not isinstance(x["base64"], str):
        raise InputError("base64 must be a string", field=where)
    try:
        raw = base64.b64decode(x["base64"].encode("ascii"), validate=True)
    except (ValueError, UnicodeEncodeError):
        raise InputError("invalid base64", field=where) from None
    dt = np.dtype(_DTYPES[kind])
    if len(raw) != dt.itemsize * int(np.prod(shape, dtype=np.int64)):
        raise InputError(f"{len(raw)} bytes do not fit shape {list(shape)}", field=where)
    arr = np.frombuffer(raw, dtype=dt).reshape(shape).astype(dt.newbyteorder("="))
    if kind == "f8" and not np.all(np.isfinite(arr)):
        raise InputError("non-finite entry", field=where)
    return arr


def mode_subject(des: ProtocolDesign) -> dict:
    """A design as a scale certificate's subject mode: the topology as packed arrays, θ,
    ΔC, δ and the informed agents.

    Parameters
    ----------
    des : ProtocolDesign
        The design.

    Returns
    -------
    dict
    """
    top = des.topology
    ea = top.edge_arrays
    return {
        "topology": {
            "name": top.name,
            "dim": top.dim,
            "agents": list(top.labels),
            "edges": len(ea.rows),
            "from": pack(ea.cols, "i8"),
            "to": pack(ea.rows, "i8"),
            "weights": pack(ea.w, "f8"),
        },
        "theta": des.theta.tolist(),
        "margin": des.lemma1_margin,
        "delta": des.delta,
        "informed": list(des.informed_agents),
    }


def topology_from_subject(sub: dict, where: str) -> Topology:
    """The topology of a scale certificate's subject (arrays), validated by the model.

    Parameters
    ----------
    sub : dict
        The subject's ``topology``.
    where : str
        The field, for messages.

    Returns
    -------
    Topology
        The validated topology.

    Raises
    ------
    InputError
        A missing or malformed field, or an invalid weight.
    """
    if not isinstance(sub, dict):
        raise InputError("expected an object", field=where)
    for key in ("dim", "agents", "edges", "from", "to", "weights"):
        if key not in sub:
            raise InputError(f"missing field '{key}'", field=where)
    d = sub["dim"]
    if isinstance(d, bool) or not isinstance(d, int) or not 1 <= d <= 64:
        raise InputError("must be an integer in 1..64", field=f"{where}.dim")
    labels = sub["agents"]
    if not isinstance(labels, list) or not labels:
        raise InputError("expected a non-empty list of labels", field=f"{where}.agents")
    if len({str(x) for x in labels}) != len(labels):
        raise InputError("labels must be unique", field=f"{where}.agents")
    e = sub["edges"]
    if isinstance(e, bool) or not isinstance(e, int) or not 0 <= e <= 50_000_000:
        raise InputError("must be an edge count", field=f"{where}.edges")
    cols = unpack(sub["from"], f"{where}.from", "i8", (e,))
    rows = unpack(sub["to"], f"{where}.to", "i8", (e,))
    w = unpack(sub["weights"], f"{where}.weights", "f8", (e, d, d))
    n = len(labels)
    if cols.size and (min(cols.min(), rows.min()) < 0 or max(cols.max(), rows.max()) >= n):
        raise InputError("an edge index is out of range", field=where)

    if out_of_range(w):  # so no product in a proof overflows or underflows
        raise InputError(f"{RANGE_TEXT}", field=f"{where}.weights")
    return Topology.from_arrays(tuple(labels), d, rows, cols, w.reshape(-1, d, d), sub.get("name"))


#: δ = C + ΔC is re-derived to this relative tolerance (C is an eigenvalue; the issuer's
#: and the verifier's LAPACK may round it differently).
MARGIN_RTOL = 1e-9


def margin_check(name: str, sub: dict, where: str, top: Topology, delta: float) -> list[Check]:
    """Lemma 1's subject: δ = C + ΔC with a margin ΔC > 0 (read, never trusted: a
    certificate whose subject states ΔC <= 0 is not about a Lemma 1 design), and the
    stated δ re-derived from the subject's topology and ΔC as the design chooses it
    (:func:`ntc_design.protocol.lemma1_delta`: C from Assumption 2's decomposition), so a
    margin changed in the subject and re-sealed no longer verifies.

    Parameters
    ----------
    name : str
        The mode's name.
    sub : dict
        The mode's subject entry.
    where : str
        The field, for messages.
    top : Topology
        The subject's topology (read and validated).
    delta : float
        The subject's δ.

    Returns
    -------
    list of Check
        ΔC > 0, and (when a margin is stated) δ = C + ΔC.

    Raises
    ------
    InputError
        ``margin`` is missing, or neither null (δ given directly) nor a finite number.
    """
    if "margin" not in sub:
        raise InputError("missing", field=f"{where}.margin")
    if sub["margin"] is None:  # δ given directly: the subject makes no Lemma 1 claim
        return [Check(f"{name}: margin ΔC > 0", True, "none stated: δ was given directly")]
    m = number(need(sub, "margin", (int, float), where), f"{where}.margin")
    checks = [Check(f"{name}: margin ΔC > 0", m > 0, f"ΔC = {m:g}")]
    if m > 0:
        checks.append(_delta_check(name, top, m, delta))
    return checks


def _delta_check(name: str, top: Topology, margin: float, delta: float) -> Check:
    """δ as Lemma 1 chooses it for ΔC from the topology (δ = C + ΔC, or ΔC when C is
    undefined or C + ΔC <= 0), against the stated δ."""
    title = f"{name}: δ = C + ΔC (C from the topology)"
    try:
        c, want = lemma1_delta(top, margin)
    except (InputError, ArithmeticError, np.linalg.LinAlgError) as exc:
        return Check(title, False, f"C cannot be re-derived ({exc.__class__.__name__})")
    ok = abs(delta - want) <= MARGIN_RTOL * max(abs(want), abs(delta))
    c_text = "undefined (no agent can be in V1)" if c is None else f"{c:.10g}"
    detail = f"C = {c_text}, ΔC = {margin:g}: δ = {want:.10g}"
    return Check(title, ok, detail if ok else f"stated δ = {delta!r}, but {detail}")


def read_array_mode(
    sub: Any, where: str, size: int
) -> tuple[Topology, float, np.ndarray, tuple[Check, ...]]:
    """One mode of a scale certificate's subject: its topology (arrays, validated by the
    model), δ, θ, and the check that its informed agents are U.

    Parameters
    ----------
    sub : Any
        The mode's subject entry.
    where : str
        The field, for messages (it ends with the mode's name).
    size : int
        The certificate's Nd.

    Returns
    -------
    tuple
        (topology, δ, θ, the checks: informed agents = U, ΔC > 0 and δ = C + ΔC).

    Raises
    ------
    InputError
        A missing or malformed field, or a size that differs from the certificate's.
    """
    if not isinstance(sub, dict):
        raise InputError("expected an object", field=where)
    top = topology_from_subject(need(sub, "topology", dict, where), f"{where}.topology")
    if top.nd != size:
        raise InputError(f"topology has Nd={top.nd}, certificate size is {size}", field=where)
    delta = number(need(sub, "delta", (int, float), where), f"{where}.delta")
    if not delta > 0 or out_of_range(delta):
        raise InputError("must be a positive number in [2^-250, 2^250]", field=f"{where}.delta")
    theta = vector(need(sub, "theta", list, where), top.dim, f"{where}.theta")
    informed = need(sub, "informed", list, where)
    try:
        inf_idx = sorted(top.index(x) for x in informed)
    except InputError:
        raise InputError("lists an unknown agent", field=f"{where}.informed") from None
    ok_u = inf_idx == sorted(top.antagonised)
    name = where.rsplit("subject.modes.", 1)[-1]
    check = Check(f"{name}: informed agents are U", ok_u, "V_I = U" if ok_u else "V_I ≠ U")
    return top, float(delta), theta, (check, *margin_check(name, sub, where, top, float(delta)))


__all__ = [
    "MARGIN_RTOL",
    "margin_check",
    "mode_subject",
    "pack",
    "read_array_mode",
    "topology_from_subject",
    "unpack",
]
