"""Tests of :mod:`ntc_design.certify.robust.report`."""

import warnings

import numpy as np
import pytest

from ntc_design.certify.robust import robust
from tests.support.robust import independent_lap_b


def test_the_table_names_the_method_of_each_proven_end(mid_robust):
    _, rep, sparse = mid_robust
    said = [r[-1].text for r in rep.table().rows]
    assert "Riccati search" in said[0] and "S-procedure, reduced" in said[1]
    assert "Riccati search at α = 0" in said[2]
    assert "block dominance" in [r[-1].text for r in sparse.table().rows][0]


def test_per_edge_brackets_are_not_stated_at_one_radius(tri_robust):
    from tests.support.robust import TRI_SET

    _, des, rep = tri_robust
    assert sorted(rep.radii) == [0.02, 0.02, 0.5] and rep.radius == 0.5
    table = rep.table()
    assert table.title == f"tri: robust brackets for {TRI_SET}"
    assert "at ρ = 0.5" not in table.text()
    assert table.notes[-1] == (
        "the decay and offset brackets hold for the per-edge radii; the margin radius is one "
        "ρ on every edge"
    )
    # why: every weight at −50 % (inside one radius 0.5, outside the per-edge set) decays
    # slower than the proven α, so "α at ρ = 0.5" would be false
    half = {k: 0.5 * a for k, a in des.topology.weights.items()}
    slow = float(np.min(np.linalg.eigvals(independent_lap_b(des, half)).real))
    assert slow < rep.decay.lower
    assert slow == pytest.approx(0.52885211, rel=1e-6)  # the protocol (B_i, δ) nominal
    # a uniform radius is still said as one
    assert "robust brackets at ρ = 0.05" in robust_uniform_title(des)


def robust_uniform_title(des):
    import dataclasses

    top = dataclasses.replace(des.topology, uncertainty={})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return robust(dataclasses.replace(des, topology=top), 0.05, starts=1).table().title
