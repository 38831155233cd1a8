"""Tests of :mod:`ntc_design.protocol.timevarying`."""

import numpy as np
import pytest

from ntc_design.model.paper import THETA
from ntc_design.protocol import design_topology
from ntc_design.protocol.timevarying import TimeVaryingDesign


def test_lemma1_batch_matches_design_at_each_instant(g1tv):
    des = TimeVaryingDesign(g1tv, np.array(THETA, float), 0.1)
    ts = np.array([0.0, 1.3, 3.9, 17.0, 48.9])
    b = des.at(ts)
    lap = b.lap_b(des.structure)
    u = b.input_vector()
    for k, t in enumerate(ts):
        d = design_topology(g1tv.at(float(t)), THETA, 0.1, thresholds=False)
        assert b.delta[k] == pytest.approx(d.delta, rel=1e-12)
        assert bool(b.assumption_holds[k]) == d.assumption_holds
        np.testing.assert_allclose(lap[k], np.asarray(d.grounded_laplacian()), atol=1e-12)
        np.testing.assert_allclose(u[k], d.input_vector(), atol=1e-12)
        np.testing.assert_allclose(b.x0[k], d.x0, rtol=1e-12)
    # Lemma 1's identity −L_B(t)(1⊗θ) + u(t) = 0 at every instant
    res = -np.einsum("kij,j->ki", lap, np.tile(THETA, 7)) + u
    assert np.max(np.abs(res)) < 1e-12 * np.max(np.abs(lap))
    assert np.ptp(b.delta) > 0.1  # δ(t) really moves
