"""Tests of :mod:`ntc_design.reports.examples`."""

import warnings
from pathlib import Path
from types import SimpleNamespace

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_rgba
from matplotlib.patches import Circle, FancyArrowPatch

from ntc_design.errors import AssumptionWarning
from ntc_design.model import paper
from ntc_design.reports import examples, style
from ntc_design.simulate.result import MeanSquareBand
from tests.conftest import X0

matplotlib.use("Agg")  # files only, whatever the machine's display

T_SHORT = 0.1  # the paper's T = 100 shortened (the schedule's timeline stays small)
STEMS = [
    "g1_topology", "g2_topology", "g3_topology", "coupling", "switching_schedule",
    "g1_ms_error", "switching_ms_error", "g1_gain_energy_states", "gain_energy",
]  # fmt: skip
# What the stand-in simulations return: curves and paths known in closed form, so that
# each figure can be checked to draw what regenerate() handed it.
S = np.linspace(0.0, T_SHORT, 11)
MEAN = np.exp(-S)[:, None] * np.arange(1.0, 8.0)  # agent i: (i + 1)·e^(−t)
EXACT = 0.5 * MEAN
FINE_T = np.linspace(0.0, T_SHORT, 21)


def fake_result(top):
    mode = next(iter(top.modes.values())) if hasattr(top, "modes") else top
    band = MeanSquareBand(mean=MEAN, lo=0.9 * MEAN, hi=1.1 * MEAN)
    exact = SimpleNamespace(ms_error=EXACT)
    return SimpleNamespace(save_times=S, mc=band, exact=exact, labels=list(mode.labels))


def fake_paths(x0):
    """Path 0 goes linearly from x0 to θ; path 1 sits far away (it must not be drawn)."""
    goal = np.tile(paper.THETA, 7)
    first = x0 + (goal - x0) * (FINE_T / T_SHORT)[:, None]
    return np.stack([first, np.full_like(first, 100.0)])


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    """regenerate() with the simulations replaced by recorders (the paper's runs take
    minutes; :mod:`ntc_design.simulate` has its own tests), the designs without the
    critical couplings (the figure then marks δ alone) and style.save keeping the figures
    for inspection instead of drawing 27 files."""
    designs, sims, fines, figs = [], [], [], {}
    real_design = examples.design

    def design(top, theta, margin):
        designs.append((top, theta, margin))
        return real_design(top, theta, margin, thresholds=False)

    def sim(top, theta, **kw):
        sims.append((top, theta, kw))
        return fake_result(top)

    def fine(*args):
        fines.append(args)
        return {"t": FINE_T, "paths": fake_paths(args[2])}

    def save(fig, stem):
        figs[stem.name] = fig
        return style.SavedFigure(stem, {"png": stem.with_suffix(".png")}, b"")

    out = tmp_path_factory.mktemp("examples") / "new" / "figures"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(examples, "T_END", T_SHORT)
        mp.setattr(examples, "design", design)
        mp.setattr(examples, "simulate", sim)
        mp.setattr(examples, "fine_paths", fine)
        mp.setattr(style, "save", save)
        with pytest.warns(AssumptionWarning, match="Assumption 2 fails for G3"):
            written = examples.regenerate(out, paths=4)
    yield SimpleNamespace(
        out=out, written=written, designs=designs, sims=sims, fines=fines, figs=figs
    )
    plt.close("all")


def informed(top):
    """Agents with an antagonistic (negative semidefinite, non-zero) in-weight."""
    return {i for (i, _), w in top.weights.items() if np.linalg.eigvalsh(w).min() < -1e-12}


def test_regenerate_writes_every_readme_figure_in_order(regenerated):
    r = regenerated
    assert r.out.is_dir()  # made with its parents
    assert r.written == [r.out / f"{s}.png" for s in STEMS]
    assert list(r.figs) == STEMS


def test_regenerate_designs_and_simulates_with_the_papers_settings(regenerated):
    r = regenerated
    ((sw_design, theta, margin),) = r.designs
    assert set(sw_design.modes) == {"G1", "G2", "G3"} and list(theta) == [1.0, 2.0, -1.0]
    assert margin == 0.1
    (g1, th1, kw1), (sw, th2, kw2) = r.sims
    assert g1.name == "G1" and set(sw.modes) == {"G1", "G2", "G3"}
    for th, kw in ((th1, kw1), (th2, kw2)):
        assert list(th) == [1.0, 2.0, -1.0]
        assert (kw["noise"].sigma, kw["noise"].f) == (0.4, 0.3)
        np.testing.assert_array_equal(kw["initial"], X0)  # uniform on [-3, 3], seed 1
        assert (kw["T"], kw["dt"], kw["ds"], kw["stepping"]) == (T_SHORT, 1e-3, 1e-3, "intrinsic")
        assert (kw["paths"], kw["seed"], kw["gain"], kw["workers"]) == (4, 0, "1/(1+t)", 2)
        assert kw["save_every"] == pytest.approx(T_SHORT / 1000)
    ((top, gain, x0, t_end, dt, stepping, seed),) = r.fines
    assert top.name == "G1" and gain == "(1+t)^(-1/3)"
    np.testing.assert_array_equal(x0, X0)
    assert (t_end, dt, stepping, seed) == (T_SHORT, 1e-3, "intrinsic", 0)


def test_topology_figures_draw_each_mode_with_its_informed_agents(regenerated):
    green = to_rgba(style.GREEN)
    for name, top in (("g1", paper.g1()), ("g2", paper.g2()), ("g3", paper.g3())):
        ax = regenerated.figs[f"{name}_topology"].axes[0]
        assert sum(isinstance(p, Circle) for p in ax.patches) == top.n + 1  # + x0
        arrows = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
        signal = [a for a in arrows if a.get_edgecolor() == green]
        assert len(signal) == len(informed(top)) > 0
        assert len(arrows) - len(signal) == len(top.edges)
    assert informed(paper.g1()) == {1, 2}  # agents 2 and 3 (the paper's G1)


def test_coupling_and_schedule_figures(regenerated):
    legend = " ".join(t.get_text() for t in regenerated.figs["coupling"].legends[0].get_texts())
    assert all(f"G{k}:" in legend for k in (1, 2, 3))
    ax = regenerated.figs["switching_schedule"].axes[0]
    # one period of the paper's schedule: G2 G2 G1 G3 G3, 0.02 each
    assert [t.get_text() for t in ax.texts] == ["G2", "G2", "G1", "G3", "G3"]
    assert ax.get_xlim() == pytest.approx((0.0, 0.1))


def test_ms_error_figures_draw_the_simulated_curves(regenerated):
    for stem, panels in (("g1_ms_error", 1), ("switching_ms_error", 2)):
        fig = regenerated.figs[stem]
        assert len(fig.axes) == panels  # the switching run adds its mode timeline
        drawn = [np.asarray(ln.get_ydata()) for ln in fig.axes[0].get_lines()]
        for i in range(7):
            assert any(np.array_equal(y, MEAN[:, i]) for y in drawn)
            assert any(np.array_equal(y, EXACT[:, i]) for y in drawn)


def test_states_figure_draws_the_first_fine_path(regenerated):
    axes = regenerated.figs["g1_gain_energy_states"].axes
    assert len(axes) == 3  # one panel per component of θ
    x0 = X0.reshape(7, 3)
    for k, ax in enumerate(axes):
        paths = [np.asarray(ln.get_ydata()) for ln in ax.get_lines() if len(ln.get_ydata()) > 2]
        assert len(paths) == 7
        assert sorted(p[0] for p in paths) == pytest.approx(sorted(x0[:, k]))
        assert all(p[-1] == pytest.approx(paper.THETA[k]) for p in paths)  # not path 1


def test_gain_figure_is_the_energy_gain(regenerated):
    ax = regenerated.figs["gain_energy"].axes[0]
    (ln,) = ax.get_lines()
    t = np.asarray(ln.get_xdata())
    assert t[0] == 0.0 and t[-1] == pytest.approx(T_SHORT)
    np.testing.assert_allclose(ln.get_ydata(), (1 + t) ** (-1 / 3), rtol=1e-12)


# -- main -----------------------------------------------------------------------------------


@pytest.fixture
def stub(monkeypatch):
    calls = []

    def regenerate(out, paths):
        calls.append((out, paths))
        for text in ("beta", "alpha", "beta"):  # one note per distinct message
            warnings.warn(text, AssumptionWarning, stacklevel=2)
        return [out / "a.png", out / "b.png"]

    monkeypatch.setattr(examples, "regenerate", regenerate)
    return calls


def test_main_reports_the_files_and_each_warning_once(stub, tmp_path, capsys):
    plt.switch_backend("svg")  # main must put it back to files-only Agg
    examples.main(["--out", str(tmp_path), "--paths", "7"])
    assert stub == [(tmp_path, 7)]
    assert capsys.readouterr().out.splitlines() == [
        f"wrote {tmp_path / 'a.png'} (+ .svg, .pdf)",
        f"wrote {tmp_path / 'b.png'} (+ .svg, .pdf)",
        "note: alpha",
        "note: beta",
    ]
    assert matplotlib.get_backend().lower() == "agg"


def test_main_defaults_to_the_readme_folder_and_the_papers_paths(stub, capsys):
    examples.main([])
    assert stub == [(Path("examples/figures"), paper.PATHS)]
    assert paper.PATHS == 1000


def test_main_refuses_a_bad_path_count(stub, capsys):
    with pytest.raises(SystemExit) as exc:
        examples.main(["--paths", "many"])
    assert exc.value.code == 2 and stub == []
    err = capsys.readouterr().err
    assert "python -m ntc_design.reports.examples" in err and "--paths: invalid int value" in err
