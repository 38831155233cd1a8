"""Tests of :mod:`ntc_design.simulate.robust_sampling`."""

import pytest

from tests.cli_helpers import assert_input_error
from tests.support.robust import _scenario


@pytest.mark.hostile
@pytest.mark.parametrize(
    "block, needle",
    [
        ("robust: {realizations: 0}", "robust.realizations"),
        ("robust: {radius: 1.5}", "robust.radius"),
        ("robust: {realisations: 3}", "robust.realisations: unknown field"),
        ("robust: 7", "robust: expected"),
    ],
)
def test_a_bad_robust_block_is_one_line_exit_2(tmp_path, block, needle, capsys, monkeypatch):
    sc = _scenario(tmp_path, block)
    args = ["simulate", sc, "--out", tmp_path / "o"]
    assert_input_error(args, capsys, monkeypatch, needle, str(sc))
    assert not (tmp_path / "o").exists()
