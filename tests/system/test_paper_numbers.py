"""The paper's Section 5 numbers, reproduced from the example files."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol import SwitchingDesign


def test_g1_design_matches_paper(examples):
    top = nd.load(examples / "g1.yaml")
    d = nd.design(top, THETA, margin=0.1)
    assert d.assumption_holds
    assert [top.labels[i] for i in d.decomposition.v1] == [2, 3]
    assert [top.labels[i] for i in d.decomposition.v2] == [1, 4, 5, 6, 7]
    assert d.C == pytest.approx(7.1440, abs=5e-5)
    assert d.delta == pytest.approx(7.2440, abs=5e-5)
    assert d.k1 == pytest.approx(1 + 2 / d.delta, rel=1e-15)
    np.testing.assert_allclose(d.x0, [1.2761, 2.5522, -1.2761], atol=5e-5)
    assert [top.labels[i] for i in d.informed] == [2, 3]
    i2, i3 = top.index(2), top.index(3)
    a = lambda i, j: top.abs_weight(top.index(i), top.index(j))  # noqa: E731
    np.testing.assert_array_equal(d.B[i2], a(2, 1) + a(2, 6))
    np.testing.assert_array_equal(d.B[i3], a(3, 6))
    assert d.identity_residual < 1e-12


def test_g1_c_i_by_hand(examples):
    """C_2 = ½ λmax(A12 + A52 − I) since Σ_Ω|A_2j| = I and Σ_N |A_2j| = I."""
    top = nd.load(examples / "g1.yaml")
    a12 = np.diag([1.0, 1, 2])
    a52 = np.array([[10.0, 1, 2], [1, 8, 1], [2, 1, 12]])
    expect = 0.5 * np.linalg.eigvalsh(a12 + a52 - np.eye(3))[-1]
    rep = nd.design(top, THETA, thresholds=False).to_dict()
    assert rep["C_i"]["2"] == pytest.approx(expect, rel=1e-12)
    assert rep["C_i"]["3"] == pytest.approx(4.5, rel=1e-12)  # ½ λmax((0.1A)^-1 (A − 0.1A))


def test_switching_designs_match_paper(examples):
    sw = nd.load(examples / "switching.yaml")
    assert isinstance(sw, nd.SwitchingTopology)
    assert sw.period == pytest.approx(0.1)
    res = nd.design(sw, THETA)
    assert isinstance(res, SwitchingDesign)
    g2, g3, g1 = res.modes["G2"], res.modes["G3"], res.modes["G1"]
    assert g1.delta == pytest.approx(7.2440, abs=5e-5)
    assert g2.delta == pytest.approx(7.0495, abs=5e-5)
    np.testing.assert_allclose(g2.x0, [1.2837, 2.5674, -1.2837], atol=5e-5)
    assert [g2.topology.labels[i] for i in g2.informed] == [1, 2, 3, 4, 6]
    assert g3.delta == pytest.approx(3.1000, abs=5e-5)
    np.testing.assert_allclose(g3.x0, [1.6452, 3.2903, -1.6452], atol=5e-5)
    assert [g3.topology.labels[i] for i in g3.informed] == [1, 2, 3, 6]
    for des in (g1, g2, g3):
        assert des.identity_residual < 1e-12


def test_switching_b_matrices_match_section5(examples):
    res = nd.design(nd.load(examples / "switching.yaml"), THETA)
    t2, t3 = res.modes["G2"], res.modes["G3"]
    a2 = lambda i, j: t2.topology.abs_weight(i - 1, j - 1)  # noqa: E731
    a3 = lambda i, j: t3.topology.abs_weight(i - 1, j - 1)  # noqa: E731
    expect2 = {1: a2(1, 2), 2: a2(2, 6), 3: a2(3, 6), 4: a2(4, 3) + a2(4, 7), 6: a2(6, 2)}
    expect3 = {1: a3(1, 5), 2: a3(2, 1), 3: a3(3, 7), 6: a3(6, 3)}
    for des, expect in ((t2, expect2), (t3, expect3)):
        assert sorted(i + 1 for i in des.B) == sorted(expect)
        for lab, b in expect.items():
            np.testing.assert_array_equal(des.B[lab - 1], b)
    # B_6(G2) = |A47| is only semidefinite, as the paper notes (⪰ 0).
    assert np.linalg.eigvalsh(t2.B[5])[0] == pytest.approx(0.0, abs=1e-14)


def test_schedule_pattern(examples):
    sw = nd.load(examples / "switching.yaml")
    got = [sw.mode_at(t) for t in (0.0, 0.019, 0.02, 0.039, 0.04, 0.059, 0.06, 0.099, 0.1, 0.14)]
    assert got == ["G2", "G2", "G2", "G2", "G1", "G1", "G3", "G3", "G2", "G1"]
    segs = sw.segments(0.25)
    assert [m for _, _, m in segs] == ["G2", "G2", "G1", "G3", "G3"] * 2 + ["G2", "G2", "G1"]
    np.testing.assert_allclose([a for a, _, _ in segs], 0.02 * np.arange(13), atol=1e-15)
    assert segs[-1][1] == 0.25


def test_g3_breaks_assumption2_but_gives_the_papers_delta(examples):
    """In G3, agents 4 and 7 are not in-degree-dominated (A43 − A34 and A75 − |A37| are
    indefinite) and have no antagonistic in-edge, so Assumption 2 fails as stated; the
    paper's δ = 3.1 is C taken over U, which is what the design falls back to."""
    top = nd.load(examples / "g3.yaml")
    d = nd.design(top, THETA)
    assert d.assumption_holds is False
    assert sorted(top.labels[v.agent] for v in d.decomposition.violations) == [4, 7]
    for lab, (i, j) in ((4, (3, 3)), (7, (5, 3))):
        ii = top.index(lab)
        diff = top.abs_weight(ii, top.index(i)) - top.abs_weight(top.index(j), ii)
        lam = np.linalg.eigvalsh(diff)
        assert lam[0] < 0 < lam[-1]
    assert d.C == pytest.approx(3.0, abs=1e-12)
    assert d.delta == pytest.approx(3.1, abs=1e-12)


def test_builtin_paper_topologies_match_example_files(examples):
    from ntc_design.model import paper

    for name, build in (("g1", paper.g1), ("g2", paper.g2), ("g3", paper.g3)):
        a, b = build(), nd.load(examples / f"{name}.yaml")
        assert a.labels == b.labels and set(a.weights) == set(b.weights)
        for k in a.weights:
            np.testing.assert_array_equal(a.weights[k], b.weights[k])
    sw = nd.load(examples / "switching.yaml")
    assert paper.switching().schedule == sw.schedule
