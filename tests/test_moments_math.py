"""The exact moment equations against an independent integration: from the SDE of
Niu & Wu (eq. (5) in error form), dε = −c L_B ε dt + c Σ_e g_e dw₁ₑ + c Σ_e K_e ε dw₂ₑ with
g_e = e_i ⊗ σ|A_ij|1_d and K_e = e_i(e_j − e_i)ᵀ ⊗ |A_ij|F for each edge j → i, Itô's rule
gives m' = −c L_B m and S' = −c(L_B S + S L_Bᵀ) + c²Σ g_e g_eᵀ + c²Σ K_e S K_eᵀ. Here those
are built from the topology's weights and integrated by SciPy's adaptive Runge–Kutta."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import ntc_design as nd
from ntc_design.simulate import NoiseModel, simulate

SIGMA, F = 0.4, 0.3


def _abs(a: np.ndarray) -> np.ndarray:
    return a if np.linalg.eigvalsh(a).max() > 0 else -a


def _moment_rhs(top, lap_b: np.ndarray, gain):
    n, d = top.n, top.dim
    g_sum = np.zeros((n * d, n * d))
    ks = []
    for (i, j), a in top.weights.items():
        aa = _abs(np.asarray(a, dtype=float))
        e_i, e_j = np.eye(n)[i], np.eye(n)[j]
        g = np.kron(e_i, SIGMA * aa @ np.ones(d))
        g_sum += np.outer(g, g)
        ks.append(np.kron(np.outer(e_i, e_j - e_i), F * aa))
    nd_ = n * d

    def rhs(t, y):
        c = gain(t)
        m, s = y[:nd_], y[nd_:].reshape(nd_, nd_)
        ds = -c * (lap_b @ s + s @ lap_b.T) + c * c * (g_sum + sum(k @ s @ k.T for k in ks))
        return np.concatenate([-c * lap_b @ m, ds.ravel()])

    return rhs


@pytest.mark.parametrize(
    "gain_text, gain",
    [("1/(1+t)", lambda t: 1 / (1 + t)), ("(1+t)^(-1/3)", lambda t: (1 + t) ** (-1 / 3))],
)
def test_exact_moments_match_an_independent_integration(g1, theta, gain_text, gain):
    rng = np.random.default_rng(np.random.SeedSequence(7))
    x_init = rng.uniform(-3, 3, size=g1.n * g1.dim)
    saves = np.linspace(0.0, 3.0, 13)
    res = simulate(
        g1,
        theta,
        method="exact",
        gain=gain_text,
        noise=NoiseModel(SIGMA, F),
        initial=x_init,
        T=3.0,
        save_times=saves.tolist(),
    )
    des = next(iter(res.designs.values()))
    eps0 = x_init - np.tile(theta, g1.n)
    y0 = np.concatenate([eps0, np.outer(eps0, eps0).ravel()])
    sol = solve_ivp(
        _moment_rhs(g1, des.grounded_laplacian(), gain),
        (0.0, 3.0),
        y0,
        t_eval=saves,
        rtol=1e-10,
        atol=1e-12,
        method="DOP853",
    )
    assert sol.success
    nd_ = g1.n * g1.dim
    for k in range(saves.size):
        s = sol.y[nd_:, k].reshape(nd_, nd_)
        per_agent = np.einsum("iaia->i", s.reshape(g1.n, g1.dim, g1.n, g1.dim))
        np.testing.assert_allclose(res.exact.ms_error[k], per_agent, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(
            res.exact.mean[k], sol.y[:nd_, k], rtol=1e-6, atol=1e-9 * np.abs(eps0).max()
        )


@pytest.mark.filterwarnings("ignore::ntc_design.AssumptionWarning")
def test_scalar_pair_has_the_closed_form():
    """Two agents, d = 1: 2 listens to 1 through an antagonistic edge (so 2 is informed),
    1 listens to 2 cooperatively. Without noise the moments are m(t) = exp(−L_B t)ε(0) and
    S = m mᵀ in closed form (c = 1); the RK4 error is measured against the scale of S(0)."""
    from scipy.linalg import expm

    top = nd.Topology.from_edges(2, 1, [(1, 2, -np.eye(1) * 2.0), (2, 1, np.eye(1) * 1.0)])
    times = [0.0, 0.5, 1.0, 2.0]
    res = simulate(
        top, [1.0], method="exact", gain="1", noise=NoiseModel(0.0, 0.0), initial=[0.0, 0.0],
        T=2.0, save_times=times,
    )  # fmt: skip
    lap_b = next(iter(res.designs.values())).grounded_laplacian()
    eps0 = -np.ones(2)  # x(0) = 0, θ = 1
    for k, t in enumerate(times):
        m = expm(-lap_b * t) @ eps0
        np.testing.assert_allclose(res.exact.mean[k], m, rtol=0, atol=1e-5)
        np.testing.assert_allclose(res.exact.ms_error[k], m**2, rtol=0, atol=1e-4)
