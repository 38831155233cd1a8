"""Tests of :mod:`ntc_design.certify.result`."""

import pytest

import ntc_design as nd
from ntc_design.certify import certify
from tests.conftest import ROOT


@pytest.mark.parametrize("file", ["g1.yaml", "switching.yaml"])
def test_terminal_and_html_show_the_kinds_rows(file, tmp_path, capsys, monkeypatch):
    """One presentation model: the kind's rows, labels written once, in both faces."""
    from ntc_design.reports.report import certificate_tables
    from tests.cli_helpers import run_cli

    args = ["certify", ROOT / "examples" / file, "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    res = certify(nd.load(ROOT / "examples" / file), [1.0, 2.0, -1.0], gain="1/(1+t)")
    summary, _, _ = certificate_tables(res, tmp_path / "c.json", tmp_path)
    html = {(a, b) for a, b in summary.rows if isinstance(b, str)}
    assert res.rows
    for row in res.rows:
        assert f"{row.label}: {row.value}" in out
        assert (row.label, row.value) in html


@pytest.mark.hostile
@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"noise_sigma": 5e-324}, "noise_sigma: 5e-324 has a nonzero |entry| outside"),
        ({"noise_f": 1e300}, "noise_f: 1e+300 has a nonzero |entry| outside"),
    ],
)
def test_a_noise_no_certificate_can_state_is_refused_up_front(g1, kwargs, needle):
    # the subnormal σ once gave a certificate that failed its own well-formedness check
    from ntc_design.certify import certify
    from ntc_design.errors import InputError
    from ntc_design.model.paper import THETA
    from ntc_design.protocol.digital import Digital

    with pytest.raises(InputError) as err:
        certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 1), **kwargs)
    assert str(err.value).startswith(needle) and "\n" not in str(err.value)
