"""Tests of :mod:`ntc_design.certify.ctrue`: the spectral radius of the augmented
second-moment map against a dense Kronecker construction, and c_true at its edge."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import ctrue
from ntc_design.certify import digital as dg
from ntc_design.model.generate import random_network


def _dense_g(e, n, d):
    gm = np.zeros((n, n))
    k = e.absw @ e.f
    gm[e.i * d : e.i * d + d, e.j * d : e.j * d + d] += k
    gm[e.i * d : e.i * d + d, e.i * d : e.i * d + d] -= k
    return gm


def test_spectral_radius_matches_a_dense_kronecker_map():
    top = random_network(3, 1, seed=2)
    lap = nd.design(top, [1.0], thresholds=False).grounded_laplacian()
    edges = dg.edge_noises(top, np.array([[0.3]]), 0.4)
    n = lap.shape[0]
    gms = [_dense_g(e, n, 1) for e in edges]
    for delay, h, c in [(0, 0.1, 0.5), (1, 0.1, 0.4), (2, 0.2, 0.3)]:
        m = n * (delay + 1)
        a = np.zeros((m, m))
        a[:n, :n] = np.eye(n)
        a[:n, m - n :] -= h * c * lap
        a[n:, : m - n] += np.eye(m - n)
        big = np.kron(a, a)
        for ge in gms:
            gh = np.zeros((m, m))
            gh[:n, m - n :] = ge
            big += h * c * c * np.kron(gh, gh)
        want = np.max(np.abs(np.linalg.eigvals(big)))
        assert ctrue.spectral_radius(lap, edges, 1, h, delay, c) == pytest.approx(want, rel=1e-8)
    ct, _ = ctrue.ms_limit([lap], [edges], 1, 0.1, 1)
    assert ctrue.spectral_radius(lap, edges, 1, 0.1, 1, ct * 0.999) < 1
    assert ctrue.spectral_radius(lap, edges, 1, 0.1, 1, ct * 1.001) > 1
