"""c(t) as balls: a schedule's series is its interpolation, an expression's Taylor
coefficients are the derivatives written out (1/(1+t): (−1)^j/(1+t)^(j+1))."""

from __future__ import annotations

import pytest
from flint import arb

from ntc_design.certify.deadline_gain import GainBalls
from ntc_design.errors import InputError


def test_schedule_gain_series_is_its_interpolation():
    g = GainBalls(
        {"t": [0, 1, 2], "c": [1.0, 0.5, 0.25], "interpolation": "linear", "tail": "1/(1+t)"}
    )
    c = g.series(arb(0.5), 3)
    assert float(c[0].mid()) == pytest.approx(0.75) and float(c[1].mid()) == pytest.approx(-0.5)
    assert float(g.value(arb(3.0)).mid()) == pytest.approx(0.25)  # the tail after the table


def test_expression_series_are_the_derivatives():
    c = GainBalls("1/(1+t)").series(arb(1.0), 5)
    for j, v in enumerate(c):
        assert float(v.mid()) == pytest.approx((-1) ** j / 2 ** (j + 1), rel=1e-15)
    wide = GainBalls("(1+t)^(-1/3)").series(arb(0).union(arb(1)), 3)
    assert wide[0].contains(arb(2) ** (-arb(1) / 3)) and wide[0].contains(arb(1))


@pytest.mark.hostile
def test_a_gain_that_is_not_analytic_is_named():
    with pytest.raises(InputError, match="^gain: deadline needs an analytic c"):
        GainBalls("Min(1, 1/t)").series(arb(1.0), 3)
    from ntc_design.errors import options_written_as

    with options_written_as({"deadline": "--deadline"}), pytest.raises(InputError) as err:
        GainBalls("Min(1, 1/t)").series(arb(1.0), 3)  # ntc certify's words
    assert str(err.value).startswith("gain: --deadline needs an analytic c")
