"""Robust certification from scratch: L_B(A') rebuilt independently, weight
realisations sampled in the set, their decay and offset, forged certificates."""

import copy
import warnings
from pathlib import Path

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import verify
from ntc_design.certify.format import finish
from ntc_design.certify.robust import robust
from ntc_design.model.paper import THETA
from tests.conftest import ROOT


def independent_lap_b(des, weights: dict) -> np.ndarray:
    """L_B(A') from scratch: L_ii = Σ_j |A'_ij| (|A| by eigen-decomposition), L_ij = −A'_ij,
    plus δ·blockdiag(B_i) (the nominal protocol)."""
    top = des.topology
    n, d = top.n, top.dim
    lap = np.zeros((n * d, n * d))
    for (i, j), a in weights.items():
        lam, q = np.linalg.eigh(a)
        absa = (q * np.abs(lam)) @ q.T
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += absa
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
    for i, b in des.B.items():
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += des.delta * b
    return lap


def sample(des, radius, rng, kind):
    """A random realisation: per weight |A'| = F(I + E)F with E symmetric, ‖E‖ <= ρ."""
    out = {}
    for key, a in des.topology.weights.items():
        lam, q = np.linalg.eigh(a)
        s = 1.0 if lam[-1] > 0 else -1.0 if lam[0] < 0 else 0.0
        absa = s * a
        lw, qw = np.linalg.eigh(absa)
        f = (qw * np.sqrt(np.clip(lw, 0, None))) @ qw.T
        d = a.shape[0]
        if kind == "vertex":
            e = radius * np.diag(rng.choice([-1.0, 1.0], size=d))
            r = np.linalg.qr(rng.normal(size=(d, d)))[0]
            e = r @ e @ r.T
        else:
            x = rng.normal(size=(d, d))
            lam_e, qe = np.linalg.eigh(x + x.T)
            e = (qe * np.clip(lam_e, -radius, radius)) @ qe.T
        out[key] = s * (f @ (np.eye(d) + e) @ f)
        out[key] = 0.5 * (out[key] + out[key].T)
    return out


def features(des, weights):
    lap = independent_lap_b(des, weights)
    alpha = float(np.min(np.linalg.eigvals(lap).real))
    x = np.linalg.solve(lap, des.input_vector())
    return alpha, float(np.linalg.norm(x - np.tile(des.theta, des.topology.n)))


@pytest.fixture(scope="session")
def g1_robust():
    des = nd.design(nd.load(ROOT / "examples" / "g1.yaml"), THETA, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.05)
    return des, rep


def realised(des, edges):
    top = des.topology
    w = dict(top.weights)
    for e in edges:
        w[(top.index(e["to"]), top.index(e["from"]))] = np.asarray(e["weight"], dtype=float)
    return w


def in_set(des, w, radius):
    for key, a in des.topology.weights.items():
        lam = np.linalg.eigvalsh(a)
        s = 1.0 if lam[-1] > 0 else -1.0
        lo = np.linalg.eigvalsh(s * w[key] - (1 - radius) * s * a)[0]
        hi = np.linalg.eigvalsh((1 + radius) * s * a - s * w[key])[0]
        if min(lo, hi) < -1e-9 * np.max(np.abs(a)):
            return False
    return True


def forged_valid(doc: dict, edit) -> bool:
    """Whether ``doc`` still verifies after ``edit`` (its digests recomputed)."""
    bad = copy.deepcopy(doc)
    edit(bad)
    for k in ("digest", "subject_digest", "versions"):
        bad.pop(k, None)
    return verify(finish(bad)).valid


def raise_alpha_to(value: float):
    """An edit stating decay rate ``value``, in the results and in the claims."""

    def raise_alpha(d):
        d["results"]["decay"]["lower"] = value
        for c in d["claims"]:
            if c["property"] == "robust_decay" and "alpha" in c:
                c["alpha"] = d["results"]["decay"]["lower"]

    return raise_alpha


# -- simulating weight realisations (scenario key robust:) ---------------------------------


def _scenario(tmp_path, robust_block: str, paths: int = 60) -> Path:
    p = tmp_path / "sc.yaml"
    p.write_text(
        f"topology: {ROOT / 'examples' / 'g1.yaml'}\ntheta: [1, 2, -1]\ngain: '1/(1+t)'\n"
        "noise: {sigma: 0.4, f: 0.3}\ninitial: {uniform: [-3, 3], seed: 1}\n"
        f"T: 2\ndt: 0.002\npaths: {paths}\nworkers: 1\n{robust_block}\n"
    )
    return p


# -- per-edge radii: a 3-agent cycle whose radii differ (0.02, 0.5, 0.02) -----------------

TRI = """name: tri
dim: 1
agents: 3
edges:
  - {from: 1, to: 2, weight: [[1]], uncertainty: 0.02}
  - {from: 2, to: 3, weight: [[-1]], uncertainty: 0.5}
  - {from: 3, to: 1, weight: [[2]], uncertainty: 0.02}
"""

#: How every face names TRI's set (edges in the robust bounds' order, (to, from)).
TRI_SET = "the per-edge radii (max 0.5; 3→1: 0.02, 1→2: 0.02, 2→3: 0.5)"


@pytest.fixture(scope="session")
def tri_robust(tmp_path_factory):
    """TRI's file, its design and its robust report (the radii come from the file)."""
    p = tmp_path_factory.mktemp("tri") / "tri.yaml"
    p.write_text(TRI, encoding="utf-8")
    des = nd.design(nd.load(p), [1.0], thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = robust(des, 0.05, starts=2)
    return p, des, rep
