"""Tests of :mod:`ntc_design.tune.loss`: the largest tolerable loss against the exact
moments recomputed at and around it, and its refusals."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.digital import digital_grid, digital_moments
from ntc_design.simulate.loss import loss_moments
from ntc_design.simulate.prepare import make_gain, prepare_modes
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune.loss import ATOL, STEP, largest_tolerable_loss
from tests.conftest import EXAMPLES

SCENARIO = EXAMPLES / "scenarios" / "g1_deadline.yaml"


@pytest.fixture(scope="module")
def g1_scenario():
    top, spec, _ = load_scenario(SCENARIO)
    return top, spec


def _final(top, spec, p, policy, t_end=10.0):
    base = spec.replace(T=t_end, digital=None, method="exact")
    gain = make_gain(base.gain)[0]
    pm = prepare_modes(top, base, gain)
    grid, _ = digital_grid(Digital(0.1), t_end, np.array([t_end]))
    s = pm.systems[0]
    if p == 0:
        dm = digital_moments(pm, grid, gain, 0)
        return float(dm.moments.ms_error[-1].sum())
    lm = loss_moments(s, grid, gain, pm.eps0, pm.theta, 0, np.full(s.n_edges, p), policy)
    return float(lm.moments.ms_error[-1].sum())


@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_answer_is_the_edge_of_the_bound(g1_scenario, policy):
    top, spec = g1_scenario
    res = largest_tolerable_loss(top, spec, 10.0, Digital(0.1), policy, 0.1)
    base = _final(top, spec, 0.0, policy)
    assert res.lossless_final == pytest.approx(base, rel=1e-12)
    assert res.loss is not None and 0 < res.loss < 1
    bound = 1.1 * base
    assert _final(top, spec, res.loss, policy) <= bound
    assert _final(top, spec, res.loss + ATOL, policy) > bound
    # every scanned loss below the answer passed, each recomputed
    below = [p for p in res.curve if p.loss <= res.loss]
    on_grid = {
        round(p.loss / STEP) for p in below if abs(p.loss / STEP - round(p.loss / STEP)) < 1e-9
    }
    assert on_grid == set(range(int(res.loss / STEP) + 1))
    for p in below[::4]:
        assert p.ok and _final(top, spec, p.loss, policy) == pytest.approx(p.final, rel=1e-12)
    doc = res.to_dict()
    assert (
        doc["loss"] == res.loss and doc["policy"] == policy and len(doc["curve"]) == len(res.curve)
    )
    assert res.table().title.startswith("largest tolerable loss p = ")


def test_skip_tolerates_about_a_tenth_on_g1(g1_scenario):
    top, spec = g1_scenario
    res = largest_tolerable_loss(top, spec, 10.0, Digital(0.1), "skip", 0.1)
    assert res.loss == pytest.approx(0.096, abs=1e-3)
    assert res.curve[-1].offset > 0  # skip moves the mean


@pytest.mark.hostile
def test_bad_options_are_refused_naming_the_parameter(g1_scenario, switching_set):
    # the Python caller's names; ntc tune --loss auto names the flags
    top, spec = g1_scenario
    with pytest.raises(InputError, match=r"^tolerance: "):
        largest_tolerable_loss(top, spec, 10.0, Digital(0.1), "skip", -1)
    with pytest.raises(InputError, match=r"^policy: unknown policy"):
        largest_tolerable_loss(top, spec, 10.0, Digital(0.1), "drop")
    with pytest.raises(InputError, match=r"^loss: lossy links are modelled on one fixed"):
        largest_tolerable_loss(switching_set, spec, 10.0, Digital(0.1))
