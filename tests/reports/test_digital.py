"""Tests of :mod:`ntc_design.reports.digital`: the digital section of a run's report, its
numbers against the simulator's and the certificate's, and ntc report --period."""

import json
import re

import numpy as np
import pytest

from ntc_design.reports.digital import DELAYS, digital_drawings, digital_facts
from ntc_design.reports.report import write_report
from ntc_design.reports.rundata import load_run
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.scenario import write_outputs
from ntc_design.tune.period import period_curve
from tests.cli_helpers import run_cli

X0 = np.linspace(-3, 3, 21)


@pytest.fixture(scope="module")
def digital_run(tmp_path_factory):
    """A digital run (h = 0.1, D = 1) on a 3-agent signed cycle (d = 1): its report's
    certificate is issued in about 0.2 s (G1's delay line in about 10 s, whose certificate
    tests/certify/kinds/test_digital.py checks)."""
    import ntc_design as nd

    folder = tmp_path_factory.mktemp("digital")
    (folder / "cycle.yaml").write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    res = simulate(
        nd.load(folder / "cycle.yaml"), [1], T=3.0, initial=[-3, 0.5, 3],
        noise=NoiseModel(0.4, 0.3), method="exact", digital={"period": 0.1, "delay": 1},
        save_every=0.1,
    )  # fmt: skip
    out = folder / "run"
    write_outputs(res, out)
    return res, out


def test_the_section_reports_the_runs_numbers(digital_run):
    res, out = digital_run
    run = load_run(out)
    from ntc_design.reports.parts import certify_run

    cert = certify_run(run)
    assert cert.certificate["kind"] == "digital" and cert.verification.valid
    f = digital_facts(run, cert.certificate)
    assert f is not None and f.period == 0.1 and f.delay == 1
    dg = res.summary()["digital"]
    assert float(f.sampled[-1]) == pytest.approx(float(res.exact.ms_error[-1].sum()), rel=1e-12)
    assert float(np.max(f.sampled)) <= dg["ms_error_peak"] * (1 + 1e-12)
    assert f.continuous_final == pytest.approx(dg["continuous_final_ms_error"], rel=1e-6)
    assert f.k0 == cert.certificate["results"]["digital"]["k0"]
    k = int(np.argmin(np.abs(f.periods - 0.2)))
    want = period_curve(run.topology(), _spec(run), 3.0, 2, f.periods[k : k + 1])[0]
    assert f.final[2][k] == pytest.approx(want[0], rel=1e-12)
    assert f.peak[2][k] == pytest.approx(want[1], rel=1e-12)
    assert set(f.final) == set(DELAYS)
    drawn = digital_drawings(f)
    assert [d.stem for d in drawn] == ["digital_periods", "digital_curve"]
    ax = drawn[0].figure.axes[0]
    assert len(ax.lines) == len(DELAYS) + 2  # a curve per delay, the continuous level, h
    rows = {r[0]: r[1] for r in f.table().rows}
    assert (
        rows["measurement delay D"] == "1"
        and "k₀ = " in rows["certified: contracts in mean square from step"]
    )


def _spec(run):
    from ntc_design.simulate import SimulationSpec
    from ntc_design.simulate.noise import noise_from_document

    p = run.summary["parameters"]
    return SimulationSpec.build(
        p["theta"], margin=p["margin"], gain=run.gain,
        noise=noise_from_document(p["noise"]), initial=p["initial"],
    )  # fmt: skip


@pytest.mark.slow
def test_the_report_has_the_digital_section_and_its_figures(digital_run):
    _, out = digital_run
    path = write_report(out)
    html = path.read_text()
    assert 'id="run-digital"' in html and "Digital protocol" in html
    text = re.sub("<[^>]+>", " ", html[html.index('id="run-digital"') :][:4000])
    assert "certified: contracts in mean square from step" in text
    assert (out / "figures" / "run_digital_periods.png").is_file()
    assert (out / "figures" / "run_digital_curve.svg").is_file()
    cert = json.loads((out / "certificate.json").read_text())
    assert cert["kind"] == "digital"


@pytest.mark.slow
def test_report_period_adds_the_section_to_a_continuous_run(g1, tmp_path, capsys, monkeypatch):
    res = simulate(g1, [1, 2, -1], T=2.0, initial=X0, noise=NoiseModel(0.4, 0.3), method="exact")
    out = tmp_path / "cont"
    write_outputs(res, out)
    code, _, err = run_cli(["report", out, "--period", "0.2"], capsys, monkeypatch)
    assert code == 0, err
    html = (out / "report.html").read_text()
    assert 'id="run-digital"' in html
    assert json.loads((out / "certificate.json").read_text())["subject"]["digital"]["period"] == 0.2
    # without --period, a continuous run's report has none
    code, _, _ = run_cli(["report", out], capsys, monkeypatch)
    assert code == 0 and 'id="run-digital"' not in (out / "report.html").read_text()


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--period", "5"], "--period: h = 5 is longer than the horizon T = 3"),
        (["--period", "1e-300"], "--period: T/h = 3e+300 steps exceed the limit"),
        (["--period", "0.1", "--delay", "10000"], "--delay: the exact moments of the delayed"),
    ],
)
def test_report_refuses_a_period_or_delay_before_writing_anything(
    digital_run, tmp_path, capsys, monkeypatch, flags, needle
):
    import shutil

    from tests.cli_helpers import assert_input_error

    out = tmp_path / "run"
    shutil.copytree(digital_run[1], out)
    before = sorted(p.name for p in out.iterdir())
    assert_input_error(["report", out, *flags], capsys, monkeypatch, needle)
    assert sorted(p.name for p in out.iterdir()) == before  # no certificate, no figures


def test_curves_that_are_not_computed_are_not_drawn_on_a_log_scale(digital_run):
    from dataclasses import replace

    run = load_run(digital_run[1])
    f = digital_facts(run, {})
    nan = {d: np.full(f.periods.size, np.nan) for d in DELAYS}
    none = replace(f, final=nan, peak=nan, continuous=np.full(f.t.size, np.nan), sampled=None)
    assert digital_drawings(none) == []
    kept = replace(f, final=nan, peak=nan)  # the curves over time are still shown
    assert [d.stem for d in digital_drawings(kept)] == ["digital_curve"]
