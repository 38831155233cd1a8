"""Tests of :mod:`ntc_design.certify.dense`."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ntc_design.certify.dense import prove_hurwitz
from ntc_design.certify.lyapunov import decay_rate_lmi


def _matrix_with_known_spectrum(seed, worst_real):
    """Permutation-similar to a block upper triangular matrix whose diagonal blocks are
    [a] or [[a, b], [-b, a]]: its eigenvalues are known exactly in floating point."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 9))
    t = np.triu(rng.normal(size=(n, n)), 1)
    reals = rng.uniform(0.1, 3.0, size=n)
    k = int(rng.integers(n))
    reals[k] = worst_real
    i = 0
    while i < n:
        if i + 1 < n and rng.random() < 0.35:  # a complex pair a ± ib
            a, b = min(reals[i], reals[i + 1]), float(rng.uniform(0.5, 2))
            t[i, i] = t[i + 1, i + 1] = a
            t[i, i + 1], t[i + 1, i] = b, -b
            reals[i] = reals[i + 1] = a
            i += 2
        else:
            t[i, i] = reals[i]
            i += 1
    perm = rng.permutation(n)
    return t[np.ix_(perm, perm)], float(np.min(reals))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([0.0, -1e-12, -0.3, -2.0]))
def test_no_hurwitz_certificate_for_unstable_matrices(seed, worst):
    """A matrix L_B with an eigenvalue of real part <= 0 (−L_B has one with real part >= 0)
    never gets a Hurwitz certificate, exact or floating."""
    m, lo = _matrix_with_known_spectrum(seed, worst)
    assert lo <= 0
    assert not prove_hurwitz(m, exact=True).holds
    assert not prove_hurwitz(m, exact=False).holds
    assert decay_rate_lmi(m).p is None


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_hurwitz_certificate_issued_for_stable_matrices(seed):
    m, lo = _matrix_with_known_spectrum(seed, 0.2)
    if np.linalg.cond(m) < 1e8:
        assert prove_hurwitz(m, exact=True).holds
        assert prove_hurwitz(m, exact=False).holds
