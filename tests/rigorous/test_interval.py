"""Tests of :mod:`ntc_design.rigorous.interval`.

Every enclosure is checked against the exact value: rational expressions in
:class:`fractions.Fraction` arithmetic at rational points of the interval, transcendental
ones against mpmath at 60 digits (its error is far below the balls' radii)."""

import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest
import sympy as sp
from flint import arb

from ntc_design.expr.symbolic import parse_expression, symbol
from ntc_design.rigorous.interval import NotEnclosable, bounds, enclose, lower, t_ball, upper

T = symbol("t")


def _exact(x: arb) -> Fraction:
    """An exact ball endpoint (a dyadic number) as a Fraction."""
    assert x.is_exact()
    m, e = x.mid().man_exp()
    return Fraction(int(m)) * Fraction(2) ** int(e)


def _ends(ball: arb) -> tuple[Fraction, Fraction]:
    assert ball.is_finite(), ball
    return _exact(ball.lower()), _exact(ball.upper())


def _samples(a: Fraction, b: Fraction, k: int, seed: int) -> list[Fraction]:
    """The ends, the midpoint and k random rationals of [a, b]."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    inner = [a + (b - a) * Fraction(int(n), 997) for n in rng.integers(0, 998, size=k)]
    return [a, b, (a + b) / 2, *inner]


def _encloses(ball: arb, values) -> None:
    """Every value lies in the ball, and in the doubles of :func:`bounds` too."""
    lo, hi = _ends(ball)
    dlo, dhi = bounds(ball)
    assert Fraction(dlo) < lo and hi < Fraction(dhi)  # one ulp outwards, strictly
    for v in values:
        assert lo <= v <= hi, (float(lo), float(v), float(hi))


def _mp(x) -> Fraction:
    """An mpmath value at 60 digits as a Fraction (exact enough against 53-bit balls)."""
    return Fraction(mpmath.nstr(x, 60, min_fixed=-math.inf, max_fixed=math.inf))


# -- t_ball ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "a, b", [(0.0, 1.0), (0.1, 0.3), (1 / 3, 1 / 3), (-2.5, 1e-300), (7.0, 1e6)]
)
def test_t_ball_contains_the_interval_of_doubles(a, b):
    lo, hi = _ends(t_ball(a, b))
    assert lo <= Fraction(a) and Fraction(b) <= hi
    # Arb's union is tight up to its radius's 30-bit rounding (a few units of 2^-30)
    assert hi - lo <= Fraction(b) - Fraction(a) + Fraction(max(abs(a), abs(b), 1e-300)) / 2**26


def test_t_ball_for_one_point_is_that_point():
    lo, hi = _ends(t_ball(0.1, 0.1))
    assert lo <= Fraction(0.1) <= hi and hi - lo <= Fraction(0.1) / 2**50


# -- rational expressions against Fraction arithmetic -----------------------------------


RATIONAL = [
    ("t^3 - 2*t + 1/3", lambda t: t**3 - 2 * t + Fraction(1, 3)),
    ("(t - 1/3)^2", lambda t: (t - Fraction(1, 3)) ** 2),
    ("1/(1 + t^2)", lambda t: 1 / (1 + t**2)),
    ("(1 + t)^(-2)", lambda t: (1 + t) ** -2),
    ("3/7*t^5 - t^4/11 + 5", lambda t: Fraction(3, 7) * t**5 - t**4 / 11 + 5),
    ("(2*t - 1)/(t + 3) - 1/(t + 4)^3", lambda t: (2 * t - 1) / (t + 3) - 1 / (t + 4) ** 3),
    ("-t", lambda t: -t),
    ("7", lambda t: Fraction(7)),
    ("-1/3", lambda t: Fraction(-1, 3)),
]


@pytest.mark.parametrize("text, f", RATIONAL, ids=[r[0] for r in RATIONAL])
@pytest.mark.parametrize(
    "a, b", [(0.0, 1.0), (0.25, 0.375), (1.5, 4.0), (3.0, 3.0)], ids=["01", "narrow", "wide", "pt"]
)
def test_rational_expressions_are_enclosed(text, f, a, b):
    expr = parse_expression(text, "f")
    A, B = Fraction(a), Fraction(b)
    ball = enclose(expr, t_ball(a, b))
    _encloses(ball, [f(x) for x in _samples(A, B, 12, 1)])


def test_a_point_ball_of_a_polynomial_is_tight():
    # at one exact t the only error is Arb's rounding: a few ulps
    expr = parse_expression("t^3 - 2*t + 1/3", "f")
    lo, hi = _ends(enclose(expr, t_ball(0.75, 0.75)))
    v = Fraction(3, 4) ** 3 - Fraction(3, 2) + Fraction(1, 3)
    assert lo <= v <= hi and hi - lo <= abs(v) / 2**48


@pytest.mark.parametrize("seed", range(4))
def test_random_polynomials_are_enclosed(seed):
    rng = np.random.default_rng(np.random.SeedSequence(100 + seed))
    coef = [
        Fraction(int(p), int(q))
        for p, q in zip(rng.integers(-9, 10, 5), rng.integers(1, 9, 5), strict=True)
    ]
    expr = sum((sp.Rational(c.numerator, c.denominator) * T**k for k, c in enumerate(coef)), 0)
    a, b = sorted(rng.uniform(-3, 3, 2).round(3).tolist())
    ball = enclose(expr, t_ball(a, b))
    xs = _samples(Fraction(a), Fraction(b), 20, seed)
    _encloses(ball, [sum(c * x**k for k, c in enumerate(coef)) for x in xs])


def test_enclosures_shrink_with_the_interval():
    # over [a, a + h] the enclosure of a smooth expression is O(h) wide and still encloses:
    # 64 pieces of [0, 1] together contain every sampled value, each piece tightly
    expr = parse_expression("(t - 1/3)^3 - t/(t + 2)", "f")

    def f(x):
        return (x - Fraction(1, 3)) ** 3 - x / (x + 2)

    widths = []
    for k in range(64):
        a, b = Fraction(k, 64), Fraction(k + 1, 64)
        ball = enclose(expr, t_ball(float(a), float(b)))
        _encloses(ball, [f(x) for x in _samples(a, b, 3, k)])
        lo, hi = _ends(ball)
        widths.append(hi - lo)
    # |f'| <= 1.5 on [0, 1]: a piece's true range is at most 1.5/64 wide; ball arithmetic
    # overestimates by a bounded factor, not by more
    assert max(widths) <= 8 * Fraction(3, 2) / 64


def test_float_coefficients_are_the_doubles_they_hold():
    # tvfiles builds sp.Float(v)·s(t): the constant is the double v itself
    expr = sp.Float(0.1) * T + sp.Float(1.0 / 3.0)
    ball = enclose(expr, t_ball(2.0, 2.0))
    _encloses(ball, [Fraction(0.1) * 2 + Fraction(1.0 / 3.0)])


# -- powers --------------------------------------------------------------------------------


def test_half_integer_powers_at_perfect_squares():
    # t = r² (a double): t^(3/2) = r³, t^(-1/2) = 1/r, √t = r, t^(-3/2) = r⁻³ exactly
    for r in (Fraction(1, 2), Fraction(3, 4), Fraction(5, 2)):
        x = float(r * r)
        assert Fraction(x) == r * r
        for text, v in (
            ("t^(3/2)", r**3),
            ("t^(-1/2)", 1 / r),
            ("sqrt(t)", r),
            ("t^(-3/2)", r**-3),
        ):
            _encloses(enclose(parse_expression(text, "f"), t_ball(x, x)), [v])


def test_half_integer_powers_over_an_interval():
    # t^(5/2) on [1/4, 9/4], checked at the squares (k/8)², where it is (k/8)⁵ exactly
    ball = enclose(parse_expression("t^(5/2)", "f"), t_ball(0.25, 2.25))
    _encloses(ball, [Fraction(k, 8) ** 5 for k in range(4, 13)])


def test_general_powers_use_exp_log():
    # t^(1/3) at cubes and 2^t at integers: exact rational values
    for r in (Fraction(1, 2), Fraction(2), Fraction(3, 2)):
        x = float(r**3)
        _encloses(enclose(parse_expression("t^(1/3)", "f"), t_ball(x, x)), [r])
    for n in (0, 1, 5):
        _encloses(enclose(parse_expression("2^t", "f"), t_ball(n, n)), [Fraction(2**n)])
    _encloses(
        enclose(parse_expression("2^t", "f"), t_ball(0, 3)), [Fraction(2**k) for k in range(4)]
    )


def test_negative_integer_power_through_zero_is_not_finite():
    ball = enclose(parse_expression("(t - 1)^(-2)", "f"), t_ball(0.0, 2.0))
    assert not ball.is_finite()
    assert bounds(ball) == (-math.inf, math.inf)


# -- Abs, Min, Max ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "a, b, lo_max, hi_min",
    [
        (0.75, 1.0, Fraction(1, 4), Fraction(1, 2)),  # t − 1/2 >= 0: the ball itself
        (0.0, 0.25, Fraction(1, 4), Fraction(1, 2)),  # t − 1/2 <= 0: its negation
        (0.0, 1.0, Fraction(0), Fraction(1, 2)),  # through 0: [0, max |end|]
        (0.25, 1.0, Fraction(0), Fraction(1, 2)),
    ],
)
def test_abs_in_each_case(a, b, lo_max, hi_min):
    ball = enclose(parse_expression("Abs(t - 1/2)", "f"), t_ball(a, b))
    lo, hi = _ends(ball)
    assert lo <= lo_max and hi >= hi_min
    assert lo >= -Fraction(1, 2**26)  # |·| never encloses much below 0
    assert hi <= hi_min + Fraction(1, 2**26)  # and is tight at the top
    _encloses(ball, [abs(x - Fraction(1, 2)) for x in _samples(Fraction(a), Fraction(b), 10, 3)])


@pytest.mark.parametrize(
    "text, f",
    [
        ("Max(t, 1 - t)", lambda t: max(t, 1 - t)),
        ("Min(t, 1 - t)", lambda t: min(t, 1 - t)),
        ("Min(t^2, 1/3, 2 - t)", lambda t: min(t * t, Fraction(1, 3), 2 - t)),
        (
            "Max(t^2, 1/3) - Min(t, 1/5)",
            lambda t: max(t * t, Fraction(1, 3)) - min(t, Fraction(1, 5)),
        ),
    ],
)
@pytest.mark.parametrize("a, b", [(0.0, 1.0), (0.0, 0.125), (0.625, 2.0)])
def test_min_max_are_enclosed(text, f, a, b):
    ball = enclose(parse_expression(text, "f"), t_ball(a, b))
    _encloses(ball, [f(x) for x in _samples(Fraction(a), Fraction(b), 12, 4)])


@pytest.mark.parametrize(
    "text, lo_exact, hi_exact",
    [
        # the rule is [pick of the lows, pick of the highs]: tight for one ramp and a level
        ("Max(t, 1/3)", Fraction(1, 3), Fraction(1)),
        ("Min(t, 1/3)", Fraction(0), Fraction(1, 3)),
    ],
)
def test_min_max_rule_is_tight_where_it_can_be(text, lo_exact, hi_exact):
    lo, hi = _ends(enclose(parse_expression(text, "f"), t_ball(0.0, 1.0)))
    tol = Fraction(1, 2**26)
    assert lo_exact - tol <= lo <= lo_exact and hi_exact <= hi <= hi_exact + tol


# -- transcendental functions against mpmath --------------------------------------------


TRANSCENDENTAL = [
    ("exp(t)", mpmath.exp),
    ("log(1 + t)", lambda x: mpmath.log(1 + x)),
    ("sin(3*t)", lambda x: mpmath.sin(3 * x)),
    ("cos(t)^2 - sin(t)/2", lambda x: mpmath.cos(x) ** 2 - mpmath.sin(x) / 2),
    ("tan(t/2)", lambda x: mpmath.tan(x / 2)),
    ("sinh(t) - cosh(t)", lambda x: mpmath.sinh(x) - mpmath.cosh(x)),
    ("tanh(2*t)", lambda x: mpmath.tanh(2 * x)),
    ("atan(t - 1)", lambda x: mpmath.atan(x - 1)),
    ("pi*t + E", lambda x: mpmath.pi * x + mpmath.e),
    ("E^(-t)*sin(pi*t)", lambda x: mpmath.exp(-x) * mpmath.sin(mpmath.pi * x)),
    ("2^sin(t)", lambda x: mpmath.power(2, mpmath.sin(x))),
]


@pytest.mark.parametrize("text, f", TRANSCENDENTAL, ids=[r[0] for r in TRANSCENDENTAL])
@pytest.mark.parametrize("a, b", [(0.0, 1.0), (0.5, 0.5), (1.25, 2.5)])
def test_transcendental_expressions_are_enclosed(text, f, a, b):
    ball = enclose(parse_expression(text, "f"), t_ball(a, b))
    with mpmath.workdps(60):
        values = [
            _mp(f(mpmath.mpf(x.numerator) / x.denominator))
            for x in _samples(Fraction(a), Fraction(b), 8, 5)
        ]
    _encloses(ball, values)


def test_constants_pi_and_e():
    with mpmath.workdps(60):
        pi, e = _mp(mpmath.pi), _mp(mpmath.e)
    t = t_ball(0.0, 1.0)
    lo, hi = _ends(enclose(sp.pi, t))
    assert lo < pi < hi and hi - lo <= Fraction(1, 2**48)
    lo, hi = _ends(enclose(sp.E, t))
    assert lo < e < hi and hi - lo <= Fraction(1, 2**48)


@pytest.mark.parametrize(
    "text, a, b",
    [
        ("1/(t - 1/2)", 0.0, 1.0),  # a pole inside
        ("log(t)", 0.0, 1.0),  # log near 0
        ("tan(t)", 1.0, 2.0),  # tan's pole at π/2
        ("exp(exp(t))", 1000.0, 1001.0),  # overflow
    ],
)
def test_unbounded_on_the_interval_is_not_finite(text, a, b):
    ball = enclose(parse_expression(text, "f"), t_ball(a, b))
    assert not ball.is_finite()
    assert bounds(ball) == (-math.inf, math.inf)
    assert lower(ball) == -math.inf and upper(ball) == math.inf


@pytest.mark.parametrize(
    "expr, name",
    [
        (sp.asin(T), "asin"),
        (sp.floor(T), "floor"),
        (sp.Function("f")(T) + 1, "f"),
        (sp.Integer(1) + sp.acosh(1 + T), "acosh"),
    ],
)
def test_operations_without_a_rule_are_refused(expr, name):
    with pytest.raises(NotEnclosable, match=f"^no interval rule for {name}$"):
        enclose(expr, t_ball(0.0, 1.0))
    assert issubclass(NotEnclosable, ValueError)


# -- the cache -------------------------------------------------------------------------


def test_cache_is_filled_and_reused():
    expr = parse_expression("sin(t)^2 + sin(t)", "f")
    t = t_ball(0.0, 1.0)
    cache: dict = {}
    first = enclose(expr, t, cache)
    assert sp.sin(T) in cache and T in cache and expr in cache
    assert cache[expr] is first
    # a second call answers from the cache: the very same ball object
    assert enclose(expr, t, cache) is first
    assert enclose(sp.sin(T), t, cache) is cache[sp.sin(T)]


def test_cache_entries_stand_for_their_subexpressions():
    # the cache is trusted for "this same t": a seeded entry is used as the enclosure
    cache = {sp.sin(T): arb(3)}
    lo, hi = _ends(enclose(parse_expression("sin(t) + 1", "f"), t_ball(0.0, 1.0), cache))
    assert lo == hi == 4


def test_without_a_cache_each_call_starts_afresh():
    expr = parse_expression("t + 1", "f")
    a = enclose(expr, t_ball(0.0, 1.0))
    lo, hi = _ends(enclose(expr, t_ball(5.0, 5.0)))  # no stale t = [0, 1] reused
    assert lo <= 6 <= hi and hi - lo < Fraction(1, 2**40)
    assert _ends(a)[1] >= 2


# -- bounds, lower, upper --------------------------------------------------------------


@pytest.mark.parametrize("x", [0.5, -3.0, 1e-300, 2.0**1000])
def test_bounds_of_an_exact_double_are_one_ulp_outwards(x):
    lo, hi = bounds(arb(x))
    assert lo == np.nextafter(x, -np.inf) and hi == np.nextafter(x, np.inf)
    assert (lower(arb(x)), upper(arb(x))) == (lo, hi)


@pytest.mark.parametrize("p, q", [(1, 3), (-2, 7), (22, 7), (1, 10**20)])
def test_bounds_of_a_rational_ball_contain_it_exactly(p, q):
    x = arb(p) / q
    lo, hi = bounds(x)
    assert Fraction(lo) < Fraction(p, q) < Fraction(hi)
    # a handful of ulps wide, not more
    assert hi - lo <= 8 * math.ulp(abs(p / q))


def test_bounds_beyond_the_doubles_stay_valid():
    big = arb(2) ** 2000  # finite for Arb, overflows a double
    lo, hi = bounds(big)
    assert hi == math.inf and lo == np.finfo(float).max and Fraction(lo) < 2**2000
    tiny = arb(2) ** -2000
    lo, hi = bounds(tiny)
    assert lo < 0 < hi and Fraction(hi) > 0
    lo, hi = bounds(-big)
    assert lo == -math.inf and hi == -np.finfo(float).max


def test_bounds_of_a_non_finite_ball():
    assert bounds(arb("nan")) == (-math.inf, math.inf)
    assert bounds(arb(0).union(arb("inf"))) == (-math.inf, math.inf)


# -- regressions: a NaN inside Min/Max, and powers of a ball that holds 0 ---------------------


@pytest.mark.parametrize(
    ("text", "a", "b"),
    [("Min(5, tan(t))", 0.0, 2.0), ("Max(-5, 1/(t - 1/2))", 0.0, 1.0), ("Abs(1/(t-1/2))", 0, 1)],
)
def test_an_unbounded_argument_is_never_a_finite_answer(text, a, b):
    # tan has a pole at π/2 in [0, 2] (Min was once exactly 5, though Min(5, tan 0) = 0)
    assert not enclose(parse_expression(text, "f"), t_ball(a, b)).is_finite()


@pytest.mark.parametrize(
    ("text", "lo", "hi"),
    [
        ("(t - 1/2)^2", Fraction(0), Fraction(1, 4)),  # flint's ** gave NaN here
        ("(t - 1/2)^3", Fraction(-1, 8), Fraction(1, 8)),
        ("t^2", Fraction(1, 16), Fraction(1)),  # on [1/4, 1]: flint's ** gave ±1.01
        ("t^5", Fraction(-32), Fraction(1)),  # on [-2, 1]
    ],
)
def test_integer_powers_are_enclosed_tightly_from_the_ends(text, lo, hi):
    a, b = {"t^2": (0.25, 1.0), "t^5": (-2.0, 1.0)}.get(text, (0.0, 1.0))
    e_lo, e_hi = _ends(enclose(parse_expression(text, "f"), t_ball(a, b)))
    assert e_lo <= lo and hi <= e_hi  # sound: the exact range is inside
    # tight: the range itself, widened only by the balls' 30-bit radii (flint's mag_t)
    assert e_hi - e_lo <= (hi - lo) * (1 + 1e-7)
