"""Tests of :mod:`ntc_design.simulate.loss_run`: when a run has lossy links, the per-edge
losses it uses and the ``digital.loss`` block it reports."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss_run import loss_plan
from ntc_design.simulate.system import mode_system


@pytest.fixture(scope="module")
def g1_system(g1):
    return mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))


def test_no_loss_is_no_plan(g1_system):
    assert loss_plan(None, [g1_system], THETA, True) is None
    assert loss_plan(Digital(0.1), [g1_system], THETA, True) is None
    assert loss_plan(Digital(0.1, 0, 0.0, "hold"), [g1_system], THETA, True) is None


def test_a_plan_carries_the_per_edge_losses_and_reports_the_offset(g1_system):
    s = g1_system
    lab = s.labels
    first = (str(lab[int(s.src[0])]), str(lab[int(s.dst[0])]))
    plan = loss_plan(Digital(0.1, 0, 0.1), [s], THETA, True, {first: 0.4})
    assert plan is not None
    assert plan.loss.tolist() == [0.4] + [0.1] * (s.n_edges - 1)
    assert plan.block() == {"policy": "skip", "p": 0.4, "offset": None}
    assert plan.note(7) is None
    grid, _ = digital_grid(Digital(0.1), 1.0, np.array([1.0]))
    eps0 = np.linspace(-3, 3, 21) - np.tile(THETA, 7)
    dm = plan.moments(grid, lambda t: 1 / (1 + t), eps0, 0)
    assert dm.moments.ms_error.shape == (2, 7)
    assert plan.block()["offset"] > 0
    assert "‖x* − 1⊗θ‖" in plan.note(7)
    # a per-edge loss alone (the uniform one zero) is lossy too
    only = loss_plan(Digital(0.1), [s], THETA, True, {first: 0.2})
    assert only is not None and only.loss.max() == 0.2


@pytest.mark.hostile
def test_a_plan_refuses_what_it_does_not_model(g1_system):
    lossy = Digital(0.1, 0, 0.1)
    with pytest.raises(InputError, match=r"^digital\.loss: lossy links are modelled on one"):
        loss_plan(lossy, [g1_system, g1_system], THETA, False)
    assert loss_plan(lossy, [g1_system], THETA, True, None, "gpu") is not None
    with pytest.raises(InputError, match=r"^digital\.loss: no edge 1->1"):
        loss_plan(lossy, [g1_system], THETA, True, {("1", "1"): 0.2})


def test_a_topology_files_edge_losses_drive_the_run(tmp_path, g1_system):
    from ntc_design.model.load import load
    from ntc_design.simulate import simulate
    from ntc_design.simulate.loss import loss_moments
    from ntc_design.simulate.loss_run import topology_losses
    from tests.conftest import EXAMPLES

    text = (EXAMPLES / "g1.yaml").read_text(encoding="utf-8")
    text = text.replace(
        "- {from: 6, to: 3, weight: {matrix: A12, scale: -0.1}}",
        "- {from: 6, to: 3, weight: {matrix: A12, scale: -0.1}, loss: 0.4}",
    )
    (tmp_path / "g1.yaml").write_text(text, encoding="utf-8")
    top = load(tmp_path / "g1.yaml")
    assert topology_losses(top) == {("6", "3"): 0.4}
    assert topology_losses(object()) == {}
    x0 = np.linspace(-3, 3, 21)
    res = simulate(
        top, THETA, gain="1/(1+t)", noise=NoiseModel(0.4, 0.3), T=1.0, initial=x0.tolist(),
        method="exact", digital=Digital(0.1, 0, 0.1), save_every=1.0,
    )  # fmt: skip
    s = g1_system
    lab = s.labels
    p = np.array(
        [
            0.4 if (str(lab[j]), str(lab[i])) == ("6", "3") else 0.1
            for i, j in zip(s.dst, s.src, strict=True)
        ]
    )
    grid, _ = digital_grid(Digital(0.1), 1.0, np.array([1.0]))
    want = loss_moments(s, grid, lambda t: 1 / (1 + t), x0 - np.tile(THETA, 7), THETA, 0, p, "skip")
    assert res.exact.ms_error[-1] == pytest.approx(want.moments.ms_error[-1], rel=1e-12)
    assert res.summary()["digital"]["loss"]["p"] == 0.4
