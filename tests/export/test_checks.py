"""Tests of :mod:`ntc_design.export.checks`: the emitted gain is the analysed gain at every
sample (a gain whose constants cancel in floating point is refused, naming it), its values
stay in a range the state can take (c(0) = 1e300 is refused), and the sampled steps."""

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.export.checks import (
    GAIN_RTOL,
    MAX_SAMPLES,
    check_emitted_gain,
    lb_norm_bound,
    sample_steps,
)
from ntc_design.export.run import export
from ntc_design.export.source import ExportOptions
from ntc_design.gain.code import GainCode
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def g1_law(g1, theta):
    des = nd.design(g1, theta, thresholds=False)
    return agent_law(des, Digital(0.1, 1), "1/(1+t)", 0.4, 0.3)


def test_the_norm_bound_is_the_dense_row_sum_bound(g1, theta, g1_law):
    # ‖L_B‖∞ <= max_i (2 Σ_j ‖A_ij‖∞ + δ‖B_i‖∞), the dense matrix's row sums below it
    lb = nd.design(g1, theta, thresholds=False).grounded_laplacian()
    dense = float(np.abs(lb).sum(axis=1).max())
    bound = lb_norm_bound(g1_law)
    assert dense <= bound <= 2 * dense


def test_the_samples():
    assert sample_steps(5).tolist() == [0, 1, 2, 3, 4]
    k = sample_steps(10**9)
    assert k.size <= MAX_SAMPLES and k[0] == 0 and k[-1] == 10**9 - 1
    assert (np.diff(k) > 0).all() and k[MAX_SAMPLES // 2 - 1] == MAX_SAMPLES // 2 - 1


def test_a_rounding_that_sets_in_late_is_met(g1_law):
    # exp(t − 1100) − exp(t − 1100) absorbs 1/(1+t) from t ≈ 1,140 on: the samples of a
    # certificate's horizon (10^10 steps of 0.1 s) spread geometrically, so many fall there
    k = sample_steps(10**10)
    assert (k * 0.1 > 1200).sum() > 1000
    law = replace(g1_law, gain=GainCode.of("1/(1+t)+exp(t-1100)-exp(t-1100)"))
    with pytest.raises(InputError, match="gain"):
        check_emitted_gain(law, 10**10)


@pytest.mark.parametrize("gain", ["1/(1+t)", "exp(-t)*sin(t)^2+1/(1+t)", "(1+t)^(-0.6)"])
def test_a_faithful_gain_passes(g1_law, gain):
    law = replace(g1_law, gain=GainCode.of(gain))
    check_emitted_gain(law, 3000)
    # and the emitted value is within the tolerance of exact fractions where they apply
    if gain == "1/(1+t)":
        for k in (0, 7, 2999):
            t = k * 0.1
            exact = 1 / (1 + Fraction(t))
            assert abs(Fraction(law.gain.value(t)) - exact) <= GAIN_RTOL * exact


@pytest.mark.hostile
def test_a_gain_whose_constants_cancel_is_refused(g1_law):
    law = replace(g1_law, gain=GainCode.of("1/(1+t)+exp(40)-exp(40)"))
    assert law.gain.value(0.0) == 0.0  # what the code computes: the agents never move
    with pytest.raises(InputError) as err:
        check_emitted_gain(law, 100, "s.yaml: gain")
    msg = str(err.value)
    assert msg.startswith("s.yaml: gain: c(t) = 1/(1+t)+exp(40)-exp(40) computes to 0.0")
    assert "is 1.0 (the analysed gain)" in msg and "\n" not in msg


@pytest.mark.hostile
@pytest.mark.parametrize("gain", ["1e300/(1+t)^2", "1e12/(1+t)"])
def test_a_gain_the_state_cannot_take_is_refused(g1_law, gain):
    law = replace(g1_law, gain=GainCode.of(gain))
    with pytest.raises(InputError) as err:
        check_emitted_gain(law, 100, "gain")
    msg = str(err.value)
    assert msg.startswith(f"gain: c(t) = {gain} is ") and "exceeds 1e+10" in msg, msg


@pytest.mark.hostile
def test_a_schedule_tail_is_compared_and_its_table_range_checked(g1_law):
    # the table is emitted as its doubles: only the tail is compared; every value is
    # range-checked
    ok = ScheduleGain([0.0, 1.0], [1.0, 0.5], tail="1/(1+t)")
    check_emitted_gain(replace(g1_law, gain=GainCode.of(ok)), 300)
    bad = ScheduleGain([0.0, 1.0], [1.0, 0.5], tail="1/(1+t)+exp(40)-exp(40)")
    with pytest.raises(InputError, match=r"computes to 0.0 at t = 1 "):
        check_emitted_gain(replace(g1_law, gain=GainCode.of(bad)), 300)
    # a table value past the step bound (a schedule caps its values at 1e6; h = 1e10 here)
    big = replace(g1_law, gain=GainCode.of(ok), digital=Digital(1e10, 0))
    with pytest.raises(InputError, match=r"is 1 at t = 0 \(step 0\): one step"):
        check_emitted_gain(big, 3)


@pytest.mark.hostile
def test_export_refuses_the_cancelled_gain_and_writes_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(InputError) as err:
        export(
            EXAMPLES / "scenarios" / "g1_deadline.yaml",
            "c",
            out,
            ExportOptions(period=0.1, gain="1/(1+t)+exp(40)-exp(40)"),
        )
    assert "g1_deadline.yaml: gain: c(t) = 1/(1+t)+exp(40)-exp(40) computes to" in str(err.value)
    assert not out.exists()
