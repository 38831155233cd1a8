"""Tests of :mod:`ntc_design.certify.delayline`: the step matrix against the expectation
written out from the recursion's matrices, c_true against a dense Kronecker construction,
the gain's growth proof, and the issued certificate's inequality on the exact second
moments of the delayed recursion from k₀ on (random and worst-case initial delay lines)."""

import json

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.certify import delayline as dl
from ntc_design.certify import digital as dg
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital

F = 0.3 * np.eye(3)
SIGMA = 0.4


def _dense_g(e, n, d):
    gm = np.zeros((n, n))
    k = e.absw @ e.f
    gm[e.i * d : e.i * d + d, e.j * d : e.j * d + d] += k
    gm[e.i * d : e.i * d + d, e.i * d : e.i * d + d] -= k
    g = np.zeros(n)
    g[e.i * d : e.i * d + d] = e.sigma * e.absw @ np.ones(d)
    return gm, g


@pytest.fixture(scope="module")
def g1_lap(g1):
    lap = nd.design(g1, THETA, thresholds=False).grounded_laplacian()
    return lap, dg.edge_noises(g1, F, SIGMA)


def _psd(rng, n, scale=1.0):
    a = rng.normal(size=(n, n))
    return scale * (a @ a.T / n + 0.1 * np.eye(n))


def _literal_h(s, rs, ts, lap, gms, alpha, c, g, h):
    """RHS − LHS of the step inequality, from x_{k+1} = A(τ) x_k + B ν in the coordinates
    x = (e, δ_0, …, δ_{D−1}), written out with dense block matrices."""
    n, dd = lap.shape[0], len(rs)
    m = n * (dd + 1)
    tau = h * c
    blk = [np.zeros((n, m)) for _ in range(dd + 1)]
    for b in range(dd + 1):
        blk[b][:, b * n : (b + 1) * n] = np.eye(n)
    ey = blk[0] - sum(blk[1:])  # y = e_{k−D} = e_k − Σ δ_j
    a = blk[0].T @ (blk[0] - tau * lap @ ey) + blk[1].T @ (-tau * lap @ ey)
    for j in range(1, dd):
        a += blk[j + 1].T @ blk[j]  # δ_j ← δ_{j−1}
    w = 1 / tau + g
    wplus = blk[0].T @ s @ blk[0] + sum(w * blk[j + 1].T @ rs[j] @ blk[j + 1] for j in range(dd))
    noise_w = sum(ge.T @ (s + w * rs[0]) @ ge for ge in gms)
    lhs = a.T @ wplus @ a + h * c * c * ey.T @ noise_w @ ey
    rn = [*rs, np.zeros((n, n))]
    rhs = (1 - alpha * tau) * blk[0].T @ s @ blk[0]
    for j in range(dd):
        rp = (1 + g * tau) * rn[j + 1] + tau * ts[j]
        rhs += blk[j + 1].T @ (rp / tau) @ blk[j + 1]
    return rhs - lhs


@pytest.mark.parametrize("delay", [1, 2, 3])
def test_step_matrix_is_the_written_out_expectation(g1_lap, delay):
    lap, edges = g1_lap
    n = lap.shape[0]
    rng = np.random.default_rng(np.random.SeedSequence(46 + delay))
    s = _psd(rng, n)
    rs = [_psd(rng, n, 2.0 - 0.3 * j) for j in range(delay)]
    ts = [_psd(rng, n, 0.5) for _ in range(delay)]
    gms = [_dense_g(e, n, 3)[0] for e in edges]
    for c, g, h in [(0.3, 1.0, 0.1), (0.01, 0.0, 0.05), (1.7, 2.5, 0.2)]:
        want = _literal_h(s, rs, ts, lap, gms, 0.2, c, g, h)
        got = dl.step_matrix(s, rs, ts, lap, edges, 3, 0.2, c, g, h, exact=False)
        assert np.allclose(got.val, want, rtol=1e-9, atol=1e-9 * np.max(np.abs(want)))
        exact = dl.step_matrix(s, rs, ts, lap, edges, 3, 0.2, c, g, h, exact=True).to_float()
        assert np.allclose(exact, want, rtol=1e-9, atol=1e-9 * np.max(np.abs(want)))
    # the additive constant: γ(S) + Σ γ(T_j) from g_e
    gam = sum(float(_dense_g(e, n, 3)[1] @ (s + sum(ts)) @ _dense_g(e, n, 3)[1]) for e in edges)
    assert float(dl.delay_line_gamma(s, ts, edges, 3)) == pytest.approx(gam, rel=1e-12)


def test_growth_bound_and_its_proof():
    assert dl.growth_bound("1/(1+t)") == pytest.approx(1.01, rel=1e-6)
    g = dl.growth_bound("2/(3+t)**0.8")  # (1/c)' = 0.4 (3+t)^(−0.2): largest at t = 0
    assert g == pytest.approx(1.01 * 0.4 * 3**-0.2, rel=1e-6)
    assert dl.prove_growth("2/(3+t)**0.8", g, 0.0)[0] is True
    assert dl.prove_growth("2/(3+t)**0.8", 0.9 * 0.4 * 3**-0.2, 0.0)[0] is not True
    assert dl.prove_growth("1/(1+t)", 0.99, 5.0)[0] is False  # (1/c)' = 1
    assert dl.growth_bound({"t": [0, 1], "c": [1, 0.5]}) is None


def _moments_check(doc, h, delay, z0s, steps=400):
    """Ṽ_{k+1} <= (1 − αhc_k)Ṽ_k + h(c_k²γ(S) + Σ_j c_{k−1−j}²γ(T_j)) and E e_kᵀSe_k <= Ṽ_k
    for k >= k₀, on the exact second moments of the recursion (an independent loop in the
    coordinates z = (e_k, …, e_{k−D}))."""
    res = doc["results"]["digital"]
    mats = doc["matrices"]["P"]
    s = np.array(mats["digital"])
    rs = [np.array(mats[f"digital_R{j}"]) for j in range(delay)]
    ts = [np.array(mats[f"digital_T{j}"]) for j in range(delay)]
    g1 = nd.load("examples/g1.yaml")
    lap = nd.design(g1, THETA, thresholds=False).grounded_laplacian()
    edges = dg.edge_noises(g1, F, SIGMA)
    n = lap.shape[0]
    gs = [_dense_g(e, n, 3) for e in edges]
    gam = lambda x: sum(float(g @ x @ g) for _, g in gs)  # noqa: E731
    m = n * (delay + 1)
    blk = [np.zeros((n, m)) for _ in range(delay + 1)]
    for b in range(delay + 1):
        blk[b][:, b * n : (b + 1) * n] = np.eye(n)
    diffs = [blk[j] - blk[j + 1] for j in range(delay)]  # δ_j = e_{k−j} − e_{k−j−1}
    alpha, k0 = res["alpha"], res["k0"]
    c = 1 / (1 + h * np.arange(k0 + steps + 2))
    worst = 0.0
    for z0 in z0s:
        zz = z0.copy()
        vt = []
        for k in range(k0 + steps + 1):
            tau = h * c[k]
            floor = sum(
                h * c[k - 1 - j] ** 2 * gam(rs[j]) / tau for j in range(delay) if k - 1 - j >= 0
            )
            v = np.trace(s @ zz[:n, :n]) + sum(
                np.trace(rs[j] @ diffs[j] @ zz @ diffs[j].T) / tau for j in range(delay)
            )
            vt.append((v - floor, np.trace(s @ zz[:n, :n])))
            a = np.zeros((m, m))
            a[:n, :n] = np.eye(n)
            a[:n, m - n :] -= tau * lap
            a[n:, : m - n] += np.eye(m - n)
            zd = zz[m - n :, m - n :]
            nz = a @ zz @ a.T
            nz[:n, :n] += h * c[k] ** 2 * sum(ge @ zd @ ge.T + np.outer(g, g) for ge, g in gs)
            zz = 0.5 * (nz + nz.T)
        for k in range(k0, k0 + steps):
            add = h * (
                c[k] ** 2 * gam(s) + sum(c[k - 1 - j] ** 2 * gam(ts[j]) for j in range(delay))
            )
            bound = (1 - alpha * h * c[k]) * vt[k][0] + add
            assert vt[k + 1][0] <= bound * (1 + 1e-9), (k, vt[k + 1][0], bound)
            assert vt[k][1] <= vt[k][0] * (1 + 1e-9)
            worst = max(worst, vt[k + 1][0] / bound)
        # the simplified statement with c̄_k = max(c_k, …, c_{k−D}) and γ'
        k = k0 + 5
        assert vt[k + 1][0] <= (1 - alpha * h * c[k]) * vt[k][0] + h * c[k - delay] ** 2 * res[
            "gamma"
        ] * (1 + 1e-9)
    return worst


@pytest.fixture(scope="module")
def g1_delay_line():
    g1 = nd.load("examples/g1.yaml")
    out = {}
    for h, delay in [(0.1, 1)]:
        doc = certify(g1, THETA, gain="1/(1+t)", digital=Digital(h, delay)).certificate
        out[(h, delay)] = json.loads(json.dumps(doc))
    return out


@pytest.mark.slow
def test_the_delay_line_certificate_on_g1_meets_its_targets(g1_delay_line):
    doc = g1_delay_line[(0.1, 1)]
    res = doc["results"]["digital"]
    assert res["bound"] == "delay_line"
    assert verify(json.loads(json.dumps(doc))).valid
    # κ >= 0.5 c_true (issue 46; the Razumikhin bound gave 0.7 %), k₀·h <= 4 s
    assert res["kappa"] >= 0.5 * res["c_true"]
    assert res["c_true"] == pytest.approx(0.4716, rel=1e-3)
    assert res["k0"] * 0.1 <= 4.0


@pytest.mark.slow
def test_the_certified_inequality_holds_on_the_exact_moments(g1_delay_line):
    doc = g1_delay_line[(0.1, 1)]
    n, delay = 21, 1
    m = n * (delay + 1)
    rng = np.random.default_rng(np.random.SeedSequence(4601))
    a = rng.normal(size=(m, m))
    random_line = a @ a.T  # a random distribution of the initial delay line
    # the worst one for the functional at k₀: the top eigenvector of the delay terms
    s = np.array(doc["matrices"]["P"]["digital_R0"])
    w, v = np.linalg.eigh(s)
    top = np.concatenate([v[:, -1], -v[:, -1]])  # e_0 = −e_{−1}: the largest increment
    held = np.tile(rng.normal(size=n), delay + 1)  # the held start of the simulator
    zs = [random_line, np.outer(top, top) * 100, np.outer(held, held)]
    worst = _moments_check(doc, 0.1, delay, zs, steps=150)
    assert 0 < worst <= 1 + 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("delay", [1, 2])
def test_a_generated_network_meets_the_target(delay):
    top = random_network(4, 2, seed=1)
    doc = certify(top, [1.0, -1.0], gain="1/(1+t)", digital=Digital(0.1, delay)).certificate
    res = doc["results"]["digital"]
    assert res["bound"] == "delay_line" and verify(json.loads(json.dumps(doc))).valid
    assert 0.5 * res["c_true"] <= res["kappa"] < res["c_true"]


@pytest.mark.parametrize("edge", [0.3, 0.57, 0.66, 0.97])
def test_the_search_for_kappa_brackets_the_edge_within_its_resolution(edge):
    # a made-up SDP feasible up to edge·c_hi, whose matrices reach halfway to the edge
    c_hi, solved = 2.0, []

    def solve(c):
        solved.append(c)
        return ("matrices", c) if c <= edge * c_hi else None

    def reach(sol, c):
        return c + 0.5 * (edge * c_hi - c)

    lo, best = dl.largest_level(solve, reach, c_hi)
    assert len(solved) <= dl.KAPPA_STEPS
    assert best is not None and best[1] <= lo <= edge * c_hi
    # within 15 % of the edge in four solves, wherever the edge is
    assert lo >= 0.85 * edge * c_hi


def test_the_search_for_kappa_finds_nothing_when_no_level_is_feasible():
    lo, best = dl.largest_level(lambda c: None, lambda s, c: c, 1.0)
    assert (lo, best) == (0.0, None)
