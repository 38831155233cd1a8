"""Tests of :mod:`ntc_design.simulate.loss`: the exact moments of the three policies
against an exact enumeration of the arrivals (x coordinates, the weights read from the
topology) and against a written-out NumPy Monte Carlo, the offset under skip against the
linear solve, and the issue's figures on G1."""

import itertools
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design import Topology
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid, digital_moments
from ntc_design.simulate.loss import (
    check_loss_moments,
    edge_terms,
    loss_moments,
    loss_note,
    loss_width,
    mean_offset,
    multipliers,
)
from ntc_design.simulate.moments import PreparedModes
from ntc_design.simulate.system import mode_system

X0_LIN = np.linspace(-3, 3, 21)
NOISE = NoiseModel(sigma=0.4, f=0.3)
POLICIES = ("skip", "rescale", "hold")


def gain(t):
    return 1 / (1 + np.asarray(t, dtype=float))


@pytest.fixture(scope="module")
def g1_sys(g1):
    des = nd.design(g1, THETA, thresholds=False)
    return mode_system(des, NOISE), X0_LIN - np.tile(THETA, 7), des


@pytest.fixture(scope="module")
def tiny():
    """Three agents, d = 2, one antagonistic edge."""
    top = Topology.from_edges(
        3,
        2,
        [
            (2, 1, np.array([[1.0, 0.2], [0.2, 0.5]])),
            (3, 2, -np.array([[0.8, 0.0], [0.0, 0.6]])),
            (1, 3, np.array([[0.7, 0.1], [0.1, 0.9]])),
        ],
    )
    theta = np.array([1.0, -0.5])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        des = nd.design(top, theta, thresholds=False)
    noise = NoiseModel(sigma=0.3, f=0.2)
    return top, des, mode_system(des, noise), theta, (0.3, 0.2)


def _x_model(top, des, sig, fsc):
    """Per edge (i, j, A_ij, |A_ij|, g_e, K_e), u and the grounding blocks δ B_i, from the
    topology and the design (not from L_B)."""
    d = top.dim
    edges = []
    for i, j in top.edges:
        a, ab = top.weight(i, j), top.abs_weight(i, j)
        edges.append((i, j, a, ab, sig * ab @ np.ones(d), fsc * ab))
    ground = np.zeros((top.n, d, d))
    for i, b in des.B.items():
        ground[i] = des.delta * np.asarray(b)
    return edges, des.input_vector(), ground


def enumerate_moments(top, des, noise, x0, h, delay, k_steps, loss, policy):
    """E[x_K] and E[x_K x_Kᵀ] by summing over every arrival pattern (2^(E·K)), each with
    its own linear-Gaussian moment recursion on (x_k … x_{k−D}, 1, y) in x coordinates."""
    sig, fsc = noise
    edges, u, ground = _x_model(top, des, sig, fsc)
    n, d, ne = top.n, top.dim, len(edges)
    nd_ = n * d
    hold = policy == "hold"
    one = (delay + 1) * nd_
    w = one + 1 + (ne * d if hold else 0)
    lo = delay * nd_
    z0 = np.zeros(w)
    z0[:one] = np.tile(x0, delay + 1)
    z0[one] = 1.0
    for e, (i, j, a, ab, _, _) in enumerate(edges):
        if hold:
            z0[one + 1 + e * d : one + 1 + (e + 1) * d] = (
                a @ x0[j * d : j * d + d] - ab @ x0[i * d : i * d + d]
            )
    q = 1.0 - np.asarray(loss)
    m_sum, z_sum = np.zeros(w), np.zeros((w, w))
    for pattern in itertools.product((0, 1), repeat=ne * k_steps):
        chi = np.array(pattern).reshape(k_steps, ne)
        prob = float(np.prod(np.where(chi == 1, q, 1 - q)))
        if prob == 0.0:
            continue
        m, zz = z0.copy(), np.outer(z0, z0)
        for k in range(k_steps):
            c = float(gain(k * h))
            tau = c * h
            mat = np.zeros((w, w))
            mat[:nd_, :nd_] = np.eye(nd_)
            for b in range(delay):
                mat[(b + 1) * nd_ : (b + 2) * nd_, b * nd_ : (b + 1) * nd_] = np.eye(nd_)
            mat[one, one] = 1.0
            mat[:nd_, one] += tau * u
            for i in range(n):
                mat[i * d : i * d + d, lo + i * d : lo + i * d + d] -= tau * ground[i]
            noise_terms = []  # (placement W×d, cov-from-zz function)
            for e, (i, j, a, ab, g, kk) in enumerate(edges):
                row = np.zeros((d, w))  # a_e as a row block of z
                row[:, lo + j * d : lo + j * d + d] += a
                row[:, lo + i * d : lo + i * d + d] -= ab
                diff = np.zeros((d, w))
                diff[:, lo + j * d : lo + j * d + d] += np.eye(d)
                diff[:, lo + i * d : lo + i * d + d] -= np.eye(d)
                ch = chi[k, e]
                place = np.zeros((w, d))
                if hold:
                    y = one + 1 + e * d
                    mat[y : y + d, y : y + d] = (1 - ch) * np.eye(d)
                    mat[y : y + d, :] += ch * row
                    place[y : y + d] = ch / np.sqrt(h) * np.eye(d)
                    # x uses the new y: τ (y_old (1 − χ) + χ (a + n/√h ... )) at agent i
                    mat[i * d : i * d + d, y : y + d] += tau * (1 - ch) * np.eye(d)
                    mat[i * d : i * d + d, :] += tau * ch * row
                    place[i * d : i * d + d] = tau * ch / np.sqrt(h) * np.eye(d)
                else:
                    mult = ch / q[e] if policy == "rescale" else ch
                    mat[i * d : i * d + d, :] += tau * mult * row
                    place[i * d : i * d + d] = tau * mult / np.sqrt(h) * np.eye(d)
                noise_terms.append((place, g, kk, diff))
            new = mat @ zz @ mat.T
            for place, g, kk, diff in noise_terms:
                cov = np.outer(g, g) + kk @ diff @ zz @ diff.T @ kk.T
                new += place @ cov @ place.T
            zz, m = new, mat @ m
        m_sum += prob * m
        z_sum += prob * zz
    return m_sum[:nd_], z_sum[:nd_, :nd_]


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("delay", [0, 1])
def test_exact_moments_equal_the_enumeration_of_every_arrival_pattern(tiny, policy, delay):
    top, des, s, theta, noise = tiny
    x0 = np.array([0.5, -1.0, 2.0, 0.3, -1.5, 1.0])
    loss = np.array([0.3, 0.5, 0.1])
    h, k_steps = 0.2, 3
    grid, _ = digital_grid(Digital(h, delay), h * k_steps, np.array([h * k_steps]))
    eps0 = x0 - np.tile(theta, 3)
    got = loss_moments(s, grid, gain, eps0, theta, delay, loss, policy)
    m, zz = enumerate_moments(top, des, noise, x0, h, delay, k_steps, loss, policy)
    th = np.tile(theta, 3)
    want_ms = np.array(
        [
            np.trace(zz[2 * i : 2 * i + 2, 2 * i : 2 * i + 2])
            - 2 * th[2 * i : 2 * i + 2] @ m[2 * i : 2 * i + 2]
            + th[2 * i : 2 * i + 2] @ th[2 * i : 2 * i + 2]
            for i in range(3)
        ]
    )
    assert got.moments.ms_error[-1] == pytest.approx(want_ms, rel=1e-10)
    assert got.moments.mean[-1] == pytest.approx(m - th, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("delay", [0, 1])
@pytest.mark.parametrize("t_end", [3.0, 3.04])  # 3.04: a last partial step of 0.04
def test_without_loss_every_policy_is_the_lossless_recursion(g1_sys, delay, t_end):
    s, eps0, _ = g1_sys
    grid, _ = digital_grid(Digital(0.1, delay), t_end, np.array([1.0, t_end]))
    want = digital_moments(PreparedModes.of([s], eps0), grid, gain, delay)
    for policy in POLICIES:
        got = loss_moments(s, grid, gain, eps0, THETA, delay, np.zeros(s.n_edges), policy)
        assert got.moments.ms_error == pytest.approx(want.moments.ms_error, rel=1e-11)
        assert got.peak == pytest.approx(want.peak, rel=1e-11)
        assert got.offset == 0.0


def _written_out_mc(s, des, top, x0, h, k_steps, loss, policy, paths, seed):
    """Σ_i ‖x_i(K h) − θ‖² per path, by a plain NumPy loop over the steps (D = 0)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    edges, u, ground = _x_model(top, des, 0.4, 0.3)
    n, d = top.n, top.dim
    x = np.tile(x0, (paths, 1)).reshape(paths, n, d)
    q = 1.0 - loss
    y = np.stack(
        [a @ x0[j * d : j * d + d] - ab @ x0[i * d : i * d + d] for i, j, a, ab, _, _ in edges]
    )
    y = np.tile(y, (paths, 1, 1))
    for k in range(k_steps):
        c = float(gain(k * h))
        xi = rng.standard_normal((paths, 2, len(edges)))
        chi = rng.random((paths, len(edges))) < q
        dx = c * h * (u.reshape(n, d) - np.einsum("iab,pib->pia", ground, x))
        for e, (i, j, a, ab, g, kk) in enumerate(edges):
            meas = x[:, j] @ a.T - x[:, i] @ ab.T
            nz = (
                g[None] * xi[:, 0, e, None] + ((x[:, j] - x[:, i]) @ kk.T) * xi[:, 1, e, None]
            ) / np.sqrt(h)
            ch = chi[:, e, None]
            if policy == "hold":
                y[:, e] = np.where(ch, meas + nz, y[:, e])
                dx[:, i] += c * h * y[:, e]
            else:
                mult = ch / q[e] if policy == "rescale" else ch
                dx[:, i] += c * h * mult * (meas + nz)
        x = x + dx
    return ((x - THETA) ** 2).sum(axis=(1, 2))


@pytest.mark.parametrize("policy", POLICIES)
def test_exact_moments_lie_in_the_band_of_a_written_out_monte_carlo(g1, g1_sys, policy):
    s, eps0, des = g1_sys
    h, k_steps, p = 0.1, 20, 0.2
    loss = np.full(s.n_edges, p)
    grid, _ = digital_grid(Digital(h), h * k_steps, np.array([h * k_steps]))
    got = loss_moments(s, grid, gain, eps0, THETA, 0, loss, policy)
    sq = _written_out_mc(s, des, g1, X0_LIN, h, k_steps, loss, policy, 20000, 11)
    band = 4.0 * sq.std(ddof=1) / np.sqrt(sq.size)
    assert abs(float(got.moments.ms_error[-1].sum()) - sq.mean()) <= band


def test_the_offset_under_skip_solves_the_mean_equation(g1, g1_sys):
    s, _, des = g1_sys
    rng = np.random.default_rng(3)
    loss = rng.uniform(0.0, 0.5, s.n_edges)
    edges, u, ground = _x_model(g1, des, 0.4, 0.3)
    d, n = 3, 7
    mat = np.zeros((n * d, n * d))
    for i in range(n):
        mat[i * d : i * d + d, i * d : i * d + d] += ground[i]
    for (i, j, a, ab, _, _), p in zip(edges, loss, strict=True):
        mat[i * d : i * d + d, i * d : i * d + d] += (1 - p) * ab
        mat[i * d : i * d + d, j * d : j * d + d] -= (1 - p) * a
    x_star = np.linalg.solve(mat, u)
    got = mean_offset(s, THETA, loss, "skip")
    assert got == pytest.approx(x_star - np.tile(THETA, n), rel=1e-9, abs=1e-12)
    assert mean_offset(s, THETA, loss, "rescale").tolist() == [0.0] * 21


def test_the_mean_under_skip_converges_to_the_offset_with_a_constant_gain(g1_sys):
    s, eps0, _ = g1_sys
    loss = np.full(s.n_edges, 0.2)
    grid, _ = digital_grid(Digital(0.1), 100.0, np.array([100.0]))
    got = loss_moments(s, grid, lambda t: np.ones_like(t), eps0, THETA, 0, loss, "skip")
    want = mean_offset(s, THETA, loss, "skip")
    assert got.moments.mean[-1] == pytest.approx(want, abs=1e-6)


@pytest.mark.parametrize(
    ("policy", "p", "final", "peak", "offset"),
    [  # the issue's figures on G1 (h = 0.1, D = 0, c = 1/(1+t), σ = 0.4, f = 0.3)
        ("skip", 0.1, None, None, 0.143),
        ("skip", 0.3, 4.33, None, 0.450),
        ("rescale", 0.0, None, 289.0, 0.0),
        ("rescale", 0.3, None, 7419.0, 0.0),
    ],
)
def test_the_issue_figures_on_g1(g1_sys, policy, p, final, peak, offset):
    s, eps0, _ = g1_sys
    grid, _ = digital_grid(Digital(0.1), 10.0, np.array([10.0]))
    got = loss_moments(s, grid, gain, eps0, THETA, 0, np.full(s.n_edges, p), policy)
    assert got.offset == pytest.approx(offset, abs=1.5e-3)
    if final is not None:
        assert float(got.moments.ms_error[-1].sum()) == pytest.approx(final, rel=2e-3)
    if peak is not None:
        assert got.peak == pytest.approx(peak, rel=1e-3)
    # 2.2 % of ‖1⊗θ‖ at 10 % loss under skip
    if policy == "skip" and p == 0.1:
        assert got.offset / np.linalg.norm(np.tile(THETA, 7)) == pytest.approx(0.022, abs=5e-4)


def test_edge_terms_rebuild_l_b(g1_sys):
    s, _, _ = g1_sys
    et = edge_terms(s, THETA)
    d = 3
    lap = et.grounding.copy()
    for e in range(s.n_edges):
        i, j = int(s.dst[e]), int(s.src[e])
        lap[i * d : i * d + d, i * d : i * d + d] += et.absw[e]
        lap[i * d : i * d + d, j * d : j * d + d] -= et.signed[e]
    assert lap == pytest.approx(s.lap_b.toarray(), abs=1e-14)
    # b_e vanishes on a cooperative edge and is −2|A|θ on an antagonistic one
    neg = [e for e in range(s.n_edges) if np.allclose(et.signed[e], -et.absw[e])]
    assert neg, "G1 has antagonistic edges"
    for e in neg:
        assert et.offset[e] == pytest.approx(-2 * et.absw[e] @ THETA)


def test_multipliers_and_widths():
    mu, var, sq = multipliers(np.array([0.8]), "skip")
    assert (mu[0], var[0], sq[0]) == pytest.approx((0.8, 0.16, 0.8))
    mu, var, sq = multipliers(np.array([0.8]), "rescale")
    assert (mu[0], var[0], sq[0]) == pytest.approx((1.0, 0.25, 1.25))
    assert loss_width(21, 1, 8, 3, "hold") == 42 + 1 + 24
    assert loss_width(21, 1, 8, 3, "skip") == 43


@pytest.mark.hostile
def test_too_large_lossy_moments_are_refused_in_one_line():
    with pytest.raises(InputError, match=r"^method: exact moments at Nd"):
        check_loss_moments(10**6, 0, 1, 1, "skip")
    with pytest.raises(InputError, match=r"^digital\.loss: the exact moments"):
        check_loss_moments(3000, 5, 10**5, 3, "hold")


def test_the_note_says_where_the_mean_goes():
    assert "0.143" in loss_note("skip", np.full(3, 0.1), 0.1433, 6.48)
    assert "2.2%" in loss_note("skip", np.full(3, 0.1), 0.1433, 6.48)
    assert "p_e in [0.1, 0.3]" in loss_note("skip", np.array([0.1, 0.3]), 0.2, 6.48)
    assert "goes to 1⊗θ" in loss_note("hold", np.full(3, 0.1), 0.0, 6.48)
