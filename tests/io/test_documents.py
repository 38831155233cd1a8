"""Tests of :mod:`ntc_design.io.documents`."""

import json

import pytest

from ntc_design.errors import InputError
from ntc_design.io import documents
from ntc_design.io.documents import read_document, type_name


def test_yaml_and_json_read_to_the_same_mapping(tmp_path):
    doc = {"dim": 2, "agents": [1, "b"], "edges": [{"from": 1, "to": "b", "weight": [[1, 0]]}]}
    (tmp_path / "a.json").write_text(json.dumps(doc), encoding="utf-8")
    (tmp_path / "a.yaml").write_text(
        "dim: 2\nagents: [1, b]\nedges:\n  - {from: 1, to: b, weight: [[1, 0]]}\n",
        encoding="utf-8",
    )
    assert read_document(tmp_path / "a.json") == read_document(tmp_path / "a.yaml") == doc


@pytest.mark.hostile
@pytest.mark.parametrize(
    "name, text, needle",
    [
        ("list.yaml", "- 1\n- 2\n", "expected a mapping at the top level, got list"),
        ("empty.yaml", "", "the file is empty"),
        ("null.yaml", "~\n", "expected a mapping at the top level, got nothing"),
        ("bad.json", "{", "not valid JSON"),
        ("bad.yaml", "a: [1\n", "not valid YAML"),
    ],
)
def test_a_document_that_is_not_a_mapping_is_one_line_naming_the_file(tmp_path, name, text, needle):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as exc:
        read_document(p)
    msg = str(exc.value)
    assert msg.startswith(str(p)) and needle in msg and "\n" not in msg


@pytest.mark.hostile
def test_the_limits_are_refused_before_the_document_is_built(tmp_path, monkeypatch):
    deep = tmp_path / "deep.json"
    deep.write_text(
        '{"a": ' + "[" * (documents.MAX_DEPTH + 1) + "]" * (documents.MAX_DEPTH + 1) + "}"
    )
    with pytest.raises(InputError, match="nest"):
        read_document(deep)
    # aliases counted expanded: 4 × 4 × 4 = 64 nodes from a few lines
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text("a: &a [1, 1, 1, 1]\nb: &b [*a, *a, *a, *a]\nc: [*b, *b, *b, *b]\n")
    monkeypatch.setattr(documents, "MAX_EXPANDED_NODES", 50)
    with pytest.raises(InputError, match=str(bomb)):
        read_document(bomb)
    monkeypatch.setattr(documents, "MAX_FILE_BYTES", 10)
    with pytest.raises(InputError, match=str(deep)):
        read_document(deep)


def test_type_name_says_what_a_value_is():
    assert [type_name(x) for x in (None, 1, "a", [1], {"k": 1})] == [
        "nothing", "int", "str", "list", "dict",
    ]  # fmt: skip


@pytest.mark.hostile
@pytest.mark.parametrize("value", ["0_05", "-1_0", "1_000.5", "1_000"])
@pytest.mark.parametrize("big", [False, True], ids=["small", "compiled-reader-size"])
def test_yaml_numbers_with_underscores_are_refused(value, big, tmp_path):
    # YAML 1.1 (PyYAML) and yaml-rs (past COMPILED_YAML_MIN_CHARS) read 0_05 as 5, -1_0
    # as -10; a label such as n1_2 stays text (the last line)
    pad = "# " + "x" * 78 + "\n"
    f = tmp_path / "u.yaml"
    f.write_text(
        f"a: 1\nb: {value}\nc: n1_2\n"
        + (pad * (documents.COMPILED_YAML_MIN_CHARS // 80 + 1) if big else ""),
        encoding="utf-8",
    )
    with pytest.raises(InputError, match=f"line 2: '{value}' is a number with underscores"):
        read_document(f)


def test_yaml_text_with_underscores_stays_text(tmp_path):
    f = tmp_path / "u.yaml"
    f.write_text('a: "0_05"\nb: my_name\nc: 0.05\nd: n1_2\n', encoding="utf-8")
    assert read_document(f) == {"a": "0_05", "b": "my_name", "c": 0.05, "d": "n1_2"}


@pytest.mark.hostile
@pytest.mark.parametrize(
    "name, text, field",
    [
        ("t.json", '{"agents": [1, "\\ud800"]}', "agents[1]"),
        ("t.json", '{"name": "G\\udfff", "dim": 1}', "name"),
        ("t.yaml", '{"agents": [1, "\\ud800"]}', "agents[1]"),  # JSON text in a YAML file
    ],
)
def test_a_lone_surrogate_is_refused_naming_the_field(tmp_path, name, text, field):
    from ntc_design.io.documents import read_document

    p = tmp_path / name
    p.write_text(text, encoding="ascii")
    with pytest.raises(InputError) as info:
        read_document(p)
    assert str(info.value).startswith(f"{p}: {field}: a string that is not Unicode text")
    str(info.value).encode("utf-8")  # the message itself can be printed


def test_a_surrogate_pair_and_an_escaped_backslash_are_text(tmp_path):
    from ntc_design.io.documents import read_document

    p = tmp_path / "t.json"
    p.write_text('{"name": "\\ud83d\\ude00", "path": "C:\\\\ud800"}', encoding="ascii")
    assert read_document(p) == {"name": "\U0001f600", "path": "C:\\ud800"}


@pytest.mark.hostile
@pytest.mark.parametrize("text", ['agents: [1, "\\ud800"]\n', 'name: "\\U0000DBFF"\n'])
def test_a_yaml_surrogate_escape_is_refused_by_the_yaml_reader(tmp_path, text):
    from ntc_design.io.documents import read_document

    p = tmp_path / "t.yaml"
    p.write_text(text, encoding="ascii")
    with pytest.raises(InputError, match="invalid Unicode character escape"):
        read_document(p)
