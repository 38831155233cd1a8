"""Tests of :mod:`ntc_design.protocol.loss` and the loss fields of
:class:`ntc_design.protocol.digital.Digital`: the checks of p, the policy and the
per-edge losses, each error one line naming its field."""

import math

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.protocol.digital import Digital
from ntc_design.protocol.loss import POLICIES, edge_losses, require_loss, require_policy


def test_a_loss_in_range_is_kept():
    assert require_loss("digital.loss", 0) == 0.0
    assert require_loss("digital.loss", 0.999) == 0.999
    assert POLICIES == ("skip", "rescale", "hold")
    assert require_policy("digital.policy", "hold") == "hold"


@pytest.mark.hostile
@pytest.mark.parametrize("bad", [1.0, -0.1, math.nan, math.inf, 7, "0.1", True, None])
def test_a_bad_loss_names_the_field(bad):
    with pytest.raises(InputError, match=r"^digital\.loss: ") as err:
        require_loss("digital.loss", bad)
    assert "\n" not in str(err.value)


@pytest.mark.hostile
@pytest.mark.parametrize("bad", ["drop", "", "SKIP", 3, None, "x" * 500])
def test_an_unknown_policy_names_the_field(bad):
    with pytest.raises(InputError, match=r"^--loss-policy: unknown policy") as err:
        require_policy("--loss-policy", bad)
    assert len(str(err.value)) < 120


def test_per_edge_losses_override_the_uniform_one():
    edges = [(1, 0), (2, 1), (0, 2)]  # 1 -> 2, 2 -> 3, 3 -> 1 by label
    got = edge_losses(edges, [1, 2, 3], 0.2, {("2", "3"): 0.5})
    assert got.tolist() == [0.2, 0.5, 0.2]
    assert edge_losses(edges, [1, 2, 3], 0.0).tolist() == [0.0, 0.0, 0.0]


@pytest.mark.hostile
def test_a_per_edge_loss_on_a_missing_edge_or_out_of_range_is_refused():
    edges = [(1, 0)]
    with pytest.raises(InputError, match=r"^loss: no edge 2->1 in the topology$"):
        edge_losses(edges, [1, 2], 0.1, {("2", "1"): 0.5})
    with pytest.raises(InputError, match=r"^loss of edge 1->2: a loss probability"):
        edge_losses(edges, [1, 2], 0.1, {("1", "2"): 1.5})


def test_the_digital_block_reads_and_writes_loss_and_policy():
    dg = Digital.from_document({"period": 0.1, "delay": 1, "loss": 0.3, "policy": "rescale"})
    assert (dg.loss, dg.policy, dg.lossy) == (0.3, "rescale", True)
    assert dg.to_dict() == {"period": 0.1, "delay": 1, "loss": 0.3, "policy": "rescale"}
    # a lossless block reads and writes as before
    plain = Digital.from_document({"period": 0.1})
    assert plain.to_dict() == {"period": 0.1, "delay": 0}
    assert not plain.lossy
    assert Digital.from_document(dg.to_dict()) == dg


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("doc", "field"),
    [
        ({"period": 0.1, "loss": 1}, "digital.loss"),
        ({"period": 0.1, "loss": np.nan}, "digital.loss"),
        ({"period": 0.1, "policy": "drop"}, "digital.policy"),
        ({"period": 0.1, "lossy": 0.1}, "digital.lossy"),
    ],
)
def test_a_bad_digital_block_names_the_field(doc, field):
    with pytest.raises(InputError, match=rf"^{field}: "):
        Digital.from_document(doc)


def test_a_lossy_design_shows_its_loss_in_its_table(g1):
    import ntc_design as nd
    from ntc_design.model.paper import THETA
    from ntc_design.protocol.digital import DigitalDesign

    des = nd.design(g1, THETA, thresholds=False)
    rows = DigitalDesign(des, Digital(0.1, 0, 0.2, "hold"), "1/(1+t)").table().rows
    labels = [r[0].text for r in rows]
    assert labels[-2:] == ["message loss p", "lost messages"]
    plain = DigitalDesign(des, Digital(0.1), "1/(1+t)").table().rows
    assert "message loss p" not in [r[0].text for r in plain]
