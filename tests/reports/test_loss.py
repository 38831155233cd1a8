"""Tests of :mod:`ntc_design.reports.loss`: the lossy-link section of a run's report, its
numbers against the exact moments recomputed here, and the section in the HTML."""

import re

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.protocol.loss import POLICIES
from ntc_design.reports.loss import loss_drawings, loss_facts
from ntc_design.reports.parts import certify_run
from ntc_design.reports.report import write_report
from ntc_design.reports.rundata import load_run
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss import loss_moments
from ntc_design.simulate.scenario import write_outputs
from ntc_design.simulate.system import mode_system
from tests.support.reports import stand_in_save

X0 = np.linspace(-3, 3, 21)


@pytest.fixture(scope="module")
def lossy_run(g1, tmp_path_factory):
    res = simulate(
        g1, THETA, T=2.0, initial=X0, noise=NoiseModel(0.4, 0.3), method="exact",
        digital={"period": 0.1, "loss": 0.1}, save_every=0.1, gain="1/(1+t)",
    )  # fmt: skip
    out = tmp_path_factory.mktemp("loss") / "run"
    write_outputs(res, out)
    return res, out


def test_the_section_reports_the_exact_curves(g1, lossy_run):
    _, out = lossy_run
    run = load_run(out)
    cert = certify_run(run)
    assert cert.certificate["kind"] == "digital_loss" and cert.verification.valid
    f = loss_facts(run, cert.certificate)
    assert f is not None and f.loss == 0.1 and f.policy == "skip"
    assert 0.1 in f.losses.tolist() and f.losses[0] == 0.0
    s = mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))
    grid, _ = digital_grid(Digital(0.1), 2.0, np.array([2.0]))
    m = f.losses.tolist().index(0.1)
    for policy in POLICIES:
        want = loss_moments(
            s, grid, lambda t: 1 / (1 + t), X0 - np.tile(THETA, 7), THETA, 0,
            np.full(s.n_edges, 0.1), policy,
        )  # fmt: skip
        assert f.final[policy][m] == pytest.approx(float(want.moments.ms_error[-1].sum()))
    assert f.offset["skip"][m] == pytest.approx(0.1433, abs=1e-4)
    assert f.offset["rescale"].tolist() == [0.0] * f.losses.size
    assert "k₀ = 19" in f.certified and "x* at 0.1433" in f.certified
    assert len(f.table().rows) == f.losses.size
    assert [d.stem for d in loss_drawings(f)] == ["loss_curves"]
    assert loss_drawings(None) == []


def test_a_lossless_run_has_no_section(tmp_path, g1):
    res = simulate(
        g1, THETA, T=1.0, initial=X0, noise=NoiseModel(0.4, 0.3), method="exact",
        digital={"period": 0.1}, save_every=0.5,
    )  # fmt: skip
    write_outputs(res, tmp_path / "r")
    assert loss_facts(load_run(tmp_path / "r"), {}) is None


def test_the_report_has_the_lossy_section(lossy_run, monkeypatch):
    _, out = lossy_run
    # the text is what is read: only the lossy curves are drawn (their SVG is checked)
    saved = stand_in_save(monkeypatch, draw=("loss_curves",), formats=("png", "svg"))
    html = write_report(out).read_text()
    assert 'id="run-loss"' in html
    text = re.sub("<[^>]+>", " ", html[html.index('id="run-loss"') :][:5000])
    assert "certified: E‖x − x*‖² contracts from step k₀ = 19" in text
    assert (out / "figures" / "run_loss_curves.svg").read_text().lstrip().startswith("<?xml")
    assert [s.name for s in saved].count("run_loss_curves") == 1
    digital = re.sub("<[^>]+>", " ", html[html.index('id="run-digital"') :][:3000])
    assert "These curves are without message loss" in digital
