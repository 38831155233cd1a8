"""Tests of :mod:`ntc_design.certify.kinds.registry`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.claims import Property
from ntc_design.certify.dense import DENSE_CERT_MAX_ND
from ntc_design.certify.kinds.base import CertificateKind
from ntc_design.certify.kinds.registry import KINDS, kind_for
from ntc_design.model import SwitchingTopology
from ntc_design.model.generate import random_network
from ntc_design.protocol.timevarying import TimeVaryingDesign

THETA3 = [1.0, 2.0, -1.0]


def _design(n: int, d: int = 3):
    return nd.design(random_network(n, d, seed=1), THETA3[:d], thresholds=False)


@pytest.fixture(scope="module")
def switching_design(switching_set, theta):
    # G3 breaks Assumption 2 as stated in the paper: the warning is expected
    with pytest.warns(nd.AssumptionWarning, match="G3"):
        return nd.design(switching_set, theta, thresholds=False)


def test_every_kind_is_registered_under_its_own_name():
    assert set(KINDS) == {
        "hurwitz",
        "hurwitz-scale",
        "switching",
        "switching-scale",
        "time_varying",
        "robust",
        "digital",
        "digital_loss",
        "digital_switching",
    }
    assert all(isinstance(k, CertificateKind) for k in KINDS.values())
    assert len({type(k) for k in KINDS.values()}) == len(KINDS)


def test_kinds_declare_consistent_properties():
    for kind in KINDS.values():
        assert kind.required <= set(kind.properties), kind.name
        assert len(set(kind.properties)) == len(kind.properties), kind.name
        assert kind.description and kind.method, kind.name
    # every property some certificate can prove has a kind that proves it
    assert set().union(*(k.properties for k in KINDS.values())) == set(Property)
    assert {k.name for k in KINDS.values() if k.switching} == {
        "switching",
        "switching-scale",
        "digital_switching",
    }


def test_every_method_of_every_kind_is_documented():
    # overrides without a docstring inherit the base's: help() never shows an empty one
    for kind in KINDS.values():
        for name in ("accepts", "issue", "read", "claims", "prove", "audit", "verdicts"):
            assert getattr(type(kind), name).__doc__, f"{kind.name}.{name}"


def test_a_fixed_design_goes_to_the_dense_kind_up_to_its_size(g1, theta):
    assert kind_for(nd.design(g1, theta, thresholds=False)).name == "hurwitz"
    # Nd = 60 is the largest dense certificate, 63 the first sparse one
    at, past = _design(20), _design(21)
    assert at.topology.nd == DENSE_CERT_MAX_ND < past.topology.nd
    assert kind_for(at).name == "hurwitz"
    assert kind_for(past).name == "hurwitz-scale"


def test_a_switching_design_goes_to_a_switching_kind(switching_design):
    assert kind_for(switching_design) is KINDS["switching"]
    big = random_network(21, 3, seed=1)
    sw = SwitchingTopology({"A": big, "B": big}, (("A", 1.0), ("B", 2.0)))
    assert kind_for(nd.design(sw, THETA3, thresholds=False)) is KINDS["switching-scale"]


def test_a_time_varying_design_goes_to_its_kind(g1tv):
    des = TimeVaryingDesign(g1tv, np.array(THETA3), 0.1)
    assert kind_for(des) is KINDS["time_varying"]


def test_exactly_one_kind_accepts_each_design(g1, theta, switching_design):
    designs = [nd.design(g1, theta, thresholds=False), _design(21), switching_design]
    for des in designs:
        takers = [k.name for k in KINDS.values() if k.accepts(des)]
        assert len(takers) == 1, takers
    # robust certificates are only issued on request
    assert not any(KINDS["robust"].accepts(des) for des in designs)


@pytest.mark.parametrize("thing", [object(), "g1.yaml", None])
def test_a_non_design_is_refused(thing):
    with pytest.raises(TypeError, match=rf"^no certificate kind accepts a {type(thing).__name__}$"):
        kind_for(thing)


def test_a_topology_is_not_a_design(g1):
    with pytest.raises(TypeError, match=r"accepts a Topology$"):
        kind_for(g1)
