"""Tests of :mod:`ntc_design.protocol.digital`: the sampled protocol's options and the mode
each sample uses on a switching schedule."""

from fractions import Fraction

import numpy as np
import pytest

from ntc_design import SwitchingTopology
from ntc_design.errors import InputError
from ntc_design.protocol.digital import (
    MAX_DELAY,
    Digital,
    ScheduleTicks,
    decimal_fraction,
    step_modes,
)


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


def _exact_truth(schedule, names, h, steps):
    """The mode of t_k = k·h with h and the durations as exact fractions of their decimals,
    written out: τ = t_k − ⌊t_k / P⌋·P, the first entry whose end exceeds τ."""
    hq = Fraction(repr(h))
    ds = [Fraction(repr(d)) for _, d in schedule]
    period = sum(ds)
    out = []
    for k in range(steps):
        t = k * hq
        tau = t - (t // period) * period
        end, pick = Fraction(0), len(ds) - 1
        for s, d in enumerate(ds):
            end += d
            if tau < end:
                pick = s
                break
        out.append(names.index(schedule[pick][0]))
    return out


def test_step_modes_are_the_exact_schedule_at_every_sample(switching_set):
    """The rule at t_k = k·h in exact arithmetic (the switching instants, which belong to
    the next mode, included: h = 0.01 and 0.013 hit them, h = 0.1 = P hits the start)."""
    sw: SwitchingTopology = switching_set
    names = list(sw.modes)
    for h, steps in ((0.01, 400), (0.013, 2000), (0.05, 400), (0.1, 1000)):
        got = step_modes(sw.schedule, np.arange(steps) * h, names, h)
        assert got.tolist() == _exact_truth(sw.schedule, names, h, steps), h
    # h = P = 0.1: every step starts the period, so G2 runs at every one
    assert set(step_modes(sw.schedule, np.arange(1000) * 0.1, names, 0.1).tolist()) == {
        names.index("G2")
    }
    # h = 0.013: the doubles' τ = t − ⌊t/P⌋P put some instants on the wrong side; the
    # exact rule does not (the issue counted 44 of 2,000 steps)
    t = np.arange(2000) * 0.013
    tau = t - np.floor(t / 0.1) * 0.1
    ends = np.cumsum([d for _, d in sw.schedule])
    old = np.minimum(np.searchsorted(ends, tau, "right"), 4)
    index = np.array([names.index(m) for m, _ in sw.schedule])
    assert int((index[old] != step_modes(sw.schedule, t, names, 0.013)).sum()) > 0
    # every mode of the schedule is visited at h = 0.01
    assert set(step_modes(sw.schedule, np.arange(10) * 0.01, names, 0.01).tolist()) == set(
        names.index(m) for m, _ in sw.schedule
    )


def test_schedule_ticks_past_int64_use_exact_integers():
    sch = [("a", 0.1 / 3), ("b", 0.05)]  # 17 decimals: P = 8.3e15 ticks
    tk = ScheduleTicks.of(sch, 0.013)
    assert tk.period == 8333333333333333 and tk.unit == 10**17
    got = step_modes(sch, np.arange(300) * 0.013, ["a", "b"], 0.013)
    assert got.tolist() == _exact_truth(sch, ["a", "b"], 0.013, 300)
    assert decimal_fraction(0.1) == Fraction(1, 10)
