"""Figures in the paper's conventions (matplotlib, Agg backend).

Every figure is sized for a journal column (``ONE_COLUMN`` 3.5 in, ``TWO_COLUMN`` 7.16 in),
has no title (the caption says what it shows), fonts of 8-9 pt (legends >= 8 pt), and is
written as vector PDF and SVG beside a 300-dpi PNG by :func:`save`.

* Topology Ĝ: agents on a circle, the external signal x0 (vertex 0) outside the circle next
  to the informed agents, its edges curved around the agents and in the legend; positive
  edges blue, negative red; definite solid, semidefinite dashed; arrows j -> i (i listens
  to j); optional weight labels.
* Agents differ by colour, line style and marker (:func:`agent_style`).
* States of all agents over time, one panel per dimension, θ dashed.
* E‖x_i − θ‖² per agent on a log scale: the legend says which lines are Monte Carlo (solid,
  95% band shaded) and which exact (dashed).
* A switching schedule is a thin timeline under the time axis; when its segments are too
  short to draw they are aggregated (share of each mode per bin), and
  :func:`schedule_figure` shows one period.
* The decay rate and λ_min(L_B + L_Bᵀ) against δ with Lemma 1's δ, δ_H, δ_S and the best δ.
* The gain: c(t), ∫c and ∫c², labelled in mathtext from the parsed expression.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

# no matplotlib.use() here: a notebook keeps its inline backend (the CLI sets MPLBACKEND)
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.artist import Artist
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..gain.conditions import parse_gain
from ..present.rows import counted
from ..simulate import make_gain
from ..simulate.result import MeanSquareBand
from ..sweep.robust import study_radius_text
from .style import (
    BLUE,
    LINESTYLES,
    MODE_COLOURS,
    ONE_COLUMN,
    TWO_COLUMN,
    SavedFigure,
    agent_style,
    markevery,
    paper_style,
    save,
)

# ---------------------------------------------------------------------- mode timelines


def _mode_colours(segments) -> dict[str, str]:
    names = list(dict.fromkeys(m for _, _, m in segments))
    return {m: MODE_COLOURS[k % len(MODE_COLOURS)] for k, m in enumerate(sorted(names))}


def mode_timeline(ax, segments: Sequence[tuple[float, float, str]], bins: int = 200) -> list:
    """Draw the active mode on a thin axis ``ax`` (x shared with the plot above); segments
    shorter than 1/``bins`` of the axis are aggregated into the share of each mode per bin.
    Returns legend handles."""
    col = _mode_colours(segments)
    t0, t1 = segments[0][0], segments[-1][1]
    span = t1 - t0
    short = min(b - a for a, b, _ in segments) < span / bins
    ax.set_yticks([])
    for s in ("left", "right", "top"):
        ax.spines[s].set_visible(False)
    if not short:
        for a, b, m in segments:
            ax.axvspan(a, b, color=col[m], linewidth=0)
        label = "active mode"
    else:
        starts = np.array([a for a, _, _ in segments])
        stops = np.array([b for _, b, _ in segments])
        modes = np.array([m for _, _, m in segments])
        edges = np.linspace(t0, t1, bins + 1)
        share = {}
        for m in col:
            sel = modes == m
            # time of mode m in each bin: overlap of its segments with the bin, summed
            cum = np.concatenate([[0.0], np.cumsum(stops[sel] - starts[sel])])

            def upto(x, a=starts[sel], b=stops[sel], cum=cum):
                k = np.searchsorted(a, x, side="right")
                inside = np.clip(x - a[np.maximum(k - 1, 0)], 0, (b - a)[np.maximum(k - 1, 0)])
                return cum[np.maximum(k - 1, 0)] + np.where(k > 0, inside, 0.0)

            share[m] = np.diff(upto(edges)) / np.diff(edges)
        bottom = np.zeros(bins)
        for m in col:
            ax.bar(
                edges[:-1],
                share[m],
                width=np.diff(edges),
                bottom=bottom,
                align="edge",
                color=col[m],
                linewidth=0,
            )
            bottom += share[m]
        ax.set_ylim(0, 1)
        label = "share of time"
    ax.set_ylabel(label, rotation=0, ha="right", va="center", fontsize=7)
    return [Patch(color=col[m], label=f"mode {m}") for m in col]


def schedule_figure(schedule: Sequence[tuple[str, float]], width: float = ONE_COLUMN):
    """One period of a switching schedule as a bar of modes with their durations.

    Parameters
    ----------
    schedule : sequence of (str, float)
        (mode, duration) pairs.
    width : float, optional
        Figure width in inches.

    Returns
    -------
    matplotlib.figure.Figure
    """
    segs, t = [], 0.0
    for m, dur in schedule:
        segs.append((t, t + dur, m))
        t += dur
    col = _mode_colours(segs)
    with paper_style():
        fig, ax = plt.subplots(figsize=(width, 0.95), layout="constrained")
        for a, b, m in segs:
            ax.axvspan(a, b, color=col[m], linewidth=0.5, ec="white")
            ax.text(0.5 * (a + b), 0.5, m, ha="center", va="center", fontsize=8)
        ax.set_xlim(0, t)
        ax.set_yticks([])
        ax.set_xticks([a for a, _, _ in segs] + [t])
        ax.tick_params(axis="x", labelsize=7)
        for s in ("left", "right", "top"):
            ax.spines[s].set_visible(False)
        ax.set_xlabel(f"t within one period ({t:g}); the schedule repeats")
    return fig


def _time_axes(d_panels: int, segments, width: float, height: float):
    """Panels sharing t, plus a thin timeline under them when segments are given."""
    ratios = [1.0] * d_panels + ([0.12] if segments else [])
    fig, axes = plt.subplots(
        len(ratios),
        1,
        figsize=(width, height),
        sharex=True,
        gridspec_kw={"height_ratios": ratios},
        layout="constrained",
    )
    axes = list(np.atleast_1d(axes))
    tl = axes.pop() if segments else None
    return fig, axes, tl


# ------------------------------------------------------------------------ time series

HIGHLIGHTED = 3  # agents drawn in colour in a sample path; the others in grey


def states_figure(
    t,
    path: np.ndarray,
    theta: np.ndarray,
    labels,
    title: str | None = None,
    segments=None,
    width: float = TWO_COLUMN,
    gid: str | None = None,
):
    """One sample path: x_i^(k)(t) for every agent i, one panel per dimension k, θ dashed.

    Parameters
    ----------
    t
        Times (S,).
    path
        States (S, N·d).
    theta
        θ (d,).
    labels
        Agent labels (N).
    title
        Optional short title.
    segments
        Switching segments ``(start, stop, mode)`` for the timeline, or None.
    width
        Figure width in inches.
    gid
        When given, agent i's artists get SVG ids ``{gid}-ag{i}-…`` (for toggling).

    Returns
    -------
    matplotlib.figure.Figure
    """
    d = theta.size
    n = len(labels)
    x = path.reshape(t.size, n, d)
    # a few agents in colour (the farthest from θ at the end), the others in grey behind
    far = np.linalg.norm(x[-1] - theta, axis=1)
    shown = set(np.argsort(far)[::-1][:HIGHLIGHTED].tolist()) if n > HIGHLIGHTED else set(range(n))
    coarse = t.size <= 300  # few stored states: mark each, the lines only join them
    with paper_style():
        fig, axes, tl = _time_axes(d, segments, width, 1.45 * d + 1.0)
        for k, ax in enumerate(axes):
            for i in range(n):
                s = agent_style(i)
                hi = i in shown
                ax.plot(
                    t,
                    x[:, i, k],
                    gid=f"{gid}-ag{i}-{k}" if gid else None,
                    lw=0.9 if hi else 0.5,
                    color=s.colour if hi else "0.75",
                    ls=s.linestyle if hi else "-",
                    marker=(s.marker if hi else ".") if coarse else (s.marker if hi else None),
                    markersize=2.5 if coarse else 3,
                    markevery=None if coarse else markevery(i, t.size),
                    zorder=3 if hi else 2,
                )
            ax.axhline(theta[k], color="black", ls=(0, (5, 2)), lw=1.0)
            ax.set_ylabel(f"$x_i^{{({k + 1})}}$")
        last = tl if tl is not None else axes[-1]
        last.set_xlabel("$t$")
        handles = [
            Line2D(
                [],
                [],
                color=agent_style(i).colour,
                ls=agent_style(i).linestyle,
                marker=agent_style(i).marker,
                markersize=3,
                label=f"agent {labels[i]}",
            )
            for i in sorted(shown)
        ]
        if len(shown) < n:
            handles.append(
                Line2D(
                    [],
                    [],
                    color="0.75",
                    lw=0.5,
                    label=f"the other {counted(n - len(shown), 'agent')}",
                )
            )
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                ls=(0, (5, 2)),
                label=r"$\theta = (" + ", ".join(f"{v:g}" for v in theta) + ")$",
            )
        )
        if tl is not None:
            handles += mode_timeline(tl, segments)
        if title:
            fig.suptitle(title)
        fig.legend(
            handles=handles, loc="outside lower center", ncol=min(len(handles), 5), frameon=False
        )
    return fig


def ms_error_figure(
    t,
    mc: MeanSquareBand | None,
    exact: np.ndarray | None,
    labels,
    title: str | None = None,
    segments=None,
    width: float = TWO_COLUMN,
    gid: str | None = None,
):
    """E‖x_i − θ‖² per agent on a log scale: Monte Carlo mean (solid) with its 95% band,
    exact moments (dashed); agents differ by colour and marker.

    Parameters
    ----------
    t
        Save times (S,).
    mc
        The Monte Carlo mean and band, arrays (S, N) (a
        :class:`~ntc_design.simulate.result.MonteCarloCurves` will do), or None.
    exact
        Exact E‖x_i − θ‖² (S, N), or None.
    labels
        Agent labels.
    title
        Optional short title.
    segments
        Switching segments for the timeline, or None.
    width
        Figure width in inches.
    gid
        When given, agent i's artists get SVG ids ``{gid}-ag{i}-…`` (for toggling).

    Returns
    -------
    matplotlib.figure.Figure
    """
    floor = 1e-12
    with paper_style():
        fig, (ax,), tl = _time_axes(1, segments, width, 3.0)
        for i in range(len(labels)):
            s = agent_style(i)
            tag = f"{gid}-ag{i}-" if gid else None
            if mc is not None:
                ax.plot(
                    t,
                    np.maximum(mc.mean[:, i], floor),
                    gid=tag and tag + "mc",
                    color=s.colour,
                    lw=1.0,
                    marker=s.marker,
                    markersize=3,
                    markevery=markevery(i, t.size),
                )
                ax.fill_between(
                    t,
                    np.maximum(mc.lo[:, i], floor),
                    np.maximum(mc.hi[:, i], floor),
                    color=s.colour,
                    alpha=0.18,
                    lw=0,
                    gid=tag and tag + "band",
                )
            if exact is not None:
                ax.plot(
                    t,
                    np.maximum(exact[:, i], floor),
                    gid=tag and tag + "exact",
                    color=s.colour,
                    lw=1.1,
                    ls=(0, (4, 2)),
                    marker=None if mc is not None else s.marker,
                    markersize=3,
                    markevery=markevery(i, t.size),
                )
        ax.set_yscale("log")
        ax.set_ylabel(r"$E\,\|x_i - \theta\|^2$")
        (tl if tl is not None else ax).set_xlabel("$t$")
        handles = _ms_legend(labels, mc is not None, exact is not None)
        if tl is not None:
            handles += mode_timeline(tl, segments)
        if title:
            ax.set_title(title)
        fig.legend(handles=handles, loc="outside right center", ncol=1, frameon=False, fontsize=8)
    return fig


def _ms_legend(labels, with_mc: bool, with_exact: bool) -> list[Artist]:
    """One entry per agent (colour and marker), then what solid, band and dashed mean."""
    handles: list[Artist] = [
        Line2D(
            [],
            [],
            color=agent_style(i).colour,
            marker=agent_style(i).marker,
            markersize=3,
            label=f"agent {a}",
        )
        for i, a in enumerate(labels)
    ]
    if with_mc:
        handles.append(Line2D([], [], color="0.3", lw=1.0, label="Monte Carlo mean (solid)"))
        handles.append(Patch(color="0.3", alpha=0.25, label="Monte Carlo 95% band"))
    if with_exact:
        handles.append(
            Line2D([], [], color="0.3", lw=1.1, ls=(0, (4, 2)), label="exact moments (dashed)")
        )
    return handles


# ------------------------------------------------------------------ coupling and gain


@dataclass(frozen=True)
class CouplingCurve:
    """Decay rate and λ_min(L_B + L_Bᵀ) of one mode against δ, with its marks."""

    name: str
    delta: np.ndarray
    rate: np.ndarray  # −max Re λ(−L_B(δ))
    sym_min: np.ndarray  # λ_min(L_B(δ) + L_B(δ)ᵀ)
    lemma_delta: float
    delta_h: float | None
    delta_s: float | None
    best_delta: float | None
    best_rate: float


def coupling_curve(des, points: int = 240) -> CouplingCurve:
    """Sample the decay rate ``−max Re λ(−L_B(δ))`` and ``λ_min(L_B + L_Bᵀ)`` over a
    logarithmic δ range around Lemma 1's δ and the critical couplings of ``des``
    (a :class:`~ntc_design.protocol.ProtocolDesign`; without thresholds only δ is marked).

    Parameters
    ----------
    des : ProtocolDesign
        The design.
    points : int, optional
        Samples of δ.

    Returns
    -------
    CouplingCurve
    """
    th = des.thresholds
    crit = (th.hurwitz, th.symmetric, th.best_rate_delta) if th is not None else ()
    marks = [des.delta] + [v for v in crit if v is not None and v > 0]
    lo, hi = min(marks) / 30.0, max(marks) * 30.0
    delta = np.geomspace(lo, hi, points)
    lap, dmat = des.topology.laplacian(), des.coupling_matrix()
    s0 = lap + lap.T
    rate = np.array([np.min(np.linalg.eigvals(lap + x * dmat).real) for x in delta])
    sym = np.array([np.linalg.eigvalsh(s0 + 2 * x * dmat)[0] for x in delta])
    return CouplingCurve(
        des.topology.name or "topology",
        delta,
        rate,
        sym,
        des.delta,
        *(
            (th.hurwitz, th.symmetric, th.best_rate_delta, th.best_rate)
            if th is not None
            else (None,) * 4
        ),
    )


def coupling_figure(curves: Sequence[CouplingCurve], width: float = TWO_COLUMN):
    """Two panels against δ (log scale): the decay rate −max Re λ(−L_B(δ)) and
    λ_min(L_B + L_Bᵀ)(δ); per mode Lemma 1's δ (circle), δ_H (triangle), δ_S (square) and
    the best δ (star). A δ_H of 0 is stated in the legend (it has no place on a log axis).

    Parameters
    ----------
    curves : sequence of CouplingCurve
        One per mode.
    width : float, optional
        Figure width in inches.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with paper_style():
        fig, (a1, a2) = plt.subplots(
            1, 2, figsize=(width, 2.4 + 0.2 * len(curves)), layout="constrained", sharex=True
        )
        handles = []
        for k, c in enumerate(curves):
            col = agent_style(k).colour
            ls = LINESTYLES[k % 4]
            for ax, y in ((a1, c.rate), (a2, c.sym_min)):
                ax.plot(c.delta, y, color=col, ls=ls, lw=1.2)

            def at(x, y=None, c=c):
                return float(np.interp(np.log(x), np.log(c.delta), y))

            marks = [
                ("o", c.lemma_delta, r"Lemma 1 $\delta$"),
                ("^", c.delta_h, r"$\delta_H$"),
                ("s", c.delta_s, r"$\delta_S$"),
                ("*", c.best_delta, r"best $\delta$"),
            ]
            txt = []
            for mk, x, lab in marks:
                if x is None:
                    txt.append(
                        f"{lab}: none" if mk != "*" else r"rate grows as $\delta \to \infty$"
                    )
                    continue
                if x <= 0:
                    txt.append(f"{lab} = 0 (left of the log axis: not drawn)")
                    continue
                txt.append(f"{lab} = {x:.4g}")
                for ax, y in ((a1, c.rate), (a2, c.sym_min)):
                    ax.plot(
                        [x],
                        [at(x, y)],
                        marker=mk,
                        color=col,
                        markersize=8 if mk == "*" else 5,
                        markeredgecolor="black",
                        markeredgewidth=0.6,
                        ls="none",
                        zorder=4,
                    )
            handles.append(
                Line2D([], [], color=col, ls=ls, lw=1.2, label=f"{c.name}: " + ", ".join(txt))
            )
        for ax in (a1, a2):
            ax.set_xscale("log")
            ax.axhline(0.0, color="black", lw=0.6)
            ax.set_xlabel(r"coupling $\delta$")
        a1.set_ylabel(r"$-\max\,\mathrm{Re}\,\lambda(-L_B)$")
        a2.set_ylabel(r"$\lambda_{\min}(L_B + L_B^{\top})$")
        keys = [
            Line2D([], [], marker=m, color="0.6", markeredgecolor="black", ls="none", label=lab)
            for m, lab in (
                ("o", r"Lemma 1 $\delta$"),
                ("^", r"$\delta_H$"),
                ("s", r"$\delta_S$"),
                ("*", r"best $\delta$"),
            )
        ]
        # the curves' legend above and the marker key below the axes, never on a curve
        fig.legend(handles=handles, loc="outside upper center", ncol=1, frameon=False)
        fig.legend(handles=keys, loc="outside lower center", ncol=4, frameon=False)
    return fig


def gain_latex(text: str) -> str:
    """``c(t) = …`` in mathtext from the parsed gain (sympy.latex of the expression, never
    of the raw text); falls back to the plain text if mathtext cannot typeset it.

    Parameters
    ----------
    text : str
        The gain as the user wrote it.

    Returns
    -------
    str
    """
    from matplotlib.mathtext import MathTextParser
    from sympy.printing.latex import LatexPrinter

    class Printer(LatexPrinter):
        def _print_Pow(self, expr):  # (1+t)^{-1/3} as the paper writes it, not 1/∛(1+t)
            b, e = expr.as_base_exp()
            if e.is_Rational and not e.is_Integer:
                base = self._print(b)
                if not (b.is_Symbol or b.is_Number):
                    base = f"({base})"
                return f"{base}^{{{e.p}/{e.q}}}"
            return super()._print_Pow(expr)

    expr = parse_gain(text)
    tex = Printer().doprint(expr).replace(r"\left", "").replace(r"\right", "")
    tex = tex.replace(r"\frac", r"\dfrac")
    out = f"$c(t) = {tex}$"
    try:
        MathTextParser("agg").parse(out)
    except ValueError:
        return f"c(t) = {text}"
    return out


def gain_figure(text: str | Callable, t_end: float, width: float = TWO_COLUMN):
    """c(t), ∫₀ᵗ c and ∫₀ᵗ c² on [0, T] (cumulative trapezoid on a fine grid).

    Parameters
    ----------
    text : str or callable
        The gain c(t): an expression, or a callable such as a schedule.
    t_end : float
        T.
    width : float, optional
        Figure width in inches.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        The gain does not parse (or is not an expression).
    """
    from scipy.integrate import cumulative_trapezoid

    c, _ = make_gain(text)
    t = np.linspace(0.0, t_end, 20001)
    y = c(t)
    ints = (y, cumulative_trapezoid(y, t, initial=0.0), cumulative_trapezoid(y**2, t, initial=0))
    labels = ("$c(t)$", r"$\int_0^t c\,ds$", r"$\int_0^t c^2\,ds$")
    with paper_style():
        fig, axes = plt.subplots(1, 3, figsize=(width, 2.1), layout="constrained")
        for ax, v, lab in zip(axes, ints, labels, strict=True):
            ax.plot(t, v, color=BLUE, lw=1.2)
            ax.set_ylabel(lab)
            ax.set_xlabel("$t$")
            ax.set_ylim(bottom=0)
        title = gain_latex(text) if isinstance(text, str) else getattr(text, "text", "c(t)")
        fig.suptitle(title, fontsize=9)
    return fig


# ----------------------------------------------------------------------------- saving


__all__ = [
    "CouplingCurve",
    "SavedFigure",
    "coupling_curve",
    "coupling_figure",
    "gain_figure",
    "gain_latex",
    "ms_error_figure",
    "save",
    "schedule_figure",
    "states_figure",
]


def robust_figure(reports: Sequence, margin: tuple[float | None, float | None] | None = None):
    """The decay and consensus-offset brackets against the radius ρ: the proven end as a
    line, the end a realisation attains as markers, the bracket shaded between them.

    Parameters
    ----------
    reports : sequence of RobustReport
        One per radius (:func:`ntc_design.certify.robust.search.robust_sweep`).
    margin : (float, float), optional
        The margin bracket (ρ_lower, ρ_upper), drawn as a band where stability is no
        longer proven.

    Returns
    -------
    matplotlib.figure.Figure
    """
    rho = np.array([r.radius for r in reports])

    def ends(key: str) -> tuple[np.ndarray, np.ndarray]:
        lo = [getattr(r, key).lower for r in reports]
        hi = [getattr(r, key).upper for r in reports]
        return (np.array([np.nan if v is None else v for v in lo]),
                np.array([np.nan if v is None else v for v in hi]))  # fmt: skip

    with paper_style():
        fig, axes = plt.subplots(1, 2, figsize=(TWO_COLUMN, 2.4), layout="constrained")
        for ax, key, ylabel, proven in (
            (axes[0], "decay", "decay rate min Re λ(L_B(A'))", "lower"),
            (axes[1], "offset", "consensus offset ‖x* − 1⊗θ‖₂", "upper"),
        ):
            lo, hi = ends(key)
            ax.fill_between(rho, lo, hi, color="0.85", label="bracket")
            cert = lo if proven == "lower" else hi
            seen = hi if proven == "lower" else lo
            ax.plot(rho, cert, "-", color="C0", lw=1.4, label=f"proven {proven} bound")
            ax.plot(rho, seen, "o", color="C3", ms=3.5, label="attained by a realisation")
            if margin is not None and margin[0] is not None:
                ax.axvspan(margin[0], margin[1] or 1.0, color="C1", alpha=0.15, lw=0,
                           label="beyond the proven margin")  # fmt: skip
            ax.set_xlabel("relative radius ρ of every weight")
            ax.set_ylabel(ylabel)
            ax.set_xlim(0, max(float(rho.max(initial=0.0)), margin[1] or 0.0) if margin else None)
        axes[0].legend(fontsize=7, loc="lower left")
    return fig


def realisations_figure(study: dict):
    """Simulated weight realisations against the proven brackets: each realisation's
    exact decay rate and consensus offset as a point, the proven lower bound on the decay
    rate and upper bound on the offset as lines (a point beyond a line would be a false
    proof).

    Parameters
    ----------
    study : dict
        ``summary.json``'s ``robust`` (:meth:`ntc_design.sweep.robust.RobustStudy.to_dict`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = study["rows"]
    x = np.array([r["decay_rate"] for r in rows], dtype=float)
    y = np.array([r["offset"] for r in rows], dtype=float)
    b = study.get("brackets") or {}
    lo = (b.get("decay") or {}).get("lower")
    hi = (b.get("offset") or {}).get("upper")
    with paper_style():
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.6), layout="constrained")
        ax.plot(x, y, "o", color="C0", ms=4, label=f"{len(rows)} realisations")
        if lo is not None:
            ax.axvline(lo, color="C3", lw=1.2, label="proven lower bound on the decay rate")
        if hi is not None:
            ax.axhline(hi, color="C1", lw=1.2, ls="--", label="proven upper bound on the offset")
        nom = b.get("nominal_decay")
        if nom is not None:
            ax.plot([nom], [0.0], "k*", ms=7, label="nominal network")
        ax.set_xlabel("decay rate min Re λ(L_B(A'))")
        ax.set_ylabel("consensus offset ‖x* − 1⊗θ‖₂")
        ax.set_title(f"weights within {study_radius_text(study, short=True)}", fontsize=8)
        ax.legend(fontsize=6.5, loc="best")
    return fig
