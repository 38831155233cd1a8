"""The public API documents its interface in numpydoc form, and the docs cite the paper by its
printed numbers.

Modelled on python-control's ``control/tests/docstrings_test.py``. A function of the public
API (every name the ``__all__`` of ``ntc_design`` or of one of its packages exports, and the
public methods of those classes; a method that overrides a documented one may inherit its
docstring) must have

* a summary line;
* a ``Parameters`` section naming every parameter of its signature, and no parameter it does
  not have (a renamed argument leaves a stale entry behind);
* a ``Returns`` (``Yields`` for a generator) section when it returns a value: by its return
  annotation, or, unannotated, by a ``return <value>`` in its body;
* a ``Raises`` section naming every exception class it raises itself, and ``InputError`` when
  it calls an ``ntc_design`` function that raises ``InputError`` itself (one level deep: the
  ``require_*`` validators, readers, parsers).

Public classes need a docstring; their properties need one too (a property is read as an
attribute, so no sections are asked of it). Every other name a module exports (its
``__all__``, or what it defines without a leading underscore) needs a summary line: what a
reader of the module needs, without sections that repeat the signature.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import re
import textwrap
from pathlib import Path

import pytest

import ntc_design
from ntc_design.errors import InputError, require_positive

ROOT = Path(ntc_design.__file__).parent

# Not API: the command line (documented by --help) and the ``python -m`` entry.
SKIP_MODULES = {
    "ntc_design.cli.commands",
    "ntc_design.cli.app",
    "ntc_design.cli.runs",
    "ntc_design.__main__",
}

SECTION = re.compile(r"^([A-Z][A-Za-z ]+)\n-{3,}\s*$", re.M)
ENTRY = re.compile(r"^(\*{0,2}[A-Za-z_][\w]*(?:\s*,\s*\*{0,2}[A-Za-z_][\w]*)*)\s*(?::.*)?$")


def _modules():
    """Every importable ``ntc_design`` module except the CLI, by dotted name."""
    names = ["ntc_design"]
    for info in pkgutil.walk_packages([str(ROOT)], prefix="ntc_design."):
        if info.name not in SKIP_MODULES:
            names.append(info.name)
    return sorted(names)


def _ours(obj) -> bool:
    return getattr(obj, "__module__", "").split(".")[0] == "ntc_design"


def _exported(mod) -> list[str]:
    if hasattr(mod, "__all__"):
        return list(mod.__all__)
    # no __all__: every name without an underscore that the module defines
    return [
        a
        for a, o in vars(mod).items()
        if not a.startswith("_") and getattr(o, "__module__", None) == mod.__name__
    ]


def _inherits_doc(cls, name: str, member) -> bool:
    """An override without a docstring of its own, of a documented method of a base."""
    if getattr(member, "__doc__", None):
        return False
    return any(getattr(getattr(base, name, None), "__doc__", None) for base in cls.__mro__[1:])


def _public_api():
    """(qualified name, kind, object, tier) for every documented function, class, method
    and property: tier ``api`` for what a package's ``__all__`` exports (and the public
    members of those classes), ``module`` for the rest of the modules' exports."""
    seen: dict[int, tuple[str, str, object, str]] = {}

    def add(name, kind, obj, tier):
        old = seen.get(id(obj))
        if old is None or (tier == "api" and old[3] != "api"):
            seen[id(obj)] = (name, kind, obj, tier)

    for modname in _modules():
        mod = importlib.import_module(modname)
        package = hasattr(mod, "__path__")
        for attr in _exported(mod):
            obj = getattr(mod, attr)
            if not _ours(obj):
                continue
            tier = "api" if package else "module"
            if inspect.isfunction(obj):
                add(f"{obj.__module__}.{obj.__qualname__}", "function", obj, tier)
            elif inspect.isclass(obj):
                add(f"{obj.__module__}.{obj.__qualname__}", "class", obj, tier)
                for mname, member in vars(obj).items():
                    if mname.startswith("_"):
                        continue
                    qual = f"{obj.__module__}.{obj.__qualname__}.{mname}"
                    if isinstance(member, (classmethod, staticmethod)):
                        member = member.__func__
                    if inspect.isfunction(member):
                        if not _inherits_doc(obj, mname, member):
                            add(qual, "function", member, tier)
                    elif isinstance(member, property) and member.fget is not None:
                        add(qual, "property", member.fget, tier)
    return sorted(seen.values(), key=lambda t: t[0])


API = _public_api()
FUNCTIONS = [
    pytest.param(obj, id=name)
    for name, kind, obj, tier in API
    if kind == "function" and tier == "api"
]
MODULE_FUNCTIONS = [
    pytest.param(obj, id=name)
    for name, kind, obj, tier in API
    if kind == "function" and tier == "module"
]
OTHERS = [pytest.param(obj, id=name) for name, kind, obj, _ in API if kind != "function"]


def sections(doc: str) -> dict[str, list[str]]:
    """The numpydoc sections of a cleaned docstring: header -> its lines."""
    out: dict[str, list[str]] = {}
    marks = list(SECTION.finditer(doc))
    for k, m in enumerate(marks):
        end = marks[k + 1].start() if k + 1 < len(marks) else len(doc)
        out[m.group(1).strip()] = doc[m.end() : end].strip("\n").splitlines()
    return out


def entries(lines: list[str]) -> list[tuple[list[str], bool]]:
    """The entries of a section: the names declared at the section's own indent
    (``a, b : float`` declares a and b) and whether an indented description follows."""
    out: list[tuple[list[str], bool]] = []
    for k, line in enumerate(lines):
        if not line or line[0].isspace():
            continue
        m = ENTRY.match(line.rstrip())
        if m:
            described = (
                k + 1 < len(lines) and lines[k + 1][:1].isspace() and bool(lines[k + 1].strip())
            )
            out.append(([n.strip().lstrip("*") for n in m.group(1).split(",")], described))
    return out


def entry_names(lines: list[str]) -> list[str]:
    """Every name an entry of the section declares."""
    return [n for names, _ in entries(lines) for n in names]


def _body(fn) -> ast.AST:
    src = textwrap.dedent(inspect.getsource(inspect.unwrap(fn)))
    return ast.parse(src).body[0]


def _own_nodes(node: ast.AST):
    """The nodes of a function body, not descending into nested functions or classes."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        yield child
        yield from _own_nodes(child)


def _raised(fn) -> set[str]:
    """Exception class names raised by ``raise Name(...)`` / ``raise Name`` in fn's own body."""
    out = set()
    for node in _own_nodes(_body(fn)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            name = exc.attr if isinstance(exc, ast.Attribute) else getattr(exc, "id", None)
            if name and name[0].isupper():
                out.add(name)
            elif name and isinstance(node.exc, ast.Call):
                # ``raise _err(...)``: a factory whose annotation names the exception
                made = _factory_exception(fn.__globals__.get(name))
                if made:
                    out.add(made)
    return out


def _factory_exception(f) -> str | None:
    if not inspect.isfunction(f):
        return None
    ann = f.__annotations__.get("return")
    ann = getattr(ann, "__name__", ann)
    return ann if isinstance(ann, str) and re.fullmatch(r"\w*(Error|Exception)", ann) else None


def _returns_value(fn) -> bool:
    ann = inspect.signature(fn).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None", "NoReturn", "Never")
    for node in _own_nodes(_body(fn)):
        if isinstance(node, ast.Return) and node.value is not None:
            if not (isinstance(node.value, ast.Constant) and node.value.value is None):
                return True
    return False


def _calls_input_error_raiser(fn) -> str | None:
    """The first ntc_design function that fn calls by name and that raises InputError,
    outside a ``try`` that catches InputError (or Exception)."""
    nodes = list(_own_nodes(_body(fn)))
    caught = set()
    for node in nodes:
        if isinstance(node, ast.Try) and any(_catches_input_error(h) for h in node.handlers):
            caught.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    for node in nodes:
        if isinstance(node, ast.Call) and id(node) not in caught:
            f = node.func
            name = f.id if isinstance(f, ast.Name) else None
            callee = fn.__globals__.get(name) if name else None
            if inspect.isfunction(callee) and _ours(callee) and callee is not fn:
                try:
                    if "InputError" in _raised(callee):
                        return name
                except (OSError, TypeError):
                    continue
    return None


def _catches_input_error(handler: ast.ExceptHandler) -> bool:
    t = handler.type
    names = t.elts if isinstance(t, ast.Tuple) else [t] if t is not None else []
    return t is None or any(
        getattr(n, "id", None) in ("InputError", "Exception", "BaseException") for n in names
    )


def check_function(fn) -> list[str]:
    """Every way fn's docstring misstates its interface (empty when it is right)."""
    doc = inspect.getdoc(fn) or ""
    if not doc.strip():
        return ["no docstring"]
    problems = []
    if SECTION.match(doc):
        problems.append("no summary line before the sections")
    sec = sections(doc)
    sig = inspect.signature(fn)
    params = [
        (("*" if p.kind == p.VAR_POSITIONAL else "**" if p.kind == p.VAR_KEYWORD else "") + name)
        for name, p in sig.parameters.items()
        if name not in ("self", "cls") and not name.startswith("_")
    ]
    documented = entry_names(sec.get("Parameters", []) + sec.get("Other Parameters", []))
    if params and "Parameters" not in sec:
        problems.append("no Parameters section")
    for p in params:
        if p.lstrip("*") not in documented:
            problems.append(f"parameter {p!r} not documented")
    for names, described in entries(sec.get("Parameters", [])):
        if not described:
            problems.append(f"parameter {', '.join(names)!r} has no description")
    wanted = {p.lstrip("*") for p in params}
    for name in documented:
        if name not in wanted:
            problems.append(f"documents {name!r}, which is not a parameter")
    if inspect.isgeneratorfunction(inspect.unwrap(fn)):  # also a @contextmanager's
        if "Yields" not in sec:
            problems.append("a generator without a Yields section")
    elif _returns_value(fn) and "Returns" not in sec:
        problems.append("returns a value but has no Returns section")
    raises_text = "\n".join(sec.get("Raises", []))
    raised = _raised(fn)
    indirect = _calls_input_error_raiser(fn)
    if indirect:
        raised.add("InputError")
    for exc in sorted(raised):
        if not re.search(rf"\b{exc}\b", raises_text):
            why = f" (through {indirect}())" if exc == "InputError" and indirect else ""
            problems.append(f"raises {exc}{why} but its Raises section does not say so")
    return problems


@pytest.mark.parametrize("fn", FUNCTIONS)
def test_public_function_documents_its_interface(fn):
    problems = check_function(fn)
    assert not problems, "; ".join(problems)


def _own_doc(obj) -> str:
    """obj's docstring, without the ``Name(field: type, ...)`` that @dataclass makes up."""
    doc = (inspect.getdoc(obj) or "").strip()
    if inspect.isclass(obj) and doc.startswith(f"{obj.__name__}("):
        return ""
    return doc


@pytest.mark.parametrize("obj", OTHERS)
def test_public_class_or_property_has_a_docstring(obj):
    assert _own_doc(obj)


@pytest.mark.parametrize("fn", MODULE_FUNCTIONS)
def test_a_module_export_has_a_summary_line(fn):
    doc = inspect.getdoc(fn) or ""
    assert doc.strip() and not SECTION.match(doc), "no summary line"


def test_the_checked_api_is_the_whole_api():
    # the package, certify/ and simulate/ export their layers; a silently empty walk would
    # pass every test above
    names = {name for name, kind, _, tier in API if tier == "api"}
    assert len(FUNCTIONS) >= 200
    for must in (
        "ntc_design.protocol.lemma1.design",
        "ntc_design.model.load.load",
        "ntc_design.certify.result.certify",
        "ntc_design.certify.verify.verify",
        "ntc_design.gain.conditions.analyse_gain",
        "ntc_design.simulate.driver.simulate",
    ):
        assert must in names


# -- the checker itself: it must catch what it claims to catch ---------------------------


def _bad(x, y=1):
    """Summary.

    Parameters
    ----------
    x : int
        An x.
    z : int
        Not a parameter any more.
    """
    if x < 0:
        raise ValueError("negative")
    return x + y


def _good(x, *, y=1):
    """Summary.

    Parameters
    ----------
    x, y : int
        Two numbers.

    Returns
    -------
    int
        Their sum.

    Raises
    ------
    ValueError
        When x is negative.
    """
    if x < 0:
        raise ValueError("negative")
    return x + y


def _gen(n):
    """Count.

    Parameters
    ----------
    n : int
        How far.
    """
    yield from range(n)


def _validates(x):
    """Check.

    Parameters
    ----------
    x : float
        A value.
    """
    require_positive("x", x)


def _validates_quietly(x):
    """Check, turning a bad value into False.

    Parameters
    ----------
    x : float
        A value.

    Returns
    -------
    bool
        Whether x is positive.
    """
    try:
        require_positive("x", x)
    except InputError:
        return False
    return True


def test_checker_finds_each_kind_of_mistake():
    problems = check_function(_bad)
    assert "parameter 'y' not documented" in problems
    assert "documents 'z', which is not a parameter" in problems
    assert "returns a value but has no Returns section" in problems
    assert any(p.startswith("raises ValueError") for p in problems)
    assert check_function(_good) == []
    assert check_function(_gen) == ["a generator without a Yields section"]
    # one call deep: a validator that raises InputError itself
    assert check_function(_validates) == [
        "raises InputError (through require_positive()) but its Raises section does not say so"
    ]
    # ... but not when the call sits in a try that catches InputError
    assert check_function(_validates_quietly) == []


# -- citations: printed numbers, not the spec's internal labels ---------------------------

# Labels from the LaTeX source and files users do not have; the printed numbers are in the
# published paper (eq. (8) is L_B, eq. (5) the noisy SAN, eq. (11) the L_B(1⊗θ) property).
# This paper's arXiv id is not known: "arXiv" must come with an id (only the authors'
# earlier paper, arXiv:2602.11822, has one here).
INTERNAL = re.compile(
    r"NOTES\.md|paper\.tex|\beq\.?\s*\(?(?:LB|LBt|LBP|SAN|FAN)\w*|\bSAN_noise\b|\bFAN_noise\b"
    r"|\\(?:label|ref|eqref)\{|\barXiv\b(?!:\d{4}\.\d{4,5})"
    # Definitions 1-2 are the two consensus notions (eqs. (6), (7)); the positive-negative
    # path and in-degree domination are Definitions 3 and 4
    r"|Definitions? 1\s*[–-]\s*2|positive-negative path[^.]{0,40}Definition 1\b"
    r"|in-degree[- ]domina[^.]{0,40}Definition 2\b"
)


# docs/conf.py writes the CLI reference from the commands' help; sphinx-gallery its timings
SITE_BUILD_WRITES = {"cli_commands.rst", "sg_execution_times.rst"}


def _doc_files():
    files = sorted(ROOT.rglob("*.py")) + sorted(ROOT.rglob("*.html"))
    yield from files
    readme = ROOT.parent / "README.md"
    if readme.exists():
        yield readme
    docs = ROOT.parent / "docs"  # the user guide, the site's pages and the gallery
    for pattern in ("guide/*.md", "*.rst", "gallery/*.py"):
        # not the pages the site's build writes (their text is the sources' above): CI
        # builds the site beside the slow lane, and both workers must collect one list
        yield from sorted(p for p in docs.glob(pattern) if p.name not in SITE_BUILD_WRITES)


@pytest.mark.parametrize("path", list(_doc_files()), ids=lambda p: str(p.relative_to(ROOT.parent)))
def test_citations_use_printed_numbers(path):
    bad = [
        f"{path.name}:{k}: {line.strip()}"
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if INTERNAL.search(line)
    ]
    assert not bad, "internal labels or wrong numbers:\n" + "\n".join(bad)


def test_the_paper_is_referenced_once_in_full():
    doc = ntc_design.__doc__ or ""
    assert "References" in doc and "Niu" in doc and "Information Sciences" in doc
    # 2602.11822 is the authors' earlier, noise-free paper: never this paper's id
    for path in _doc_files():
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"2602\.11822", text):
            before = text[max(0, m.start() - 200) : m.start()]
            assert "earlier" in before or "noise-free" in before, f"{path.name}: {before!r}"
