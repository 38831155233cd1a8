"""A report's digital section (a run of the sampled protocol, ``digital:`` in its scenario):
the exact error at T and the peak against the period for delays 0, 1 and 2, the certified
k₀, and the continuous design's curve beside the sampled one."""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import NullFormatter

from ..errors import InputError
from ..present.rows import fmt
from ..simulate.digital import digital_moments
from ..simulate.prepare import make_gain, prepare_modes, sampled_grid
from ..tune.period import period_curve
from .figlist import Drawn
from .html import Table
from .rundata import RunData
from .style import ONE_COLUMN, TWO_COLUMN, paper_style

#: The delays the period figure compares.
DELAYS = (0, 1, 2)
#: Periods drawn: geometric from h/8 to 4h (at most T), the run's own among them.
SPAN = (1 / 8, 4.0)
POINTS = 13


@dataclass(frozen=True)
class DigitalFacts:
    """What the digital section shows: the run's period and delay, the curves error(h)
    and peak(h) per delay, the continuous reference, the certified k₀ (None when not
    certified: then ``stopped`` says why) and both curves over time."""

    period: float
    delay: int
    periods: np.ndarray
    final: dict[int, np.ndarray]
    peak: dict[int, np.ndarray]
    continuous_final: float
    continuous_peak: float
    t: np.ndarray
    continuous: np.ndarray
    t_sampled: np.ndarray
    sampled: np.ndarray | None
    k0: int | None
    kappa: float | None
    stopped: str
    note: str

    def table(self) -> Table:
        """The section's table.

        Returns
        -------
        Table
        """
        rows = [
            ("sampling period h", fmt(self.period)),
            ("measurement delay D", str(self.delay)),
            ("continuous design: Σ_i E‖x_i(T) − θ‖² (exact)", fmt(self.continuous_final)),
            ("continuous design: peak", fmt(self.continuous_peak)),
        ]
        if self.sampled is not None:
            rows += [
                ("sampled: Σ_i E‖x_i(T) − θ‖² (exact)", fmt(float(self.sampled[-1]))),
                ("sampled: peak over the samples", fmt(float(np.max(self.sampled)))),
            ]
        if self.k0 is not None:
            rows.append(
                (
                    "certified: contracts in mean square from step",
                    f"k₀ = {self.k0} (t = {fmt(self.k0 * self.period)}; c(t) < κ = {fmt(self.kappa)} from there)",
                )
            )
        else:
            rows.append(("certified contraction", f"not certified: {self.stopped}"))
        return Table(("quantity", "value"), rows)


def digital_facts(run: RunData, certificate: dict) -> DigitalFacts | None:
    """The digital section of a run, or None for a continuous one.

    Parameters
    ----------
    run : RunData
        The run.
    certificate : dict
        Its certificate (a ``digital`` kind states k₀).

    Returns
    -------
    DigitalFacts or None

    Raises
    ------
    InputError
        A malformed topology in the run.
    """
    dg = run.digital
    if dg is None:
        return None
    t_end = float(run.t[-1])
    res = certificate.get("results", {}).get("digital", {})
    stopped = (
        res.get("stopped", "the certificate is not of a digital kind") if "k0" not in res else ""
    )
    spec = run.design_spec()
    top = run.topology()
    periods = np.unique(
        np.append(
            np.geomspace(dg.period * SPAN[0], min(dg.period * SPAN[1], t_end), POINTS), dg.period
        )
    )
    final, peak = {}, {}
    note = ""
    try:
        for d in DELAYS:
            got = np.array(period_curve(top, spec, t_end, d, periods, stop_above=1e300))
            final[d], peak[d] = got[:, 0], got[:, 1]
        gain = make_gain(run.gain)[0]
        pm = prepare_modes(top, spec.replace(T=t_end), gain)
        cont = pm.moments(gain, run.t).ms_error.sum(axis=1)
        grid = sampled_grid(top, pm, dg, t_end, run.t)
        dm = digital_moments(pm, grid, gain, dg.delay)
        t_s, sampled = grid.save_times, dm.moments.ms_error.sum(axis=1)
        if dg.lossy:  # the curves here are the lossless recursion's
            note = (
                "These curves are without message loss; the Lossy links section has the lossy ones."
            )
    except InputError as exc:
        note = f"the period curves are not computed: {exc}"
        cont = np.full(run.t.size, np.nan)
        final = {d: np.full(periods.size, np.nan) for d in DELAYS}
        peak = dict(final)
        t_s, sampled = run.t, None
    return DigitalFacts(
        dg.period,
        dg.delay,
        periods,
        final,
        peak,
        float(cont[-1]),
        float(np.nanmax(cont)) if np.any(np.isfinite(cont)) else float("nan"),
        run.t,
        cont,
        t_s,
        sampled,
        int(res["k0"]) if "k0" in res else None,
        float(res["kappa"]) if "kappa" in res else None,
        stopped,
        note,
    )


def period_figure(f: DigitalFacts):
    """E Σ‖x_i(T) − θ‖² and the peak against the period, per delay, beside the continuous
    design's (horizontal) and the run's own period (vertical).

    Parameters
    ----------
    f : DigitalFacts
        The section's facts.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with paper_style():
        fig, axes = plt.subplots(1, 2, figsize=(TWO_COLUMN, 2.5), layout="constrained")
        for ax, data, ref, name in (
            (axes[0], f.final, f.continuous_final, "E Σ‖x_i(T) − θ‖²"),
            (axes[1], f.peak, f.continuous_peak, "peak of E Σ‖x_i − θ‖²"),
        ):
            for d, ls in zip(DELAYS, ("-", "--", ":"), strict=True):
                ax.plot(f.periods, data[d], ls, marker="o", ms=2.5, label=f"delay D = {d}")
            ax.axhline(ref, color="k", lw=0.8, label="continuous design")
            ax.axvline(f.period, color="0.6", lw=0.8, ls="-.", label="this run's h")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())  # no overlapping minor labels
            ax.set_xlabel("sampling period h")
            ax.set_ylabel(name)
        axes[0].legend(fontsize=6.5, loc="best")
    return fig


def curve_figure(f: DigitalFacts):
    """The continuous design's exact curve beside the sampled recursion's, with the
    certified k₀.

    Parameters
    ----------
    f : DigitalFacts
        The section's facts.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with paper_style():
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.5), layout="constrained")
        ax.plot(f.t, f.continuous, "k-", lw=1.0, label="continuous (exact)")
        if f.sampled is not None:
            ax.plot(
                f.t_sampled,
                f.sampled,
                "C3--",
                lw=1.2,
                label=f"sampled h = {f.period:g}, D = {f.delay}",
            )
        if f.k0 is not None and f.k0 * f.period <= f.t[-1]:
            ax.axvline(f.k0 * f.period, color="C2", lw=0.8, ls=":", label="certified k₀·h")
        ax.set_yscale("log")
        ax.set_xlabel("t")
        ax.set_ylabel("Σ_i E‖x_i − θ‖²")
        ax.legend(fontsize=6.5, loc="best")
    return fig


def digital_drawings(f: DigitalFacts | None) -> list[Drawn]:
    """The section's two figures (none for a continuous run).

    Parameters
    ----------
    f : DigitalFacts or None
        The section's facts.

    Returns
    -------
    list of Drawn
    """
    if f is None:
        return []
    drawn = []
    # a log scale needs a positive value: curves not computed (the section's note says
    # why) are not drawn
    if _positive(*f.final.values(), *f.peak.values()):
        drawn.append(
            Drawn(
                "digital_periods",
                "digital-periods",
                "The sampled protocol's exact error at T (left) and its peak (right) against "
                "the period h, for delays of 0, 1 and 2 samples, beside the continuous design.",
                period_figure(f),
            )
        )
    if _positive(f.continuous, *([f.sampled] if f.sampled is not None else [])):
        drawn.append(
            Drawn(
                "digital_curve",
                "digital-curve",
                "The continuous design's exact Σ_i E‖x_i − θ‖² beside the sampled recursion's, "
                "with the step from which the sampled recursion is certified to contract.",
                curve_figure(f),
            )
        )
    return drawn


def _positive(*curves: np.ndarray) -> bool:
    """Some curve has a finite positive value (a log axis can show it)."""
    return any(bool(np.any(np.isfinite(c) & (c > 0))) for c in curves)


__all__ = [
    "DELAYS",
    "DigitalFacts",
    "curve_figure",
    "digital_drawings",
    "digital_facts",
    "period_figure",
]
