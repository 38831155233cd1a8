"""Tests of :mod:`ntc_design.tune.search`."""

import math

import pytest

from ntc_design.tune import (
    Dimension,
    search,
)

# -- the search ---------------------------------------------------------------------------


def test_search_finds_an_interior_minimum_and_respects_its_budget():
    calls = []

    def f(p):
        calls.append(p)
        return (p["x"] - 0.3) ** 2 + (math.log(p["y"]) - 1.0) ** 2 + 1e-3

    tr = search(f, [Dimension("x", 0, 1), Dimension("y", 0.1, 10, log=True)], max_evaluations=90)
    (x, y), v = tr.best
    assert x == pytest.approx(0.3, abs=2e-3) and y == pytest.approx(math.e, rel=5e-3)
    assert v == pytest.approx(1e-3, abs=1e-5)
    assert len(calls) == len(tr.values) <= 90


def test_search_skips_infinite_candidates():
    tr = search(
        lambda p: math.inf if p["x"] > 0.5 else (p["x"] - 0.4) ** 2 + 1, [Dimension("x", 0, 1)]
    )
    assert tr.best[0][0] == pytest.approx(0.4, abs=2e-3)
