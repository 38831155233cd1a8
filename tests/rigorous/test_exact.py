"""Tests of :mod:`ntc_design.rigorous.exact`."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ntc_design.rigorous.exact import Dyadic, exact_pd, verified_float_pd

# -------------------------------------------------------------- exact and float proofs


def test_exact_and_float_pd_agree_on_boundary_cases():
    eps = 2.0**-40
    a = np.array([[1.0, 1.0], [1.0, 1.0 + eps]])  # det = eps > 0: PD, barely
    assert exact_pd(Dyadic.of(a)).holds
    b = np.array([[1.0, 1.0], [1.0, 1.0]])  # singular
    assert not exact_pd(Dyadic.of(b)).holds
    assert not verified_float_pd(b, np.zeros((2, 2))).holds
    assert verified_float_pd(np.eye(50), np.zeros((50, 50))).holds
    # an error bound bigger than the smallest eigenvalue prevents a proof
    assert not verified_float_pd(np.eye(3) * 1e-6, np.full((3, 3), 1e-6)).holds


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 9), st.sampled_from([-1e-3, 0.0, 1e-9, 0.5]))
def test_exact_pd_agrees_with_eigenvalues(seed, n, shift):
    """FLINT's fraction-free LU (Sylvester) against LAPACK eigenvalues, on matrices whose
    smallest eigenvalue is clearly away from 0 or exactly 0 (a rank-deficient Gram matrix)."""
    rng = np.random.default_rng(seed)
    g = rng.integers(-4, 5, size=(n, max(n - 1, 1))).astype(float)
    m = g @ g.T  # singular (rank <= n-1) for n >= 2, exact in doubles
    m = m + shift * np.eye(n)
    lam = np.linalg.eigvalsh(m)[0]
    pd = exact_pd(Dyadic.of(m)).holds
    if abs(lam) > 1e-6 * max(1.0, np.abs(m).max()):
        assert pd == (lam > 0)
    elif shift <= 0:
        assert not pd  # singular or shifted down: never positive definite
