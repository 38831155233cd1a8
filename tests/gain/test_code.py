"""Tests of :mod:`ntc_design.gain.code`: c(t) one t at a time, as the exported
code computes it, against the vectorised gains the simulator uses."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.expr.tree import numeric_function
from ntc_design.gain.code import GainCode
from ntc_design.gain.schedule import ScheduleGain, join_tail


def _table(interpolation="linear"):
    t = np.concatenate([[0.0], np.sort(np.random.default_rng(3).uniform(0, 10, 40)), [10.0]])
    c = 2.0 / (1.0 + t) ** 0.7 + 0.1 * np.sin(3 * t)
    tail = join_tail(10.0, float(c[-1]))
    return ScheduleGain(t, c, interpolation, tail)


@pytest.mark.parametrize("interpolation", ["linear", "previous"])
def test_schedule_agrees_with_its_vectorised_call(interpolation):
    g = _table(interpolation)
    times = np.concatenate([np.arange(0, 2000) * 0.0077, g.t, [g.end, 10.5, 1e3]])
    code = GainCode.of(g)
    got = np.array(code.values(times))
    want = g(times)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=0)
    assert code.is_schedule and code.end == 10.0
    # at the table's times the values are the table's, exactly
    assert [code.value(t) for t in g.t[:-1]] == g.c[:-1].tolist()


def test_linear_table_between_points():
    g = ScheduleGain([0.0, 1.0, 3.0], [2.0, 1.0, 0.0 + 0.5], tail="1.5/(1+t)")
    code = GainCode.of(g)
    assert code.value(0.5) == 1.5
    assert code.value(2.0) == 0.75  # slope -0.25 from (1, 1)
    assert code.value(3.0) == 1.5 / 4.0  # the tail from T on
    assert code.value(-1.0) == 2.0  # before the table: c_0, as np.interp


def test_previous_table_is_a_step():
    code = GainCode.of(ScheduleGain([0.0, 1.0, 2.0], [3.0, 2.0, 1.0], "previous", "2/(1+t)"))
    assert code.values([0.0, 0.99, 1.0, 1.5, -0.5]) == [3.0, 3.0, 2.0, 2.0, 3.0]


@pytest.mark.parametrize("text", ["1/(1+t)", "0.9374/(0.3738 + t)", "(1+t)^(-0.75)", "2"])
def test_expression_agrees_with_numpy(text):
    t = np.arange(0, 5000) * 0.013
    got = np.array(GainCode.of(text).values(t))
    np.testing.assert_allclose(got, numeric_function(text, "gain")(t), rtol=1e-13, atol=0)
    assert not GainCode.of(text).is_schedule


@pytest.mark.hostile
def test_a_python_function_cannot_be_exported():
    with pytest.raises(InputError, match="gain: .*function cannot be exported"):
        GainCode.of(lambda t: 1 / (1 + t))  # type: ignore[arg-type]


@pytest.mark.hostile
def test_a_bad_tail_names_its_field():
    g = ScheduleGain([0.0, 1.0], [1.0, 0.5], tail="1/(1+t)")
    object.__setattr__(g, "tail", "__import__('os')")
    with pytest.raises(InputError, match=r"^gain\.tail: "):
        GainCode.of(g)
