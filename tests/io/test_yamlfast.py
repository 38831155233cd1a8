"""Tests of :mod:`ntc_design.io.yamlfast`."""

import math

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from ntc_design.errors import InputError
from ntc_design.io import documents
from ntc_design.io.documents import read_document
from ntc_design.io.yamlfast import load_fast, node_bound
from ntc_design.model.generate import random_network, write_topology
from tests.conftest import ROOT


def same(a, b) -> bool:
    """Equal with the same types all the way down (1 != 1.0 != True; -0.0 != 0.0)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float):
        return (math.isnan(a) and math.isnan(b)) or (
            a == b and math.copysign(1, a) == math.copysign(1, b)
        )
    return a == b


def fast(text: str):
    return load_fast(text, documents.MAX_DEPTH, documents.MAX_EXPANDED_NODES)


def check(text: str) -> bool:
    """The fast reader's result is PyYAML's, or None; True when it read the text."""
    try:
        ref, ok = yaml.load(text, Loader=yaml.SafeLoader), True
    except yaml.YAMLError:
        ref, ok = None, False
    got = fast(text)
    if got is None:
        return False
    assert ok, f"read a text PyYAML refuses: {text!r} -> {got!r}"
    assert same(got, ref), f"{text!r}: {got!r} != {ref!r}"
    return True


def read_both(path, monkeypatch):
    """read_document's document (or error) with the fast reader and without it."""
    results = []
    for use_fast in (True, False):
        with monkeypatch.context() as m:
            if not use_fast:
                m.setattr(documents, "load_fast", lambda *a: None)
            try:
                results.append(("doc", read_document(path)))
            except InputError as exc:
                results.append(("error", str(exc)))
    return results


@pytest.mark.parametrize("seed,d,labels", [(1, 3, None), (2, 2, "names"), (3, 1, None)])
def test_generated_files_are_read_fast_and_the_same(tmp_path, monkeypatch, seed, d, labels):
    top = random_network(300, d, seed=seed)
    path = write_topology(top, tmp_path / "net.yaml")
    if labels:  # text labels, written as write_topology writes
        doc = top.to_dict()
        doc["agents"] = [f"node-{a}" for a in top.labels]
        for e in doc["edges"]:
            e["from"], e["to"] = f"node-{e['from']}", f"node-{e['to']}"
        path.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
    text = path.read_text()
    doc = fast(text)
    assert doc is not None  # machine-written: inside the subset
    assert same(doc, yaml.load(text, Loader=yaml.SafeLoader))
    (k1, a), (k2, b) = read_both(path, monkeypatch)
    assert k1 == k2 == "doc" and same(a, b)
    assert len(doc["edges"]) == len(top.edge_arrays.rows)
    assert isinstance(doc["dim"], int) and isinstance(doc["edges"][0]["weight"][0][0], float)


def test_a_generated_file_never_reaches_pyyaml(tmp_path, monkeypatch):
    """A work-counting spy: machine-written files are not composed event by event."""
    path = write_topology(random_network(50, 2, seed=4), tmp_path / "net.yaml")
    calls = []

    class Spy:
        def __init__(self, text):
            calls.append(text)
            raise AssertionError("the full reader was used")

    monkeypatch.setattr(documents, "_Loader", Spy)
    assert read_document(path)["dim"] == 2
    assert calls == []


@pytest.mark.parametrize(
    "path", sorted(p for p in ROOT.joinpath("examples").rglob("*") if p.suffix in (".yaml", ".yml"))
)
def test_examples_read_the_same(path, monkeypatch):
    (k1, a), (k2, b) = read_both(path, monkeypatch)
    assert k1 == k2 and same(a, b)
    check(path.read_text())


READ = {  # texts inside the subset, and the values PyYAML gives them
    "a: 1\nb: -0\nc: -0.0\nd: 1.5e+5\ne: 1.0E-05\n": {
        "a": 1,
        "b": 0,
        "c": -0.0,
        "d": 150000.0,
        "e": 1e-05,
    },
    "x: [a, b-c, d.e, _f, NaN, Infinity, yes-no]\n": {
        "x": ["a", "b-c", "d.e", "_f", "NaN", "Infinity", "yes-no"]
    },
    "a:\nb:\n- 1\n- {c: 2}\n- []\n- {}\n": {"a": None, "b": [1, {"c": 2}, [], {}]},
    "- a: 1\n  b:\n    c: [1,\n      2]\n- 3\n": [{"a": 1, "b": {"c": [1, 2]}}, 3],
    "a: 1\na: 2\n": {"a": 2},
    "n: 123456789012345678901234567890\n": {"n": 123456789012345678901234567890},
}


@pytest.mark.parametrize("text", list(READ))
def test_texts_in_the_subset(text):
    assert same(fast(text), READ[text])
    assert check(text)


DECLINED = [
    "a: yes\n",  # YAML 1.1 booleans and nulls
    "a: Off\n",
    "a: null\n",
    "a: ~\n",
    "on: 1\n",
    "a: 1e5\n",  # numbers JSON reads otherwise
    "a: 1.5e5\n",
    "a: 1E+5\n",
    "a: 010\n",
    "a: 0x1F\n",
    "a: 1_000\n",
    "a: .inf\n",
    "a: 1.\n",
    "a: +1\n",
    "a: 1:30\n",
    "a: 2020-01-01\n",
    "1: a\n",
    "a: 'q'\n",  # quotes, comments, anchors, tags, block scalars, tabs
    'a: "q"\n',
    "a: 1  # c\n",
    "a: &x [1]\nb: *x\n",
    "a: !!str 1\n",
    "a: |\n  t\n",
    "a:\t1\n",
    "a: [1, [2]]\n",  # nested flow, several words, odd layout
    "a: b c\n",
    "a: b, c\n",
    "a: b\n  c\n",
    "- - 1\n",
    "--- \na: 1\n",
    "a: 1\n...\n",
    "[1, 2]\n",
    "a: [1], [2]\n",
    "- [1], [2]\n",
    "a: [1,\nb]\n",
    "a: 1\n b: 2\n",
    "a:\n- 1\n b: 2\n",
    "a: [1, 2,]\n",
    "a: {b}\n",
    "a: é\n",
]


@pytest.mark.parametrize("text", DECLINED)
def test_texts_outside_the_subset_are_declined(text):
    assert fast(text) is None
    check(text)


@pytest.mark.parametrize(
    "text",
    ["a: 1\n b: 2\n", "a: [1, 2\n", "a: [1, 2]]\n", "- 1\na: 2\n", "a: b: c\n", "a: [1] x\n"],
)
def test_bad_files_give_the_same_error(tmp_path, monkeypatch, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    (k1, a), (k2, b) = read_both(path, monkeypatch)
    assert k1 == k2 == "error" and a == b


def test_depth_bound(tmp_path):
    deep = "".join(f"{'  ' * k}k:\n" for k in range(70)) + "  " * 70 + "k: 1\n"
    assert fast(deep) is None
    shallow = "".join(f"{'  ' * k}k:\n" for k in range(20)) + "  " * 20 + "k: 1\n"
    assert check(shallow)
    path = tmp_path / "deep.yaml"
    path.write_text(deep)
    with pytest.raises(InputError, match="nested deeper than 64 levels"):
        read_document(path)


def test_node_bound(tmp_path, monkeypatch):
    text = "a: [" + ", ".join(["1"] * 100) + "]\n"
    assert node_bound(text) >= 102
    assert load_fast(text, 64, 50) is None and load_fast(text, 64, 1000) is not None
    path = tmp_path / "many.yaml"
    path.write_text(text)
    monkeypatch.setattr(documents, "MAX_EXPANDED_NODES", 50)
    with pytest.raises(InputError, match="more than 50 nodes"):
        read_document(path)


def test_node_bound_of_a_large_text_counts():
    text = "a: [" + ", ".join(["1"] * 400_000) + "]\n"  # over 1 MiB: counted, not its length
    assert 400_002 <= node_bound(text) < len(text)


SCALARS = st.one_of(
    st.integers(-(10**20), 10**20),
    st.floats(allow_nan=False, width=64),
    st.sampled_from(["a", "b_1", "x-y", "yes", "null", "1e5", "010", "a b", "", "-", "G.1"]),
    st.booleans(),
    st.none(),
)


KEYS = st.sampled_from(["from", "to", "weight", "a", "k_1", "yes", "1e5"]) | st.integers(0, 3)


DOCS = st.recursive(
    SCALARS,
    lambda c: st.lists(c, max_size=4) | st.dictionaries(KEYS, c, max_size=4),
    max_leaves=20,
)


@settings(max_examples=200, deadline=None)  # derandomized: the same 200 documents each run
@given(DOCS, st.sampled_from([None, False, True]), st.sampled_from([20, 80]), st.data())
def test_random_documents(doc, style, width, data):
    text = yaml.safe_dump({"edges": doc}, default_flow_style=style, width=width, sort_keys=False)
    check(text)
    check(text.replace("'", ""))  # quoted words unquoted: booleans, numbers, texts
    pos = data.draw(st.integers(0, len(text)))
    junk = data.draw(st.sampled_from([" ", "\n", "- ", ": ", ",", "]", "[", "e", "-", "  "]))
    check(text[:pos] + junk + text[pos:])  # layouts and tokens the dumper never writes
