"""Tests of :mod:`ntc_design.protocol.lemma1`."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.io import loadmat

import ntc_design as nd
from ntc_design.model import Topology, paper
from ntc_design.model.generate import random_network
from ntc_design.present.rows import fmt
from ntc_design.protocol import AssumptionWarning
from tests.cli_helpers import run_cli
from tests.conftest import EXAMPLES, random_topology
from tests.support.model import seeds
from tests.support.rows import _squash, _text


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
    ("G1", lambda: paper.g1()),
    ("G2", lambda: paper.g2()),
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
    # the definitions only: the critical couplings (0.3-0.7 s a network) are test_thresholds.py's
    des = nd.design(top, theta, 0.1, thresholds=False)
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


@settings(max_examples=40, deadline=None)
@given(
    seeds,
    st.lists(st.floats(-10, 10), min_size=2, max_size=2).filter(lambda t: max(map(abs, t)) > 1e-3),
    st.floats(1e-3, 1e3),
)
def test_identity_residual_any_theta_any_delta(seed, theta, delta):
    """-L_B(1⊗θ) + k1(Δ⊗I)Bθ = 0 for every θ and every δ > 0 (Lemma 1 identity)."""
    top = random_topology(seed, n=5, d=2)
    des = nd.design(top, theta, delta=delta, thresholds=False)
    assert des.identity_residual < 1e-12
    r = -des.grounded_laplacian() @ np.tile(des.theta, top.n) + des.input_vector()
    assert np.max(np.abs(r)) <= 1e-11 * (1 + np.abs(des.grounded_laplacian()).max()) * np.max(
        np.abs(theta)
    )


def test_design_labels_are_the_same_in_the_terminal_and_the_notebook(capsys, monkeypatch):
    top = nd.load(EXAMPLES / "g1.yaml")
    des = nd.design(top, [1, 2, -1], 0.1)
    table = des.table()
    code, out, _ = run_cli(
        ["design", EXAMPLES / "g1.yaml", "--theta", "1,2,-1"], capsys, monkeypatch
    )
    assert code == 0
    flat = _squash(out)
    page = _text(des._repr_html_())
    for label, row in zip(table.labels, table.rows, strict=True):
        assert label in flat and label in page, label
        value = row[1].plain()
        assert _squash(value) in flat, (label, value)
        # a matrix is a grid in HTML: the same entries in the same order
        entries = value.replace("[", " ").replace("]", " ").replace(",", " ")
        assert _squash(entries) in page if row[1].matrix else _squash(value) in page, label
    assert fmt(des.delta) == "7.2440" and "7.2440" in flat and "7.2440" in page


def test_failing_assumption_warns_and_violators_are_in_neither_set():
    # agent 2 sends more than it hears and has no antagonistic in-edge (issue 8)
    top = Topology.from_edges(
        ["a", "b", "c"], 1, [("a", "b", [[1.0]]), ("b", "c", [[5.0]]), ("b", "a", [[-1.0]])]
    )
    with pytest.warns(AssumptionWarning, match="Assumption 2 fails"):
        des = nd.design(top, [1.0])
    assert not des.assumption_holds
    assert des.violating_agents == ("b",)
    assert "b" not in des.v1_agents and "b" not in des.v2_agents
    doc = des.to_dict()
    assert "b" not in doc["V2"] and "b" not in doc["V1"]


def test_public_results_use_labels(tmp_path):
    top = random_network(30, 2, seed=4, family="ring")
    relab = Topology(tuple(f"x{k}" for k in range(top.n)), top.dim, dict(top.weights))
    des = nd.design(relab, [1.0, 2.0])
    assert des.informed_agents == tuple(relab.labels[i] for i in des.informed)
    assert all(isinstance(a, str) and a.startswith("x") for a in des.informed_agents)
    assert set(des.v1_agents) | set(des.v2_agents) == set(relab.labels)
    assert set(des.B_by_agent) == set(des.informed_agents)
    doc = des.to_dict()
    assert doc["informed"] == list(des.informed_agents)
    assert doc["V1"] == list(des.v1_agents)


def test_design_mat_loads_in_scipy_with_the_toolkits_l_b(tmp_path, capsys, monkeypatch, g1, theta):
    out = tmp_path / "design.mat"
    code, _, err = run_cli(
        ["design", EXAMPLES / "g1.yaml", "--theta", "1,2,-1", "--out", out], capsys, monkeypatch
    )
    assert code == 0, err
    m = loadmat(out)
    des = nd.design(g1, theta, 0.1)
    assert sp.issparse(m["L_B"]) and np.array_equal(m["L_B"].toarray(), des.grounded_laplacian())
    assert float(m["delta"].ravel()[0]) == des.delta and float(m["k1"].ravel()[0]) == des.k1
    np.testing.assert_array_equal(m["x0"].ravel(), des.x0)
    np.testing.assert_array_equal(m["informed"].ravel(), np.array(des.informed) + 1)
    np.testing.assert_array_equal(m["B"], np.vstack([des.B[i] for i in des.informed]))
    assert [str(x[0]) for x in m["labels"].ravel()] == [str(a) for a in g1.labels]
    code, _, err = run_cli(
        ["design", EXAMPLES / "g1.yaml", "--theta", "1,2,-1", "--out", tmp_path / "d.json"],
        capsys,
        monkeypatch,
    )
    assert code == 0 and (tmp_path / "d.json").read_text().startswith("{")


@pytest.mark.parametrize(
    "thresholds, why",
    [(False, "(not asked for here; "), (None, "by default above Nd = ")],
)
def test_the_note_on_critical_couplings_not_computed_reads_as_a_sentence(
    g1, theta, monkeypatch, thresholds, why
):
    from ntc_design.protocol import lemma1

    monkeypatch.setattr(lemma1, "THRESHOLDS_DEFAULT_MAX_ND", 1)  # G1 (Nd = 21) is above
    (note,) = [n for n in nd.design(g1, theta, thresholds=thresholds).notes if "δ_H" in n]
    assert note.startswith(f"critical couplings δ_H, δ_S not computed {why}")
    assert note.endswith(  # a Python caller's words; ntc design's below
        "ntc design with its thresholds flag computes them, as does the thresholds option of "
        "design in Python)"
    )
    from ntc_design.errors import options_written_as

    with options_written_as({"thresholds": "--thresholds"}):
        (note,) = [n for n in nd.design(g1, theta, thresholds=thresholds).notes if "δ_H" in n]
    assert note.endswith(
        "ntc design --thresholds computes them, as does the thresholds option of design in Python)"
    )
    assert "herentc" not in note and "=True" not in note


def test_uninformed_modes_are_those_whose_design_has_no_informed_agent(g1):
    import warnings

    from ntc_design.model import SwitchingTopology
    from ntc_design.protocol.lemma1 import no_informed_agent_text, uninformed_modes

    w = np.eye(2)
    coop = Topology(("a", "b", "c"), 2, {(1, 0): w, (2, 1): w, (0, 2): w})
    assert uninformed_modes(coop) == [None] and uninformed_modes(g1) == []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumptionWarning)
        # the same answer as the design's U, found without designing
        assert not nd.design(coop, [1, 2]).has_informed_agents
        assert nd.design(g1, [1, 2, -1]).has_informed_agents
    neg = Topology(("a", "b", "c"), 2, {(1, 0): -w, (2, 1): w, (0, 2): w})
    sw = SwitchingTopology({"x": coop, "y": neg}, (("x", 1.0), ("y", 1.0)))
    assert uninformed_modes(sw) == ["x"]
    assert no_informed_agent_text(["x"]).startswith("mode(s) x have no informed agent")
    assert no_informed_agent_text([None]).startswith("the network has no informed agent")
