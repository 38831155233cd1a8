"""The Examples sections of the public entry points run as written (doctest), from the
checkout's root so that examples/ is found."""

import doctest
import importlib
import os

import pytest

from .conftest import ROOT

# modules by name: the packages re-export functions of the same names as these modules
ENTRY_POINTS = [
    getattr(importlib.import_module(m), f)
    for m, f in (
        ("ntc_design.loader", "load"),
        ("ntc_design.design.lemma1", "design"),
        ("ntc_design.certify.result", "certify"),
        ("ntc_design.certify.verify", "verify"),
        ("ntc_design.simulate.driver", "simulate"),
        ("ntc_design.generate", "random_network"),
    )
]


@pytest.mark.parametrize("fn", ENTRY_POINTS, ids=lambda f: f.__name__)
def test_entry_point_examples_run(fn, monkeypatch):
    monkeypatch.chdir(ROOT)
    tests = doctest.DocTestFinder().find(fn, fn.__name__, globs={})
    examples = [t for t in tests if t.examples]
    assert examples, f"{fn.__name__} has no Examples section"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in examples:
        runner.run(t)
    res = runner.summarize(verbose=False)
    assert res.failed == 0 and res.attempted >= 2
    assert os.getcwd() == str(ROOT)
