"""Tests of :mod:`ntc_design.tune.operators`."""

import numpy as np
import pytest

from ntc_design.simulate.prepare import prepare_modes
from ntc_design.tune.operators import MomentOperators


def test_operators_reproduce_the_moment_right_hand_side(g1, g1_spec):
    pm = prepare_modes(g1, g1_spec.replace(T=1.0, method="exact"), lambda t: 1 + 0 * t)
    ops = MomentOperators.build(pm.systems[0], pm.n, pm.d)
    from ntc_design.simulate.moments import MomentRhs

    rhs = MomentRhs(pm.systems[0], pm.n, pm.d)
    rng = np.random.default_rng(np.random.SeedSequence(7))
    a = rng.normal(size=(21, 21))
    s = a @ a.T
    a1, a2 = ops.products(ops.pack(s))
    for c in (0.3, 2.0):
        _, ds = rhs(c, np.zeros(21), s)
        assert np.allclose(c * a1 + c * c * (a2 + ops.q), ds.ravel(), rtol=1e-12, atol=1e-10)
    # the transposed map is the adjoint of the products on every matrix, symmetric or not
    y, mu = rng.normal(size=441), rng.normal(size=441)
    p1, p2 = ops.products(y)
    lhs = mu @ (0.7 * p1 + 0.49 * p2)
    assert lhs == pytest.approx(ops.transpose(mu, 0.7) @ y, rel=1e-12)
