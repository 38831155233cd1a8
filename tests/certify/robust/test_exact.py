"""Tests of :mod:`ntc_design.certify.robust.exact`."""

import numpy as np


def test_exact_psi_and_gamma_leave_out_the_edges_of_radius_zero(g1_robust):
    # an edge of radius 0 is not perturbed: its channel's rows are left out, which keeps
    # a certificate that listed them valid (Ψ and Γ are then principal submatrices)
    from ntc_design.certify.robust.exact import exact_channels, gamma_exact, psi_exact
    from ntc_design.certify.robust.lmi import active_columns
    from ntc_design.rigorous.exact import Dyadic

    des, rep = g1_robust
    top = des.topology
    ch = exact_channels(top)
    m, n = len(ch), top.nd
    sizes = [c.vwv.num.shape[0] for c in ch]
    rng = np.random.default_rng(4)
    lap = Dyadic.of(des.grounded_laplacian())
    a = rng.normal(size=(n, n))
    p, tau = a @ a.T + n * np.eye(n), rng.uniform(1, 2, m)
    rad = np.full(m, 0.05)
    rad[[0, 3]] = 0.0
    kept = active_columns(n, sizes, tuple(e for e in range(m) if rad[e] > 0))
    tiny = np.where(rad > 0, rad, 2.0**-600)  # kept, ρ_e² exactly 2^−1200: no channel term
    full = psi_exact(lap, ch, p, tau, 0.3, tiny)
    got = psi_exact(lap, ch, p, tau, 0.3, rad)
    idx = kept[:-1]  # Ψ has no last coordinate
    sub = Dyadic(full.num[np.ix_(idx, idx)], full.exp)
    assert got.num.shape == sub.num.shape == (len(idx), len(idx))
    np.testing.assert_allclose(got.to_float(), sub.to_float(), rtol=1e-12)
    # Γ: the kept coordinates of ξ, Y's columns for the left-out channels unused
    k = n + sum(sizes) + 1
    y = rng.normal(size=(n, k))
    target = np.tile(des.theta, top.n)
    r0 = Dyadic.of(rng.normal(size=(n, 1)))
    lam = rng.uniform(0.5, 1.0, m)
    g = gamma_exact(lap, ch, target, r0, 2.0, lam, y, rad)
    assert g.num.shape == (len(kept), len(kept))
    y2 = y.copy()
    y2[:, [c for c in range(k) if c not in kept]] = 7.0  # what the left-out columns hold
    assert np.array_equal(gamma_exact(lap, ch, target, r0, 2.0, lam, y2, rad).num, g.num)
