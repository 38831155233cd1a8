"""Hostile topology and switching files, YAML/JSON attacks and hostile expressions.

Every case: exit code 2, one line on stderr naming the file or field, nothing on stdout,
no traceback, nothing executed (a sentinel file is never created), under 10 s. The cases
are generated: every field of the topology and switching formats × values that are wrong
for it, in both YAML and JSON; parser attacks (aliases, nesting, tags, sizes, encodings);
expressions with every forbidden construct, through ``ntc gain``, ``ntc certify --gain``
and a scenario's ``gain``. Hypothesis strategies then draw wrong values per field and
arbitrary text.
"""

import copy
import json
import math

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ntc_design.errors import InputError
from ntc_design.expr.symbolic import parse_expression, symbol
from ntc_design.io.documents import MAX_FILE_BYTES, read_document
from ntc_design.model.load import load
from tests.cli_helpers import assert_input_error
from tests.conftest import ROOT

pytestmark = pytest.mark.hostile
NAN, INF = float("nan"), float("inf")
HUGE = 10**400  # float() of it overflows
G1 = str(ROOT / "examples" / "g1.yaml")

TOPOLOGY = {
    "name": "T",
    "dim": 2,
    "agents": 3,
    "matrices": {"A": [[1, 0], [0, 1]]},
    "edges": [
        {"from": 1, "to": 2, "weight": [[1, 0], [0, 1]]},
        {"from": 2, "to": 3, "weight": {"matrix": "A", "scale": 0.5}},
        {"from": 3, "to": 1, "weight": {"diag": [1, 2]}},
    ],
}
SWITCHING = {
    "modes": {"G1": copy.deepcopy(TOPOLOGY), "G2": copy.deepcopy(TOPOLOGY)},
    "schedule": [{"mode": "G1", "duration": 1.0}, {"mode": "G2", "duration": 0.5}],
}
DROP = object()

# ------------------------------------------------------------------ topology fields × values

_NOT_NUMBERS = [None, True, "x", [], {}, [1], "1\n2"]
_BAD_LABELS = [None, True, 9, 0, "9", [1], {"a": 1}, 1.5, HUGE, NAN, "a\nb", "x" * 500]
TOPOLOGY_BAD = {
    ("dim",): [None, True, "2", 2.0, 0, -1, HUGE, 10**6, [], {}, NAN, INF, 3, [2]],
    ("agents",): [
        None,
        True,
        0,
        -5,
        2.5,
        "3",
        [],
        [1, 1],
        [1, [2], 3],
        [True, 2, 3],
        {"a": 1},
        HUGE,
        10**7,
        NAN,
        [1, 2],
        ["a\nb", "c", "d"],
        [HUGE, 2, 3],
    ],
    ("matrices",): [
        "x",
        [1],
        5,
        True,
        None,
        {"A": "x"},
        {"A": [[1, 0]]},
        {"A": [[NAN, 0], [0, 1]]},
        {"A": None},
        {"A": {"diag": [1]}},
        {"A": [[HUGE, 0], [0, 1]]},
        {"A": {"bogus": 1}},
        {"B": [[1, 0], [0, 1]]},
    ],
    ("edges",): [None, "x", 5, {}, {"from": 1}, [1], [None], [[]], True, NAN],
    ("edges", 0): [
        None,
        5,
        "e",
        [],
        {},
        {"from": 1, "to": 2},
        {"from": 1, "to": 2, "weight": [[1, 0], [0, 1]], "extra": 1},
        {"to": 2, "weight": 1},
        {"from": 2, "to": 3, "weight": 1},  # duplicates edge 2->3
    ],
    ("edges", 0, "from"): [*_BAD_LABELS, 2],  # 2 -> 2 is a self-loop
    ("edges", 0, "to"): [*_BAD_LABELS, 1],
    ("edges", 0, "weight"): [
        *_NOT_NUMBERS,
        [[1, 0]],
        [[1, 0], [0]],
        [[1, 2], [0, 1]],
        {"diag": [1, -1]},
        [[NAN, 0], [0, 1]],
        [[INF, 0], [0, 1]],
        [[-INF, 0], [0, 1]],
        [[HUGE, 0], [0, 1]],
        {"diag": [1]},
        {"diag": "x"},
        {"diag": [1, NAN]},
        {"identity": "x"},
        {"identity": NAN},
        {"identity": HUGE},
        {"matrix": "B"},
        {"matrix": "A", "scale": "x"},
        {"matrix": "A", "scale": INF},
        {"matrix": ["A"]},
        {"matrix": "A", "scale": 1, "x": 2},
        {"bogus": 1},
        NAN,
        INF,
        HUGE,
        [[[1]]],
        [["x", 0], [0, 1]],  # a string entry is an expression in t (time-varying)
        [["__import__('os').system('touch {S}')", 0], [0, 1]],
        [["t**(10**10)", 0], [0, 1]],
        [["1/(t-t)", 0], [0, 1]],
        [["exp(t)", "t"], ["t", 1]],  # not symmetric for every t
        [[True, 0], [0, 1]],
        [[1, 0], [0, 1], [0, 0]],
    ],
    ("bogus",): [1],
    ("dim\nerror: forged",): [2],
}


def _set(doc, path, value):
    doc = copy.deepcopy(doc)
    cur = doc
    for k in path[:-1]:
        cur = cur[k]
    if value is DROP:
        del cur[path[-1]]
    else:
        cur[path[-1]] = value
    return doc


def _cases(bad: dict) -> list:
    out = []
    for path, values in bad.items():
        for k, v in enumerate(values):
            for fmt in ("yaml", "json"):
                out.append(pytest.param(path, v, fmt, id=f"{'.'.join(map(str, path))}-{k}-{fmt}"))
    return out


def write(tmp_path, doc, fmt, name="doc"):
    p = tmp_path / f"{name}.{fmt}"
    if fmt == "json":
        p.write_text(json.dumps(doc))  # NaN/Infinity are read back by Python's json
    else:
        p.write_text(yaml.safe_dump(doc))
    return p


def refused(args, capsys, monkeypatch, tmp_path, *needles):
    sentinel = tmp_path / "SENTINEL"
    line = assert_input_error(args, capsys, monkeypatch, *needles)
    assert not sentinel.exists()
    return line


@pytest.mark.parametrize("path, value, fmt", _cases(TOPOLOGY_BAD))
def test_topology_field(tmp_path, capsys, monkeypatch, path, value, fmt):
    p = write(tmp_path, _set(TOPOLOGY, path, value), fmt)
    p.write_text(p.read_text().replace("{S}", str(tmp_path / "SENTINEL")))
    line = refused(["check", p], capsys, monkeypatch, tmp_path, str(p))
    assert "forged" not in line or "'dim\\n" in line  # a key with a newline stays quoted


def test_the_bases_are_valid(tmp_path, capsys, monkeypatch):
    from tests.cli_helpers import run_cli

    for doc in (TOPOLOGY, SWITCHING):
        for fmt in ("yaml", "json"):
            code, _, err = run_cli(["check", write(tmp_path, doc, fmt)], capsys, monkeypatch)
            assert code == 0, err


# ------------------------------------------------------------------ switching fields × values

SWITCHING_BAD = {
    ("modes",): [
        None,
        [],
        {},
        "x",
        5,
        {"G1": 5, "G2": TOPOLOGY},
        {"G1": "missing.yaml", "G2": TOPOLOGY},
        {"G1": None, "G2": TOPOLOGY},
        {"G1": [1], "G2": TOPOLOGY},
        {"G1": {"dim": 2}, "G2": TOPOLOGY},
        {"G1": _set(TOPOLOGY, ("dim",), 0), "G2": TOPOLOGY},
        {"G1": _set(TOPOLOGY, ("edges", 0, "weight"), [[NAN, 0], [0, 1]]), "G2": TOPOLOGY},
        {"G1": "/dev/zero", "G2": TOPOLOGY},
        {"G1": "/etc/passwd", "G2": TOPOLOGY},
        {"G1": "x\x00y", "G2": TOPOLOGY},
        {"G1": ".", "G2": TOPOLOGY},
    ],
    ("modes", "G1", "agents"): [0, [1, 1], HUGE],
    ("modes", "G2", "edges", 1, "weight"): [{"diag": [1, -1]}, {"matrix": "Z"}, "x"],
    ("schedule",): [
        None,
        [],
        "x",
        5,
        [{}],
        [{"mode": "G1"}],
        [1],
        [{"mode": "G3", "duration": 1}],
        [{"mode": ["G1"], "duration": 1}],
        [{"mode": "G1", "duration": 1, "x": 1}],
    ],
    ("schedule", 0, "duration"): [-1, 0, NAN, INF, -INF, "1", True, None, HUGE, [1]],
    ("name\nerror: forged",): [1],
}


@pytest.mark.parametrize("path, value, fmt", _cases(SWITCHING_BAD))
def test_switching_field(tmp_path, capsys, monkeypatch, path, value, fmt):
    p = write(tmp_path, _set(SWITCHING, path, value), fmt)
    refused(["check", p], capsys, monkeypatch, tmp_path, str(p))


# ------------------------------------------------------------------ parser attacks


def _laughs(levels: int, width: int = 9) -> str:
    out = ['a0: &a0 ["lol"]']
    for k in range(1, levels + 1):
        out.append(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * width) + "]")
    return "\n".join(out) + "\n"


def _deep_flow(n: int) -> str:
    return "x: " + "[" * n + "]" * n + "\n"


def _deep_block(n: int) -> str:
    return "x:\n" + "".join("  " * (k + 1) + "- \n" for k in range(n - 1)) + "  " * n + "- 1\n"


RAW_YAML = {
    "laughs-9": _laughs(9),
    "laughs-12": _laughs(12, 4),
    "laughs-30x2": _laughs(30, 2),
    "laughs-in-edges": "dim: 1\nagents: 2\n" + _laughs(9).replace("a9:", "edges:"),
    "laughs-merge": "a: &a {x: 1}\n"
    + "".join(
        f"b{k}: &b{k} {{<<: *{'a' if k == 0 else f'b{k - 1}'}, y{k}: [*a, *a]}}\n"
        for k in range(40)
    ),
    "recursive-alias": "a: &a [1, *a]\n",
    "recursive-map": "a: &a {b: *a}\n",
    "undefined-alias": "dim: *nope\n",
    "deep-flow-65": _deep_flow(65),
    "deep-flow-1e3": _deep_flow(1000),
    "deep-flow-1e5": _deep_flow(100_000),  # libyaml's own composer segfaults here
    "deep-map-1e4": "x: " + "{a: " * 10_000 + "1" + "}" * 10_000 + "\n",
    "deep-block-200": _deep_block(200),
    "deep-dash-1e5": "- " * 100_000 + "1\n",
    "python-apply": "dim: !!python/object/apply:os.system ['touch {S}']\n",
    "python-name": "dim: !!python/name:os.system\n",
    "python-new": "dim: !!python/object/new:os.system ['touch {S}']\n",
    "python-module": "dim: !!python/module:os\n",
    "python-tuple": "dim: !!python/tuple [1, 2]\n",
    "custom-tag": "dim: !mytag 2\n",
    "binary-tag": "dim: !!binary aGVsbG8=\nagents: 2\nedges: []\n",
    "set-tag": "dim: !!set {a, b}\n",
    "timestamp-dim": "dim: 2001-12-14\nagents: 2\nedges: []\n",
    "two-documents": "dim: 2\n---\ndim: 3\n",
    "list-top": "- 1\n- 2\n",
    "scalar-top": "hello\n",
    "null-top": "~\n",
    "only-comment": "# nothing\n",
    "only-dashes": "---\n",
    "whitespace": "   \n\n  \t \n",
    "tab-indent": "dim:\t2\nedges:\n\t- 1\n",
    "unclosed": "edges: [1, 2\n",
    "bad-indent": "dim: 2\n  agents: 3\n",
    "unhashable-key": "? [1, 2]\n: x\n",
    "dup-anchor-use": "a: &x 1\nb: &x [*x, *x]\nc: *x\n",
    "huge-int": "dim: " + "9" * 5000 + "\n",
    "huge-int-ok-digits": "dim: " + "9" * 4000 + "\nagents: 2\nedges: []\n",
    "huge-int-weight": "dim: 1\nagents: 2\nedges: [{from: 1, to: 2, weight: " + "9" * 400 + "}]\n",
    "hex-huge": "dim: 0x" + "f" * 4000 + "\n",
    "sexagesimal": "dim: 190:20:30\nagents: 2\nedges: []\n",
    "nan-dim": "dim: .nan\n",
    "inf-weight": "dim: 1\nagents: 2\nedges: [{from: 1, to: 2, weight: .inf}]\n",
    "control-chars": "dim: 2\x07\n",
    "nul-byte": "dim: 2\x00\n",
    "long-key": "x" * 2000 + ": 1\n",
    "long-line-value": "name: " + "y" * 100_000 + "\ndim: 0\n",
}
RAW_BYTES = {
    "invalid-utf8": b"dim: \xff\xfe\n",
    "utf16": "dim: 2\n".encode("utf-16"),
    "latin1": "name: caf\xe9\n".encode("latin-1"),
    "binary-junk": bytes(range(256)) * 4,
}
RAW_JSON = {
    "deep-1e5": "[" * 100_000 + "]" * 100_000,
    "deep-70": '{"a": ' + "[" * 70 + "]" * 70 + "}",
    "deep-obj-1e4": '{"a": ' * 10_000 + "1" + "}" * 10_000,
    "huge-int": '{"dim": ' + "9" * 5000 + "}",
    "huge-int-400": '{"dim": 1, "agents": 2, "edges": [{"from": 1, "to": 2, "weight": '
    + "9" * 400
    + "}]}",
    "big-exp": '{"dim": 1e999}',
    "nan": '{"dim": NaN}',
    "infinity-weight": '{"dim": 1, "agents": 2, "edges": [{"from": 1, "to": 2, "weight": '
    "-Infinity}]}",
    "trailing-comma": '{"dim": 2,}',
    "single-quotes": "{'dim': 2}",
    "list-top": "[1, 2]",
    "string-top": '"x"',
    "null-top": "null",
    "two-values": '{"dim": 2} {"dim": 3}',
    "comment": '{"dim": 2 /* c */}',
    "unterminated": '{"dim": "2',
    "bad-escape": '{"dim": "\\x41"}',
    "lone-surrogate": '{"name": "\\ud800", "dim": 0}',
    "empty-key-dup": '{"dim": 2, "dim": 0, "agents": 2, "edges": []}',
}


@pytest.mark.parametrize("name", sorted(RAW_YAML))
def test_yaml_attack(tmp_path, capsys, monkeypatch, name):
    sentinel = tmp_path / "SENTINEL"
    p = tmp_path / "attack.yaml"
    p.write_text(RAW_YAML[name].replace("{S}", str(sentinel)))
    refused(["check", p], capsys, monkeypatch, tmp_path, str(p))


@pytest.mark.parametrize("name", sorted(RAW_BYTES))
def test_bytes_attack(tmp_path, capsys, monkeypatch, name):
    p = tmp_path / "attack.yaml"
    p.write_bytes(RAW_BYTES[name])
    refused(["check", p], capsys, monkeypatch, tmp_path, str(p))


@pytest.mark.parametrize("name", sorted(RAW_JSON))
def test_json_attack(tmp_path, capsys, monkeypatch, name):
    p = tmp_path / "attack.json"
    p.write_text(RAW_JSON[name])
    refused(["check", p], capsys, monkeypatch, tmp_path, str(p))


@pytest.mark.parametrize("suffix", ["yaml", "json"])
def test_file_too_large(tmp_path, capsys, monkeypatch, suffix):
    p = tmp_path / f"big.{suffix}"
    with p.open("wb") as fh:  # sparse: no disk or time spent; refused before reading
        fh.truncate(MAX_FILE_BYTES + 1)
    refused(["check", p], capsys, monkeypatch, tmp_path, str(p), "MB")


@pytest.mark.parametrize(
    "make",
    [
        lambda d: d / "missing.yaml",
        lambda d: d,  # a directory
        lambda d: d / "a\nb.yaml",
        lambda d: d / "empty.yaml",
        lambda d: d / ("x" * 300 + ".yaml"),
    ],
    ids=["missing", "directory", "newline-name", "empty", "long-name"],
)
def test_bad_paths(tmp_path, capsys, monkeypatch, make):
    (tmp_path / "empty.yaml").write_text("")
    p = make(tmp_path)
    refused(["check", p], capsys, monkeypatch, tmp_path)


def test_limits_in_process():
    """The billion laughs document is refused without expanding it, quickly."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "l.yaml"
        p.write_text(_laughs(9))
        constructed = []
        real = yaml.SafeLoader.construct_document

        def spy(self, node):
            constructed.append(node)
            return real(self, node)

        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(yaml.SafeLoader, "construct_document", spy)
            with pytest.raises(InputError, match="expands to more than"):
                read_document(p)
        assert constructed == []  # refused while composing, before any expansion
        p.write_text("a: &a [1, 2]\nb: [*a, *a, *a]\n")  # modest aliases are fine
        assert read_document(p) == {"a": [1, 2], "b": [[1, 2]] * 3}
        p.write_text("x: " + "[" * 64 + "]" * 64 + "\n")  # exactly the depth limit
        with pytest.raises(InputError, match="nested deeper"):
            read_document(p)
        p.write_text("x: " + "[" * 63 + "]" * 63 + "\n")
        assert read_document(p)["x"] is not None


# ------------------------------------------------------------------ hostile expressions


def _expr_cases(sentinel: str) -> list[str]:
    touch = f"touch {sentinel}"
    cases = [
        f"__import__('os').system('{touch}')",
        f"t*0+__import__('os').system('{touch}')",
        "t*0+len(open('/etc/passwd').read())",
        f"exec('import os; os.system(\"{touch}\")')",
        "eval('1')+t",
        "globals()",
        "locals()['t']",
        "getattr(t, 'func')",
        "compile('1', 'x', 'eval')",
        "t.__class__.__mro__",
        "t.func",
        "(1).__class__",
        "t[0]",
        "t[1:2]",
        "'t'",
        "b't'",
        "f'{t}'",
        "1j*t",
        "...",
        "None",
        "True*t",
        "[t]",
        "(t, t)",
        "{t}",
        "{t: 1}",
        "[x for x in (1, 2)]",
        "(x for x in (1,))",
        "{x for x in (1,)}",
        "lambda: t",
        "(y := t)",
        "t if t else 1",
        "t and 1",
        "t or 1",
        "not t",
        "t < 1",
        "t == 1",
        "t % 2",
        "t // 2",
        "t @ t",
        "t << 2",
        "t >> 2",
        "t & 1",
        "t | 1",
        "~t",
        "exp(*[t])",
        "exp(**{'x': t})",
        "exp(x=t)",
        "exp(t, t)",
        "max(t)",
        "exp",
        "t;t",
        "t\nt",
        "import os",
        "yield t",
        "await t",
        "x + t",
        "T",
        "oo",
        "zoo",
        "nan",
        "I",
        "S",
        "Symbol('x')",
        "Integral(t, t)",
        "Piecewise((1, t < 1), (t, True))",
        "Function('f')(t)",
        "factorial(10**9)",
        "factorial(t)",
        "gamma(t)",
        "binomial(t, 2)",
        "Sum(t, (t, 1, 10))",
        "Derivative(t, t)",
        "Lambda(t, t)",
        "sympify('t')",
        "S('t')",
        "Rational(1, 2)",
        "E.func",
        "pi()",
        "t()",
        "(t)(1)",
        "exp(t)(1)",
        "t**(10**10)",
        "t**-(10**10)",
        "t**1001",
        "(t**1000)**1000",
        "2**2**2**2**2**2",
        "9**9**9**9",
        "10**10**10",
        "10**1000",
        "(10**200)**5",
        "9" * 100,
        "1" + "0" * 61 + "*t",
        "1e999",
        "1e-999",
        "1e400*t",
        "exp(1000)",
        "exp(exp(exp(100)))",
        "exp(10**6)",
        "cosh(1000)",
        "sin((pi**1000)**1000)",
        "log(0)",
        "log(-1)",
        "sqrt(-1)",
        "(-8)**(1/3)",
        "1/0",
        "0**-1",
        "1/(t-t)",
        "t/(0*t)",
        "0.0/0.0",
        "",
        " ",
        "(" * 250 + "t" + ")" * 250,
        "-" * 500 + "t",
        "+".join(["t"] * 300),
        "*".join(["(1+t)"] * 150),
        "t+" * 600 + "t",
        "exp(" * 70 + "t" + ")" * 70,
        "1/(1+",
        "1/(1+t))",
        "t t",
        "2t",
        "t,",
        "t =1",
        "t\x00",
        "t\x1b[2J",
        "t # \n",
    ]
    return cases


EXPRESSIONS = _expr_cases("{SENTINEL}")


@pytest.mark.parametrize("k", range(len(EXPRESSIONS)), ids=[e[:30] for e in EXPRESSIONS])
def test_gain_expression(tmp_path, capsys, monkeypatch, k):
    expr = EXPRESSIONS[k].replace("{SENTINEL}", str(tmp_path / "SENTINEL"))
    refused(["gain", expr], capsys, monkeypatch, tmp_path, "gain")


@pytest.mark.parametrize("k", range(0, len(EXPRESSIONS), 4), ids=lambda k: EXPRESSIONS[k][:30])
def test_scenario_gain(tmp_path, capsys, monkeypatch, k):
    """The same parser guards a scenario's gain; nothing is written."""
    expr = EXPRESSIONS[k].replace("{SENTINEL}", str(tmp_path / "SENTINEL"))
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        yaml.safe_dump({"topology": G1, "theta": [1, 2, -1], "gain": expr, "T": 0.1, "paths": 2})
    )
    out = tmp_path / "out"
    refused(["simulate", sc, "--out", out], capsys, monkeypatch, tmp_path, "gain")
    assert not out.exists()


@pytest.mark.parametrize("k", range(1, len(EXPRESSIONS), 12), ids=lambda k: EXPRESSIONS[k][:30])
def test_certify_gain(tmp_path, capsys, monkeypatch, k):
    expr = EXPRESSIONS[k].replace("{SENTINEL}", str(tmp_path / "SENTINEL"))
    args = ["certify", G1, "--theta", "1,2,-1", "--gain", expr, "--out", tmp_path / "c.json"]
    refused(args, capsys, monkeypatch, tmp_path, "gain")
    assert not (tmp_path / "c.json").exists()


# ------------------------------------------------------------------ Hypothesis


def _wrong_for(field: str):
    """Values that are never valid for a field of the topology format."""
    junk = st.one_of(
        st.none(),
        st.booleans(),
        st.text(max_size=20),
        st.dictionaries(st.text(max_size=5), st.integers(), max_size=3),
    )
    if field == "dim":
        return st.one_of(
            junk,
            st.integers(max_value=0),
            st.integers(min_value=1001),
            st.floats(allow_nan=True, allow_infinity=True),
        )
    if field == "agents":
        return st.one_of(
            st.none(),
            st.booleans(),
            st.integers(max_value=0),
            st.floats(),
            st.just([]),
            st.lists(st.integers(4, 50), min_size=1, max_size=5),  # edges use 1..3
        )
    if field == "weight":
        return st.one_of(
            junk,
            st.floats(allow_nan=False).filter(lambda x: not math.isfinite(x)),
            st.just(NAN),
            st.lists(st.lists(st.floats(), min_size=3, max_size=3), min_size=1, max_size=3),
            st.lists(st.lists(st.text(max_size=3), min_size=2, max_size=2), min_size=2, max_size=2),
        )
    if field == "from":
        return st.one_of(
            st.none(),
            st.booleans(),
            st.integers(min_value=4),
            st.integers(max_value=0),
            st.floats(),
            st.text(max_size=10).filter(lambda s: s not in ("1", "2", "3")),
        )
    raise ValueError(field)


_FIELDS = {
    "dim": ("dim",),
    "agents": ("agents",),
    "weight": ("edges", 1, "weight"),
    "from": ("edges", 2, "from"),
}


@pytest.mark.parametrize("field", sorted(_FIELDS))
@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_hypothesis_wrong_field(tmp_path_factory, field, data):
    value = data.draw(_wrong_for(field), label=field)
    fmt = data.draw(st.sampled_from(["yaml", "json"]), label="format")
    d = tmp_path_factory.mktemp("h")
    p = write(d, _set(TOPOLOGY, _FIELDS[field], value), fmt)
    with pytest.raises(InputError) as info:
        load(p)
    msg = str(info.value)
    assert "\n" not in msg and str(p) in msg


@settings(max_examples=200, deadline=None, suppress_health_check=list(HealthCheck))
@given(text=st.text(max_size=300))
def test_hypothesis_any_text_is_a_mapping_or_one_line(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("t") / "x.yaml"
    try:
        p.write_bytes(text.encode("utf-8", "surrogatepass"))
    except UnicodeEncodeError:
        return
    try:
        doc = read_document(p)
    except InputError as exc:
        assert "\n" not in str(exc)
    else:
        assert isinstance(doc, dict)


_ATOMS = st.sampled_from(
    ["t", "1", "2.5", "pi", "E", "x", "__import__", "'s'", "10**10", "1e999", "[t]", "t.a"]
)
_OPS = st.sampled_from(["+", "-", "*", "/", "**", "^", "%", "//", "<", " and ", ","])
_FUNCS = st.sampled_from(["exp", "log", "sin", "sqrt", "factorial", "eval", "open", "max"])


@st.composite
def _expressions(draw, depth=0):
    if depth > 3 or draw(st.booleans()):
        return draw(_ATOMS)
    kind = draw(st.integers(0, 2))
    a = draw(_expressions(depth + 1))
    if kind == 0:
        return f"({a}){draw(_OPS)}({draw(_expressions(depth + 1))})"
    if kind == 1:
        return f"{draw(_FUNCS)}({a})"
    return f"-{a}"


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(text=_expressions())
def test_hypothesis_expressions(text):
    try:
        expr = parse_expression(text, "gain")
    except InputError as exc:
        assert str(exc).startswith("gain: ") and "\n" not in str(exc)
    else:
        assert expr.free_symbols <= {symbol("t")}


# -- magnitudes, .npz members, θ of a time-varying file (issue 16) ---------------------


def _npz(path, w, d=1):
    import numpy as np

    np.savez(
        path,
        format=np.array("ntc-design/edge-list"),
        version=np.array(1),
        dim=np.array(d),
        labels=np.array([1, 2, 3]),
        **{
            "from": np.array([1, 2, 0, 1]),
            "to": np.array([0, 0, 1, 2]),
            "weights": np.array(w, dtype=float).reshape(-1, d, d),
        },
    )


@pytest.mark.parametrize("command", ["design", "certify"])
@pytest.mark.parametrize(
    "w, magnitude",
    [
        ([-1.7e308, -1.7e308, 1.0, 1.0], "1.7e+308"),  # their sum on agent 1 overflows
        ([-1e200, -1e200, 1.0, 1.0], "1e+200"),
        ([-5e-324, -5e-324, 1.0, 1.0], "4.94e-324"),  # subnormal
        ([1.0, 1.0, 1e-80, 1.0], "1e-80"),
    ],
)
def test_weights_outside_the_magnitude_range_are_refused(
    command, w, magnitude, tmp_path, capsys, monkeypatch
):
    f = tmp_path / "net.npz"
    _npz(f, w)
    line = assert_input_error([command, f, "--theta", "1"], capsys, monkeypatch, "net.npz: edge")
    assert f"magnitude {magnitude}, outside [2^-250, 2^250]" in line


def test_the_magnitude_range_is_the_certificates():
    from ntc_design.certify.format import NUMBER_EXP
    from ntc_design.model import Topology
    from ntc_design.numerics.linalg import MAGNITUDE_EXP, out_of_range

    assert NUMBER_EXP == MAGNITUDE_EXP == 250
    edge = 2.0**MAGNITUDE_EXP  # the bounds themselves are accepted
    top = Topology.from_edges(2, 1, [(1, 2, [[edge]]), (2, 1, [[2.0**-MAGNITUDE_EXP]])])
    assert top.n == 2 and not out_of_range(edge) and out_of_range(edge * 2)
    with pytest.raises(InputError, match="outside"):
        Topology.from_edges(2, 1, [(1, 2, [[edge * 2]])])


@pytest.mark.parametrize("member", ["X.npy", "X"])  # garbage in a .npy member, or no .npy
def test_npz_members_that_are_not_arrays(member, tmp_path, capsys, monkeypatch):
    import zipfile

    f = tmp_path / "net.npz"
    with zipfile.ZipFile(f, "w") as z:
        for k in ["format", "dim", "labels", "from", "to", "weights"]:
            z.writestr(member.replace("X", k), b"not an array")
    assert_input_error(
        ["design", f, "--theta", "1"], capsys, monkeypatch, "net.npz: dim: not a .npy array"
    )


def test_time_varying_theta_of_the_wrong_length_writes_nothing(tmp_path, capsys, monkeypatch):
    tv = {
        "dim": 2,
        "agents": 3,
        "period": "2*pi",
        "edges": [
            {"from": 1, "to": 2, "weight": {"diag": ["-1 - 0.5*sin(t)", -2]}},
            {"from": 2, "to": 3, "weight": [[2, 0], [0, 1]]},
            {"from": 3, "to": 1, "weight": {"identity": 1}},
            {"from": 2, "to": 1, "weight": {"identity": 1}},
        ],
    }
    f = tmp_path / "tv.yaml"
    f.write_text(yaml.safe_dump(tv))
    out = tmp_path / "cert.json"
    for args in (
        ["certify", f, "--theta", "1", "--gain", "1/(1+t)", "--out", out],
        ["design", f, "--theta", "1"],
    ):
        assert_input_error(args, capsys, monkeypatch, "theta: expected 2 numbers")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tv.yaml"]
