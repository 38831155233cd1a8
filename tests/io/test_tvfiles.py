"""Tests of :mod:`ntc_design.io.tvfiles`."""

import math

import numpy as np
import pytest
import sympy as sp

from ntc_design.errors import InputError
from ntc_design.expr.symbolic import symbol
from ntc_design.io.tvfiles import (
    MAX_PERIOD,
    ExprEdgeData,
    ExprWeight,
    TimeVaryingData,
    parse_expr_weight,
    parse_time_varying,
)

T = symbol("t")
W = np.array([[2.0, 0.0], [0.0, 3.0]])
NAMED = {"W": W}


def _at(weight: ExprWeight, t: float) -> np.ndarray:
    """The weight's entries evaluated at t (SymPy's own evaluation, entry by entry)."""
    return np.array([[float(e.subs(T, t)) for e in row] for row in weight.entries])


def _w(spec, dim: int = 2) -> ExprWeight:
    return parse_expr_weight(spec, dim, "f.yaml", "edge 1->2", NAMED)


def _doc(**over) -> dict:
    doc = {
        "dim": 2,
        "agents": 3,
        "matrices": {"W": [[2, 0], [0, 3]]},
        "edges": [
            {"from": 1, "to": 2, "weight": {"matrix": "W", "scale": "1 + sin(t)/2"}},
            {"from": 2, "to": 3, "weight": {"diag": ["-1 - cos(t)^2", -1]}},
        ],
    }
    doc.update(over)
    return {k: v for k, v in doc.items() if v is not None}


# -- one weight ------------------------------------------------------------------------


def test_constant_rows_are_exact_numbers():
    w = _w([[1, 0.5], [0.5, 2]])
    assert w.form == "rows" and w.constant and w.base is None and w.scale is None
    assert w.text == [[1, 0.5], [0.5, 2]]
    np.testing.assert_array_equal(_at(w, 0.0), [[1.0, 0.5], [0.5, 2.0]])
    assert w.entries[0][0] == sp.Float(1.0)


def test_rows_with_expressions_of_t():
    w = _w([["2 + sin(t)", "t/4"], ["t/4", 3]])
    assert w.form == "rows" and not w.constant
    for t in (0.0, 0.7, 5.0):
        np.testing.assert_allclose(
            _at(w, t), [[2 + math.sin(t), t / 4], [t / 4, 3.0]], rtol=1e-14, atol=0
        )


def test_a_scalar_expression_means_a_multiple_of_the_identity():
    w = _w("2 + cos(t)")
    assert w.form == "scale" and not w.constant
    np.testing.assert_array_equal(w.base, np.eye(2))
    assert sp.simplify(w.scale - (2 + sp.cos(T))) == 0
    np.testing.assert_allclose(_at(w, 1.3), (2 + math.cos(1.3)) * np.eye(2), rtol=1e-14)
    assert w.entries[0][1] == 0 and w.entries[1][0] == 0


def test_diag_form():
    w = _w({"diag": ["1 + t^2", -0.5]})
    assert w.form == "diag" and not w.constant
    np.testing.assert_allclose(_at(w, 2.0), np.diag([5.0, -0.5]), rtol=1e-15)
    assert w.entries[0][1] == 0 and w.entries[1][0] == 0


def test_named_matrix_scaled_by_an_expression():
    w = _w({"matrix": "W", "scale": "1 + sin(t)/2"})
    assert w.form == "scale" and w.base is W
    for t in (0.0, 1.0, 4.0):
        np.testing.assert_allclose(_at(w, t), (1 + math.sin(t) / 2) * W, rtol=1e-14)
    # a zero entry of W stays an exact zero, not 0·s(t)
    assert w.entries[0][1] == sp.Integer(0)


def test_a_constant_scale_uses_double_arithmetic():
    # s = 2π is constant: the entries are float(2π)·W exactly, as in a constant file
    w = _w({"matrix": "W", "scale": "2*pi"})
    assert w.constant and w.form == "scale"
    assert [[float(e) for e in row] for row in w.entries] == (float(2 * sp.pi) * W).tolist()


def test_a_named_matrix_without_a_scale_is_constant():
    w = _w({"matrix": "W"})
    assert w.constant
    np.testing.assert_array_equal(_at(w, 0.0), W)


@pytest.mark.parametrize(
    "spec, needle",
    [
        ([["t", 0]], "expected a 2x2 matrix"),
        ([["t", 0], [0]], "expected a 2x2 matrix"),
        ([["t", 0], "ab"], "expected a 2x2 matrix"),
        ([["t", None], [0, 1]], "weight[0][1]: expected a number or an expression of t, got None"),
        ([["t", 0], [True, 1]], "weight[1][0]: expected a number or an expression of t, got True"),
        ([["t", float("inf")], [0, 1]], "weight[0][1]: entry is inf; weights must be finite"),
        ([["t", "x"], [0, 1]], "uses x"),
        ({"diag": ["t"]}, "diag must list 2 entries"),
        ({"diag": "t"}, "diag must list 2 entries"),
        ({"diag": ["t", [1]]}, "diag[1]: expected a number or an expression of t"),
        ({"matrix": "V", "scale": "t"}, "unknown matrix 'V' (known: W)"),
        ({"matrix": "W", "scale": "t", "x": 1}, "unknown weight form ['matrix', 'scale', 'x']"),
        ({"identity": "t", "scale": 2}, "unknown weight form ['identity', 'scale']"),
        ({"identity": "sqrt("}, "identity"),
    ],
)
def test_bad_weights_name_the_file_and_edge(spec, needle):
    with pytest.raises(InputError, match=r"^f\.yaml: edge 1->2: ") as exc:
        _w(spec)
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg


def test_unknown_matrix_with_none_defined():
    with pytest.raises(InputError, match=r"unknown matrix 'A' \(known: none defined\)"):
        parse_expr_weight({"matrix": "A", "scale": "t"}, 2, None, "edge 1->2", {})


def test_error_without_a_source_names_only_the_field():
    with pytest.raises(InputError, match=r"^edge 1->2: weight\[0\]\[0\]: entry is nan"):
        parse_expr_weight([[float("nan"), "t"], [0, 1]], 2, None, "edge 1->2", {})


# -- a whole file ----------------------------------------------------------------------


def test_parse_a_periodic_file():
    doc = _doc(period="2*pi", name=7)
    data = parse_time_varying(doc, "tv.yaml")
    assert isinstance(data, TimeVaryingData)
    assert (data.name, data.dim, data.labels, data.source) == ("7", 2, (1, 2, 3), "tv.yaml")
    assert data.period == 2 * sp.pi and data.constant_after is None
    assert data.document is doc
    e0, e1 = data.edges
    assert isinstance(e0, ExprEdgeData)
    assert (e0.source, e0.target, e0.field) == (1, 2, "edge 1->2")
    assert (e1.source, e1.target, e1.weight.form) == (2, 3, "diag")
    np.testing.assert_allclose(
        _at(e1.weight, 0.4), np.diag([-1 - math.cos(0.4) ** 2, -1.0]), rtol=1e-14
    )


def test_time_constants_are_exact():
    # a decimal period is read as the rational it spells, not its nearest double
    assert parse_time_varying(_doc(period=0.1)).period == sp.Rational(1, 10)
    assert parse_time_varying(_doc(constant_after=3)).constant_after == sp.Integer(3)
    assert parse_time_varying(_doc(constant_after="E^2")).constant_after == sp.exp(2)
    assert parse_time_varying(_doc(period=MAX_PERIOD)).period == int(MAX_PERIOD)
    data = parse_time_varying(_doc(name=None))
    assert data.name is None and data.period is None and data.constant_after is None


def test_string_labels_and_no_matrices():
    doc = {
        "dim": 1,
        "agents": ["a", "b"],
        "matrices": None,
        "edges": [{"from": "a", "to": "b", "weight": "1 + t"}],
    }
    data = parse_time_varying(doc, "s.yaml")
    assert data.labels == ("a", "b") and data.edges[0].target == "b"


@pytest.mark.parametrize(
    "over, needle",
    [
        ({"colour": 1}, "colour: unknown field (allowed: agents, constant_after,"),
        ({"period": 1, "constant_after": 2}, "period: declare either period or constant_after"),
        ({"dim": None}, "dim: missing"),
        ({"agents": None}, "agents: missing"),
        ({"edges": None}, "edges: missing"),
        ({"dim": True}, "dim: expected an integer in 1..64, got True"),
        ({"dim": 65}, "dim: expected an integer in 1..64, got 65"),
        ({"dim": "2"}, "dim: expected an integer in 1..64, got '2'"),
        ({"matrices": [1]}, "matrices: expected a mapping of name -> matrix"),
        ({"matrices": {"W": [[1, 2]]}}, "matrices.W"),
        ({"edges": {"from": 1}}, "edges: expected a list of {from, to, weight}"),
        ({"edges": [3]}, "edges[0]: expected a mapping {from, to, weight}"),
        (
            {"edges": [{"from": 1, "to": 2, "weight": "t", "uncertainty": 0.1}]},
            "edges[0]: unknown field 'uncertainty'",
        ),
        ({"edges": [{"from": 1, "to": 9, "weight": "t"}]}, "edge 1->9: unknown agent label '9'"),
        ({"edges": [{"from": 0, "to": 2, "weight": "t"}]}, "unknown agent label '0' in 'from'"),
        ({"edges": [{"from": 2, "to": 2, "weight": "t"}]}, "edge 2->2: self-loop"),
        (
            {"edges": [{"from": 1, "to": 2, "weight": "t"}, {"from": 1, "to": 2, "weight": 1}]},
            "edge 1->2: duplicated edge",
        ),
        ({"period": 0}, "period: must be in (0, 1e+06], got 0"),
        ({"period": -2}, "period: must be in (0, 1e+06], got -2"),
        ({"constant_after": 2e6}, "constant_after: must be in (0, 1e+06], got 2e+06"),
        ({"period": "t + 1"}, "period: uses t"),
        ({"period": "pi - 4"}, "period: must be in (0, 1e+06]"),
        ({"period": True}, "period: expected a positive number or expression such as 2*pi"),
        ({"constant_after": [1]}, "constant_after: expected a positive number"),
        # an infinite or NaN time once crashed in sympy.Rational (an internal error)
        ({"period": float("inf")}, "period: must be in (0, 1e+06], got inf"),
        ({"constant_after": float("nan")}, "constant_after: must be in (0, 1e+06], got nan"),
        ({"period": 10**400}, "period: must be in (0, 1e+06], got inf"),  # an exact integer
        # robust radii are for fixed weights: a time-varying file refuses them
        ({"uncertainty": 0.1}, "uncertainty: unknown field (allowed: agents, constant_after,"),
    ],
)
def test_bad_files_are_one_line_errors(over, needle):
    with pytest.raises(InputError, match=r"^tv\.yaml: ") as exc:
        parse_time_varying(_doc(**over), "tv.yaml")
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg
