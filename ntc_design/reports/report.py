"""Self-contained HTML reports (``ntc report DIR``), rendered from the Jinja2 templates in
``templates/`` with autoescaping: a table of contents, the design with its matrices, the
coupling figure (decay rate and λ_min(L_B + L_Bᵀ) against δ), the certificate, gain and
theorem verdicts, a convergence table (fitted against predicted decay exponent), the
figures (PNG inline; PNG, SVG and PDF linked), final errors, links to every data file, the
parameters as a table and a re-run command."""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ntc_design.certify.format import package_versions

from ..certify import CertifyResult, certify
from ..certify.kinds.time_varying import time_varying_results
from ..errors import InputError
from ..gain.conditions import T, limit_at_infinity, parse_gain
from ..gain.schedule import ScheduleGain
from ..io.outputs import check_output_file
from ..model import SwitchingTopology, Topology
from ..model.paper import F_SCALE
from ..model.timevarying import from_document
from ..present.rows import fmt
from ..protocol import ProtocolDesign, SwitchingDesign
from ..protocol.digital import Digital, DigitalDesign
from ..protocol.timevarying import TimeVaryingDesign
from ..simulate.digital import check_digital_moments
from ..simulate.moments import MOMENTS_MAX_ND
from ..simulate.result import MeanSquareBand
from ..sweep.robust import study_sentence
from . import figures, graph_figure, style
from .aggregate import AGGREGATE_ABOVE, aggregate_section
from .digital import DigitalFacts, digital_drawings, digital_facts
from .figlist import Drawn, FigureSpec, first, render_figures
from .html import (
    RunSection,
    Table,
    html_table,
    render,
    write_html,
)
from .loss import LossFacts, loss_drawings, loss_facts
from .parts import (
    certificate_tables,
    certify_run,
    companion_paths,
    data_links,
    fitted_exponent,
    mc_band,
    parameter_table,
    window_warning,
)
from .rundata import RunData, load_run
from .timevarying import lambda_min_figure, weights_figure

# --------------------------------------------------------------------------- sections


def _modes(des: ProtocolDesign | SwitchingDesign) -> dict[str, ProtocolDesign]:
    if isinstance(des, SwitchingDesign):
        return dict(des.modes)
    return {des.topology.name or "topology": des}


def design_tables(des: ProtocolDesign | SwitchingDesign) -> tuple[list, dict]:
    """The Lemma 1 parameters as one table with a column per mode (the design's own
    table); and the designs' dict forms."""
    return [("", html_table(des.table()))], _design_docs(des)


def _design_docs(des: ProtocolDesign | SwitchingDesign) -> dict:
    return {name: d.to_dict() for name, d in _modes(des).items()}


# ------------------------------------------------------------------------ convergence


def predicted_exponent(gain: str, rate: float) -> tuple[float | None, str]:
    """The decay exponent p of E‖x − 1⊗θ‖² ~ t^(−p) that the moment equations give for a
    gain c ~ t^(−β) (the second-moment ODE of the error dynamics, Niu & Wu, eq. (12):
    dΣ/dt = −c(L_BΣ + ΣL_Bᵀ) + c²(…) with a constant additive-noise term): β for
    0 < β < 1 (Σ follows c/2 times the noise covariance), min(1, 2α) for β = 1 (α the decay
    rate of −L_B), 0 for β > 1 (∫c < ∞: the error stalls) and 0 when c does not tend to 0.
    None when c is not a power of t."""
    import sympy as sp

    # the power of c at infinity, lim log c / log t (sympy, time-bounded)
    p = limit_at_infinity(sp.log(parse_gain(gain)) / sp.log(T))
    if p == -sp.oo:
        return 0.0, "c decays faster than any power of t: ∫c < ∞, so the error stalls"
    if p is None or p == sp.oo or isinstance(p, sp.AccumBounds):
        return None, "c(t) is not asymptotically a power of t: no prediction"
    beta = float(-p)
    if beta <= 0:
        return 0.0, "c does not tend to 0: the error settles at a noise floor (exponent 0)"
    if beta > 1:
        return 0.0, f"c ~ t^-{beta:g}, β > 1: ∫c < ∞, so the error stalls (exponent 0)"
    if abs(beta - 1) < 1e-12:
        return min(1.0, 2 * rate), (
            f"c ~ 1/t: exponent min(1, 2α) with α = {rate:.4g} the decay rate of −L_B"
        )
    return beta, f"c ~ t^-{beta:g}, 0 < β < 1: the error follows c, exponent β"


def convergence_table(run: RunData, mc, exact, rate: float) -> tuple[str, Table, dict]:
    """Fitted exponents per agent and in total over t ∈ [T/10, T] beside the prediction."""
    t = run.t
    t_end = float(t[-1])
    t_from = t_end / 10
    gain = run.gain
    if isinstance(gain, ScheduleGain):
        pred, why = None, "a tabulated schedule on [0, T]: no closed-form prediction"
    else:
        try:
            pred, why = predicted_exponent(gain, rate)
        except InputError:
            pred, why = None, "the gain is a callable: no prediction"
    rows = []
    fits = {}
    series = [(a, k) for k, a in enumerate(run.labels)] + [("all (Σ_i)", None)]
    for a, k in series:

        def col(m, k=k):
            if m is None:
                return None
            return m[:, k] if k is not None else m.sum(axis=1)

        fe = fitted_exponent(t, col(exact), t_from) if exact is not None else None
        fm = fitted_exponent(t, col(mc.mean), t_from) if mc is not None else None
        fits[a] = {"exact": fe, "mc": fm}
        rows.append((a, fmt(fe, 3), fmt(fm, 3), fmt(pred, 3)))
    note = (
        f"Decay exponent p of E‖x_i − θ‖² ≈ K(1+t)^(−p), fitted by least squares in log–log "
        f"over t ∈ [{t_from:g}, {t_end:g}], against the prediction for c(t) = {gain}: {why}."
    )
    note += window_warning(t_from, t_end)
    return (
        note,
        Table(("agent", "fitted p (exact moments)", "fitted p (Monte Carlo)", "predicted p"), rows),
        {"predicted": pred, "fits": fits},
    )


def _average_rate(des: ProtocolDesign | SwitchingDesign, top) -> float:
    """Decay rate of −L_B, or of the schedule-averaged −L̄_B for a switching design."""
    if isinstance(des, SwitchingDesign):
        per = top.period
        lb = sum(dur / per * des.modes[m].grounded_laplacian() for m, dur in top.schedule)
    else:
        lb = des.grounded_laplacian()
    return float(np.min(np.linalg.eigvals(lb).real))


# --------------------------------------------------------------------------- one run


@dataclass(frozen=True)
class TimeVaryingFacts:
    """A run over weights given as expressions of t: its time-varying certificate
    (:mod:`ntc_design.certify.time_varying`) and what its figures show."""

    res: CertifyResult
    design: TimeVaryingDesign
    lambda2: float
    domain: str
    intervals: list


def _time_varying(run: RunData, p: dict) -> TimeVaryingFacts | None:
    tvp = p.get("time_varying")
    if not isinstance(tvp, dict) or not isinstance(tvp.get("topology"), dict):
        return None
    tv = from_document(tvp["topology"], f"{run.path}/summary.json: time_varying")
    spec = run.spec  # the noise as the simulation read it, with its defaults
    noise = spec.noise
    f = noise.f if isinstance(noise.f, (int, float, np.ndarray)) else F_SCALE
    res = certify(
        tv, spec.theta.tolist(), spec.margin, run.gain, noise_sigma=noise.sigma, noise_f=f
    )
    r = time_varying_results(res.certificate)
    assert isinstance(res.design, TimeVaryingDesign)  # certify() of an ExpressionTopology
    return TimeVaryingFacts(
        res, res.design, r["lambda2"], r["domain_text"], res.certificate["intervals"]
    )


@dataclass(frozen=True)
class RunFacts:
    """Everything a run's section shows, computed before anything is drawn: the
    fixed-topology result (designs per mode), the result whose certificate and theorems
    are shown (the time-varying one for A(t)), the curves, the tables and the sample
    paths the figures use."""

    run: RunData
    top: Topology | SwitchingTopology  # the run's, parsed once
    res: CertifyResult
    design: ProtocolDesign | SwitchingDesign  # res's (a run's topology is never A(t) here)
    tv: TimeVaryingFacts | None
    cert_tab: Table
    checks: Table
    cert: dict
    mc: MeanSquareBand | None
    exact: np.ndarray | None
    convergence: tuple[str, Table, dict]
    fine: dict | None
    robust: Table | None
    robust_note: str
    digital: DigitalFacts | None = None  # a run of the sampled protocol
    loss: LossFacts | None = None  # a run of the sampled protocol on lossy links

    @property
    def cert_res(self) -> CertifyResult:
        """The result whose certificate and theorems the section shows."""
        return self.tv.res if self.tv is not None else self.res


def run_facts(run: RunData, base: Path, fine: dict | None = None) -> RunFacts:
    """Compute what a run's section shows: certify (writing certificate.json beside the
    run), the Monte Carlo band and exact moments, the convergence fits, the robust study's
    table and the finer sample paths.

    Parameters
    ----------
    run : RunData
        The run, as :func:`load_run` reads it.
    base : pathlib.Path
        The folder links are relative to.
    fine : dict, optional
        Sample paths at a finer decimation (``{"t", "paths"}``); by default a companion
        run's when the stored paths are too coarse to draw.

    Returns
    -------
    RunFacts

    Raises
    ------
    InputError
        A malformed run folder or certificate input.
    """
    p = run.summary["parameters"]
    top = run.topology()
    res = certify_run(run)
    # weights as expressions of t: the design tables show t = 0, the certificate and the
    # theorems are the time-varying ones (uniform Λ₂), with two figures over a period
    tv = _time_varying(run, p)
    cert_tab, checks, cert = certificate_tables(
        tv.res if tv else res, run.path / "certificate.json", base
    )
    des = res.design.base if isinstance(res.design, DigitalDesign) else res.design
    assert isinstance(des, (ProtocolDesign, SwitchingDesign))  # RunData.topology() is not A(t)
    mc, exact = mc_band(run), run.ms("exact")
    conv = convergence_table(run, mc, exact, _average_rate(des, top))
    if fine is None and run.npz["paths"].size:  # the stored paths are too coarse to draw
        fine = companion_paths(run, top)
    rob, rob_note = _robust_table(run)
    return RunFacts(
        run,
        top,
        res,
        des,
        tv,
        cert_tab,
        checks,
        cert,
        mc,
        exact,
        conv,
        fine,
        rob,
        rob_note,
        digital_facts(run, res.certificate),
        loss_facts(run, res.certificate),
    )


def _final_table(run: RunData, mc: MeanSquareBand | None, exact: np.ndarray | None) -> Table:
    """E‖x_i − θ‖² per agent at T (Monte Carlo with its band, exact) and at t = 0."""
    rows = []
    for k, a in enumerate(run.labels):
        if mc is not None and np.isfinite(mc.lo[-1, k]):
            band = f"[{fmt(float(mc.lo[-1, k]), 5)}, {fmt(float(mc.hi[-1, k]), 5)}]"
        else:
            band = "none (fewer than 2 paths)" if mc is not None else "—"
        start = exact[0, k] if exact is not None else (mc.mean[0, k] if mc is not None else None)
        rows.append(
            (
                a,
                fmt(float(mc.mean[-1, k]), 5) if mc is not None else "—",
                band,
                fmt(float(exact[-1, k]), 5) if exact is not None else "—",
                fmt(float(start), 5) if start is not None else "—",
            )
        )
    return Table(
        ("agent", f"MC E‖x_i − θ‖² at t = {run.t[-1]:g}", "95% band", "exact", "at t = 0"), rows
    )


def _robust_table(run: RunData) -> tuple[Table | None, str]:
    """The weight realisations of summary.json's ``robust`` (a scenario's ``robust:``):
    a table and a sentence; nothing without it."""
    st = run.summary.get("robust")
    if not isinstance(st, dict) or not st.get("rows"):
        return None, ""
    num = functools.partial(fmt, digits=5)  # None shows as "—"
    rows = [
        (
            str(r["realization"]),
            num(r["decay_rate"]),
            num(r["offset"]),
            num(r["mc_offset_T"]),
            num(r["final_ms_error"]),
        )
        for r in st["rows"]
    ]
    table = Table(
        (
            "realisation",
            "decay rate (exact)",
            "offset ‖x* − 1⊗θ‖ (exact)",
            f"MC ‖mean x(T) − 1⊗θ‖ at T = {run.t[-1]:g}",
            "Σ E‖x_i − θ‖² at T",
        ),
        rows,
    )
    return table, study_sentence(st) + "."


def _spread_text(run: RunData) -> str:
    sp_ = run.summary.get("sample_paths", {})
    if not sp_.get("stored"):
        return ""
    return (
        f"Stored sample paths ({sp_['stored']}): over t ∈ [{sp_['late_window'][0]:g}, "
        f"{sp_['late_window'][1]:g}] ‖x(t) − 1⊗θ‖ still moves by "
        f"{sp_['late_fluctuation_mean']:.4f} on average (max {sp_['late_fluctuation_max']:.4f}); "
        f"at t = {run.t[-1]:g} its mean is {sp_['final_error_norm_mean']:.4f} with spread "
        f"{fmt(sp_['final_error_norm_spread'])}."
    )


# ---------------------------------------------------------------- the run's figure list


def _segments(f: RunFacts):
    top = f.top
    return top.segments(float(f.run.t[-1])) if isinstance(top, SwitchingTopology) else None


def _coupling(f: RunFacts, gid: str | None) -> list[Drawn]:
    curves = [figures.coupling_curve(m) for m in _modes(f.design).values()]
    return [
        Drawn(
            "coupling",
            "coupling",
            "Decay rate −max Re λ(−L_B(δ)) (left) and λ_min(L_B + L_Bᵀ)(δ) (right) against "
            "the coupling δ, with B_i and the informed agents fixed: Lemma 1's δ (circle) is "
            "sufficient, δ_H and δ_S (triangle, square) are the exact thresholds and the star "
            "the best δ.",
            figures.coupling_figure(curves),
        )
    ]


def _topologies(f: RunFacts, gid: str | None) -> list[Drawn]:
    return [
        Drawn(
            f"topology_{name}",
            f"topology-{name}",
            f"Ĝ of {name}: the agents and, outside their circle, vertex 0 (the external "
            "signal x0) with its edges to the informed agents.",
            graph_figure.topology_figure(m.topology, m.informed, m.B),
        )
        for name, m in _modes(f.design).items()
    ]


def _time_varying_figures(f: RunFacts, gid: str | None) -> list[Drawn]:
    if f.tv is None:
        return []
    tv = f.tv
    return [
        Drawn(
            "lambda_min",
            "lambda_min",
            f"λ_min(L_B(t) + L_B(t)ᵀ) over {tv.domain} for Lemma 1 at each t, with the "
            f"certified uniform bound Λ₂ = {tv.lambda2:.6g} (dashed) and the bound proven on "
            "each t-interval (grey).",
            lambda_min_figure(tv.design, tv.lambda2, tv.intervals),
        ),
        Drawn(
            "weights",
            "weights",
            "The time-varying weights (every entry) and δ(t) = C(t) + ΔC; the design tables "
            "above show t = 0.",
            weights_figure(tv.design),
        ),
    ]


def _schedule(f: RunFacts, gid: str | None) -> list[Drawn]:
    top = f.top
    if not isinstance(top, SwitchingTopology):
        return []
    return [
        Drawn(
            "schedule",
            "schedule",
            f"The switching schedule, one period of {top.period:g}; it repeats up to "
            f"T = {f.run.t[-1]:g}.",
            figures.schedule_figure(top.schedule),
        )
    ]


def _ms(f: RunFacts, gid: str | None) -> list[Drawn]:
    segs = _segments(f)
    what = " and ".join(
        w
        for w, x in (("Monte Carlo (solid, 95% band)", f.mc), ("exact moments (dashed)", f.exact))
        if x is not None
    )
    return [
        Drawn(
            "ms_error",
            "ms",
            f"E‖x_i − θ‖² per agent, {what}"
            + ("; the strip under the axis shows the active mode." if segs else "."),
            figures.ms_error_figure(f.run.t, f.mc, f.exact, f.run.labels, segments=segs, gid=gid),
        )
    ]


def _states(f: RunFacts, gid: str | None) -> list[Drawn]:
    run = f.run
    if f.fine is not None and f.fine["paths"].size:
        t_p, path0 = f.fine["t"], f.fine["paths"][0]
        dec = (
            "a finer decimation than the statistics (a companion run of the same scenario and seed)"
        )
    elif run.npz["paths"].size:
        t_p, path0, dec = run.npz["t"], run.npz["paths"][0], "the statistics' save times"
    else:
        return []
    marked = ", each marked: lines only join them" if t_p.size <= 300 else ""
    return [
        Drawn(
            "states",
            "states",
            f"One sample path, per dimension, θ dashed: the {figures.HIGHLIGHTED} agents "
            f"farthest from θ at the end in colour, the others grey; stored at {dec} "
            f"({t_p.size} points{marked}).",
            figures.states_figure(
                t_p, path0, run.theta, run.labels, segments=_segments(f), gid=gid
            ),
        )
    ]


def _gain(f: RunFacts, gid: str | None) -> list[Drawn]:
    try:
        fig = figures.gain_figure(f.run.gain, float(f.run.t[-1]))
    except InputError:
        return []  # a callable gain: nothing to plot
    return [
        Drawn(
            "gain",
            "gain",
            "The gain c(t) and its integrals ∫c (infinite: the cumulative effect needed for "
            "consensus) and ∫c² (finite: the noise energy that almost-sure consensus needs).",
            fig,
        )
    ]


def _robust(f: RunFacts, gid: str | None) -> list[Drawn]:
    if f.robust is None:
        return []
    return [
        Drawn(
            "robust",
            "robust",
            "Each simulated weight realisation's exact decay rate and consensus offset "
            "(points) against the proven bounds (lines): no point may lie left of the solid "
            "line or above the dashed one.",
            figures.realisations_figure(f.run.summary["robust"]),
        )
    ]


def _digital(f: RunFacts, gid: str | None) -> list[Drawn]:
    return digital_drawings(f.digital)


def _loss(f: RunFacts, gid: str | None) -> list[Drawn]:
    return loss_drawings(f.loss)


#: The run report's figures, in order: one function each, drawing from :class:`RunFacts`.
RUN_FIGURES = (
    FigureSpec("coupling", style.TWO_COLUMN, _coupling),
    FigureSpec("topology", style.ONE_COLUMN, _topologies),
    FigureSpec("topology", style.TWO_COLUMN, _time_varying_figures),
    FigureSpec("topology", style.ONE_COLUMN, _schedule),
    FigureSpec("ms", style.TWO_COLUMN, _ms),
    FigureSpec("paths", style.TWO_COLUMN, _states),
    FigureSpec("gain", style.TWO_COLUMN, _gain),
    FigureSpec("robust", style.ONE_COLUMN, _robust, interactive=False),
    FigureSpec("digital", style.TWO_COLUMN, _digital, interactive=False),
    FigureSpec("loss", style.TWO_COLUMN, _loss, interactive=False),
)


def render_run(
    facts: RunFacts,
    figdir: Path,
    title: str,
    key: str,
    base: Path,
    rerun: str | None = None,
    interactive: bool = False,
) -> RunSection:
    """A run's section from its computed facts: the tables, and the figures of
    :data:`RUN_FIGURES` written to ``figdir``. Nothing is certified or simulated here.

    Parameters
    ----------
    facts : RunFacts
        What :func:`run_facts` computed.
    figdir : pathlib.Path
        Where the figures are written.
    title : str
        The section's title.
    key : str
        A prefix for figure files and element ids.
    base : pathlib.Path
        The folder links are relative to.
    rerun : str, optional
        The command shown to re-run it.
    interactive : bool, optional
        SVG figures with per-agent toggles.

    Returns
    -------
    RunSection
    """
    run = facts.run
    p = run.summary["parameters"]
    figs = render_figures(RUN_FIGURES, facts, figdir, key, base, interactive)
    designs, _ = design_tables(facts.design)
    conv_note, conv, _ = facts.convergence
    cert_res = facts.cert_res
    labels = run.labels
    return RunSection(
        key=key,
        title=title,
        rerun=rerun or run.rerun,
        designs=designs,
        coupling=first(figs["coupling"]),
        certificate=facts.cert_tab,
        checks=facts.checks,
        gain=html_table(cert_res.gain.table())
        if cert_res.gain is not None
        else Table(("condition", "holds", "reason"), [("no gain was given", "—", "")]),
        gain_figure=first(figs["gain"]),
        theorems=html_table(cert_res.theorems_table()),
        ms_figure=figs["ms"][0],
        convergence_note=conv_note,
        convergence=conv,
        topology_figures=figs["topology"],
        path_figures=figs["paths"],
        final=_final_table(run, facts.mc, facts.exact),
        spread=_spread_text(run),
        data_links=data_links(run, figdir, key, base),
        parameters=parameter_table(p, len(labels), run.theta.size, run.summary.get("run", {})),
        versions=Table(("package", "version"), sorted(package_versions().items())),
        interactive_agents=[(a, f"{key}-ag{i}") for i, a in enumerate(labels)]
        if interactive
        else [],
        robust=facts.robust,
        robust_figure=first(figs["robust"]),
        robust_note=facts.robust_note,
        digital=facts.digital.table() if facts.digital is not None else None,
        digital_figures=figs["digital"],
        digital_note=facts.digital.note if facts.digital is not None else "",
        loss=facts.loss.table() if facts.loss is not None else None,
        loss_figures=figs["loss"],
        loss_text=(f"{facts.loss.certified}. {facts.loss.note}".strip() if facts.loss else ""),
    )


def run_section(
    run: RunData,
    figdir: Path,
    title: str,
    key: str,
    base: Path | None = None,
    rerun: str | None = None,
    interactive: bool = False,
    fine: dict | None = None,
) -> tuple[RunSection, dict]:
    """One run's section of a report (figures written to ``figdir``, links relative to
    ``base``), and the facts a summary table needs: :func:`run_facts`, then
    :func:`render_run`.

    Parameters
    ----------
    run : RunData
        The run, as :func:`load_run` reads it.
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
    interactive : bool, optional
        SVG figures with per-agent toggles.
    fine : dict, optional
        Sample paths at a finer decimation (``{"t", "paths"}``) for the states figure.

    Returns
    -------
    (RunSection, dict)
        The section and the facts (designs, certificate, verdicts, errors).

    Raises
    ------
    InputError
        A malformed run folder.
    """
    base = base or run.path
    facts = run_facts(run, base, fine)
    section = render_run(facts, figdir, title, key, base, rerun, interactive)
    des_docs = _design_docs(facts.design)
    doc = facts.cert_res.to_dict()
    exact, mc = facts.exact, facts.mc
    summary = {
        "designs": des_docs,
        "certificate": facts.cert,
        "gain": doc["gain"],
        "theorems": doc["theorems"],
        "exact_first": exact[0].sum() if exact is not None else None,
        "exact_last": exact[-1].sum() if exact is not None else None,
        "exact_curve": exact.sum(axis=1) if exact is not None else None,
        "mc_last": mc.mean[-1].sum() if mc is not None else None,
        "sample_paths": run.summary.get("sample_paths", {}),
        "T": float(run.t[-1]),
        "convergence": facts.convergence[2],
    }
    return section, summary


def check_report_digital(run: RunData, digital: Digital) -> None:
    """Refuse a period and delay the run's report cannot show, before anything is written:
    a period longer than the run's horizon, too many steps, or the delayed recursion's
    exact moments past the memory or work limits.

    Parameters
    ----------
    run : RunData
        The run.
    digital : Digital
        The sampled protocol asked for.

    Raises
    ------
    InputError
        Naming ``digital.period`` or ``digital.delay``.
    """
    k_steps, _ = digital.steps(float(run.t[-1]))
    nd_ = len(run.labels) * run.theta.size
    if nd_ <= MOMENTS_MAX_ND:  # larger runs report no exact curves (the aggregate report)
        check_digital_moments(nd_, digital.delay, k_steps)


def write_report(
    directory: str | Path, interactive: bool = False, digital: Digital | None = None
) -> Path:
    """`ntc report DIR`: DIR/report.html (``report_interactive.html`` with
    ``interactive``) for one simulation output directory.

    Parameters
    ----------
    directory
        A simulation output directory (written by ``ntc simulate``).
    interactive
        Embed the figures as SVG with per-agent toggles instead of PNG images (the page
        stays one self-contained file either way).
    digital
        The sampled protocol to report (period h, delay D) instead of the run's own
        ``digital`` block, or for a continuous run.

    Returns
    -------
    Path
        The written report.

    Raises
    ------
    InputError
        A missing or unreadable output file (named), or a period and delay the run's
        report cannot show (:func:`check_report_digital`).
    """
    run = load_run(directory)
    if digital is not None:  # certified and reported for this period and delay
        check_report_digital(run, digital)  # before the certificate and figures are written
        params = {**run.summary["parameters"], "digital": digital.to_dict()}
        run = replace(run, summary={**run.summary, "parameters": params}, asked=digital)
    # the interactive page has its own name: it never replaces the static report
    name = "report_interactive.html" if interactive else "report.html"
    check_output_file(run.path / name, "report")  # before the certificate and figures
    scen = run.summary.get("scenario") or str(run.path)
    title = f"Run {Path(scen).stem}"
    if len(run.labels) > AGGREGATE_ABOVE:  # quantiles over the agents, not one curve each
        section, _ = aggregate_section(run, run.path / "figures", title, "run", run.path)
    else:
        section, _ = run_section(
            run, run.path / "figures", title, "run", run.path, interactive=interactive
        )
    out = run.path / name
    write_html(
        out,
        render(
            "report.html",
            title=f"ntc-design report: {Path(scen).name}",
            sections=[section],
            toc=section.toc()["children"],
            interactive=interactive,
        ),
    )
    return out


__all__ = [
    "RUN_FIGURES",
    "RunData",
    "RunFacts",
    "check_report_digital",
    "load_run",
    "render_run",
    "run_facts",
    "write_report",
]
