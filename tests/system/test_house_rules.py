"""Whole-program checks: the house rules of CONTRIBUTING.md that a file layout can break.

Tests mirror the package (``ntc_design/p/a.py`` is tested in ``tests/p/test_a.py``), the
whole-program checks live in ``tests/system/``, shared helpers in ``tests/support/``, and
every part of the package sits in one layer of the import contract."""

import ast
import functools
import re
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


# -- the import graph: no circles, no private names, no probing ----------------------------


def _module_name(p: Path) -> str:
    parts = p.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@functools.cache
def _imports() -> list[tuple[str, str, int, bool, list[str]]]:
    """(module, imported module, line, inside a function, names) for every import of the
    package by the package: top-level, ``TYPE_CHECKING`` and function-level alike. Walked
    when a test asks, once per process (not at collection: every worker of both lanes
    collected it, about 6 s each)."""
    files = {_module_name(p): p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts}
    out = []
    for mod, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        base = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
        inside: set[int] = set()
        for fn in ast.walk(tree):
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                inside.update(id(n) for n in ast.walk(fn) if n is not fn)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [(a.name, []) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                parts = base.split(".")
                head = parts[: len(parts) - node.level + 1] if node.level else []
                target = ".".join(head + ([node.module] if node.module else []))
                names = [a.name for a in node.names]
                # ``from . import x`` of a submodule imports the submodule
                subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in files]
                targets = [(s, []) for s in subs] or [(target, names)]
            else:
                continue
            for target, names in targets:
                while target and target not in files:
                    target = target.rpartition(".")[0]
                if target and target != mod:
                    out.append((mod, target, node.lineno, id(node) in inside, names))
    return out


def test_no_import_cycle_among_modules():
    graph: dict[str, set[str]] = {}
    for a, b, *_ in _imports():
        graph.setdefault(a, set()).add(b)
    state: dict[str, int] = {}  # 1: on the path, 2: done
    cycles = []

    def visit(v: str, path: list[str]) -> None:
        state[v] = 1
        for w in sorted(graph.get(v, ())):
            if state.get(w) == 1:
                cycles.append(path[path.index(w) :] + [w])
            elif w not in state:
                visit(w, [*path, w])
        state[v] = 2

    for v in sorted(graph):
        if v not in state:
            visit(v, [v])
    assert len(_imports()) > 500  # the walk found the package
    assert cycles == []


def test_no_private_name_is_imported_from_another_module():
    private = [
        f"{a}:{line} imports {n} from {b}"
        for a, b, line, _, names in _imports()
        for n in names
        if n.startswith("_") and not n.startswith("__")
    ]
    assert private == []


def test_no_module_decides_by_what_is_already_imported():
    probes = [
        str(p.relative_to(ROOT))
        for p in PACKAGE.rglob("*.py")
        if "sys.modules" in p.read_text(encoding="utf-8")
    ]
    assert probes == []


def test_no_spec_is_told_apart_by_its_attributes():
    """A Monte Carlo spec says what it is by its type and methods (PathBlocks), never
    by which attributes it happens to have."""
    probes = [
        f"{p.relative_to(ROOT)}:{i}"
        for p in PACKAGE.rglob("*.py")
        for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
        if re.search(r"\b(get|has)attr\((m?spec|self\.spec)\b", line)
    ]
    assert probes == []


#: Why a module imports another inside a function rather than at its top (start-up time:
#: what a command loads only when it needs it). The CLI does so throughout: ``ntc --help``
#: and a mistyped option answer without loading the layers.
LAZY = {
    # Numba compiles (or loads from its cache) the kernels when their module is imported
    ("ntc_design.simulate.montecarlo", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.rng", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.replay", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.modes", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.gpu_run", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.loss_mc", "ntc_design.simulate.loss_kernels"): "Numba kernels",
    ("ntc_design.simulate.loss_mc", "ntc_design.simulate.kernels"): "Numba kernels",
    ("ntc_design.simulate.loss_mc", "ntc_design.simulate.loss_cuda"): "numba-cuda",
    ("ntc_design.simulate.montecarlo", "ntc_design.simulate.rng"): "Numba kernels",
    # numba-cuda is imported only on a GPU (or its simulator)
    ("ntc_design.simulate.gpu_run", "ntc_design.simulate.cuda_kernels"): "numba-cuda",
    ("ntc_design.simulate.gpu", "ntc_design.simulate.gpu_run"): "numba-cuda",
    ("ntc_design.simulate.gpu", "ntc_design.simulate.gpu_timevarying"): "numba-cuda",
    # SymPy loads only for expressions of t and the gain conditions
    ("ntc_design.model.load", "ntc_design.model.timevarying"): "SymPy",
    ("ntc_design.io.readers", "ntc_design.io.tvfiles"): "SymPy",
    ("ntc_design.simulate.driver", "ntc_design.simulate.timevarying"): "SymPy",
    ("ntc_design.gain.schedule", "ntc_design.gain.conditions"): "SymPy",
    # the certify package loads the gain conditions (SymPy) for a table of checks
    ("ntc_design.reports.terminal", "ntc_design.certify.checks"): "SymPy",
}


def test_imports_inside_functions_have_a_named_reason():
    lazy = {
        (a, b) for a, b, _, inside, _ in _imports() if inside and not a.startswith("ntc_design.cli")
    }
    assert sorted(lazy - set(LAZY)) == []  # a new one: hoist it, or name its reason here
    assert sorted(set(LAZY) - lazy) == []  # a reason for nothing: remove it


def test_the_top_level_is_few_modules_and_no_module_is_long():
    top = [p.name for p in PACKAGE.glob("*.py")]
    assert len(top) <= 12, top
    long = {
        str(p.relative_to(PACKAGE)): n
        for p in PACKAGE.rglob("*.py")
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > 800
    }
    assert long == {}


def test_an_unregistered_marker_is_an_error():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    options = config["tool"]["pytest"]["ini_options"]
    assert "--strict-markers" in options["addopts"].split()
    assert sorted(m.split(":")[0] for m in options["markers"]) == ["hostile", "slow"]


#: A flag string (``--period``) as the before-stop hook finds it: after a quote, a
#: parenthesis or a space.
FLAG_TEXT = re.compile(r"[\"'( ]--[a-z][a-z-]+")

#: Library modules allowed to write a flag string, each with its reason (none is a flag of
#: ``ntc``: the command line maps the library's fields to its flags, ntc_design/cli/flags.py).
FLAG_TEXT_ALLOWED: dict[str, str] = {
    # text of the files an export writes (README.txt, ntc_protocol.h): which ntc command
    # made them, the same bytes whoever calls export()
    "ntc_design/export/c.py": "the emitted C header's comments name ntc export's option",
    "ntc_design/export/run.py": "the emitted README.txt names ntc export's option",
    # a command line of ntc, quoted whole: how to make the missing input, or the re-run line
    # a report records (the same for every reader: a file's content, a user's next step)
    "ntc_design/certify/verify.py": "how a certificate is made: ntc certify ... --out",
    "ntc_design/reports/reproduce.py": "the recorded re-run line of ntc reproduce",
    "ntc_design/reports/rundata.py": "the recorded re-run line of ntc simulate",
    "ntc_design/reports/sweep.py": "how a sweep folder is made: ntc sweep ... --out",
    # a script's own command line (python -m ntc_design.reports.examples), not ntc's
    "ntc_design/reports/examples.py": "the example script's argparse options",
}


def test_no_library_module_names_a_command_line_flag():
    """The library names its parameters and the scenario's fields (``digital.period``);
    only ``ntc_design/cli`` knows the flags (errors.blame maps the one to the other)."""
    flagged = {
        str(p.relative_to(ROOT)).replace("\\", "/")
        for p in PACKAGE.rglob("*.py")
        if "cli" not in p.relative_to(PACKAGE).parts[:1]
        and FLAG_TEXT.search(p.read_text(encoding="utf-8"))
    }
    assert sorted(flagged - set(FLAG_TEXT_ALLOWED)) == []  # name the field, not the flag
    assert sorted(set(FLAG_TEXT_ALLOWED) - flagged) == []  # an exception for nothing: remove it


#: A message's head written as a field (``paths: must be ...``, ``{where}: ...``): the text
#: before the first ": " has no space outside braces.
_HEAD = re.compile(r"^(?:\{[^{}]*\}|[^\s:{}])+: ")


def _message_head(node: ast.expr) -> str | None:
    """The static start of a message argument (a literal, an f-string, a sum of them)."""
    while isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        node = node.left
    if isinstance(node, ast.Subscript):  # a message cut to a length
        node = node.value
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
    return None


def _fields_in_text(tree: ast.AST) -> list[int]:
    """The lines of error calls without ``field=`` whose message starts with ``FIELD: ``."""
    errors = {"InputError", "DenseRefused", "CertificationRefused"}
    found = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and node.args):
            continue
        func = node.func
        name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", None)
        if name not in errors or any(k.arg == "field" for k in node.keywords):
            continue  # with its field given, a message may start with the value
        head = _message_head(node.args[0])
        if head is not None and _HEAD.match(head):
            found.append(node.lineno)
    return found


def test_no_error_writes_its_field_into_its_message():
    """The field travels as data (``InputError(message, field=...)``): a message without a
    field that starts with ``FIELD: `` would hide it from the command line's field -> flag
    map (the constructor no longer reads a field out of the text)."""
    caught = 'InputError(f"{p}: x")\nInputError("digital.period: " + "y"[:3])\n'
    fine = 'InputError("x", field="p")\nInputError("a file name.yaml: x")\nInputError(msg)\n'
    assert _fields_in_text(ast.parse(caught)) == [1, 2] and _fields_in_text(ast.parse(fine)) == []
    found = [
        f"{p.relative_to(ROOT)}:{line}"
        for p in PACKAGE.rglob("*.py")
        for line in _fields_in_text(ast.parse(p.read_text(encoding="utf-8")))
    ]
    assert found == []
