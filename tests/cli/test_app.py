"""Tests of :mod:`ntc_design.cli.app`."""

import json

import numpy as np
import pytest

from ntc_design import __version__
from ntc_design.cli import app as cli_base
from ntc_design.cli.app import command_line, json_text, parse_vector
from ntc_design.errors import InputError
from tests.cli_helpers import run_cli


@pytest.mark.parametrize(
    "text, values",
    [
        ("1,2,-1", [1.0, 2.0, -1.0]),
        ("[1, 2.5]", [1.0, 2.5]),
        ("-0.5", [-0.5]),
        ("1,,2", [1.0, 2.0]),
    ],
)
def test_parse_vector_reads_comma_separated_numbers(text, values):
    assert parse_vector(text, "--theta") == values


@pytest.mark.hostile
@pytest.mark.parametrize("text", ["", "[]", "1,a", "1;2", "x"])
def test_parse_vector_refuses_with_the_field_named(text):
    with pytest.raises(InputError, match=r"^--theta: expected comma-separated numbers, got "):
        parse_vector(text, "--theta")


def test_the_command_line_is_recorded_as_typed_and_quoted(monkeypatch):
    monkeypatch.setattr(cli_base, "ARGS", ["simulate", "my scenario.yaml", "--paths", "30"])
    assert command_line() == "ntc simulate 'my scenario.yaml' --paths 30"


def test_json_text_writes_numpy_values_as_json():
    doc = json.loads(json_text({"a": np.float64(0.5), "b": np.arange(3), "c": (1, 2)}))
    assert doc == {"a": 0.5, "b": [0, 1, 2], "c": [1, 2]}


def test_version_is_printed_and_exits_zero(capsys, monkeypatch):
    code, out, _ = run_cli(["--version"], capsys, monkeypatch)
    assert code == 0 and out.strip() == f"ntc {__version__}"


@pytest.mark.hostile
@pytest.mark.parametrize(
    "args, needles",
    [
        # typed flags: typer parses them by pydantic, which read 0_05 as 5.0
        (["robust", "G1", "--theta", "1,2,-1", "--radius", "0_05"], ["--radius", "'0_05'"]),
        (["robust", "G1", "--theta", "1,2,-1", "--radius", "0.0_5"], ["--radius", "underscores"]),
        (["robust", "G1", "--theta", "1,2,-1", "--radius", "\u0660.\u0665"], ["--radius", "ASCII"]),
        (["certify", "G1", "--theta", "1,2,-1", "--margin", "1_0"], ["--margin", "'1_0'"]),
        (["generate", "--agents", "1_0", "--dim", "2", "--out", "OUT"], ["--agents", "'1_0'"]),
        (
            ["generate", "--agents", "\uff11\uff10", "--dim", "2", "--out", "OUT"],
            ["--agents", "ASCII"],
        ),
        # text vectors
        (["certify", "G1", "--theta", "1,2,-1_0"], ["--theta", "'-1_0'", "underscores"]),
        (["certify", "G1", "--theta", "1,2,\u0663"], ["--theta", "ASCII digits"]),
    ],
    ids=lambda v: " ".join(v[-2:]) if isinstance(v, list) and len(v) > 3 else None,
)
def test_number_flags_take_ascii_numerals_only(args, needles, tmp_path, capsys, monkeypatch):
    from tests.cli_helpers import assert_input_error
    from tests.conftest import EXAMPLES

    args = [{"G1": EXAMPLES / "g1.yaml", "OUT": tmp_path / "n.npz"}.get(a, a) for a in args]
    assert_input_error(args, capsys, monkeypatch, *needles)
    assert not (tmp_path / "n.npz").exists()


@pytest.mark.parametrize("text", ["0.05", " 5e-2", "+.5", "1E+2", "7"])
def test_number_flags_still_read_plain_numbers(text):
    from typer import _adapters  # patched by cli_base: the ASCII check before pydantic's

    adapter = _adapters._build_number_adapter(float, min=None, max=None, clamp=None)
    assert adapter.validate_python(text) == float(text)
