"""The suite's outcome does not depend on the machine: the memory every size check assumes
is pinned (conftest sets NTC_AVAILABLE_MEMORY), and the refusals follow it exactly."""

import json

import pytest

from ntc_design.errors import InputError
from ntc_design.numerics import linalg
from tests.cli_helpers import run_cli
from tests.conftest import EXAMPLES


@pytest.mark.parametrize(
    "text, value",
    [
        ("6G", 6 * 2**30),
        ("512M", 512 * 2**20),
        ("8GiB", 8 * 2**30),
        ("1000", 1000.0),
        ("1.5k", 1536.0),
    ],
)
def test_pinned_memory_is_read_exactly(monkeypatch, text, value):
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", text)
    assert linalg.available_memory() == value


@pytest.mark.hostile
@pytest.mark.parametrize("text", ["", "x", "-1G", "0", "1e400", "nan", "8 X", "1" * 400])
def test_a_bad_pinned_memory_is_refused_naming_the_variable(monkeypatch, text):
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", text)
    with pytest.raises(InputError, match="NTC_AVAILABLE_MEMORY"):
        linalg.available_memory()


def test_the_suite_runs_with_a_laptops_memory():
    # the value conftest pins: what an 8 GB laptop has free, on every machine
    assert linalg.available_memory() == 6 * 2**30


@pytest.mark.parametrize("memory, needle", [("6G", "of memory"), ("1T", "RK4 steps")])
def test_the_refusal_follows_the_pinned_memory(tmp_path, capsys, monkeypatch, memory, needle):
    # 5·10⁶ save times: 6.7 GiB of exact moments, and ~600 s of RK4 steps
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", memory)
    sc = tmp_path / "sc.json"
    sc.write_text(
        json.dumps(
            {
                "topology": str(EXAMPLES / "g1.yaml"),
                "theta": [1, 2, -1],
                "T": 1e7,
                "dt": 1.0,
                "save_every": 2.0,
                "method": "exact",
            }
        )
    )
    code, out, err = run_cli(["simulate", sc, "--out", tmp_path / "run"], capsys, monkeypatch)
    assert code == 2, err
    assert needle in err and err.count("\n") == 1
    assert not (tmp_path / "run").exists()
