"""Tests of :mod:`ntc_design.model.timevarying`."""

import numpy as np
import pytest
import yaml

from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.model.timevarying import ExpressionTopology, from_document
from ntc_design.protocol import design
from tests.cli_helpers import assert_input_error
from tests.support.time_varying import small


def test_example_loads_with_proven_classes(g1tv):
    assert isinstance(g1tv, ExpressionTopology)
    assert [e.cls.value for e in g1tv.edges] == ["PD", "NSD", "PD", "PD", "PD", "NSD", "ND", "PD"]
    assert g1tv.domain[1] == pytest.approx(20 * np.pi)
    # at t = 0 the example is the paper's G1: the same design (C = 7.1440, δ = 7.2440)
    d0 = design(g1tv.at(0.0), THETA)
    assert d0.C == pytest.approx(7.143995, abs=1e-5)


def test_refuses_non_periodic_and_hostile_expressions(tmp_path, capsys, monkeypatch):
    with pytest.raises(InputError, match=r"edge 2->3: .*not periodic with period 2\*pi"):
        from_document(small({"2->3": {"identity": "2 + sin(t/2)"}}, {"period": "2*pi"}), "p.yaml")
    doc = small({"2->3": {"identity": "__import__('os').system('true')"}}, {"period": 1})
    (tmp_path / "h.yaml").write_text(yaml.safe_dump(doc))
    assert_input_error(
        ["certify", tmp_path / "h.yaml", "--theta", "1,2"], capsys, monkeypatch, "edge 2->3"
    )
    doc = small({}, {"period": "t + 1"})
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(doc))
    assert_input_error(
        ["design", tmp_path / "p.yaml", "--theta", "1,2"], capsys, monkeypatch, "period"
    )
