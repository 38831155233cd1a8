"""Tests of :mod:`ntc_design.certify.robust.problem`."""

import numpy as np
import pytest


@pytest.mark.parametrize(
    "radii, radius, kw, text",
    [
        ([0.05, 0.05], 0.05, {}, "ρ = 0.05"),
        ([], 0.05, {}, "ρ = 0.05"),  # no uncertain edge: the radius asked for
        ([0.02, 0.5], 0.5, {}, "the per-edge radii (max 0.5; ρ_e = 0.02, 0.5)"),
        ([0.02, 0.5], 0.5, {"short": True}, "the per-edge radii (max 0.5)"),
        (
            [0.02, 0.5],
            0.5,
            {"edges": ["1→2", "2→3"]},
            "the per-edge radii (max 0.5; 1→2: 0.02, 2→3: 0.5)",
        ),
        (
            [0.1] * 9 + [0.2],
            0.2,
            {},
            "the per-edge radii (max 0.2; ρ_e = " + ", ".join(["0.1"] * 8) + ", …; 10 edges)",
        ),
    ],
)
def test_radius_text_names_one_radius_or_the_per_edge_radii(radii, radius, kw, text):
    from ntc_design.certify.robust import radius_phrase, radius_text

    assert radius_text(radii, radius, **kw) == text
    edges = kw.get("edges")
    phrase = radius_phrase(radii, radius, edges)
    assert phrase == ("at " if text.startswith("ρ") else "for ") + radius_text(
        radii, radius, edges=edges
    )


def test_channel_bound_keeps_a_well_conditioned_weight_and_an_exact_kernel():
    from ntc_design.certify.robust import channel_bound

    for w, piv in (
        (np.array([[2.0, 0.5], [0.5, 1.0]]), (0, 1)),
        (np.diag([2.0, 0.0]), (0,)),  # an exact kernel: one channel
        (np.array([[1.0, 1.0], [1.0, 1.0]]), (0,)),
    ):
        wb, got = channel_bound(w)
        assert wb is w and got == piv


@pytest.mark.parametrize("det_sign", [-1, 1])
def test_channel_bound_of_a_weight_singular_by_rounding(det_sign):
    # v vᵀ in floating point: exactly, full rank with a determinant of ±1e−20 or so
    from fractions import Fraction

    from ntc_design.certify.robust import CHANNEL_FLOOR, channel_bound, whitening_basis

    rng = np.random.default_rng(5)
    while True:
        v = rng.normal(size=2)
        w = np.outer(v, v)
        det = Fraction(w[0, 0]) * Fraction(w[1, 1]) - Fraction(w[0, 1]) ** 2
        if det != 0 and (det > 0) == (det_sign > 0):
            break
    wb, piv = channel_bound(w)
    assert piv == (0, 1)
    eta = np.diag(wb - w)
    # W̄ − W is diagonal, at least η ≈ CHANNEL_FLOOR·max|W| (rounded up, never below W)
    assert np.array_equal(wb - np.diag(np.diag(wb)), w - np.diag(np.diag(w)))
    assert np.all(eta >= 0.99 * CHANNEL_FLOOR * np.max(np.abs(w)))
    assert np.all(eta <= 2.01 * CHANNEL_FLOOR * np.max(np.abs(w)))
    assert np.all(
        [Fraction(x) >= Fraction(y) for x, y in zip(np.diag(wb), np.diag(w), strict=True)]
    )
    v = whitening_basis(wb)
    np.testing.assert_allclose(v.T @ wb @ v, np.eye(2), atol=1e-12)  # well conditioned


def test_whitening_basis_is_the_identity_without_positive_definiteness():
    from ntc_design.certify.robust import whitening_basis

    np.testing.assert_array_equal(whitening_basis(np.diag([1.0, -1.0])), np.eye(2))
    np.testing.assert_array_equal(whitening_basis(np.diag([1.0, 0.0])), np.eye(2))
    v = whitening_basis(np.diag([4.0, 9.0]))
    np.testing.assert_array_equal(v, np.diag([0.5, 1 / 3]))  # L = I: D^(−1/2), rounded
