"""An independent right-hand side of the moment equations (dense NumPy, from the
definitions) and the paper's noise settings."""

import numpy as np

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
