"""Tests of :mod:`ntc_design.reports.timevarying`."""

import matplotlib
import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol.timevarying import TimeVaryingDesign
from ntc_design.reports.timevarying import lambda_min_figure, weights_figure
from tests.conftest import ROOT

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def tv_design():
    tv = nd.load(ROOT / "examples" / "g1_tv.yaml")
    return tv, TimeVaryingDesign(tv, np.asarray(THETA), 0.1)


def test_lambda_min_curve_is_lemma1_at_each_instant(tv_design):
    tv, des = tv_design
    intervals = [[0.0, 1.0, 0.5], [1.0, 2.0, 0.25]]
    fig = lambda_min_figure(des, lambda2=0.2, intervals=intervals, samples=41)
    ax = fig.axes[0]
    ts, lam = (np.asarray(v) for v in ax.lines[0].get_data())
    a, b = tv.domain
    assert ts.size == 41 and ts[0] == a and ts[-1] == b
    for k in (0, 13, 40):  # Lemma 1 on the frozen topology A(t_k), with its own δ(t_k)
        frozen = nd.design(tv.at(float(ts[k])), THETA, thresholds=False)
        lb = frozen.grounded_laplacian()
        want = np.linalg.eigvalsh(lb + lb.T)[0]
        assert lam[k] == pytest.approx(want, rel=1e-9, abs=1e-12)
    step_x, step_y = ax.lines[1].get_data()
    assert list(step_x) == [0.0, 1.0, 2.0] and list(step_y) == [0.5, 0.25, 0.25]
    assert list(ax.lines[2].get_ydata()) == [0.2, 0.2]  # Λ₂, dashed
    assert ax.lines[2].get_linestyle() == "--"


def test_weights_figure_draws_each_varying_entry_and_delta(tv_design):
    tv, des = tv_design
    fig = weights_figure(des, samples=25)
    varying = [e for e in tv.edges if not e.weight.constant]
    assert len(fig.axes) == len(varying) + 1
    ts = np.linspace(*tv.domain, 25)
    w = tv.weights_at(ts)
    k0 = next(k for k, e in enumerate(tv.edges) if not e.weight.constant)
    first = fig.axes[0].lines[0]
    np.testing.assert_allclose(first.get_xdata(), ts)
    r, c = (int(x) - 1 for x in first.get_label()[len("entry (") : -1].split(", "))
    np.testing.assert_allclose(first.get_ydata(), w[:, k0, r, c])
    delta = fig.axes[-1].lines[0].get_ydata()
    for k in (0, 24):
        frozen = nd.design(tv.at(float(ts[k])), THETA, thresholds=False)
        assert delta[k] == pytest.approx(frozen.delta, rel=1e-9)
