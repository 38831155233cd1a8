"""Tests of :mod:`ntc_design.simulate.ziggurat`."""

import math

import numpy as np
import pytest

from ntc_design.simulate import ziggurat
from ntc_design.simulate.ziggurat import ZIG_R, ZIG_X


def test_ziggurat_tables_are_equal_area_layers():
    # 1024 layers of equal area V from the base edge R down to 0, independently of _tables:
    # layer i (1 ≤ i < 1024) is the strip x_i · (f(x_{i+1}) − f(x_i)), the base layer the
    # rectangle R·f(R) plus the tail beyond R, and x_0 = V / f(R)
    f = np.exp(-0.5 * ZIG_X**2)
    r, v = float(ziggurat.R_TEXT), float(ziggurat.V_TEXT)
    assert ZIG_X.size == ziggurat.LAYERS + 1 == 1025 and ZIG_X[1] == r and ZIG_X[-1] == 0.0
    assert np.all(np.diff(ZIG_X[1:]) < 0)
    areas = ZIG_X[1:-1] * (f[2:] - f[1:-1])
    np.testing.assert_allclose(areas, v, rtol=1e-9)
    base = r * math.exp(-r * r / 2) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
    assert base == pytest.approx(v, rel=1e-14)
    assert ZIG_X[0] == pytest.approx(v / math.exp(-r * r / 2), rel=1e-14)
    np.testing.assert_allclose(ZIG_R, ZIG_X[1:] / ZIG_X[:-1])
    # the fast test's failure rate the docstring states: 0.43 %
    assert 1 - ZIG_R.mean() == pytest.approx(0.0043, abs=5e-5)


def test_the_written_tables_are_the_nearest_doubles_to_the_exact_ones():
    *x, residual = ziggurat.exact_tables(40)
    assert [float(v) for v in x] == ZIG_X.tolist()  # bit for bit
    assert abs(float(residual)) < 1e-20  # R and V close the top layer at f(0) = 1
