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
