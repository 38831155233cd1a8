"""Whole-program checks: the house rules of CONTRIBUTING.md that a file layout can break.

Tests mirror the package (``ntc_design/p/a.py`` is tested in ``tests/p/test_a.py``), the
whole-program checks live in ``tests/system/``, shared helpers in ``tests/support/``, and
every part of the package sits in one layer of the import contract."""

import ast
import tomllib
from pathlib import Path

from tests.conftest import ROOT

PACKAGE = ROOT / "ntc_design"
TESTS = ROOT / "tests"
WHOLE_PROGRAM = {"system", "support"}  # test folders that mirror no module


def _modules() -> list[Path]:
    """Every module of the package, relative to it (``certify/kinds/robust.py``)."""
    return sorted(
        p.relative_to(PACKAGE)
        for p in PACKAGE.rglob("*.py")
        if p.name not in ("__init__.py", "__main__.py") and "__pycache__" not in p.parts
    )


def test_every_module_has_its_mirror_test_file():
    missing = [str(m) for m in _modules() if not (TESTS / m.parent / f"test_{m.name}").is_file()]
    assert not missing, f"modules without tests/<package>/test_<module>.py: {missing}"
    assert len(_modules()) > 100  # the walk found the package, not an empty folder


def test_every_mirrored_test_file_names_a_module():
    modules = {str(m) for m in _modules()}
    orphans = []
    for t in TESTS.rglob("test_*.py"):
        rel = t.relative_to(TESTS)
        if rel.parts[0] in WHOLE_PROGRAM:
            continue
        if str(rel.parent / rel.name[len("test_") :]) not in modules:
            orphans.append(str(rel))
    assert not orphans, f"test files that mirror no module: {orphans}"


def test_every_test_folder_is_a_package():
    # test files share basenames across folders (tests/certify/test_robust.py and
    # tests/sweep/test_robust.py): each folder needs __init__.py to be imported apart
    folders = {t.parent for t in TESTS.rglob("*.py") if "__pycache__" not in t.parts}
    assert [str(f) for f in folders if not (f / "__init__.py").is_file()] == []


def test_support_modules_hold_no_tests():
    for p in (TESTS / "support").glob("*.py"):
        assert not p.name.startswith("test_"), p
        tree = ast.parse(p.read_text(encoding="utf-8"))
        tests = [n.name for n in tree.body if getattr(n, "name", "").startswith("test_")]
        assert tests == [], (p.name, tests)


def test_every_part_of_the_package_is_in_one_layer():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    (layers,) = [
        c["layers"] for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "layers"
    ]
    named = [part.strip() for layer in layers for part in layer.split("|")]
    parts = {
        f"ntc_design.{p.stem if p.is_file() else p.name}"
        for p in PACKAGE.iterdir()
        if (p.suffix == ".py" and p.stem not in ("__init__", "__main__"))
        or (p.is_dir() and (p / "__init__.py").is_file())
    }
    assert sorted(parts - set(named)) == []
    assert len(named) == len(set(named))  # no part in two layers
