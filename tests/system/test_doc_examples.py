"""The Examples sections of the public entry points run as written (doctest), from the
checkout's root so that examples/ is found."""

import doctest
import importlib
import os

import pytest

from tests.conftest import ROOT

# modules by name: the packages re-export functions of the same names as these modules
ENTRY_POINTS = [
    getattr(importlib.import_module(m), f)
    for m, f in (
        ("ntc_design.model.load", "load"),
        ("ntc_design.protocol.lemma1", "design"),
        ("ntc_design.certify.result", "certify"),
        ("ntc_design.certify.verify", "verify"),
        ("ntc_design.simulate.driver", "simulate"),
        ("ntc_design.model.generate", "random_network"),
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


def test_every_public_example_in_the_package_runs(monkeypatch):
    """Every Examples section of a public name (a module's ``__all__``, or its names without
    a leading underscore) anywhere in the package runs as written, not only the entry
    points above."""
    import pkgutil
    import warnings

    import ntc_design

    monkeypatch.chdir(ROOT)
    found, failed, names = [], [], set()
    for info in pkgutil.walk_packages(ntc_design.__path__, "ntc_design."):
        if info.name.endswith("__main__"):
            continue
        mod = importlib.import_module(info.name)
        public = getattr(mod, "__all__", None) or [n for n in vars(mod) if n[0] != "_"]
        for name in public:
            obj = getattr(mod, name, None)
            if getattr(obj, "__module__", None) != info.name:
                continue  # re-exported: run where it is defined
            if obj in ENTRY_POINTS:
                names.add(name)  # run by the test above
                continue
            finder = doctest.DocTestFinder()
            found += [t for t in finder.find(obj, f"{info.name}.{name}", module=mod) if t.examples]
    for t in found:
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. a solver's accuracy note
            runner.run(t, out=lambda _: None)
        if runner.summarize(verbose=False).failed:
            failed.append(t.name)
    names |= {t.name.rsplit(".", 1)[1] for t in found}
    assert len(found) >= 14 and {fn.__name__ for fn in ENTRY_POINTS} <= names
    assert failed == []
