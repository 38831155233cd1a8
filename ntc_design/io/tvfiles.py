"""Reading topology files whose weights are expressions of t (time-varying topologies).

The file is a topology file (:mod:`ntc_design.io.files`) in which a weight entry, a ``diag``
entry or a ``scale`` may be an expression of ``t`` written as a string, and which declares
how the weights behave for large t:

* ``period: P`` (a number or an expression without t, e.g. ``2*pi``): A(t + P) = A(t);
* ``constant_after: T``: the expressions define A on [0, T] and A(t) = A(T) for t >= T;
* neither: the expressions hold for every t >= 0 (simulation works; certification of
  Theorems 3-4 then needs a uniform bound on [0, ∞) and is refused with the reason).

Example::

    dim: 3
    agents: 7
    period: 2*pi
    matrices: {A65: [[7, 1, 1], [1, 6, 0], [1, 0, 5]]}
    edges:
      - {from: 5, to: 6, weight: {matrix: A65, scale: "1 + 0.5*sin(t)"}}
      - {from: 1, to: 2, weight: {diag: ["-1 - 0.5*cos(2*t)", -1, 0]}}
      - {from: 2, to: 5, weight: [["10 + cos(t)", 1, 2], [1, 8, 1], [2, 1, 12]]}

Expressions are parsed by :func:`ntc_design.expr.symbolic.parse_expression` (a whitelist over
Python's syntax tree; nothing is evaluated). This module only reads and checks the form;
whether every weight keeps one sign class for every t is proven in
:mod:`ntc_design.model.timevarying`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from ..expr.symbolic import parse_expression, symbol
from .documents import type_name
from .files import (
    TOPOLOGY_KEYS,
    Label,
    edge_entries,
    field_error,
    has_text,
    is_time_varying,
    parse_labels,
    parse_weight,
)

TIME_KEYS = {"period", "constant_after"}
MAX_PERIOD = 1e6  # a declared period or constant_after above this is refused


@dataclass(frozen=True)
class ExprWeight:
    """One weight as written: ``form`` is ``"rows"``, ``"diag"`` or ``"scale"``.

    ``entries`` is the d×d matrix of sympy expressions (always filled); for the scale form
    ``base`` is the constant matrix W and ``scale`` the expression s(t) (A(t) = s(t)·W), for
    the diag form ``entries`` is diagonal."""

    form: str
    entries: tuple[tuple[sp.Expr, ...], ...]
    base: np.ndarray | None = None
    scale: sp.Expr | None = None
    text: Any = None  # the weight as written (for certificates)

    @property
    def constant(self) -> bool:
        """True when no entry depends on t."""
        t = symbol("t")
        return not any(e.has(t) for row in self.entries for e in row)


@dataclass(frozen=True)
class ExprEdgeData:
    """One directed edge j -> i whose weight A_ij(t) may hold expressions of t."""

    source: Label  # j
    target: Label  # i
    weight: ExprWeight
    field: str


@dataclass(frozen=True)
class TimeVaryingData:
    """A time-varying topology file as read: labels, d, edges with weights A_ij(t), the
    declared ``period`` or ``constant_after`` (None if absent) and the document itself."""

    name: str | None
    dim: int
    labels: tuple[Label, ...]
    edges: tuple[ExprEdgeData, ...]
    period: sp.Expr | None
    constant_after: sp.Expr | None
    source: str | None
    document: dict  # the mapping as read (re-parsed by ``ntc verify``)


def _entry(x: Any, source: str | None, field: str) -> sp.Expr:
    if isinstance(x, str):
        e = parse_expression(x, f"{source}: {field}" if source else field)
        if e.free_symbols - {symbol("t")}:
            raise field_error(source, field, "only the variable t may appear")
        return e
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise field_error(source, field, f"expected a number or an expression of t, got {x!r}")
    if not np.isfinite(float(x)):
        raise field_error(source, field, f"entry is {x!r}; weights must be finite")
    return sp.Float(float(x)) if isinstance(x, float) else sp.Integer(x)


def _constant_matrix(m: np.ndarray) -> tuple[tuple[sp.Expr, ...], ...]:
    return tuple(tuple(sp.Float(float(v)) if v != 0 else sp.Integer(0) for v in r) for r in m)


def parse_expr_weight(
    spec: Any, dim: int, source: str | None, field: str, named: dict[str, np.ndarray]
) -> ExprWeight:
    """A d×d weight whose entries may be expressions of t.

    Parameters
    ----------
    spec : Any
        Rows, ``{diag: [...]}``, ``{matrix: NAME, scale: s(t)}``, ``{identity: s(t)}``, a
        scalar expression s(t) (meaning s(t)·I) or any constant form of
        :func:`ntc_design.io.files.parse_weight`.
    dim : int
        The weight's size d.
    source : str or None
        The file it came from, for messages.
    field : str
        The field it came from, for messages.
    named : dict of str to numpy.ndarray
        The file's named constant matrices.

    Returns
    -------
    ExprWeight
        The entries as sympy expressions of t, with the form as written.

    Raises
    ------
    InputError
        A malformed weight, an expression that is not allowed or uses a variable other
        than t, a non-finite constant.
    """
    if not has_text(spec):
        m = parse_weight(spec, dim, source, field, named)
        return ExprWeight("rows", _constant_matrix(m), text=spec)
    if isinstance(spec, str):  # a scalar expression: s(t)·I
        spec = {"identity": spec}
    if isinstance(spec, list):
        if len(spec) != dim or any(not isinstance(r, list) or len(r) != dim for r in spec):
            raise field_error(source, field, f"expected a {dim}x{dim} matrix")
        rows = tuple(
            tuple(_entry(v, source, f"{field}: weight[{k}][{m}]") for m, v in enumerate(r))
            for k, r in enumerate(spec)
        )
        return ExprWeight("rows", rows, text=spec)
    if isinstance(spec, dict):
        keys = set(spec)
        if keys == {"diag"}:
            diag = spec["diag"]
            if not isinstance(diag, list) or len(diag) != dim:
                raise field_error(source, field, f"diag must list {dim} entries")
            vals = [_entry(v, source, f"{field}: diag[{k}]") for k, v in enumerate(diag)]
            rows = tuple(
                tuple(vals[k] if k == m else sp.Integer(0) for m in range(dim)) for k in range(dim)
            )
            return ExprWeight("diag", rows, text=spec)
        if keys == {"identity"}:
            s = _entry(spec["identity"], source, f"{field}: identity")
            return ExprWeight(
                "scale", _scaled(np.eye(dim), s), base=np.eye(dim), scale=s, text=spec
            )
        if "matrix" in keys and keys <= {"matrix", "scale"}:
            name = spec["matrix"]
            if not isinstance(name, str) or name not in named:
                known = ", ".join(sorted(named)) or "none defined"
                raise field_error(source, field, f"unknown matrix {name!r} (known: {known})")
            s = _entry(spec.get("scale", 1), source, f"{field}: scale")
            base = named[name]
            return ExprWeight("scale", _scaled(base, s), base=base, scale=s, text=spec)
        raise field_error(
            source,
            field,
            f"unknown weight form {sorted(keys, key=str)}; use rows, {{diag: [...]}}, "
            "{identity: s}, {matrix: NAME, scale: s} (entries may be expressions of t)",
        )
    raise field_error(source, field, f"expected a matrix, got {type_name(spec)}")


def _scaled(base: np.ndarray, s: sp.Expr) -> tuple[tuple[sp.Expr, ...], ...]:
    if not s.has(symbol("t")):  # the same double arithmetic as a constant file: s·W
        return _constant_matrix(float(s) * base)
    return tuple(
        tuple(sp.Integer(0) if v == 0 else sp.Float(float(v)) * s for v in r) for r in base
    )


def _time_constant(x: Any, source: str | None, key: str) -> sp.Expr:
    if isinstance(x, str):
        e = parse_expression(x, f"{source}: {key}" if source else key, variables=())
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        if isinstance(x, float) and not np.isfinite(x):  # sympy.Rational("inf") raises
            raise field_error(source, key, f"must be in (0, {MAX_PERIOD:g}], got {x}")
        e = sp.Rational(str(x)) if isinstance(x, float) else sp.Integer(x)
    else:
        raise field_error(
            source, key, f"expected a positive number or expression such as 2*pi, got {x!r}"
        )
    try:
        v = float(e)
    except (TypeError, ValueError):
        raise field_error(source, key, "must be a number (no t)") from None
    if not np.isfinite(v) or not 0 < v <= MAX_PERIOD:
        raise field_error(source, key, f"must be in (0, {MAX_PERIOD:g}], got {v:g}")
    return e


def parse_time_varying(doc: dict[str, Any], source: str | None = None) -> TimeVaryingData:
    """Validate a time-varying topology mapping (see the module docstring).

    Parameters
    ----------
    doc : dict
        The mapping as read.
    source : str, optional
        The file it came from, for messages.

    Returns
    -------
    TimeVaryingData
        Labels, d, edges with expression weights and the declared time structure.

    Raises
    ------
    InputError
        An unknown or missing field, both ``period`` and ``constant_after``, a bad label,
        edge, weight or time value.
    """
    # robust certification (uncertainty:) is for fixed weights, not for weights of t
    allowed = (TOPOLOGY_KEYS - {"uncertainty"}) | TIME_KEYS
    unknown = sorted(set(doc) - allowed)
    if unknown:
        raise field_error(
            source, unknown[0], f"unknown field (allowed: {', '.join(sorted(allowed))})"
        )
    if {"period", "constant_after"} <= set(doc):
        raise field_error(source, "period", "declare either period or constant_after, not both")
    for key in ("dim", "agents", "edges"):
        if key not in doc:
            raise field_error(source, key, "missing")
    dim = doc["dim"]
    if isinstance(dim, bool) or not isinstance(dim, int) or not 1 <= dim <= 64:
        raise field_error(source, "dim", f"expected an integer in 1..64, got {dim!r}")
    labels = parse_labels(doc["agents"], source)
    by_key = {str(a): a for a in labels}
    mats = doc.get("matrices") or {}
    if not isinstance(mats, dict):
        raise field_error(source, "matrices", "expected a mapping of name -> matrix")
    named = {str(k): parse_weight(v, dim, source, f"matrices.{k}") for k, v in mats.items()}
    edges_doc = doc["edges"]
    if not isinstance(edges_doc, list):
        raise field_error(source, "edges", "expected a list of {from, to, weight}")
    edges: list[ExprEdgeData] = []
    for _, e, field, j, i in edge_entries(edges_doc, by_key, source, frozenset()):
        w = parse_expr_weight(e["weight"], dim, source, field, named)
        edges.append(ExprEdgeData(j, i, w, field))
    period = _time_constant(doc["period"], source, "period") if "period" in doc else None
    after = (
        _time_constant(doc["constant_after"], source, "constant_after")
        if "constant_after" in doc
        else None
    )
    name = doc.get("name")
    return TimeVaryingData(
        str(name) if name is not None else None,
        dim,
        labels,
        tuple(edges),
        period,
        after,
        source,
        doc,
    )


__all__ = [
    "ExprEdgeData",
    "ExprWeight",
    "TimeVaryingData",
    "is_time_varying",
    "parse_expr_weight",
    "parse_time_varying",
]
