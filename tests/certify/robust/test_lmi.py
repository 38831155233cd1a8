"""Tests of :mod:`ntc_design.certify.robust.lmi`."""

from types import SimpleNamespace

import cvxpy as cp
import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify.robust.lmi import (
    FRACTIONS,
    DecayLMI,
    channels,
    decay_matrix,
    descend,
    load_cvxpy,
    offset_matrix,
    offset_sdp,
    solve_sdp,
)
from ntc_design.certify.robust.problem import dense_problem, uncertain_edges
from ntc_design.model import Topology
from ntc_design.model.generate import random_network
from tests.support.robust import features, independent_lap_b, sample

THETA = [1.0, -2.0]


def _rng(k):
    return np.random.default_rng(np.random.SeedSequence(k))


def _min_eig(m):
    return float(np.linalg.eigvalsh(0.5 * (m + m.T))[0])


@pytest.fixture(scope="module")
def prob():
    """3 agents, d = 2, one cooperative and two antagonistic edges."""
    top = random_network(3, 2, seed=0, p_negative=0.5, extra=1.0)
    return dense_problem(nd.design(top, THETA, thresholds=False))


@pytest.fixture(scope="module")
def semi():
    """Edges with exactly rank-one weights (V_e has fewer columns than d), both signs."""
    top = Topology.from_edges(
        3,
        2,
        [
            (1, 2, -np.array([[1.0, 1.0], [1.0, 1.0]])),
            (2, 3, np.diag([2.0, 0.0])),
            (1, 3, np.array([[2.0, 0.5], [0.5, 1.0]])),
            (3, 1, -np.diag([0.0, 3.0])),
        ],
    )
    # channels reads only the sizes and the edges
    return SimpleNamespace(n=6, d=2, edges=uncertain_edges(top))


def _block(n_agents, d, i):
    """E_i = e_i ⊗ I_d."""
    return np.kron(np.eye(n_agents)[:, [i]], np.eye(d))


# -- the solvers ----------------------------------------------------------------------------


def test_load_cvxpy_is_the_installed_module():
    assert load_cvxpy() is cp


def test_solve_sdp_reaches_the_optimum():
    a = np.array([[2.0, 1.0], [1.0, 2.0]])
    x = cp.Variable((2, 2), symmetric=True)
    prob = cp.Problem(cp.Minimize(cp.trace(x)), [x >> a])
    assert solve_sdp(prob)
    # min tr X over X ⪰ A is attained at X = A
    assert prob.value == pytest.approx(4.0, abs=1e-6)


@pytest.mark.parametrize("case", ["infeasible", "unbounded"])
def test_solve_sdp_reports_failure(case):
    x = cp.Variable((2, 2), symmetric=True)
    if case == "infeasible":
        prob = cp.Problem(cp.Minimize(0), [x >> np.eye(2), x << -np.eye(2)])
    else:
        prob = cp.Problem(cp.Minimize(cp.trace(x)), [x << np.eye(2)])
    assert solve_sdp(prob) is False


# -- the channels and Ψ ---------------------------------------------------------------------


def test_channels_against_their_definition(semi):
    ed = semi.edges
    assert ed.pivots == ((1,), (0,), (0, 1), (0,))  # a basis of range(W) among W's columns
    got = channels(semi)
    for e, (ewv, dwd, vwv) in enumerate(got):
        i, j, s, w = int(ed.dst[e]), int(ed.src[e]), ed.s[e], ed.w[e]
        v = w[:, list(ed.pivots[e])]
        ei, dm = _block(3, 2, i), _block(3, 2, i) - s * _block(3, 2, j)
        np.testing.assert_array_equal(ewv, ei @ w @ v)
        np.testing.assert_array_equal(dwd, dm @ w @ dm.T)
        np.testing.assert_array_equal(vwv, v.T @ w @ v)
        assert np.linalg.matrix_rank(vwv) == v.shape[1]  # VᵀWV ≻ 0 on range(W)


def test_channels_scaled_and_normalised(semi):
    raw = channels(semi)
    for (e1, q1, v1), (e2, q2, v2), e in zip(
        raw, channels(semi, 4.0, normalise=True), range(semi.edges.m), strict=True
    ):
        v = semi.edges.basis(e)
        t = np.diag(1 / np.linalg.norm(v, axis=0))  # unit columns: V → V·T
        np.testing.assert_allclose(e2, e1 @ t / 4.0, rtol=1e-15)
        np.testing.assert_allclose(q2, q1 / 4.0, rtol=1e-15)
        np.testing.assert_allclose(v2, t @ v1 @ t / 4.0, rtol=1e-15)


def test_decay_matrix_without_channels_is_the_lyapunov_form():
    rng = _rng(1)
    lap, m = rng.normal(size=(4, 4)), rng.normal(size=(4, 4))
    p = m @ m.T + np.eye(4)
    got = decay_matrix(lap, [], p, np.zeros(0), 0.3, 0.1)
    sh = lap - 0.3 * np.eye(4)
    np.testing.assert_allclose(got, p @ sh + sh.T @ p, atol=1e-14)


def test_decay_matrix_blocks(semi):
    ch = channels(semi)
    rng = _rng(2)
    lap = rng.normal(size=(6, 6))
    m = rng.normal(size=(6, 6))
    p, tau, alpha, rho = m @ m.T + np.eye(6), rng.uniform(0.5, 2.0, len(ch)), 0.2, 0.3
    psi = decay_matrix(lap, ch, p, tau, alpha, rho)
    r = sum(c[0].shape[1] for c in ch)
    assert psi.shape == (6 + r, 6 + r)
    np.testing.assert_allclose(psi, psi.T, atol=1e-13)
    sh = lap - alpha * np.eye(6)
    top = p @ sh + sh.T @ p - sum(t * rho**2 * c[1] for t, c in zip(tau, ch, strict=True))
    np.testing.assert_allclose(psi[:6, :6], top, atol=1e-12)
    col = 6
    for t, (ewv, _dwd, vwv) in zip(tau, ch, strict=True):
        k = vwv.shape[0]
        np.testing.assert_allclose(psi[:6, col : col + k], p @ ewv, atol=1e-12)
        np.testing.assert_allclose(psi[col : col + k, col : col + k], t * vwv, atol=1e-12)
        assert np.all(psi[col : col + k, 6:col] == 0)  # block diagonal in the channels
        col += k
    # a radius per edge equal to ρ is the same matrix
    np.testing.assert_array_equal(decay_matrix(lap, ch, p, tau, alpha, np.full(len(ch), rho)), psi)


def test_decay_matrix_is_congruent_for_any_basis_and_scale(prob):
    """The solver's unit-column, scaled channels prove the same LMI as verify's."""
    rng = _rng(3)
    m = rng.normal(size=(prob.n, prob.n))
    p, tau = m @ m.T + np.eye(prob.n), rng.uniform(0.5, 2.0, prob.edges.m)
    raw = decay_matrix(prob.lap_b, channels(prob), p, tau, 0.4, 0.2)
    s = 3.0
    scaled = decay_matrix(prob.lap_b / s, channels(prob, s, normalise=True), p, tau, 0.4 / s, 0.2)
    norms = np.concatenate(
        [np.linalg.norm(prob.edges.basis(e), axis=0) for e in range(prob.edges.m)]
    )
    t = np.diag(np.concatenate([np.ones(prob.n), 1 / norms]))
    np.testing.assert_allclose(scaled, t @ raw @ t / s, atol=1e-12)


# -- what a solved decay LMI proves --------------------------------------------------------


def _nominal_rate(p):
    return float(np.min(np.linalg.eigvals(p.lap_b).real))


def test_a_decay_certificate_holds_on_every_sampled_realisation(prob):
    alpha0 = _nominal_rate(prob)
    alpha, rho = 0.5 * alpha0, 0.1
    got = DecayLMI(prob, channels(prob))(alpha, rho)
    assert got is not None
    p, tau = got
    assert _min_eig(p) > 0.99 and np.all(tau >= 0)
    assert _min_eig(decay_matrix(prob.lap_b, channels(prob), p, tau, alpha, rho)) > 0
    des, rng = prob.design, _rng(4)
    for k in range(16):
        w = sample(des, rho, rng, "vertex" if k % 2 else "interior")
        lap = independent_lap_b(des, w)
        # one P for the whole set: P(L' − αI) + (L' − αI)ᵀP ≻ 0, hence min Re λ(L') > α
        sh = lap - alpha * np.eye(prob.n)
        assert _min_eig(p @ sh + sh.T @ p) > 0
        assert features(des, w)[0] > alpha


def test_no_decay_certificate_beyond_the_nominal_rate(prob):
    lmi = DecayLMI(prob, channels(prob))
    # the nominal weights are in the set: no α above their rate can be proven
    assert lmi(1.01 * _nominal_rate(prob), 0.0) is None
    assert lmi(1.01 * _nominal_rate(prob), 0.05) is None
    # per-edge radii: certain edges (ρ_e = 0) cost nothing
    assert lmi(0.5 * _nominal_rate(prob), np.array([0.1, 0.0, 0.1])) is not None


# -- Γ and what a solved offset LMI proves -------------------------------------------------


def test_offset_matrix_without_multipliers(prob):
    ch = channels(prob)
    r = sum(c[0].shape[1] for c in ch)
    k = prob.n + r + 1
    g = offset_matrix(
        prob.lap_b, ch, prob.target, prob.r0, 2.5, np.zeros(len(ch)), np.zeros((prob.n, k)), 0.1
    )
    expected = np.zeros((k, k))
    expected[: prob.n, : prob.n] = -np.eye(prob.n)
    expected[-1, -1] = 2.5  # ξᵀΓξ = γ − ‖z‖² on ξ = (z, η, 1)
    np.testing.assert_array_equal(g, expected)


def test_offset_form_on_a_realisation(prob):
    """On ξ = (z, η, 1) of a realisation, the Finsler term vanishes and ξᵀΓξ is
    γ − ‖z‖² − Σ λ_e (ρ²‖D_eᵀx*‖²_W − η_eᵀVᵀWVη_e)."""
    ch, ed, d, rho = channels(prob), prob.edges, prob.d, 0.3
    rng = _rng(5)
    x = rng.normal(size=(ed.m, d, d))
    es = np.array([rho * 0.9 * q / np.linalg.norm(q, 2) for q in x + np.transpose(x, (0, 2, 1))])
    lap = prob.lap(es)
    xs = np.linalg.solve(lap, prob.u)
    z = xs - prob.target
    etas, slack = [], []
    for e, delta in enumerate(prob.deltas(es)):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        dx = xs[i : i + d] - ed.s[e] * xs[j : j + d]
        wv = ed.w[e] @ ed.basis(e)
        eta = np.linalg.lstsq(wv, delta @ dx, rcond=None)[0]
        np.testing.assert_allclose(wv @ eta, delta @ dx, atol=1e-12)  # Δ_e dx ∈ range(W)
        q = rho**2 * dx @ ed.w[e] @ dx - eta @ ch[e][2] @ eta
        assert q >= -1e-12  # the channel's constraint holds inside the set
        etas.append(eta)
        slack.append(q)
    xi = np.concatenate([z, *etas, [1.0]])
    gam, lam = 0.7, rng.uniform(0.0, 3.0, ed.m)
    y = rng.normal(size=(prob.n, xi.size))
    g = offset_matrix(prob.lap_b, ch, prob.target, prob.r0, gam, lam, y, rho)
    np.testing.assert_allclose(g, g.T, atol=1e-13)
    expected = gam - z @ z - float(lam @ np.array(slack))
    assert xi @ g @ xi == pytest.approx(expected, abs=1e-10)


def test_an_offset_certificate_bounds_every_sampled_realisation(prob):
    rho = 0.1
    ch = channels(prob)
    got = offset_sdp(prob, ch, rho)
    assert got is not None
    gam, lam, y = got
    assert np.all(lam >= 0)
    assert _min_eig(offset_matrix(prob.lap_b, ch, prob.target, prob.r0, gam, lam, y, rho)) > 0
    des, rng, seen = prob.design, _rng(6), []
    for k in range(16):
        seen.append(features(des, sample(des, rho, rng, "vertex" if k % 2 else "interior"))[1])
    assert max(seen) > 0 and max(seen) ** 2 <= gam


# at the edge of feasibility a solver may stop at an inaccurate point: the float check decides
@pytest.mark.filterwarnings("ignore:Solution may be inaccurate")
def test_no_certificate_once_every_weight_may_vanish(prob):
    # at ρ = 1 the realisation E = −I removes every weight: L_B(A') = δ·blockdiag(B_i),
    # singular as some agent is uninformed, so neither margin nor offset can be bounded
    gone = prob.lap(-np.broadcast_to(np.eye(prob.d), (prob.edges.m, prob.d, prob.d)))
    assert np.min(np.abs(np.linalg.eigvals(gone))) < 1e-12
    ch = channels(prob)
    assert DecayLMI(prob, ch)(0.0, 1.0) is None
    assert offset_sdp(prob, ch, 1.0) is None


# -- the descent to the best verified value -------------------------------------------------


class _Counted:
    """A test that passes up to a threshold, counting its calls."""

    def __init__(self, limit):
        self.limit, self.calls = limit, []

    def __call__(self, v):
        self.calls.append(v)
        return ("ok", v) if v <= self.limit else None


def test_descend_brackets_the_largest_passing_value():
    test = _Counted(0.63)
    lo, best = descend(test, 1.0, steps=8)
    # 0.995, 0.97, 0.9, 0.75 fail and 0.5 passes: then 8 bisections of [0.5, 0.75]
    assert test.calls[:5] == [0.995, 0.97, 0.9, 0.75, 0.5]
    assert len(test.calls) == 5 + 8
    assert lo <= 0.63 < lo + 0.25 / 2**8 and best == ("ok", lo)


def test_descend_from_a_floor():
    test = _Counted(0.7)
    lo, best = descend(test, 1.0, steps=0, floor=0.6)
    assert test.calls[:2] == pytest.approx([0.6 + 0.995 * 0.4, 0.6 + 0.97 * 0.4])
    assert 0.6 <= lo <= 0.7 and best == ("ok", lo)


def test_descend_when_the_top_passes_or_nothing_does():
    lo, best = descend(_Counted(10.0), 2.0, steps=3)
    assert 0.995 * 2.0 < lo <= 2.0 and best is not None
    test = _Counted(-1.0)
    assert descend(test, 2.0, steps=5, floor=0.5) == (0.5, None)
    assert len(test.calls) == len(FRACTIONS)  # the floor itself was tried last
    assert test.calls[-1] == 0.5


# -- edges of radius 0 carry no channel --------------------------------------------------


@pytest.mark.parametrize(
    "radius, active", [(0.0, ()), (0.1, (0, 1, 2)), (np.array([0.0, 0.2, 0.0]), (1,))]
)
def test_perturbed_edges_are_those_of_positive_radius(radius, active):
    from ntc_design.certify.robust.lmi import perturbed

    assert perturbed(radius, 3) == active


def test_active_columns_keep_z_the_kept_channels_and_the_last():
    from ntc_design.certify.robust.lmi import active_columns

    # ξ = (z: 3, η_0: 2, η_1: 1, η_2: 2, 1)
    assert active_columns(3, [2, 1, 2], (0, 1, 2)) == list(range(9))
    assert active_columns(3, [2, 1, 2], (1,)) == [0, 1, 2, 5, 8]
    assert active_columns(3, [2, 1, 2], ()) == [0, 1, 2, 8]


def test_at_radius_zero_psi_is_the_nominal_lyapunov_form(semi):
    # no edge is perturbed: Ψ is P(L_B − αI) + (L_B − αI)ᵀP whatever the multipliers
    ch = channels(semi)
    n = semi.n
    rng = _rng(3)
    lap = rng.normal(size=(n, n))
    a = rng.normal(size=(n, n))
    p = a @ a.T + n * np.eye(n)
    tau = rng.uniform(1, 2, size=len(ch))
    sh = lap - 0.3 * np.eye(n)
    np.testing.assert_allclose(decay_matrix(lap, ch, p, tau, 0.3, 0.0), p @ sh + sh.T @ p)
    # one edge of radius 0 among others: Ψ without its channel's rows, which is the
    # principal submatrix of the Ψ that keeps its channel at ρ_e = 0 (so a certificate
    # that kept it still verifies)
    rad = np.array([0.1, 0.0, 0.1, 0.1])
    tiny = np.where(rad > 0, rad, 1e-150)  # the channel kept, its ρ_e² term negligible
    full = decay_matrix(lap, ch, p, tau, 0.3, tiny)
    sizes = [c[0].shape[1] for c in ch]
    keep = list(range(n)) + [n + sum(sizes[:e]) + k for e in (0, 2, 3) for k in range(sizes[e])]
    np.testing.assert_allclose(decay_matrix(lap, ch, p, tau, 0.3, rad), full[np.ix_(keep, keep)])
