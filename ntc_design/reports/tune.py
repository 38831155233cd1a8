"""The report of a tuning run (:func:`ntc_design.tune.tune`): E Σ‖x_i − θ‖² over time for
the tuned and the baseline gain, the objective over (a, γ) as a contour map with the
optimum marked, and the tables every face shows (the tuned gain, its theorem conditions,
the certificate), written as ``tune.html`` with the figures in the one style."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import yaml
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ..certify import write_certificate
from ..gain.schedule import ScheduleGain
from ..io.files import ScenarioData, jsonable
from ..io.outputs import output_folder
from ..present.rows import Table, fmt
from ..tune import ScheduleTuneResult, TuneResult, tuned_scenario
from ..tune.family import BASELINE
from . import style
from .html import figure_block, html_table, render, write_html

CURVE_CAPTION = (
    "E Σ_i ‖x_i − θ‖² over time under the tuned gain (solid) and the baseline 1/(1 + t) "
    "(dash-dot), a marker at each curve's peak; the dotted line is ε, the deadline T is the "
    "right edge."
)
#: The legend of the hatching: where no finite objective is drawn.
HATCH_LABEL = "+∞: too stiff or unstable"


SCHEDULE_GAINS_CAPTION = (
    "The gains: the optimal schedule on [0, T] (solid; its tail after T dotted), the best "
    "power law a·(b + t)^(−γ) (dashed) and 1/(1 + t) (dash-dot)."
)
SCHEDULE_CURVES_CAPTION = (
    "E Σ_i ‖x_i − θ‖² over [0, T] under the three gains (exact moments, computed "
    "independently of the optimiser); a marker at each curve's peak, the dotted line the "
    "peak bound when one was asked."
)
#: Palette index, line style and name of each gain a result holds.
_STYLES = {
    "tuned": (0, "-", "tuned"),
    "optimal": (0, "-", "optimal schedule"),
    "power": (1, "--", "best power law"),
    "baseline": (2, "-.", "baseline"),
}


def _label(key: str, result: TuneResult | ScheduleTuneResult) -> str:
    """The legend of a gain: its name, and its expression unless a table."""
    gain = result.gains[key]
    name = _STYLES[key][2]
    return name if isinstance(gain, ScheduleGain) else f"{name}: {gain.text}"


def schedule_gains_figure(result: ScheduleTuneResult):
    """c(t) of the three gains on [0, 1.3 T] (the schedule's tail shown after T).

    Parameters
    ----------
    result : ScheduleTuneResult
        The tuning.

    Returns
    -------
    matplotlib.figure.Figure
    """
    t_end = result.horizon
    t = np.linspace(0.0, t_end, 801)
    tail = np.linspace(t_end, 1.3 * t_end, 120)
    with style.paper_style():
        fig, ax = plt.subplots(figsize=(style.ONE_COLUMN, 2.4), layout="constrained")
        for key, g in result.gains.items():
            i, ls, _ = _STYLES[key]
            colour = style.PALETTE[i]
            ax.plot(t, g(t), color=colour, ls=ls, label=_label(key, result))
            ax.plot(tail, g(tail), color=colour, ls=":" if key == "optimal" else ls, lw=0.9)
        ax.axvline(t_end, color=style.GREY, lw=0.6)
        ax.set_yscale("log")
        ax.set_xlabel("t")
        ax.set_ylabel("c(t)")
        ax.set_xlim(0, 1.3 * t_end)
        fig.legend(loc="outside upper center", ncols=1, frameon=False)
    return fig


def curves_figure(result: TuneResult | ScheduleTuneResult):
    """E Σ‖x_i − θ‖² of every gain of the result over [0, T] (log scale), with the Monte
    Carlo bands where there are some, a marker at each peak, ε and the peak bound when
    asked.

    Parameters
    ----------
    result : TuneResult or ScheduleTuneResult
        The tuning.

    Returns
    -------
    matplotlib.figure.Figure
    """
    floor = 1e-12
    with style.paper_style():
        fig, ax = plt.subplots(figsize=(style.ONE_COLUMN, 2.4), layout="constrained")
        for key, c in result.curves.items():
            i, ls, _ = _STYLES[key]
            colour = style.PALETTE[i]
            ax.plot(c.t, np.maximum(c.total, floor), color=colour, ls=ls, label=_label(key, result))
            pk = c.peak
            ax.plot([pk["t"]], [pk["value"]], marker="v", color=colour, ls="none", ms=5)
            if c.lo is not None and c.hi is not None:
                lo, hi = np.maximum(c.lo, floor), np.maximum(c.hi, floor)
                ax.fill_between(c.t, lo, hi, color=colour, alpha=0.2, lw=0)
        if result.eps is not None:
            ax.axhline(result.eps, color=style.GREY, ls=":", lw=0.8, label=f"ε = {fmt(result.eps)}")
        bound = getattr(result, "max_peak", None)
        if bound is not None:
            ax.axhline(bound, color=style.GREY, ls=":", lw=0.8, label="peak bound")
        ax.set_yscale("log")
        ax.set_xlabel("t")
        ax.set_ylabel(r"$E\,\sum_i \|x_i - \theta\|^2$")
        ax.set_xlim(0, result.horizon)
        fig.legend(loc="outside upper center", ncols=1, frameon=False)
    return fig


@dataclass(frozen=True)
class LandscapeMarks:
    """What the landscape figure draws, which its caption says (one source for both)."""

    curve: bool  # one of a, γ fixed: the objective as a curve, not a map
    baseline: bool  # 1/(1 + t) (b = 1) lies on the slice: its circle is drawn
    hatched: bool  # some candidate scored +∞: the area without a finite value is hatched
    b: float


def landscape_marks(result: TuneResult) -> LandscapeMarks:
    """What :func:`landscape_figure` draws for ``result``.

    Parameters
    ----------
    result : TuneResult
        A tuning with a landscape.

    Returns
    -------
    LandscapeMarks

    Raises
    ------
    ValueError
        The result has no landscape.
    """
    land = result.landscape
    if land is None:
        raise ValueError("the result has no landscape (PowerOptions(landscape=True))")
    z = np.asarray(land.values, dtype=float)
    curve = z.shape[0] == 1 or z.shape[1] == 1
    return LandscapeMarks(
        curve=curve,
        baseline=not curve and math.isclose(land.b, BASELINE.b, rel_tol=1e-9),
        hatched=not curve and bool((~np.isfinite(z)).any()),
        b=float(land.b),
    )


def landscape_caption(result: TuneResult) -> str:
    """The landscape figure's caption, from what it draws (:func:`landscape_marks`): the
    cross is the tuned gain as the legend says, the circle is named only when drawn, the
    hatching only when there is some.

    Parameters
    ----------
    result : TuneResult
        A tuning with a landscape.

    Returns
    -------
    str
    """
    m = landscape_marks(result)
    if m.curve:
        return (
            "E Σ_i ‖x_i(T) − θ‖² against the one parameter searched (the others fixed); "
            "the cross marks the tuned gain."
        )
    text = (
        "E Σ_i ‖x_i(T) − θ‖² over the scale a (log) and the exponent γ at the tuned offset "
        f"b = {fmt(m.b)}; the cross marks the tuned gain"
    )
    text += (
        ", the circle the baseline 1/(1 + t), (a, γ) = (1, 1)"
        if m.baseline
        else "; 1/(1 + t) has b = 1 and is not on this slice"
    )
    if m.hatched:
        text += (
            "; hatched where no finite value is drawn: a candidate there is too stiff to "
            "integrate or its moments grow without bound (+∞)"
        )
    return text + "."


def landscape_figure(result: TuneResult):
    """The objective over (a, γ) at the tuned b as filled log-spaced contours; where no
    finite value is drawn (a candidate scored +∞), hatched to the contours' edge.

    Parameters
    ----------
    result : TuneResult
        A tuning with a landscape.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        The result has no landscape.
    """
    marks = landscape_marks(result)
    land = result.landscape
    assert land is not None  # landscape_marks refuses a result without one
    z = np.where(np.isfinite(land.values), land.values, np.nan)
    with style.paper_style():
        fig, ax = plt.subplots(figsize=(style.ONE_COLUMN, 2.8), layout="constrained")
        ok = z[np.isfinite(z)]
        if marks.curve:  # one of a, γ fixed: the objective as a curve
            fig.clear()
            ax = fig.subplots()
            x, xl = (land.a, "a") if z.shape[1] > 1 else (land.gamma, r"$\gamma$")
            ax.plot(x, z.ravel(), color=style.PALETTE[0])
            ax.plot(
                [result.tuned.a if xl == "a" else result.tuned.gamma],
                [result.ms_error_T["tuned"]],
                marker="X",
                color=style.PALETTE[1],
                ls="none",
                label="tuned",
            )
            ax.set_yscale("log")
            if xl == "a":
                ax.set_xscale("log")
                _plain_log_ticks(ax)
            ax.set_xlabel(xl)
            ax.set_ylabel(r"$E\,\sum_i \|x_i(T) - \theta\|^2$")
            fig.legend(loc="outside lower center", frameon=False)
            return fig
        if marks.hatched:
            # the contours fill only the cells whose four corners are finite; everything
            # else, up to their edge, is hatched (no white strip between the two: the
            # objective is not finite at a corner of those cells)
            ax.add_patch(
                Rectangle(
                    (0.0, 0.0), 1.0, 1.0, transform=ax.transAxes, fill=False, hatch="////",
                    ec="0.2", lw=0.0, zorder=0,
                )
            )  # fmt: skip
            ax.fill([], [], fc="none", hatch="////", ec="0.2", label=HATCH_LABEL)
        if ok.size >= 4 and ok.min() > 0 and ok.max() > ok.min():
            levels = np.geomspace(ok.min(), ok.max(), 14)
            cs = ax.contourf(land.a, land.gamma, z, levels=levels, norm=LogNorm(), cmap="viridis")
            fig.colorbar(cs, ax=ax, label=r"$E\,\sum_i \|x_i(T) - \theta\|^2$", format="%.3g")
        ax.set_xlim(float(np.min(land.a)), float(np.max(land.a)))
        ax.set_ylim(float(np.min(land.gamma)), float(np.max(land.gamma)))
        # markers on the γ = 1 edge are drawn whole (not clipped by the axes)
        ax.plot(
            [result.tuned.a],
            [result.tuned.gamma],
            marker="X",
            color="white",
            mec="black",
            ms=8,
            ls="none",
            label="tuned",
            clip_on=False,
            zorder=5,
        )
        if marks.baseline:
            ax.plot(
                [BASELINE.a],
                [BASELINE.gamma],
                marker="o",
                color="none",
                mec="red",
                ms=7,
                ls="none",
                label="baseline 1/(1 + t)",
                clip_on=False,
                zorder=5,
            )
        else:  # 1/(1 + t) has b = 1: it is not on this slice
            ax.set_title(
                f"slice at the tuned b = {fmt(land.b)}; 1/(1 + t) (b = 1) is not on it",
                fontsize=7,
            )
        ax.set_xscale("log")
        _plain_log_ticks(ax)
        ax.set_xlabel(f"a  (b = {fmt(land.b)})")
        ax.set_ylabel(r"$\gamma$")
        fig.legend(loc="outside lower center", ncols=2, frameon=False)
    return fig


def _plain_log_ticks(ax) -> None:
    """Ticks at 1, 2, 5 per decade written as plain numbers (a span under two decades
    would otherwise get crowded minor labels such as 2×10⁻¹)."""
    ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


#: What ``ntc tune`` writes to its output folder (an earlier tuning's folder may be replaced).
TUNE_FILES = (
    "tuned.yaml",
    "schedule.csv",
    "tune.json",
    "certificate.json",
    "tune.html",
    "figures",
)


def write_tune_outputs(
    result: TuneResult | ScheduleTuneResult, scenario: ScenarioData, out_dir: str | Path
) -> list[str]:
    """Write a tuning's folder, all or nothing (:func:`ntc_design.io.outputs.output_folder`):
    ``tuned.yaml`` (the scenario with the tuned gain, T and any stepping it needs, its
    topology path relative to the folder), ``tune.json``, ``certificate.json`` and
    ``tune.html`` with its figures.

    Parameters
    ----------
    result : TuneResult or ScheduleTuneResult
        The tuning (a schedule adds ``schedule.csv``, which ``tuned.yaml`` names).
    scenario : ScenarioData
        The scenario as read (its document and source).
    out_dir : str or Path
        The folder.

    Returns
    -------
    list of str
        The files written, in the order the command names them.

    Raises
    ------
    InputError
        The folder cannot receive the files (see :func:`ntc_design.io.outputs.output_folder`).
    """
    sched = isinstance(result, ScheduleTuneResult)
    files = (
        ["tuned.yaml"]
        + ([ScheduleTuneResult.SCHEDULE_FILE] if sched else [])
        + ["tune.json"]
        + (["certificate.json"] if result.certificate else [])
    )
    with output_folder(out_dir, TUNE_FILES) as tmp:
        if isinstance(result, ScheduleTuneResult):
            (tmp / result.SCHEDULE_FILE).write_text(result.schedule.csv_text(), encoding="utf-8")
        new = tuned_scenario(scenario.document, scenario.source, out_dir, result)
        header = f"# {new.pop('description')}\n"
        (tmp / "tuned.yaml").write_text(
            header + yaml.safe_dump(new, sort_keys=False, allow_unicode=True), encoding="utf-8"
        )
        text = json.dumps(jsonable(result.to_dict()), indent=2, ensure_ascii=False)
        (tmp / "tune.json").write_text(text + "\n", encoding="utf-8")
        if result.certificate is not None:
            write_certificate(result.certificate.certificate, tmp / "certificate.json")
        write_tune_report(result, tmp, scenario.source, files)
    return [*files, "tune.html"]


@dataclass(frozen=True)
class Section:
    """One heading of ``tune.html``: a figure (made by ``figure`` from the result, with its
    caption) or tables."""

    id: str
    title: str
    figure: Callable | None = None
    caption: str | Callable[[Any], str] = ""  # a function of the result: what it drew
    tables: Callable[[Any], list[Table]] | None = None


#: The page of each result, in order: adding a figure is one entry here.
POWER_SECTIONS = (
    Section("tuned", "Tuned gain", tables=lambda r: [r.table()]),
    Section("curves", "Mean-square error over time", curves_figure, CURVE_CAPTION),
    Section("landscape", "Objective over (a, γ)", landscape_figure, landscape_caption),
    Section(
        "theorems",
        "Theorem conditions of the tuned gain",
        tables=lambda r: [r.gain_analysis.table()],
    ),
    Section(  # the gain's conditions have their own section above
        "certificate",
        "Certificate of the tuned design",
        tables=lambda r: r.certificate.tables(gain=False),
    ),
)
SCHEDULE_SECTIONS = (
    Section("evidence", "Three gains at the deadline", tables=lambda r: [r.table()]),
    Section("gains", "The gains c(t)", schedule_gains_figure, SCHEDULE_GAINS_CAPTION),
    Section("curves", "Mean-square error over time", curves_figure, SCHEDULE_CURVES_CAPTION),
    Section("refinement", "Refinement of the schedule", tables=lambda r: [r.refinement_table()]),
    Section(
        "theorems", "Theorem conditions of the schedule", tables=lambda r: [r.gain_analysis.table()]
    ),
    Section(
        "certificate",
        "Certificate of the design with the schedule",
        tables=lambda r: r.certificate.tables(gain=False),
    ),
)


def write_tune_report(
    result: TuneResult | ScheduleTuneResult, out_dir: str | Path, scenario: str, files: list[str]
) -> Path:
    """Write ``tune.html`` and its figures (``figures/tune_*.png|svg|pdf``) into ``out_dir``:
    the result's sections (:data:`POWER_SECTIONS` or :data:`SCHEDULE_SECTIONS`), those
    with nothing to show left out (no contour map, no certificate).

    Parameters
    ----------
    result : TuneResult or ScheduleTuneResult
        The tuning.
    out_dir : str or Path
        The folder (it exists).
    scenario : str
        The scenario's name, shown in the page.
    files : list of str
        The other files written there, linked from the page.

    Returns
    -------
    Path
        The HTML page.
    """
    base = Path(out_dir)
    optimal = isinstance(result, ScheduleTuneResult)
    shown = []
    for sec in SCHEDULE_SECTIONS if optimal else POWER_SECTIONS:
        if sec.id == "certificate" and result.certificate is None:
            continue
        if sec.id == "landscape" and getattr(result, "landscape", None) is None:
            continue
        block = None
        if sec.figure is not None:
            saved = style.save(sec.figure(result), base / "figures" / f"tune_{sec.id}")
            caption = sec.caption(result) if callable(sec.caption) else sec.caption
            block = figure_block(saved, f"fig-{sec.id}", caption, base, style.ONE_COLUMN)
        tables = [html_table(t) for t in sec.tables(result)] if sec.tables else []
        shown.append({"id": sec.id, "title": sec.title, "figure": block, "tables": tables})
    intro = (
        "the gain schedule c(t) on [0, T] that minimises E Σ_i ‖x_i(T) − θ‖² at T = "
        f"{fmt(result.horizon)} ({result.method}), continued after T by an admissible tail, "
        "beside the best power law a·(b + t)^(−γ) and 1/(1 + t)."
        if optimal
        else "the gain family a·(b + t)^(−γ), tuned to minimise E Σ_i ‖x_i(T) − θ‖² at T = "
        f"{fmt(result.horizon)} ({result.method})."
    )
    page = render(
        "tune.html",
        title=(
            f"Best gain schedule for T = {fmt(result.horizon)}"
            if optimal
            else f"Gain tuned for T = {fmt(result.horizon)}"
        ),
        scenario=scenario,
        intro=intro,
        files=files,
        sections=shown,
        toc=[{"id": s["id"], "title": s["title"]} for s in shown],
        interactive=False,
    )
    path = base / "tune.html"
    write_html(path, page)
    return path
