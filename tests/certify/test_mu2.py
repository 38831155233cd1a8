"""Tests of :mod:`ntc_design.certify.mu2`."""

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.optimize import brentq

from ntc_design.certify.mu2 import T0_SCAN_END, mu2_t0, mu2_threshold, noise_sigma_bar
from ntc_design.errors import InputError
from ntc_design.expr.symbolic import symbol

PROVEN = "ball arithmetic on t0 <= t <= 1e9, c decreasing beyond (sympy)"
NUMERICAL = "numerical (the ball-arithmetic proof did not close)"
# t₀ is the crossing rounded up to 6 significant digits: at most 1e-5 relative above it
UP = 1 + 1.1e-5


# -- κ = Λ₂ / (2σ̄Λ₁N) ----------------------------------------------------------------------


def test_threshold_against_exact_arithmetic():
    got = mu2_threshold(0.6, 0.25, 0.4, 7)
    exact = Fraction("0.6") / (2 * Fraction("0.4") * Fraction("0.25") * 7)
    assert got == pytest.approx(float(exact), rel=1e-15)


@pytest.mark.parametrize(("lam2", "lam1", "sbar", "n"), [(0.6, 0.25, 0.4, 7), (2.0, 3.0, 0.1, 4)])
def test_mu2_changes_sign_at_the_threshold(lam2, lam1, sbar, n):
    kappa = mu2_threshold(lam2, lam1, sbar, n)

    def mu2(c):  # μ₂ = c[Λ₂ − 2σ̄Λ₁N c], Niu & Wu's proof of Theorem 3
        return c * (lam2 - 2 * sbar * lam1 * n * c)

    assert mu2(0.999 * kappa) > 0 > mu2(1.001 * kappa)
    assert mu2(0.5 * kappa) > 0


@pytest.mark.parametrize(("lam1", "sbar"), [(0.0, 0.4), (0.25, 0.0)])
def test_threshold_without_noise_or_weights_is_infinite(lam1, sbar):
    assert mu2_threshold(0.6, lam1, sbar, 7) == math.inf


# -- t₀ after which c(t) < κ ---------------------------------------------------------------


def test_t0_of_a_decaying_gain():
    t0, how = mu2_t0("1/(1+t)", 0.1)
    # c(t) = 1/(1+t) < 1/10 exactly when t > 9
    assert 9 < t0 <= 9 * UP
    assert Fraction(1) / (1 + Fraction(t0)) < Fraction(1, 10)
    assert how == PROVEN


def test_t0_of_an_exponential_gain():
    t0, how = mu2_t0("exp(-t)", 0.5)
    assert math.log(2) < t0 <= math.log(2) * UP
    assert how == PROVEN


def test_t0_accepts_a_sympy_expression():
    t = symbol("t")
    assert mu2_t0(1 / (1 + t), 0.1) == mu2_t0("1/(1+t)", 0.1)


def test_a_gain_below_kappa_from_the_start_has_t0_zero():
    assert mu2_t0("1/(1+t)", 2.0) == (0.0, PROVEN)
    assert mu2_t0("1/(1+t)", math.inf) == (0.0, PROVEN)  # no noise: any gain will do


@pytest.mark.parametrize(
    ("gain", "kappa", "expected"),
    [
        ("0.5", 1.0, (0.0, "constant gain below κ")),
        ("2", 1.0, (None, "constant gain 2 >= κ")),
        ("1/4", 0.25, (None, "constant gain 0.25 >= κ")),  # c < κ is strict
    ],
)
def test_constant_gains(gain, kappa, expected):
    assert mu2_t0(gain, kappa) == expected


def test_a_growing_gain_never_gets_below_kappa():
    assert mu2_t0("t", 1.0) == (None, f"c(t) >= κ = 1 still at t = {T0_SCAN_END:g}")


def test_t0_is_the_last_crossing_of_an_oscillating_gain():
    kappa = 0.1
    t0, how = mu2_t0("(2 + cos(t))/(1+t)", kappa)
    # proven on [t0, 1e9]: its split of [a, 2a] once gave the interval back ("numerical")
    assert how == "ball arithmetic on t0 <= t <= 1e9; beyond 1e9 not proven"

    def f(t):
        return (2 + math.cos(t)) / (1 + t) - kappa

    # every crossing lies below 29, where 3/(1+t) reaches κ: bracket them on a fine grid
    grid = np.linspace(0.0, 30.0, 3001)
    roots = [brentq(f, a, b) for a, b in zip(grid[:-1], grid[1:], strict=True) if f(a) * f(b) < 0]
    assert len(roots) > 1  # it does cross several times
    assert roots[-1] < t0 <= roots[-1] * UP


def test_a_gain_touching_kappa_is_not_reported_proven():
    # c(1) = κ exactly (between the scan's grid points): c < κ fails at t = 1
    t0, how = mu2_t0("1/4 - (t-1)**2", 0.25)
    assert how == NUMERICAL
    assert t0 == 0.0


def test_a_bounded_but_not_monotone_gain_is_proven_up_to_the_scan_end():
    assert mu2_t0("2 + sin(t)", 5.0) == (
        0.0,
        "ball arithmetic on t0 <= t <= 1e9; beyond 1e9 not proven",
    )


def test_a_gain_well_below_kappa_is_proven():
    # c(t) = t/(1+t)² <= 1/4 < 0.26 for every t >= 0 (maximum at t = 1)
    assert mu2_t0("t/(1+t)**2", 0.26) == (0.0, PROVEN)


@pytest.mark.parametrize(
    ("gain", "message"),
    [
        ("x + 1", r"^gain: uses x; only the variable t is allowed"),
        ("__import__('os')", r"^gain: function '__import__' not allowed"),
    ],
)
def test_a_bad_gain_is_refused(gain, message):
    with pytest.raises(InputError, match=message):
        mu2_t0(gain, 1.0)


# -- σ̄ of the noise -------------------------------------------------------------------------


def test_sigma_bar_of_a_scale_and_of_a_matrix():
    assert noise_sigma_bar(-0.3) == 0.3
    assert noise_sigma_bar(np.float64(2.0)) == 2.0
    f = np.array([[1.0, 2.0, 0.0], [0.0, -1.0, 3.0], [0.5, 0.0, 1.0]])
    # ‖F‖₂ = √λ_max(FᵀF), independently of numpy's norm
    assert noise_sigma_bar(f) == pytest.approx(math.sqrt(np.linalg.eigvalsh(f.T @ f)[-1]))
    assert noise_sigma_bar([[-2.0]]) == 2.0
    assert noise_sigma_bar(np.diag([0.5, -4.0])) == pytest.approx(4.0)
