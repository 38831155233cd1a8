"""The report of a run too large to draw agent by agent (above ``AGGREGATE_ABOVE``
agents): E‖x_i − θ‖² as quantiles over the agents (median, 10–90 %, max) with the worst
agents named, the total error with its Monte Carlo band, the distribution of the final
per-agent error, the certificate's rows and the eigenvalue picture it relies on (the
certified per-agent bounds μ_i of a component-wise certificate, or the spectrum of −L_B),
and a topology view that scales (degree distributions and the sparsity of L_B in the order
of its strongly connected components). Cost grows with the agents and edges, never with
their square."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

from ..certify import KINDS, CertifyResult
from ..certify.format import package_versions
from ..model import Topology
from ..present.rows import fmt
from ..protocol import ProtocolDesign, SwitchingDesign
from ..protocol.thresholds import strong_components
from ..simulate.result import MeanSquareBand
from .figlist import Drawn, FigureSpec, render_figures
from .figures import states_figure
from .html import RunSection, Table, html_table
from .parts import (
    certificate_tables,
    certify_run,
    data_links,
    fitted_exponent,
    mc_band,
    parameter_table,
    window_warning,
)
from .rundata import RunData
from .style import BLUE, GREY, ONE_COLUMN, RED, TWO_COLUMN, paper_style

#: Above this many agents a run's report shows quantiles over the agents instead of a
#: curve, a table row and a legend entry per agent.
AGGREGATE_ABOVE = 20
WORST = 3  # agents named in the quantile figure
WORST_ROWS = 10  # rows of the final-error table
SPY_BINS = 400  # the sparsity picture is a density on at most this many bins a side


def quantile_figure(t: np.ndarray, ms: np.ndarray, labels: list[str], total: MeanSquareBand):
    """Per-agent E‖x_i − θ‖² as quantiles over the agents, the worst agents named (left),
    and the total Σ_i E‖x_i − θ‖² with its band (right), on log scales.

    Parameters
    ----------
    t : numpy.ndarray
        Save times (S,).
    ms : numpy.ndarray
        E‖x_i − θ‖² (S, N).
    labels : list of str
        Agent labels.
    total : MeanSquareBand
        The total and its band, each (S, 1).

    Returns
    -------
    matplotlib.figure.Figure
    """
    floor = 1e-300
    q10, q50, q90 = np.quantile(ms, [0.1, 0.5, 0.9], axis=1)
    worst = np.argsort(ms[-1])[::-1][:WORST]
    with paper_style():
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(TWO_COLUMN, 2.8), layout="constrained")
        a1.fill_between(t, np.maximum(q10, floor), np.maximum(q90, floor), color=BLUE,
                        alpha=0.25, lw=0, label="10–90 % of agents")  # fmt: skip
        a1.plot(t, np.maximum(q50, floor), color=BLUE, lw=1.2, label="median agent")
        a1.plot(
            t,
            np.maximum(ms.max(axis=1), floor),
            color=GREY,
            lw=1.0,
            ls="--",
            label="max over agents",
        )
        for k, i in enumerate(worst):
            a1.plot(t, np.maximum(ms[:, i], floor), color=RED, lw=0.9, ls=(0, (1 + k, 1.5)),
                    label=f"agent {labels[i]} (worst {k + 1})")  # fmt: skip
        a1.set_yscale("log")
        a1.set_xlabel("$t$")
        a1.set_ylabel(r"$E\,\|x_i - \theta\|^2$")
        a2.fill_between(t, np.maximum(total.lo[:, 0], floor), np.maximum(total.hi[:, 0], floor),
                        color=GREY, alpha=0.3, lw=0, label="band")  # fmt: skip
        a2.plot(t, np.maximum(total.mean[:, 0], floor), color="black", lw=1.2, label=r"$\sum_i$")
        a2.set_yscale("log")
        a2.set_xlabel("$t$")
        a2.set_ylabel(r"$E\,\sum_i \|x_i - \theta\|^2$")
        fig.legend(loc="outside lower center", ncol=4, frameon=False, fontsize=7)
    return fig


def final_histogram(final: np.ndarray):
    """The distribution of the final per-agent error on a logarithmic axis.

    Parameters
    ----------
    final : numpy.ndarray
        E‖x_i(T) − θ‖² per agent.

    Returns
    -------
    matplotlib.figure.Figure
    """
    pos = final[final > 0]
    with paper_style():
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.4), layout="constrained")
        if pos.size:
            lo, hi = np.log10(pos.min()), np.log10(pos.max())
            bins = np.logspace(lo, hi + 1e-9, 40).tolist() if hi > lo else 10
            ax.hist(pos, bins=bins, color=BLUE, alpha=0.8)
            ax.set_xscale("log")
        ax.set_xlabel(r"$E\,\|x_i(T) - \theta\|^2$")
        ax.set_ylabel("agents")
    return fig


def degree_figure(top: Topology):
    """In- and out-degree distributions (edges per agent).

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ea = top.edge_arrays
    d_in = np.bincount(ea.rows, minlength=top.n)
    d_out = np.bincount(ea.cols, minlength=top.n)
    top_deg = int(max(d_in.max(initial=0), d_out.max(initial=0)))
    bins = (np.arange(top_deg + 2) - 0.5).tolist()
    with paper_style():
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.4), layout="constrained")
        ax.hist(d_in, bins=bins, color=BLUE, alpha=0.7, label="in-degree")
        ax.hist(d_out, bins=bins, histtype="step", color=RED, lw=1.2, label="out-degree")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_xlabel("edges per agent")
        ax.set_ylabel("agents")
        ax.legend(frameon=False)
    return fig


def sparsity_figure(top: Topology, lap_b):
    """Where L_B's non-zero blocks are, agents in the order of the strongly connected
    components (a topological order of the condensation: block lower triangular), as a
    density on at most SPY_BINS × SPY_BINS cells.

    Parameters
    ----------
    top : Topology
        The topology.
    lap_b : scipy.sparse matrix
        L_B, Nd × Nd.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ncomp, comp = strong_components(lap_b, top.dim)
    order = np.argsort(comp, kind="stable")
    where = np.empty(top.n, dtype=np.int64)
    where[order] = np.arange(top.n)
    ea = top.edge_arrays
    rows = np.concatenate([where[ea.rows], np.arange(top.n)])
    cols = np.concatenate([where[ea.cols], np.arange(top.n)])
    bins = min(SPY_BINS, top.n)
    dens, _, _ = np.histogram2d(rows, cols, bins=bins, range=[[0, top.n], [0, top.n]])
    with paper_style():
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, ONE_COLUMN), layout="constrained")
        ax.imshow(np.log1p(dens), cmap="Greys", origin="upper", extent=(0, top.n, top.n, 0),
                  interpolation="nearest")  # fmt: skip
        ax.set_xlabel("agent $j$ (component order)")
        ax.set_ylabel("agent $i$")
        ax.set_title(f"{ncomp} strongly connected components", fontsize=8)
    return fig


def certificate_picture(cert: dict, des: ProtocolDesign):
    """What the certificate relies on: the certified per-agent bounds μ_i (λ_min of each
    symmetric diagonal block, lowered for rounding) of a component-wise certificate, or
    the eigenvalues of −L_B when it is small enough to compute them densely.

    Parameters
    ----------
    cert : dict
        The certificate.
    des : ProtocolDesign
        The design it certifies.

    Returns
    -------
    matplotlib.figure.Figure or None
        None when neither is available (L_B too large for dense eigenvalues).

    Raises
    ------
    InputError
        The certificate's μ array is malformed.
    """
    with paper_style():
        kind = KINDS.get(str(cert.get("kind")))
        mu = kind.agent_margins(cert, des.topology.n) if kind is not None else None
        if mu is not None:
            # sorted against the fraction of agents (a quantile function): every agent is
            # visible however wide the spread, on a log axis when every μ_i > 0
            fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.4), layout="constrained")
            mu_s = np.sort(mu)
            q = (np.arange(mu_s.size) + 0.5) / max(mu_s.size, 1)
            ax.plot(q, mu_s, color=BLUE, lw=1.2, marker="." if mu_s.size <= 200 else None)
            if mu_s.size and mu_s[0] > 0:
                ax.set_yscale("log")
                ax.axhline(mu_s[0], color=RED, lw=1.0, ls="--")
                ax.annotate(
                    f"smallest μ_i = {mu_s[0]:.3g} (> 0 needed)",
                    (0.98, mu_s[0]),
                    xycoords=("axes fraction", "data"),
                    ha="right",
                    va="bottom",
                    color=RED,
                    fontsize=7,
                )
            else:
                ax.axhline(0.0, color=RED, lw=1.0, ls="--")
                ax.annotate(
                    "μ_i > 0 needed",
                    (0.98, 0.0),
                    xycoords=("axes fraction", "data"),
                    ha="right",
                    va="bottom",
                    color=RED,
                    fontsize=7,
                )
            ax.set_xlabel("fraction of agents (sorted by μ_i)")
            ax.set_ylabel(r"certified $\mu_i$")
            return fig
        if des.topology.nd > 3000:
            return None
        lam = np.linalg.eigvals(-des.grounded_laplacian())
        fig, ax = plt.subplots(figsize=(ONE_COLUMN, 2.6), layout="constrained")
        ax.scatter(lam.real, lam.imag, s=4, color=BLUE)
        ax.axvline(0.0, color=RED, lw=1.0, ls="--")
        ax.set_xlabel(r"Re $\lambda(-L_B)$")
        ax.set_ylabel(r"Im $\lambda(-L_B)$")
        return fig


def total_band(mc: MeanSquareBand) -> MeanSquareBand:
    """Σ_i E‖x_i − θ‖² with a conservative band: the per-agent half-widths added (the
    standard deviation of a sum is at most the sum of the standard deviations).

    Parameters
    ----------
    mc : MeanSquareBand
        Per-agent curves and bands (S, N).

    Returns
    -------
    MeanSquareBand
        (S, 1) arrays.
    """
    mean = mc.mean.sum(axis=1, keepdims=True)
    lo_half = np.nan_to_num(mc.mean - mc.lo, nan=0.0).sum(axis=1, keepdims=True)
    hi_half = np.nan_to_num(mc.hi - mc.mean, nan=0.0).sum(axis=1, keepdims=True)
    return MeanSquareBand(mean=mean, lo=np.maximum(mean - lo_half, 0.0), hi=mean + hi_half)


def worst_table(run: RunData, ms: np.ndarray, kind: str) -> Table:
    """The agents with the largest final error, with the quantiles over all agents.

    Parameters
    ----------
    run : RunData
        The run.
    ms : numpy.ndarray
        E‖x_i − θ‖² (S, N).
    kind : str
        "exact" or "MC", for the header.

    Returns
    -------
    Table
    """
    final = ms[-1]
    worst = np.argsort(final)[::-1][:WORST_ROWS]
    rows: list[tuple] = [
        (run.labels[i], fmt(float(final[i]), 5), fmt(float(ms[0, i]), 5)) for i in worst
    ]
    for q, name in (
        (0.9, "90 % of agents below"),
        (0.5, "median agent"),
        (0.1, "10 % of agents below"),
    ):
        rows.append(
            (name, fmt(float(np.quantile(final, q)), 5), fmt(float(np.quantile(ms[0], q)), 5))
        )
    return Table(("agent", f"{kind} E‖x_i − θ‖² at t = {run.t[-1]:g}", "at t = 0"), rows)


@dataclass(frozen=True)
class AggregateFacts:
    """What a large run's section shows, computed before anything is drawn."""

    run: RunData
    res: CertifyResult
    cert_tab: Table
    checks: Table
    cert: dict
    modes: dict  # name -> ProtocolDesign
    ms: np.ndarray  # per-agent curves (exact when the run has them)
    kind: str  # "exact" or "MC"
    total: MeanSquareBand
    fitted: float | None

    @property
    def first(self) -> ProtocolDesign:
        """The first mode's design (the topology pictures are of it)."""
        return next(iter(self.modes.values()))


def aggregate_facts(run: RunData, base: Path) -> AggregateFacts:
    """Certify a large run (writing certificate.json beside it) and reduce its curves to
    quantiles over the agents and a total with its band.

    Parameters
    ----------
    run : RunData
        The run.
    base : pathlib.Path
        The folder links are relative to.

    Returns
    -------
    AggregateFacts

    Raises
    ------
    InputError
        A malformed run folder or certificate input.
    """
    top = run.topology()
    res = certify_run(run)
    cert_tab, checks, cert = certificate_tables(res, run.path / "certificate.json", base)
    ms, kind, total = _curves(run)
    modes = (
        dict(res.design.modes)
        if isinstance(res.design, SwitchingDesign)
        else {getattr(top, "name", None) or "topology": res.design}
    )
    assert all(isinstance(m, ProtocolDesign) for m in modes.values())
    fitted = _total_fit(run.t, total.mean[:, 0])
    return AggregateFacts(run, res, cert_tab, checks, cert, modes, ms, kind, total, fitted)


# ---------------------------------------------------------- the large run's figure list


def _degrees(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    return [Drawn("degrees", "degrees", "In- and out-degree distributions.",
                  degree_figure(f.first.topology))]  # fmt: skip


def _sparsity(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    return [
        Drawn(
            "sparsity",
            "sparsity",
            "Non-zero blocks of L_B, agents in the order of the strongly connected components "
            "(sources first: block lower triangular); darker is denser.",
            sparsity_figure(f.first.topology, f.first.grounded_laplacian_sparse()),
        )
    ]


def _spectrum(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    picture = certificate_picture(f.res.certificate, f.first)
    if picture is None:
        return []
    return [
        Drawn(
            "spectrum",
            "spectrum",
            "What the certificate relies on. Component-wise certificate: the certified "
            "per-agent bounds μ_i (λ_min of agent i's symmetric diagonal block, lowered "
            "for rounding), sorted, against the fraction of agents; the proof needs every "
            "μ_i > 0, and the red dashed line marks the smallest. Otherwise the "
            "eigenvalues of −L_B, which must lie left of the red dashed line Re λ = 0.",
            picture,
        )
    ]


def _quantiles(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    return [
        Drawn(
            "ms_quantiles",
            "ms_quantiles",
            f"Left: E‖x_i − θ‖² ({f.kind}) over the {len(f.run.labels)} agents: median, "
            f"10–90 % band, maximum, and the {WORST} agents with the largest final error. "
            "Right: the total with its Monte Carlo band (per-agent half-widths added: "
            "conservative).",
            quantile_figure(f.run.t, f.ms, f.run.labels, f.total),
        )
    ]


def _worst_paths(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    run = f.run
    if not run.npz["paths"].size:
        return []
    lab = [run.labels[i] for i in run.path_agents]
    return [
        Drawn(
            "states",
            "states",
            f"One sample path, per dimension, θ dashed, of the {len(lab)} agents with the "
            f"largest final error ({', '.join(lab)}): on a network of {len(run.labels)} "
            "agents the run keeps these agents' paths (paths.npz), stored at the "
            f"statistics' save times ({run.npz['t'].size} points).",
            states_figure(run.npz["t"], run.npz["paths"][0], run.theta, lab),
        )
    ]


def _histogram(f: AggregateFacts, gid: str | None) -> list[Drawn]:
    return [Drawn("final_hist", "final_hist", f"E‖x_i(T) − θ‖² over the agents ({f.kind}).",
                  final_histogram(f.ms[-1]))]  # fmt: skip


#: The large run's figures, in order: one function each, drawing from AggregateFacts.
AGGREGATE_FIGURES = (
    FigureSpec("topology", ONE_COLUMN, _degrees),
    FigureSpec("topology", ONE_COLUMN, _sparsity),
    FigureSpec("topology", ONE_COLUMN, _spectrum),
    FigureSpec("ms", TWO_COLUMN, _quantiles),
    FigureSpec("paths", TWO_COLUMN, _worst_paths),
    FigureSpec("paths", ONE_COLUMN, _histogram),
)


def aggregate_section(
    run: RunData,
    figdir: Path,
    title: str,
    key: str,
    base: Path | None = None,
    rerun: str | None = None,
) -> tuple[RunSection, dict]:
    """A large run's section of a report: quantiles over the agents instead of a curve
    per agent; :func:`aggregate_facts` first, then the tables and
    :data:`AGGREGATE_FIGURES`.

    Parameters
    ----------
    run : RunData
        The run.
    figdir : pathlib.Path
        Where the figures are written.
    title : str
        The section's title.
    key : str
        A prefix for figure files and element ids.
    base : pathlib.Path, optional
        The folder links are relative to (default: the run's).
    rerun : str, optional
        The command shown to re-run it.

    Returns
    -------
    (RunSection, dict)
        The section and its facts (certificate, verdicts, totals).

    Raises
    ------
    InputError
        A malformed run folder or certificate input.
    """
    base = base or run.path
    f = aggregate_facts(run, base)
    figs = render_figures(AGGREGATE_FIGURES, f, figdir, key, base)
    p = run.summary["parameters"]
    top = f.first.topology
    t_end = float(run.t[-1])
    section = RunSection(
        key=key,
        title=title,
        rerun=rerun or run.rerun,
        designs=[(name, html_table(d.table())) for name, d in f.modes.items()],
        coupling=None,
        certificate=f.cert_tab,
        checks=f.checks,
        gain=_gain_table(f.res),
        gain_figure=None,
        theorems=html_table(f.res.theorems_table()),
        ms_figure=figs["ms"][0],
        convergence_note=(
            f"The total error's decay exponent, fitted over t ∈ [T/10, T]: {fmt(f.fitted, 3)}."
            + window_warning(t_end / 10, t_end)
        ),
        convergence=Table(
            ("quantity", "value"), [("fitted p of Σ_i E‖x_i − θ‖²", fmt(f.fitted, 3))]
        ),
        topology_figures=figs["topology"],
        path_figures=figs["paths"],
        final=worst_table(run, f.ms, f.kind),
        spread="",
        data_links=data_links(run, figdir, key, base),
        parameters=parameter_table(p, top.n, top.dim, run.summary.get("run", {})),
        versions=Table(("package", "version"), sorted(package_versions().items())),
        interactive_agents=[],
    )
    facts = {
        "certificate": f.cert,
        "theorems": [t.to_dict() for t in f.res.theorems],
        "total_final": float(f.total.mean[-1, 0]),
    }
    return section, facts


def _curves(run: RunData) -> tuple[np.ndarray, str, MeanSquareBand]:
    """(per-agent curves, "exact" or "MC", the total with its band): the exact moments
    when the run has them, else the Monte Carlo means."""
    mc_mean, exact = run.ms("mc"), run.ms("exact")
    mc = mc_band(run)
    ms = exact if exact is not None else mc_mean
    assert ms is not None  # load_run refuses a run without curves
    flat = ms.sum(axis=1, keepdims=True)
    total = total_band(mc) if mc is not None else MeanSquareBand(mean=flat, lo=flat, hi=flat)
    return ms, "exact" if exact is not None else "MC", total


def _gain_table(res) -> Table:
    if res.gain is None:
        return Table(("condition", "holds", "reason"), [("no gain was given", "—", "")])
    return html_table(res.gain.table())


def _total_fit(t: np.ndarray, y: np.ndarray) -> float | None:
    return fitted_exponent(t, y, float(t[-1]) / 10)


__all__ = [
    "AGGREGATE_ABOVE",
    "AGGREGATE_FIGURES",
    "AggregateFacts",
    "aggregate_facts",
    "aggregate_section",
    "certificate_picture",
    "degree_figure",
    "final_histogram",
    "quantile_figure",
    "sparsity_figure",
    "total_band",
]
