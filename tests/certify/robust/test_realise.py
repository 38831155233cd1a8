"""Tests of :mod:`ntc_design.certify.robust.realise`."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.robust.problem import dense_problem
from ntc_design.certify.robust.realise import (
    SHRINK,
    _grad_decay,
    _grad_offset,
    _project,
    abscissa,
    climb,
    offset_of,
)
from ntc_design.model.generate import random_network

THETA = [1.0, -2.0]


def _rng(k):
    return np.random.default_rng(np.random.SeedSequence(k))


def _sym(rng, m, d, scale):
    x = rng.normal(size=(m, d, d))
    return scale * 0.5 * (x + np.transpose(x, (0, 2, 1)))


@pytest.fixture(scope="module")
def prob():
    """3 agents, d = 2, one cooperative and two antagonistic edges (the offset moves)."""
    top = random_network(3, 2, seed=0, p_negative=0.5, extra=1.0)
    p = dense_problem(nd.design(top, THETA, thresholds=False))
    assert p.edges.m == 3 and set(p.edges.s) == {1.0, -1.0}
    return p


# -- the set and the two objectives --------------------------------------------------------


def test_project_clips_the_eigenvalues_of_the_symmetric_part():
    got = _project(np.diag([3.0, -0.2, -5.0]), 1.0)
    np.testing.assert_allclose(got, np.diag([1.0, -0.2, -1.0]), atol=1e-15)
    # only the symmetric part counts: a skew part is dropped
    skew = np.array([[0.0, 2.0], [-2.0, 0.0]])
    np.testing.assert_allclose(_project(np.diag([0.5, 0.1]) + skew, 1.0), np.diag([0.5, 0.1]))
    assert np.all(_project(np.ones((2, 2)), 0.0) == 0.0)


def test_project_is_the_nearest_point_of_the_set():
    rng = _rng(1)
    for _ in range(5):
        x = _sym(rng, 1, 3, 2.0)[0]
        got = _project(x, 0.5)
        assert np.allclose(got, got.T) and np.linalg.norm(got, 2) <= 0.5 + 1e-12
        # nearer (Frobenius) than any other symmetric matrix of norm <= 0.5
        for _ in range(20):
            y = _sym(rng, 1, 3, 1.0)[0]
            y *= 0.5 / max(np.linalg.norm(y, 2), 0.5)
            assert np.linalg.norm(x - got) <= np.linalg.norm(x - y) + 1e-12
        np.testing.assert_allclose(_project(got, 0.5), got, atol=1e-14)  # idempotent


@pytest.mark.parametrize(
    ("lap", "alpha"),
    [
        ([[3.0, 1.0], [0.0, -1.0]], -1.0),
        ([[2.0, -5.0], [5.0, 2.0]], 2.0),  # a complex pair 2 ± 5i
        ([[4.0, 0.0, 0.0], [1.0, 0.5, 0.0], [0.0, 7.0, 9.0]], 0.5),
    ],
)
def test_abscissa_of_hand_matrices(lap, alpha):
    assert abscissa(np.array(lap)) == pytest.approx(alpha)


def test_offset_of_solves_the_equilibrium():
    p = SimpleNamespace(u=np.array([1.0, 2.0]), target=np.array([0.0, 1.0]))
    lap = np.array([[2.0, 0.0], [1.0, 1.0]])
    # x* = (0.5, 1.5): ‖x* − target‖ = √(0.25 + 0.25)
    assert offset_of(p, lap) == pytest.approx(math.sqrt(0.5))
    assert offset_of(p, np.array([[1.0, 1.0], [1.0, 1.0]])) == math.inf  # singular


def test_nominal_offset_is_zero_by_lemma1(prob):
    # Lemma 1: x* = 1⊗θ at the nominal weights (up to the rounding of the input)
    assert offset_of(prob, prob.lap_b) < 1e-12


def _directional(fn, es, h, eps=1e-6):
    return (fn(es + eps * h) - fn(es - eps * h)) / (2 * eps)


def test_decay_gradient_matches_finite_differences(prob):
    rng = _rng(2)
    es = _sym(rng, prob.edges.m, prob.d, 0.05)
    value, g = _grad_decay(prob, es)
    assert value == pytest.approx(abscissa(prob.lap(es)), rel=1e-12)
    assert np.allclose(g, np.transpose(g, (0, 2, 1)))  # a gradient in symmetric E
    for _ in range(3):
        h = _sym(rng, prob.edges.m, prob.d, 1.0)
        fd = _directional(lambda e: abscissa(prob.lap(e)), es, h)
        assert np.sum(g * h) == pytest.approx(fd, rel=1e-5, abs=1e-8)


def test_offset_gradient_matches_finite_differences(prob):
    rng = _rng(3)
    es = _sym(rng, prob.edges.m, prob.d, 0.1)
    value, g = _grad_offset(prob, es)
    assert value == pytest.approx(0.5 * offset_of(prob, prob.lap(es)) ** 2, rel=1e-10)
    assert value > 0  # antagonistic edges move x*
    for _ in range(3):
        h = _sym(rng, prob.edges.m, prob.d, 1.0)
        fd = _directional(lambda e: 0.5 * offset_of(prob, prob.lap(e)) ** 2, es, h)
        assert np.sum(g * h) == pytest.approx(fd, rel=1e-5, abs=1e-10)


# -- the climb -----------------------------------------------------------------------------


def _in_set(es, radii):
    return all(
        np.allclose(e, e.T) and np.linalg.norm(e, 2) <= r * SHRINK * (1 + 1e-12)
        for e, r in zip(es, radii, strict=True)
    )


def _vertices(p, rho):
    eye = np.broadcast_to(np.eye(p.d), (p.edges.m, p.d, p.d))
    return [np.zeros((p.edges.m, p.d, p.d)), rho * eye, -rho * eye]


def test_decay_climb_is_no_better_than_its_starts(prob):
    rho = 0.2
    es = climb(prob, rho, "decay", starts=3, seed=4)
    assert es.shape == (prob.edges.m, prob.d, prob.d)
    assert _in_set(es, [rho] * prob.edges.m)
    got = abscissa(prob.lap(es))
    starts = [abscissa(prob.lap(v)) for v in _vertices(prob, rho)]
    assert got <= min(starts) + 1e-7
    # and below every random realisation drawn from the set
    rng = _rng(5)
    for _ in range(20):
        e = np.array([_project(x, rho) for x in _sym(rng, prob.edges.m, prob.d, 1.0)])
        assert got <= abscissa(prob.lap(e)) + 1e-7


def test_offset_climb_is_no_better_than_its_starts(prob):
    rho = 0.2
    es = climb(prob, rho, "offset", starts=2, seed=4)
    assert _in_set(es, [rho] * prob.edges.m)
    got = offset_of(prob, prob.lap(es))
    starts = [offset_of(prob, prob.lap(v)) for v in _vertices(prob, rho)]
    assert got >= max(starts) * (1 - 1e-7) and got > 0


def test_climb_keeps_each_edge_within_its_own_radius(prob):
    radii = np.array([0.3, 0.0, 0.1])
    es = climb(prob, radii, "decay", starts=3, seed=1)
    assert _in_set(es, radii)
    assert np.all(es[1] == 0.0)  # a certain edge (ρ_e = 0) never moves


def test_climb_is_reproducible_from_its_seed(prob):
    a = climb(prob, 0.2, "decay", starts=4, seed=9)
    b = climb(prob, 0.2, "decay", starts=4, seed=9)
    np.testing.assert_array_equal(a, b)


def test_cooperative_weights_never_move_the_equilibrium(prob):
    # D_eᵀ(1⊗θ) = (1 − s_e)θ = 0 for a cooperative edge: with the antagonistic weights
    # certain, x*(A') = 1⊗θ for every realisation, so there is nothing to climb
    radii = np.where(prob.edges.s > 0, 0.5, 0.0)
    es = climb(prob, radii, "offset", starts=2, seed=0)
    assert _in_set(es, radii)
    assert np.all(es[prob.edges.s < 0] == 0.0)
    moved = [radii[:, None, None] * np.eye(prob.d), -radii[:, None, None] * np.eye(prob.d), es]
    assert max(offset_of(prob, prob.lap(e)) for e in moved) < 1e-12
