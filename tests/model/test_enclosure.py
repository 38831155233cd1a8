"""Tests of :mod:`ntc_design.model.enclosure`."""

import pytest

from ntc_design.errors import InputError
from ntc_design.model.timevarying import from_document
from tests.support.time_varying import small


def test_refuses_sign_class_change_naming_edge_and_t():
    doc = small({"1->2": {"matrix": "W", "scale": "0.5 + sin(t)"}}, {"period": "2*pi"})
    doc["matrices"] = {"W": [[-1, 0], [0, -2]]}
    with pytest.raises(InputError, match=r"edge 1->2: scale = .* changes sign \(-.* at t = 3\.6"):
        from_document(doc, "flip.yaml")
    doc = small({"1->2": {"diag": ["-1", "-cos(t)"]}}, {"period": "2*pi"})
    with pytest.raises(InputError, match=r"edge 1->2: diag\[1\].* changes sign"):
        from_document(doc, "flip.yaml")
    rows = small({"2->3": [["2", "1.5*sin(t)"], ["1.5*sin(t)", "1"]]}, {"period": "2*pi"})
    with pytest.raises(InputError, match=r"edge 2->3: weight is not positive definite at t ="):
        from_document(rows, "rows.yaml")
