"""Lemma 1's design against an independent construction from the definitions (Niu & Wu,
Sec. 2-3), written here with plain NumPy loops: the signed Laplacian, |A_ij|, U, B_i,
L_B, the identity L_B(1⊗θ) = (Δ⊗I)B x0 and the Hurwitz property the lemma promises."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.generate import random_network


def _abs_weight(a: np.ndarray) -> np.ndarray:
    """|A| = sgn(A)·A for a semidefinite A, the sign read from its eigenvalues."""
    lam = np.linalg.eigvalsh(a)
    return -a if lam.max() <= 1e-12 * max(1.0, np.abs(lam).max()) and lam.min() < 0 else a


def _by_definition(top, theta: np.ndarray, delta: float):
    """(L, U, B, L_B, u) from the definitions, agent indices 0..N−1."""
    n, d = top.n, top.dim
    lap = np.zeros((n * d, n * d))
    antagonised = set()
    b = {}
    for (i, j), a in top.weights.items():
        a = np.asarray(a, dtype=float)
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a  # L_ij = −A_ij
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += _abs_weight(a)  # L_ii = Σ|A_ik|
        if np.linalg.eigvalsh(a).min() < -1e-12 * max(1.0, np.abs(a).max()):
            antagonised.add(i)  # a negative (semi)definite in-edge: i ∈ U
            b[i] = b.get(i, np.zeros((d, d))) + _abs_weight(a)  # B_i = Σ_Ω|A_ij|
    big_d = np.zeros_like(lap)
    for i, bi in b.items():
        big_d[i * d : (i + 1) * d, i * d : (i + 1) * d] = bi
    lap_b = lap + delta * big_d
    x0 = (1 + 2 / delta) * theta
    u = big_d @ np.tile(x0, n)  # (Δ⊗I)·blockdiag(B_i)·(1⊗x0), δ_i = δ on U
    return lap, sorted(antagonised), b, lap_b, u * delta


NETWORKS = [
    ("G1", lambda: nd.paper.g1()),
    ("G2", lambda: nd.paper.g2()),
    *[
        (f"{fam}-{seed}", lambda fam=fam, seed=seed: random_network(12, 2, seed, fam))
        for fam in ("random", "ring", "small-world", "scale-free")
        for seed in (0, 3)
    ],
]


@pytest.mark.parametrize("name, make", NETWORKS, ids=[n for n, _ in NETWORKS])
def test_lemma1_design_matches_the_definitions(name, make):
    top = make()
    theta = np.arange(1.0, top.dim + 1.0) * np.array([1, -1] * top.dim)[: top.dim]
    des = nd.design(top, theta, 0.1)
    lap, u_set, b, lap_b, u = _by_definition(top, theta, des.delta)
    scale = np.abs(lap_b).max()
    np.testing.assert_allclose(top.laplacian(), lap, atol=1e-12 * scale)
    assert list(des.informed) == u_set  # V_I = U
    assert set(des.B) == set(b)
    for i, bi in b.items():
        np.testing.assert_allclose(des.B[i], bi, atol=1e-12 * scale)
    np.testing.assert_allclose(des.grounded_laplacian(), lap_b, atol=1e-12 * scale)
    np.testing.assert_allclose(des.input_vector(), u, atol=1e-12 * scale * np.abs(theta).max())
    # eq. (11): L_B(1⊗θ) = (Δ⊗I)B x0, so 1⊗θ is the equilibrium of the drift
    one_theta = np.tile(theta, top.n)
    assert np.abs(lap_b @ one_theta - u).max() <= 1e-12 * scale * np.abs(theta).max() * top.n
    # Lemma 1: δ > C and k1, x0 as stated; −L_B Hurwitz (every network here satisfies
    # Assumption 2: random_network builds it in, G1 and G2 are the paper's)
    assert des.assumption_holds
    assert des.delta > des.C and des.delta == pytest.approx(des.C + 0.1)
    assert des.k1 == pytest.approx(1 + 2 / des.delta, rel=1e-15)
    np.testing.assert_allclose(des.x0, des.k1 * theta, rtol=1e-15)
    assert np.linalg.eigvals(-lap_b).real.max() < 0
