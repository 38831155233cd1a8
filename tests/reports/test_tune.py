"""Tests of :mod:`ntc_design.reports.tune`."""

import functools
import json
import re

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
import yaml
from matplotlib.collections import PolyCollection

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.errors import InputError
from ntc_design.gain.conditions import analyse_gain
from ntc_design.gain.schedule import ScheduleGain, analyse_schedule
from ntc_design.io.files import parse_scenario
from ntc_design.reports import style
from ntc_design.reports import tune as rt
from ntc_design.tune import BASELINE, Landscape, PowerGain, ScheduleTuneResult, TuneResult
from ntc_design.tune.objective import Curve
from ntc_design.tune.optimal import Level, ScheduleSolution
from tests.support.tune import PAIR

matplotlib.use("Agg")  # files only, whatever the machine's display

# Results built by hand (a real tuning takes seconds): every curve, gain and landscape
# below has a value or a peak known in closed form.
T_END = 2.0
T = np.linspace(0.0, T_END, 41)
TUNED = PowerGain(1.5, 2.0, 0.7)  # 1.5·(2 + t)^(−0.7)
FALLING = 4.0 * np.exp(-2.0 * T)  # peak 4 at t = 0, final 4e^(−4)
HUMP = 1.0 + T * (2.0 - T)  # peak 2 at t = 1, final 1
SCHED = ScheduleGain([0.0, 0.5, 1.0, 2.0], [3.0, 2.0, 1.0, 0.5], tail="1.5/(1 + t)")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture
def png_only(monkeypatch):
    # the vector formats are style.save's own business (tests/reports/test_style.py)
    monkeypatch.setattr(style, "save", functools.partial(style.save, formats=("png",), dpi=40))


@pytest.fixture
def saves(monkeypatch):
    """style.save recording where each figure goes, drawing nothing (drawing is the slow
    part, and one test below draws for real)."""
    got = []

    def save(fig, stem):
        got.append((stem, fig))
        stem.parent.mkdir(parents=True, exist_ok=True)
        stem.with_suffix(".png").write_bytes(b"")  # an empty stand-in file
        return style.SavedFigure(stem, {"png": stem.with_suffix(".png")}, b"")

    monkeypatch.setattr(style, "save", save)
    return got


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    d = tmp_path_factory.mktemp("scenario")
    (d / "nets").mkdir()
    (d / "nets" / "pair.yaml").write_text(PAIR, encoding="utf-8")
    (d / "sc.yaml").write_text(
        "name: pair run\ntopology: nets/pair.yaml\ntheta: [1.0]\nmargin: 0.1\nT: 5\n",
        encoding="utf-8",
    )
    return parse_scenario(d / "sc.yaml")


@pytest.fixture(scope="module")
def certificate(scenario):
    return certify(nd.load(scenario.topology), [1.0], gain=TUNED.text)


def landscape(b=2.0, values=None):
    a = np.geomspace(0.1, 10.0, 5)
    g = np.linspace(0.55, 1.0, 4)
    return Landscape(a, g, b, np.outer(g, a) + 1.0 if values is None else values)


@pytest.fixture(scope="module")
def power_analysis():
    return analyse_gain(TUNED.text)


def power_result(analysis, cert=None, land=None, eps=0.5, band=True, **kw):
    tuned = Curve(T, FALLING, 0.9 * FALLING, 1.1 * FALLING) if band else Curve(T, FALLING)
    return TuneResult(
        tuned=TUNED, baseline=BASELINE, delta=None, horizon=T_END, require="both",
        method="exact moments (RK4)", statistical=False,
        curves={"tuned": tuned, "baseline": Curve(T, HUMP)}, eps=eps,
        gain_analysis=analysis, certificate=cert, evaluations=12, seconds=0.5,
        landscape=land, **kw,
    )  # fmt: skip


@pytest.fixture(scope="module")
def schedule_result():
    sol = ScheduleSolution(
        t=SCHED.t, c=SCHED.c, value=0.2, optimality=1e-4, max_gain=50.0, binds=(),
        levels=(Level(4, 0.21, 10, 0.1, 100), Level(8, 0.2, 20, 0.2, 200)),
        peak=(4.0, 0.0), converged=True, message="ok",
    )  # fmt: skip
    return ScheduleTuneResult(
        schedule=SCHED, power=TUNED, baseline=BASELINE, delta=0.8, power_delta=None,
        horizon=T_END, require="both", method="optimal control (by hand)",
        curves={"optimal": Curve(T, FALLING), "power": Curve(T, 0.5 * HUMP),
                "baseline": Curve(T, HUMP)},
        solution=sol, max_peak=3.0, gain_analysis=analyse_schedule(SCHED), certificate=None,
        monte_carlo={}, seconds=1.0, stepping={"stepping": "intrinsic", "scheme": "implicit"},
    )  # fmt: skip


def labelled(ax):
    return {ln.get_label(): ln for ln in ax.get_lines() if not ln.get_label().startswith("_")}


# -- the gains figure -----------------------------------------------------------------------


def test_schedule_gains_figure_draws_each_gain_and_its_tail(schedule_result):
    fig = rt.schedule_gains_figure(schedule_result)
    ax = fig.axes[0]
    lines = labelled(ax)
    assert set(lines) == {"optimal schedule", "best power law: 1.5*(2 + t)^(-0.7)",
                          "baseline: 1/(1 + t)"}  # fmt: skip
    t = np.linspace(0.0, T_END, 801)
    expect = {
        "optimal schedule": np.interp(t, [0.0, 0.5, 1.0, 2.0], [3.0, 2.0, 1.0, 0.5]),
        "best power law: 1.5*(2 + t)^(-0.7)": 1.5 * (2.0 + t) ** -0.7,
        "baseline: 1/(1 + t)": 1.0 / (1.0 + t),
    }
    for name, y in expect.items():
        np.testing.assert_allclose(lines[name].get_xdata(), t)
        np.testing.assert_allclose(lines[name].get_ydata(), y, rtol=1e-12)
    # after T: the schedule's tail 1.5/(1 + t), dotted; the closed forms keep their style
    tails = [
        ln for ln in ax.get_lines() if ln.get_label().startswith("_") and len(ln.get_xdata()) == 120
    ]
    assert len(tails) == 3
    by_style = {ln.get_linestyle(): ln for ln in tails}
    tt = np.linspace(T_END, 1.3 * T_END, 120)
    np.testing.assert_allclose(by_style[":"].get_ydata(), 1.5 / (1.0 + tt), rtol=1e-12)
    np.testing.assert_allclose(by_style["--"].get_ydata(), 1.5 * (2.0 + tt) ** -0.7)
    assert ax.get_xlim() == pytest.approx((0.0, 1.3 * T_END)) and ax.get_yscale() == "log"
    assert any(list(ln.get_xdata()) == [T_END, T_END] for ln in ax.get_lines())  # T marked


# -- the curves figure ----------------------------------------------------------------------


def test_curves_figure_marks_peaks_band_and_eps(power_analysis):
    res = power_result(power_analysis)
    ax = rt.curves_figure(res).axes[0]
    lines = labelled(ax)
    np.testing.assert_allclose(lines[f"tuned: {TUNED.text}"].get_ydata(), FALLING)
    np.testing.assert_allclose(lines["baseline: 1/(1 + t)"].get_ydata(), HUMP)
    markers = {(float(ln.get_xdata()[0]), float(ln.get_ydata()[0]))
               for ln in ax.get_lines() if ln.get_marker() == "v"}  # fmt: skip
    assert markers == {(0.0, 4.0), (1.0, 2.0)}  # the hand-worked peaks
    bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
    assert len(bands) == 1  # only the tuned curve has a Monte Carlo band
    (eps,) = [ln for name, ln in lines.items() if name.startswith("ε")]
    assert eps.get_label() == "ε = 0.5000" and list(eps.get_ydata()) == [0.5, 0.5]
    assert "peak bound" not in lines  # a power result has no bound
    assert ax.get_xlim() == pytest.approx((0.0, T_END)) and ax.get_yscale() == "log"


def test_curves_figure_floors_zero_and_draws_the_peak_bound(schedule_result):
    curves = dict(schedule_result.curves, optimal=Curve(T, np.where(T > 1.5, 0.0, FALLING)))
    res = ScheduleTuneResult(**{**schedule_result.__dict__, "curves": curves})
    ax = rt.curves_figure(res).axes[0]
    lines = labelled(ax)
    y = lines["optimal schedule"].get_ydata()
    assert np.all(y[T > 1.5] == 1e-12) and np.all(y[T <= 1.5] == FALLING[T <= 1.5])
    assert list(lines["peak bound"].get_ydata()) == [3.0, 3.0]
    assert not any(name.startswith("ε") for name in lines)  # no ε asked
    assert not [c for c in ax.collections if isinstance(c, PolyCollection)]


# -- the landscape --------------------------------------------------------------------------


def test_landscape_figure_needs_a_landscape(power_analysis):
    with pytest.raises(ValueError, match=r"the result has no landscape \(PowerOptions\(landscape"):
        rt.landscape_figure(power_result(power_analysis))


def test_landscape_contours_span_the_values_on_a_log_scale(power_analysis):
    land = landscape()
    fig = rt.landscape_figure(power_result(power_analysis, land=land))
    ax, bar = fig.axes  # the map and its colour bar
    (filled,) = [c for c in ax.collections if hasattr(c, "levels")]
    lo, hi = land.values.min(), land.values.max()
    np.testing.assert_allclose(filled.levels, np.geomspace(lo, hi, 14), rtol=1e-12)
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "a  (b = 2.0000)"
    # plain tick labels on the log axis (not 2×10⁻¹)
    fmt = ax.xaxis.get_major_formatter()
    assert [fmt(v, 0) for v in (0.2, 1.0, 5.0)] == ["0.2", "1", "5"]
    assert "1/(1 + t) (b = 1) is not on it" in ax.get_title()  # b = 2: no baseline marker
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names == ["tuned"]


def test_landscape_with_too_few_finite_values_is_hatched_without_colours(power_analysis):
    vals = np.full((4, 5), np.inf)
    vals[0, :3] = [1.0, 2.0, 3.0]  # three finite values: no colour scale
    # b = 1: the baseline 1/(1 + t) is on this slice
    fig = rt.landscape_figure(power_result(power_analysis, land=landscape(b=1.0, values=vals)))
    assert len(fig.axes) == 1  # no colour bar
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names == ["+∞: too stiff or unstable", "tuned", "baseline 1/(1 + t)"]


@pytest.mark.parametrize("fixed", ["gamma", "a"])
def test_landscape_with_one_axis_fixed_is_a_curve(power_analysis, fixed):
    a, g = np.geomspace(0.1, 10.0, 6), np.linspace(0.55, 1.0, 5)
    if fixed == "gamma":
        land = Landscape(a, np.array([0.7]), 2.0, (1.0 + a)[None, :])
        x, y = a, 1.0 + a
    else:
        land = Landscape(np.array([1.5]), g, 2.0, (2.0 - g)[:, None])
        x, y = g, 2.0 - g
    fig = rt.landscape_figure(power_result(power_analysis, land=land))
    (ax,) = fig.axes
    curve, mark = ax.get_lines()
    np.testing.assert_allclose(curve.get_xdata(), x)
    np.testing.assert_allclose(curve.get_ydata(), y)
    # the tuned point: its a (or γ) and its final error FALLING[-1]
    expect_x = TUNED.a if fixed == "gamma" else TUNED.gamma
    assert list(mark.get_xdata()) == [expect_x] and mark.get_ydata()[0] == FALLING[-1]
    assert ax.get_xscale() == ("log" if fixed == "gamma" else "linear")
    assert ax.get_xlabel() == ("a" if fixed == "gamma" else r"$\gamma$")


# -- tune.html and the output folder --------------------------------------------------------


def sections(html):
    return re.findall(r'<h2 id="([^"]+)">', html)


def test_power_report_shows_every_section_it_has(power_analysis, certificate, tmp_path, saves):
    res = power_result(power_analysis, cert=certificate, land=landscape())
    path = rt.write_tune_report(res, tmp_path, "sc.yaml", ["tuned.yaml", "tune.json"])
    assert path == tmp_path / "tune.html"
    html = path.read_text(encoding="utf-8")
    assert sections(html) == ["tuned", "curves", "landscape", "theorems", "certificate"]
    assert "Gain tuned for T = 2.0000" in html and "<code>sc.yaml</code>" in html
    assert '<a href="tuned.yaml">tuned.yaml</a>' in html
    figs = sorted(p.name for p in (tmp_path / "figures").iterdir())
    assert figs == ["tune_curves.png", "tune_landscape.png"]
    # the landscape section got the landscape figure (its colour bar is its second axes)
    assert [(stem.name, len(fig.axes)) for stem, fig in saves] == [
        ("tune_curves", 1), ("tune_landscape", 2)
    ]  # fmt: skip


def test_power_report_leaves_out_what_it_lacks(power_analysis, tmp_path, saves):
    res = power_result(power_analysis)
    html = rt.write_tune_report(res, tmp_path, "sc.yaml", []).read_text(encoding="utf-8")
    assert sections(html) == ["tuned", "curves", "theorems"]
    assert [p.name for p in (tmp_path / "figures").iterdir()] == ["tune_curves.png"]


def test_schedule_report_sections(schedule_result, tmp_path, saves):
    html = rt.write_tune_report(schedule_result, tmp_path, "sc.yaml", []).read_text("utf-8")
    assert sections(html) == ["evidence", "gains", "curves", "refinement", "theorems"]
    assert "Best gain schedule for T = 2.0000" in html
    assert "continued after T by an admissible tail" in html
    figs = sorted(p.name for p in (tmp_path / "figures").iterdir())
    assert figs == ["tune_curves.png", "tune_gains.png"]


def test_outputs_of_a_power_tuning(power_analysis, certificate, scenario, tmp_path, png_only):
    res = power_result(power_analysis, cert=certificate, band=False)
    out = tmp_path / "out"
    files = rt.write_tune_outputs(res, scenario, out)
    assert files == ["tuned.yaml", "tune.json", "certificate.json", "tune.html"]
    assert sorted(p.name for p in out.iterdir()) == sorted([*files, "figures"])
    text = (out / "tuned.yaml").read_text(encoding="utf-8")
    first, _, rest = text.partition("\n")
    doc = yaml.safe_load(rest)
    assert first == f"# pair run — gain tuned by ntc tune for T = 2: E Σ‖x_i(T) − θ‖² = " \
        f"{4 * np.exp(-4):.6g} (exact moments (RK4))"  # fmt: skip
    assert doc["gain"] == "1.5*(2 + t)^(-0.7)" and doc["T"] == T_END and doc["margin"] == 0.1
    assert (out / doc["topology"]).resolve() == scenario.topology.resolve()
    js = json.loads((out / "tune.json").read_text(encoding="utf-8"))
    assert js["gain"] == TUNED.text and (js["a"], js["b"], js["gamma"]) == (1.5, 2.0, 0.7)
    assert js["ms_error_T"] == {"tuned": FALLING[-1], "baseline": 1.0}
    assert js["ms_error_peak"]["baseline"] == {"value": 2.0, "t": 1.0}
    cert = json.loads((out / "certificate.json").read_text(encoding="utf-8"))
    assert cert["digest"] == certificate.certificate["digest"]
    # the one figure drawn for real: a PNG, linked from the page
    assert (out / "figures" / "tune_curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert 'href="figures/tune_curves.png"' in (out / "tune.html").read_text(encoding="utf-8")


def test_outputs_of_a_schedule_tuning_replace_an_earlier_folder(
    power_analysis, schedule_result, scenario, tmp_path, saves
):
    out = tmp_path / "out"
    files = rt.write_tune_outputs(schedule_result, scenario, out)
    assert files == ["tuned.yaml", "schedule.csv", "tune.json", "tune.html"]
    doc = yaml.safe_load((out / "tuned.yaml").read_text(encoding="utf-8"))
    assert doc["gain"] == {"schedule": "schedule.csv", "tail": "1.5/(1 + t)",
                           "interpolation": "linear"}  # fmt: skip
    # the tuned δ replaces the margin; the result's stepping is written as it is
    assert doc["delta"] == 0.8 and "margin" not in doc
    assert (doc["stepping"], doc["scheme"]) == ("intrinsic", "implicit")
    rows = [ln for ln in (out / "schedule.csv").read_text().splitlines() if ln[0].isdigit()]
    assert [tuple(map(float, r.split(","))) for r in rows] == [
        (0.0, 3.0), (0.5, 2.0), (1.0, 1.0), (2.0, 0.5)
    ]  # fmt: skip
    js = json.loads((out / "tune.json").read_text(encoding="utf-8"))
    assert js["schedule"]["c"] == [3.0, 2.0, 1.0, 0.5] and js["max_peak"] == 3.0
    # a power tuning written over it: the schedule's files do not linger
    rt.write_tune_outputs(power_result(power_analysis), scenario, out)
    assert sorted(p.name for p in out.iterdir()) == ["figures", "tune.html", "tune.json",
                                                    "tuned.yaml"]  # fmt: skip


def test_outputs_refuse_a_folder_holding_other_files(power_analysis, scenario, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep", encoding="utf-8")
    with pytest.raises(InputError, match=r"^out: .*out' exists and holds other files \('mine"):
        rt.write_tune_outputs(power_result(power_analysis), scenario, out)
    assert [p.name for p in out.iterdir()] == ["mine.txt"]  # left as it was


# -- issue 41, item 16: the strip, the caption, the conditions table -----------------------


def _cliff(b=0.3738):
    """G1's shape: the objective finite up to a ≈ 1.3, +∞ beyond (too stiff)."""
    a, g = np.geomspace(0.15, 7.5, 13), np.linspace(0.51, 1.0, 8)
    vals = np.outer(g, a) + 1.0
    vals[:, a > 1.4] = np.inf
    return Landscape(a, g, b, vals)


def test_landscape_has_no_white_strip_between_contours_and_hatching(power_analysis):
    """Rendered: every pixel column inside the axes holds a colour or a hatch line. The
    contours stop at the last finite column and the hatching used to start half a cell
    past the first +∞ one, leaving a white unlabelled band."""
    fig = rt.landscape_figure(power_result(power_analysis, land=_cliff()))
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    ax = fig.axes[0]
    box = ax.get_window_extent()
    h = img.shape[0]
    x0, x1 = int(box.x0) + 3, int(box.x1) - 3
    y0, y1 = h - int(box.y1) + 3, h - int(box.y0) - 3  # image rows run downwards
    inside = img[y0:y1, x0:x1]
    white_columns = np.all(inside >= 250, axis=(0, 2))
    assert not white_columns.any(), np.flatnonzero(white_columns)[:10]
    # the hatching is one patch behind the contours, covering the whole axes
    (hatch,) = [p for p in ax.patches if p.get_hatch() and p.get_data_transform() == ax.transAxes]
    assert hatch.get_zorder() < 1 and hatch.get_width() == hatch.get_height() == 1.0


@pytest.mark.parametrize(
    "land, hatched, circle",
    [
        (_cliff(), True, False),
        (_cliff(b=1.0), True, True),
        (landscape(), False, False),
        (landscape(b=1.0), False, True),
    ],
)
def test_landscape_caption_says_what_the_legend_shows(power_analysis, land, hatched, circle):
    res = power_result(power_analysis, land=land)
    fig = rt.landscape_figure(res)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    caption = rt.landscape_caption(res)
    assert ("tuned" in legend) and "the cross marks the tuned gain" in caption
    assert (rt.HATCH_LABEL in legend) is hatched and ("hatched" in caption) is hatched
    assert ("baseline 1/(1 + t)" in legend) is circle and ("the circle" in caption) is circle
    assert "blank" not in caption and "optimum" not in caption  # what the old caption said
    assert fmt_b(land.b) in caption


def fmt_b(b):
    from ntc_design.present.rows import fmt

    return f"b = {fmt(b)}"


def test_power_report_shows_the_conditions_table_once(power_analysis, certificate, tmp_path, saves):
    res = power_result(power_analysis, cert=certificate, land=_cliff())
    html = rt.write_tune_report(res, tmp_path, "sc.yaml", []).read_text(encoding="utf-8")
    condition = "∫₀^∞ c² dt &lt; ∞"
    assert html.count(condition) == 1, html.count(condition)
    body = html.split('id="certificate"')[1]
    assert condition not in body and "Theorem 1" in body  # the verdicts stay there
    # the caption on the page is the figure's own
    assert rt.landscape_caption(res).split(";")[0] in html.replace("&#39;", "'")
