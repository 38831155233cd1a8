"""Tests of :mod:`ntc_design.protocol.digital`: the sampled protocol's options and the mode
each sample uses on a switching schedule."""

import numpy as np
import pytest

from ntc_design import SwitchingTopology
from ntc_design.errors import InputError
from ntc_design.protocol.digital import MAX_DELAY, Digital, step_modes


def test_steps_are_the_whole_periods_and_the_partial_step_that_ends_at_t():
    assert Digital(0.1, 2).steps(10.0) == (100, 0.0)
    k, part = Digital(0.3).steps(1.0)
    assert k == 3 and part == pytest.approx(0.1, rel=1e-12)
    k, part = Digital(0.4).steps(1.0)  # ⌊2.5⌋ whole steps, half a period more
    assert k == 2 and part == pytest.approx(0.2, rel=1e-12)
    k, part = Digital(0.0956).steps(10.0)  # the period: 104 steps and 0.0576
    assert k == 104 and part == pytest.approx(10.0 - 104 * 0.0956, rel=1e-12)
    # T within WHOLE_RTOL of a whole number of periods is one (no sliver step)
    assert Digital(10.0 / 3).steps(10.0 * (1 + 1e-12)) == (3, 0.0)
    assert Digital(10.0 / 3).steps(10.0 * (1 - 1e-12)) == (3, 0.0)
    k, part = Digital(0.1).steps(9.9999)
    assert k == 99 and part == pytest.approx(0.0999, rel=1e-9)


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("period", "delay", "message"),
    [
        (0.0, 0, "digital.period: must be a positive number"),
        (-0.1, 0, "digital.period: must be a positive number"),
        (float("nan"), 0, "digital.period: must be finite"),
        (float("inf"), 0, "digital.period: must be finite"),
        ("0.1", 0, "digital.period: expected a number"),
        (True, 0, "digital.period: expected a number"),
        (0.1, -1, "digital.delay: must be an integer >= 0"),
        (0.1, 1.5, "digital.delay: must be an integer >= 0"),
        (0.1, 2.0, "digital.delay: must be an integer >= 0"),
        (0.1, True, "digital.delay: must be an integer >= 0"),
        (0.1, MAX_DELAY + 1, f"digital.delay: must be at most {MAX_DELAY}"),
    ],
)
def test_bad_period_or_delay_is_one_line_naming_the_field(period, delay, message):
    with pytest.raises(InputError, match="^" + message):
        Digital(period, delay)


@pytest.mark.hostile
def test_a_period_longer_than_the_horizon_or_too_many_steps_is_refused():
    with pytest.raises(InputError, match="longer than the horizon T = 1"):
        Digital(2.0).steps(1.0)
    with pytest.raises(InputError, match="steps exceed the limit"):
        Digital(1e-12).steps(1e3)


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ([0.1], "digital: expected {period: h, delay: D}"),
        ({"delay": 1}, "digital.period: missing"),
        ({"period": 0.1, "lag": 1}, "digital.lag: unknown field"),
    ],
)
def test_a_bad_digital_block_names_the_field(doc, message):
    with pytest.raises(InputError, match=message):
        Digital.from_document(doc)


def test_the_block_round_trips():
    dg = Digital.from_document({"period": 0.05, "delay": 2})
    assert dg == Digital(0.05, 2) and Digital.from_document(dg.to_dict()) == dg
    assert Digital.from_document({"period": 1}).delay == 0


def test_step_modes_agree_with_the_schedule_at_every_sample(switching_set):
    """The rule is SwitchingTopology.mode_at at t_k = k·h (the switching instants, which
    belong to the next mode, included: h = 0.01 hits every one of G2 G2 G1 G3 G3 × 0.02)."""
    sw: SwitchingTopology = switching_set
    names = list(sw.modes)
    for h in (0.01, 0.013, 0.05):
        t = np.arange(400) * h
        got = step_modes(sw.schedule, t, names)
        want = [names.index(sw.mode_at(float(x))) for x in t]
        assert got.tolist() == want
    # every mode of the schedule is visited at h = 0.01
    assert set(step_modes(sw.schedule, np.arange(10) * 0.01, names).tolist()) == set(
        names.index(m) for m, _ in sw.schedule
    )
