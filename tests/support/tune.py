"""A two-agent network whose tuning objective has a closed form, and G1 tuned once."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.simulate import NoiseModel, SimulationSpec
from tests.support.shared import once_per_run

# -- a known optimum: two agents, d = 1, additive noise, γ = 1 ------------------------------
# Both edges antagonistic with weight −w: L_B = w[[1+δ, 1], [1, 1+δ]], eigenvalues w(2+δ)
# and wδ with eigenvectors (1, ±1)/√2, additive noise w·σ on each agent, f = 0. In the
# eigenbasis S_k' = −2λ_k c S_k + c² w²σ², which for c = a/(b + t) integrates to
# S_k(T) = S_k(0) (b/(b+T))^(2λa) + a²w²σ²/(2λa − 1)·[(b+T)^(−1) − b^(2λa−1)(b+T)^(−2λa)].

PAIR = """name: pair
dim: 1
agents: 2
edges:
  - {from: 2, to: 1, weight: [[-1.0]]}
  - {from: 1, to: 2, weight: [[-1.0]]}
"""


W, SIG, T_PAIR = 1.0, 1.0, 5.0


X0_PAIR = np.array([3.0, -1.0])


@pytest.fixture(scope="session")
def pair_topology(tmp_path_factory):
    """The two-agent network of :data:`PAIR`, loaded from its file."""
    p = tmp_path_factory.mktemp("pair") / "pair.yaml"
    p.write_text(PAIR, encoding="utf-8")
    return nd.load(p)


@pytest.fixture(scope="session")
def pair_network(pair_topology):
    """The pair, its simulation settings and E‖ε(T)‖² in closed form as a function of (a, b)."""
    top = pair_topology
    spec = SimulationSpec.build([1.0], noise=NoiseModel(SIG, 0.0), initial=X0_PAIR)
    delta = nd.design(top, [1.0]).delta
    lam = np.array([W * (2 + delta), W * delta])
    v = np.array([[1, 1], [1, -1]]) / np.sqrt(2)
    s0 = (v.T @ (X0_PAIR - 1.0)) ** 2

    def closed(a, b):
        k = 2 * lam * a
        q = (W * SIG) ** 2
        tail = (b + T_PAIR) ** -1 - b ** (k - 1) * (b + T_PAIR) ** -k
        return float(np.sum(s0 * (b / (b + T_PAIR)) ** k + a * a * q / (k - 1) * tail))

    return top, spec, closed


# -- G1, the switching set, A(t) ----------------------------------------------------------


@pytest.fixture(scope="session")
def g1_tuned(tmp_path_factory, examples):
    """`ntc tune` of the paper's G1 scenario at T = 10, with --out, as a user runs it: once
    per test run, whichever xdist worker asks first (the others read its folder)."""

    def build():
        out = tmp_path_factory.mktemp("tune") / "g1"
        args = [str(examples / "scenarios" / "g1_fixed.yaml"), "--horizon", "10", "--eps", "2"]
        proc = subprocess.run(
            [sys.executable, "-m", "ntc_design", "tune", *args, "--out", str(out), "--json"],
            capture_output=True,
            text=True,
            timeout=600,
        )
        return [proc.args, proc.returncode, proc.stdout, proc.stderr, str(out)]

    args, code, stdout, stderr, out = once_per_run(tmp_path_factory, "g1_tuned", build)
    return subprocess.CompletedProcess(args, code, stdout, stderr), Path(out)
