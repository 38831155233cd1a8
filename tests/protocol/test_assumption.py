"""Tests of :mod:`ntc_design.protocol.assumption`."""

import math
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model import (
    Topology,
    antagonistic_in_weight,
    in_degree_dominated,
    positive_negative_reachable,
)
from ntc_design.numerics.linalg import classify
from ntc_design.protocol import AssumptionWarning, assumption2, design, lemma1_coefficient
from ntc_design.protocol.assumption import lemma1_coefficients, violation_fixes
from tests.conftest import random_topology


def test_assumption2_violation_reasons():
    # agent 2 is not in-degree-dominated (it sends more than it hears) and has no
    # antagonistic in-edge: it can be in neither V1 nor V2
    top = Topology.from_edges(3, 1, [(1, 2, [[1.0]]), (2, 3, [[5.0]]), (2, 1, [[-1.0]])])
    dec = nd.assumption2(top)
    assert not dec.holds
    reasons = {top.labels[v.agent]: v.reason for v in dec.violations}
    assert "not in-degree-dominated and has no antagonistic in-edge" in reasons[2]


def test_check_tables_are_typed_rows_every_face_renders(g1, g3):
    from ntc_design.protocol import structure_report, structure_tables

    edges, agents, a2 = structure_tables(structure_report(g1), "G1")
    assert len(edges.rows) == len(g1.classes) == 8 and edges.columns == ("edge", "class")
    assert [r[0].plain() for r in agents.rows] == [str(x) for x in g1.labels]
    c2 = agents.rows[list(g1.labels).index(2)][-1].plain()
    assert c2 == "7.1440"  # C_2, the paper's C for G1
    assert a2.layout == "list" and a2.rows[0][1].verdict_word == "holds"
    assert a2.list_lines()[0] == "Assumption 2: holds (V1 = {2, 3}, V2 = {1, 4, 5, 6, 7})"
    assert "<table" in edges.html() and "PD" in edges.text()  # the HTML and terminal faces
    *_, bad = structure_tables(structure_report(g3), "G3", most=1)
    assert bad.rows[0][1].verdict_word == "fails" and len(bad.rows) == 2
    assert bad.notes[0] == "1 more (to_dict() lists them all)"  # the Python caller's words
    from ntc_design.errors import options_written_as

    with options_written_as({"json": "--json"}):  # the command line's
        *_, bad_cli = structure_tables(structure_report(g3), "G3", most=1)
    assert bad_cli.notes[0] == "1 more (--json lists them all)"
    # each fix once, for every agent it applies to (not only the rows shown)
    assert len(bad.notes) == 2 and bad.notes[1].startswith("fix (agents 4, 7): give the agent")


def test_each_violation_kind_names_its_fix():
    # 1 -> 2 cooperative, 2 -> 3 with a semidefinite antagonistic weight, 4 listens to no
    # one it can be reached through: every kind of violation, each with its own fix
    top = Topology.from_edges(
        4,
        2,
        [
            (1, 2, [[5.0, 0.0], [0.0, 5.0]]),
            (2, 3, [[-1.0, 0.0], [0.0, 0.0]]),
            (3, 1, [[1.0, 0.0], [0.0, 1.0]]),
            (1, 4, [[1.0, 0.0], [0.0, 1.0]]),
        ],
    )
    dec = nd.assumption2(top)
    fixes = {top.labels[v.agent]: v.fix for v in dec.violations}
    assert not dec.holds and all(fixes.values()), fixes
    by_fix = {f: [top.labels[i] for i in a] for f, a in violation_fixes(dec.violations).items()}
    assert sum(len(a) for a in by_fix.values()) == len(dec.violations)  # each agent once
    assert len(by_fix) == len(set(fixes.values()))  # each fix once


def _reference_assumption2(top):
    """The dense-era algorithm: V1 grown level by level, BFS from scratch each time."""
    n = top.n
    idd = [in_degree_dominated(top, i) for i in range(n)]
    cands = {
        i: lemma1_coefficient(top, i)
        for i in range(n)
        if classify(antagonistic_in_weight(top, i)).value == "PD"
    }
    if any(not idd[i] and i not in cands for i in range(n)):
        return False, None
    floor = max((cands[i] for i in range(n) if not idd[i]), default=-math.inf)
    for level in sorted({c for c in cands.values() if c >= floor}):
        v1 = [i for i in sorted(cands) if cands[i] <= level]
        paths = positive_negative_reachable(top, v1)
        if all(i in paths for i in range(n)):
            return True, (tuple(v1), paths)
    return False, None


@pytest.mark.parametrize("seed", range(12))
def test_sparse_laplacian_equals_dense_and_design_matches_reference(seed):
    top = random_topology(seed, n=6, d=2, p_edge=0.45)
    lap = top.laplacian()
    np.testing.assert_array_equal(top.laplacian_sparse().toarray(), lap)
    for (i, j), c in top.classes.items():  # batched classification = one by one
        assert c is classify(top.weights[(i, j)])
    cand, c = lemma1_coefficients(top)
    for i in range(top.n):
        assert cand[i] == (classify(antagonistic_in_weight(top, i)).value == "PD")
        if cand[i]:
            assert c[i] == pytest.approx(lemma1_coefficient(top, i), rel=1e-9, abs=1e-12)
    dec = assumption2(top)
    ok, ref = _reference_assumption2(top)
    assert dec.holds == ok
    if ok:
        assert dec.v1 == ref[0]
        for i in dec.v2:
            assert dec.paths[i] == tuple(ref[1][i])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumptionWarning)
        des = design(top, [1.0, -1.0], thresholds=False)
    lb = des.grounded_laplacian()
    np.testing.assert_allclose(des.grounded_laplacian_sparse().toarray(), lb, rtol=0, atol=0)
