"""The commands about a network and its certificates (check, design, generate, gain,
certify, verify, robust, export, examples): parse, call the library, print. They are
registered on the app, in ``ntc --help`` order, by :mod:`ntc_design.cli.program`."""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, cast

import typer

from ..choices import Language, RateMethod, choices
from ..errors import AssumptionWarning, InputError, blame, one_line, require_number
from .app import (
    DelayOpt,
    FileArg,
    JsonOpt,
    LossOpt,
    LossPolicyOpt,
    PeriodOpt,
    check_digital_flags,
    check_theta_length,
    digital_option,
    json_text,
    parse_vector,
    renamed_flag,
    require_file,
)
from .flags import FLAGS, flags_named, flags_of

if TYPE_CHECKING:
    from ..protocol import ProtocolDesign, SwitchingDesign

# Everything else loads in the command that needs it: `ntc --help` and a mistyped option
# answer without importing NumPy, SciPy, SymPy or the library's layers.


def check(
    file: FileArg,
    full: Annotated[
        bool,
        typer.Option(
            "--full",
            help="Every edge and agent even above 50 agents (default there: a summary).",
            metavar="",
        ),
    ] = False,
    as_json: JsonOpt = False,
) -> None:
    """Edge classes, U, Ω_i, in-degree-domination and the Assumption 2 decomposition
    (above 50 agents a summary, unless --full)."""
    require_file(file)  # trivially bad input before the library's layers load
    from ..model import SwitchingTopology, Topology
    from ..model.load import load
    from ..protocol import (
        SUMMARY_ABOVE,
        structure_report,
        structure_summary,
        structure_tables,
        summary_table,
    )
    from ..reports.terminal import print_table

    loaded = load(file)
    # a time-varying topology's classes are fixed: its structure at any t (no SymPy import
    # for the other kinds)
    top = loaded if isinstance(loaded, (Topology, SwitchingTopology)) else loaded.structure
    modes = top.modes if isinstance(top, SwitchingTopology) else {None: top}
    reports = {}
    for k, m in modes.items():
        title = f"mode {k}" if k is not None else m.name or str(file)
        if full or m.n <= SUMMARY_ABOVE:
            reports[k] = structure_report(m)
            if not as_json:
                for t in structure_tables(reports[k], title):
                    print_table(t)
        else:
            reports[k] = structure_summary(m)
            if not as_json:
                print_table(summary_table(reports[k], title))
    if as_json:
        print(json_text({"modes": reports} if None not in reports else reports[None]))


def design_cmd(
    file: FileArg,
    theta: Annotated[str, typer.Option(help="Target consensus state θ ≠ 0, e.g. 1,2,-1.")],
    margin: Annotated[float, typer.Option(help="ΔC > 0: δ = C + ΔC.")] = 0.1,
    thresholds: Annotated[
        bool | None,
        typer.Option(
            "--thresholds/--no-thresholds",
            help="Compute the critical couplings (default: up to Nd = 30000).",
            metavar="",
        ),
    ] = None,
    out_path: Annotated[
        Path | None,
        typer.Option(
            "--out",
            help="Also write the design: .mat (L_B sparse, delta, k1, x0, B, informed "
            "1-based, labels; for MATLAB/Simulink) or .json.",
        ),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Lemma 1 protocol parameters with the critical couplings δ_H and δ_S. Exit 1 when
    nothing can be designed (no informed agent: no antagonistic edge into any agent)."""
    from ..io.outputs import check_output_file

    th = parse_vector(theta, "--theta")  # trivially bad input before the library loads
    require_file(file)
    check_theta_length(file, th)
    if out_path is not None:
        check_output_file(out_path, "--out", (".mat", ".json"))
    import numpy as np

    from ..model.load import load
    from ..model.timevarying import ExpressionTopology
    from ..protocol import SwitchingDesign, design
    from ..reports.terminal import out, print_table

    top = load(file)
    if isinstance(top, ExpressionTopology):
        from ..protocol.timevarying import TimeVaryingDesign

        with flags_named("design", "theta"):
            tv = TimeVaryingDesign(top, np.asarray(th, dtype=float), margin)
        if as_json:
            print(json_text(tv.to_dict()))
        else:
            print_table(tv.table(f"{top.name or file}: Lemma 1 at every instant"))
        _exit_if_uninformed([] if tv.structure.informed else [None], out_path)
        return
    with warnings.catch_warnings():
        # a failing Assumption 2 is printed in the table (FAILS + violations)
        warnings.simplefilter("ignore", AssumptionWarning)
        with flags_named("design", "theta"):
            res: ProtocolDesign | SwitchingDesign = design(top, th, margin, None, thresholds)
    modes = res.modes if isinstance(res, SwitchingDesign) else {None: res}
    uninformed = [k for k, d in modes.items() if not d.has_informed_agents]
    # nothing designed is nothing written
    written = _write_design(res, out_path) if out_path is not None and not uninformed else []
    if as_json:
        print(json_text(res.to_dict()))
    elif isinstance(res, SwitchingDesign):
        for k, d in res.modes.items():
            print_table(d.table(f"mode {k}: Lemma 1 design, θ = {th}, ΔC = {margin:g}"))
    else:
        name = res.topology.name or str(file)
        print_table(res.table(f"{name}: Lemma 1 design, θ = {th}, ΔC = {margin:g}"))
    if written and not as_json:
        out.print(f"wrote {', '.join(one_line(str(p)) for p in written)}", soft_wrap=True)
    _exit_if_uninformed(uninformed, out_path)


def _exit_if_uninformed(modes: list, out_path: Path | None, verb: str = "designed") -> None:
    """Exit 1 when a design (a mode's, or None for the only one) has no informed agent:
    L_B = L then does not depend on δ and nothing draws the agents to θ, so Lemma 1
    designs nothing (one line on stderr, with the fix)."""
    from ..protocol.lemma1 import no_informed_agent_text

    if not modes:
        return
    kept = f"; nothing written to {one_line(str(out_path))}" if out_path is not None else ""
    print(f"not {verb}: {no_informed_agent_text(modes)}{kept}", file=sys.stderr)
    raise typer.Exit(1)


def _write_design(res: ProtocolDesign | SwitchingDesign, path: Path) -> list[Path]:
    """The design as .mat (one file per mode for a switching set: NAME_MODE.mat) or .json;
    the files written."""
    from ..io.outputs import write_atomic
    from ..protocol import SwitchingDesign

    if path.suffix.lower() == ".json":
        return [write_atomic(path, json_text(res.to_dict()) + "\n")]
    if isinstance(res, SwitchingDesign):
        from ..io.outputs import check_output_file

        # one file per mode, the mode's name made a safe file name; all checked first
        paths = [
            path.with_name(f"{path.stem}_{re.sub(r'[^A-Za-z0-9._-]', '_', str(k))}{path.suffix}")
            for k in res.modes
        ]
        if len(set(paths)) != len(paths):
            raise InputError(f"two modes give the same file name beside {path.name}", field="--out")
        for q in paths:
            check_output_file(q, "--out")
        for q, d in zip(paths, res.modes.values(), strict=True):
            d.to_mat(q)
        return paths
    res.to_mat(path)
    return [path]


def generate(
    out_path: Annotated[
        Path, typer.Option("--out", help="Output file: .npz (compact), .json or .yaml.")
    ],
    agents: Annotated[
        int | None, typer.Option("--agents", help="Number of agents N (>= 2; required).")
    ] = None,
    dim: Annotated[int | None, typer.Option("--dim", help="State dimension d (default 3).")] = None,
    old_n: Annotated[
        int | None, typer.Option("--n", hidden=True, help="Deprecated: --agents.")
    ] = None,
    old_d: Annotated[
        int | None, typer.Option("--d", hidden=True, help="Deprecated: --dim.")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed (numpy SeedSequence).")] = 0,
    family: Annotated[
        str, typer.Option(help="random, ring, grid, small-world or scale-free.")
    ] = "random",
    p_negative: Annotated[float, typer.Option(help="Probability of an antagonistic edge.")] = 0.3,
    as_json: JsonOpt = False,
) -> None:
    """Write a random directed signed matrix-weighted network that satisfies Assumption 2
    by construction (seeded; see ntc_design.model.generate)."""
    # the names of the other commands' help (N agents, dimension d); --n/--d still work
    n_flag, n = renamed_flag("--n", old_n, "--agents", agents)
    d_flag, d = renamed_flag("--d", old_d, "--dim", dim)
    if n is None:
        raise InputError("missing: the number of agents N (e.g. --agents 1000)", field="--agents")
    d = 3 if d is None else d
    from ..io.outputs import check_output_file
    from ..model.generate import TOPOLOGY_SUFFIXES, random_network, write_topology
    from ..reports.terminal import Progress, out

    check_output_file(out_path, "--out", TOPOLOGY_SUFFIXES)  # before the work
    with Progress("ntc generate") as prog:
        prog.stage(f"drawing {n} agents ({family})")
        with flags_named("generate", "n", "d", "family", "p_negative", "seed", n=n_flag, d=d_flag):
            top = random_network(n, d, seed, family, p_negative=p_negative)
        prog.stage(f"writing {len(top.weights)} edges to {one_line(str(out_path))}")
        write_topology(top, out_path)
    if as_json:
        doc = {"file": str(out_path), "name": top.name, "N": top.n, "d": top.dim}
        print(json_text({**doc, "edges": len(top.weights), "seed": seed, "family": family}))
        return
    out.print(f"wrote {out_path}: {top.name}, N = {top.n}, d = {top.dim}, {len(top.weights)} edges")


def gain(
    expr: Annotated[str, typer.Argument(help="c(t), e.g. '1/(1+t)' or '(1+t)^(-1/3)'.")],
    as_json: JsonOpt = False,
) -> None:
    """Decide the gain conditions of Theorems 1-4 for c(t). Exit 0 when the conditions of
    some theorem hold (mean square at least), 1 when none do or they are undetermined."""
    from ..gain.conditions import analyse_gain
    from ..reports.terminal import print_table

    analysis = analyse_gain(expr)
    print(json_text(analysis.to_dict())) if as_json else print_table(analysis.table())
    if analysis.mean_square is not True:  # no theorem's conditions on c hold (as certify)
        raise typer.Exit(1)


def certify(
    file: FileArg,
    theta: Annotated[
        str | None,
        typer.Option(help="Target consensus state θ ≠ 0, e.g. 1,2,-1 (a scenario's by default)."),
    ] = None,
    margin: Annotated[float, typer.Option(help="ΔC > 0: δ = C + ΔC.")] = 0.1,
    gain: Annotated[
        str | None,
        typer.Option(
            help="Control gain c(t), e.g. '1/(1+t)', or a schedule CSV (t,c rows with a "
            "'# tail:' line, as ntc tune --schedule optimal writes)."
        ),
    ] = None,
    out_path: Annotated[
        Path | None, typer.Option("--out", help="Write the certificate (JSON) here.")
    ] = None,
    noise_sigma: Annotated[
        float,
        typer.Option(
            help="Additive noise intensity σ_ji on every edge (the time-varying certificate "
            "uses it as p̄ in Assumption 3)."
        ),
    ] = 0.4,
    noise_f: Annotated[
        float,
        typer.Option(
            help="State-dependent noise f(x) = f·x, so σ̄ = |f| in Assumption 1 (the "
            "time-varying certificate uses it for t₀ of μ₂)."
        ),
    ] = 0.3,
    rate_method: Annotated[
        str,
        typer.Option(
            help="One topology's decay rate: lyapunov (the shifted Lyapunov equation, no SDP "
            "solver) or lmi (the LMI bisection with Clarabel)."
        ),
    ] = "lyapunov",
    period: PeriodOpt = None,
    delay: DelayOpt = None,
    loss: LossOpt = None,
    loss_policy: LossPolicyOpt = None,
    deadline: Annotated[
        str | None,
        typer.Option(
            "--deadline",
            help="With a scenario: also prove E Σ‖x_i(T) − θ‖² <= B_T and its peak over "
            "[0, T] (--deadline T overrides the scenario's T; bare --deadline uses it).",
        ),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Certify the Lemma 1 design (Lyapunov equation + LMI, or per-mode L_B + L_Bᵀ ≻ 0 and a
    common P), re-verify it exactly, and say which of Theorems 1-4 is guaranteed.
    With --period (and --delay) the sampled protocol is certified too: the step k₀ from
    which it contracts in mean square and the sampled analogues of the theorems.
    Exit 0 when one is (the sampled ones with --period; or, without --gain, when the
    certificate is valid), 1 when none is; --out is written only when the certificate is
    valid."""
    from ..io.outputs import check_output_file

    # trivially bad input before the library loads
    th = parse_vector(theta, "--theta") if theta is not None else None
    if rate_method not in choices(RateMethod):  # before any work
        raise InputError(f"expected lyapunov or lmi, got {rate_method!r}", field="--rate-method")
    sampled = digital_option(period, delay, None, None, loss, loss_policy)
    require_file(file)
    if th is not None and deadline is None:  # a scenario (--deadline) gives its own θ
        check_theta_length(file, th)
    if out_path is not None:
        check_output_file(out_path, "--out")
    from ..certify import certify as run
    from ..certify import write_certificate
    from ..gain.schedule import gain_from_option
    from ..model.load import load
    from ..protocol.lemma1 import uninformed_modes

    scenario = (
        _deadline_scenario(file, deadline, period, delay, loss, loss_policy)
        if deadline is not None
        else None
    )
    if scenario is not None:
        top, th_file, margin, gain_opt, noise_sigma, noise_f, sampled, section = scenario
        th = th if th is not None else th_file
    else:
        if th is None:
            raise InputError("missing (the target consensus state, e.g. 1,2,-1)", field="--theta")
        top, gain_opt = load(file), gain_from_option(gain, "--gain")
    uninformed = uninformed_modes(top)
    if uninformed and as_json:  # nothing to certify: said as ntc design says it
        print(json_text({"ok": False, "proven": False, "informed": []}))
    _exit_if_uninformed(uninformed, out_path, "certified")
    with warnings.catch_warnings(), flags_named("certify", "theta"):
        warnings.simplefilter("ignore", AssumptionWarning)  # printed in the verdicts
        res = run(
            top,
            th,
            margin,
            gain_opt,
            noise_sigma=noise_sigma,
            noise_f=noise_f,
            rate_method=cast("RateMethod", rate_method),  # checked above
            digital=sampled,
        )
    figures = continuous = None
    if scenario is not None and res.verification.valid:
        from ..certify.deadline_subject import add_deadline, continuous_figures

        figures = add_deadline(res.certificate, section)
        if section["period"] is not None:  # beside the continuous design's
            continuous = continuous_figures(res.certificate)
    doc = res.to_dict()  # every step that can fail runs before anything is written
    if figures is not None:
        doc["deadline"] = figures.to_dict()
    if continuous is not None:
        doc["deadline"]["continuous"] = continuous.to_dict()
    written = out_path is not None and res.verification.valid
    if out_path is not None and written:
        write_certificate(res.certificate, out_path)
    if as_json:
        print(json_text(doc))
    else:
        _print_certify(res, out_path if written else None)
        if figures is not None and continuous is not None:
            _print_beside(figures, continuous, file, section.get("delay") or 0, section["period"])
    if out_path is not None and not written:
        print(f"not proven: no certificate written to {out_path}", file=sys.stderr)
    if not res.proven:
        if out_path is None or written:
            print("not proven: no theorem is guaranteed", file=sys.stderr)
        raise typer.Exit(1)


def _deadline_scenario(file: Path, deadline: str, period, delay, loss=None, policy=None) -> tuple:
    """``ntc certify SCENARIO --deadline [T]``: the scenario's topology, θ, ΔC, gain,
    noise, digital block (with its lossy links) and the certificate's ``subject.deadline``
    (one line naming the missing field or the flag)."""
    import numpy as np

    from ..errors import number_from_text
    from ..io.files import parse_scenario
    from ..simulate.scenario import load_scenario

    sc = parse_scenario(file)
    overrides: dict = {}
    if deadline != "":
        overrides["T"] = number_from_text(deadline, "--deadline")
        if not overrides["T"] > 0:
            raise InputError(f"T must be > 0, got {deadline!r}", field="--deadline")
    elif "T" not in sc.document:
        raise InputError(
            "missing (--deadline needs the deadline; or --deadline T)", field=f"{sc.source}: T"
        )
    if sc.document.get("initial") is None:
        raise InputError(
            "missing (--deadline needs the initial state)", field=f"{sc.source}: initial"
        )
    t_doc = overrides.get("T", sc.document.get("T"))
    sampled = digital_option(period, delay, sc.document.get("digital"), t_doc, loss, policy)
    top, spec, sc = load_scenario(file, overrides, sc, {"T": "--deadline"})
    n, d = top.n, top.dim
    lossy = None
    if sampled is not None:  # before the certificate: its own work is bounded by the same steps
        from ..certify.deadline import check_sampled_work
        from ..certify.deadline_loss import check_loss_work, loss_section
        from ..model import Topology

        p, pol = sampled.loss, sampled.policy
        if not isinstance(top, Topology) and p > 0:
            raise InputError("lossy links are modelled on one fixed topology", field="--loss")
        one = top if isinstance(top, Topology) else None
        lossy = loss_section(one, p, pol) if one is not None else None
        if lossy is None or one is None:
            check_sampled_work(n * d, float(spec.T), sampled.period, sampled.delay)
        else:  # the lossy recursion's W is the larger: its estimate alone
            check_loss_work(
                n * d, len(one.edges), d, float(spec.T), sampled.period, sampled.delay,
                lossy["policy"],
            )  # fmt: skip
    x0, _ = spec.initial_state(n, d)
    noise = spec.noise
    from ..gain.schedule import ScheduleGain

    gain_doc = (
        spec.gain
        if isinstance(spec.gain, str)
        else spec.gain.to_document()
        if isinstance(spec.gain, ScheduleGain)
        else None
    )
    if gain_doc is None:
        raise InputError(
            "--deadline needs c(t) as an expression or a schedule", field=f"{sc.source}: gain"
        )
    if callable(noise.f):
        raise InputError("--deadline needs f(x) = f·x or F x", field=f"{sc.source}: noise.f")
    f = np.asarray(noise.f, dtype=float)
    section = {
        "T": float(spec.T),
        "period": sampled.period if sampled is not None else None,
        "delay": sampled.delay if sampled is not None else 0,
        "gain": gain_doc,
        "noise": {
            "sigma": float(noise.sigma),
            "f": float(f) if f.ndim == 0 else f.tolist(),
            "sigma_edges": [
                {"from": str(a), "to": str(b), "sigma": float(v)}
                for (a, b), v in noise.sigma_edges.items()
            ],
        },
        "initial": {"x0": [float(v) for v in x0]},
    }
    if lossy is not None:  # the figures of the protocol whose messages are lost
        section["loss"] = lossy
    f_opt = float(f) if f.ndim == 0 else f
    return top, list(spec.theta), spec.margin, spec.gain, noise.sigma, f_opt, sampled, section


def _print_beside(
    sampled, continuous, file: Path, delay: int = 0, period: float | None = None
) -> None:
    """The sampled figures beside the continuous design's, and one warning line when the
    period costs more than 10 % at T or 10× at the peak, naming the longest period that
    keeps both (the search of ``ntc tune --period auto``, with its dense verification)."""
    loss = sampled.loss
    lossy = f" on lossy links (p_e <= {loss['p_max']:g}, {loss['policy']})" if loss else ""
    print(
        f"proven at T = {sampled.t_end:g}: sampled{lossy} E Σ‖x_i(T) − θ‖² <= "
        f"{sampled.ms_error_bound:.7g} (peak <= {sampled.peak_bound:.7g}); continuous design "
        f"<= {continuous.ms_error_bound:.7g} (peak <= {continuous.peak_bound:.7g})"
    )
    ratio, peak = sampled.ms_error / continuous.ms_error, sampled.peak / continuous.peak
    if loss and (ratio > 1.1 or peak > 10.0):  # the period's search knows no loss
        print(
            f"warning: the period and the loss cost {ratio:.3g}× the continuous error at T and "
            f"{peak:.3g}× its peak; find the largest tolerable loss with: ntc tune {file} "
            f"--loss auto --period {period:g}",
            file=sys.stderr,
        )
    elif ratio > 1.1 or peak > 10.0:
        print(
            f"warning: the period costs {ratio:.3g}× the continuous error at T and {peak:.3g}× "
            f"its peak; {_safe_period_text(file, sampled.t_end, delay, 10.0 * continuous.peak)}",
            file=sys.stderr,
        )


def _safe_period_text(file: Path, t_end: float, delay: int, max_peak: float) -> str:
    """The longest safe period (within 10 % at T, the peak within 10× the continuous one),
    or where to find it when the search cannot run."""
    from ..simulate.scenario import load_scenario
    from ..tune.period import longest_safe_period

    hint = f"find the longest safe period with: ntc tune {file} --period auto"
    try:
        top, spec, _ = load_scenario(file, {"T": t_end})
        safe = longest_safe_period(top, spec, t_end, delay=delay, max_peak=max_peak)
    except InputError:
        return hint
    if safe.period is None:
        return "no period keeps the error within 10 % at T and the peak within 10× (" + hint + ")"
    return (
        f"the longest safe period is h = {safe.period:.4g} (every h up to it keeps the error "
        f"within 10 % at T and the peak within 10×; ntc tune {file} --period auto)"
    )


def _print_certify(res, written: Path | None) -> None:
    from ..reports.terminal import out, print_table

    for t in res.tables():  # the HTML report and notebooks show the same tables
        print_table(t)
    if written is not None:
        out.print(f"certificate written to {written} (re-check with: ntc verify {written})")


def verify(
    cert: Annotated[Path, typer.Argument(help="A certificate file (JSON).")],
    topology: Annotated[
        Path | None,
        typer.Option(
            "--topology", help="Your topology or switching file: the certificate must be about it."
        ),
    ] = None,
    theta: Annotated[
        str | None, typer.Option(help="Your θ, e.g. 1,2,-1: the certificate must be about it.")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Re-check a certificate without an SDP solver, deriving what must be proven from its
    kind. Exit 0 valid, 1 invalid (names what fails), 2 malformed."""
    # trivially bad input before the library loads
    th = parse_vector(theta, "--theta") if theta is not None else None
    require_file(cert, "; expected a certificate (the JSON file ntc certify --out writes)")
    require_file(topology)  # (a θ of another length: not the certificate's, exit 1)
    from ..certify import verify_file
    from ..model.load import load
    from ..reports.terminal import print_verification

    top = load(topology) if topology is not None else None
    ver = verify_file(cert, top, th)
    doc = ver.to_dict()
    if as_json:
        print(json_text(doc))
    else:
        print_verification(doc)
    if not ver.valid:
        names = "; ".join(c.name for c in ver.failed)
        print(f"INVALID ({ver.method}): {names}", file=sys.stderr)
        raise typer.Exit(1)
    if not as_json:
        print(f"VALID ({ver.method}): {len(ver.checks)} checks")


def robust(
    file: FileArg,
    theta: Annotated[str, typer.Option(help="Target consensus state θ ≠ 0, e.g. 1,2,-1.")],
    radius: Annotated[
        float,
        typer.Option(help="Relative radius ρ of every weight's Loewner interval, 0 <= ρ < 1."),
    ] = 0.05,
    margin: Annotated[float, typer.Option(help="ΔC > 0: δ = C + ΔC.")] = 0.1,
    out_path: Annotated[
        Path | None, typer.Option("--out", help="Write the robust certificate (JSON) here.")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Decay, consensus-offset and margin brackets when every weight is known only within
    (1−ρ)|A| ⪯ |A'| ⪯ (1+ρ)|A|: a proven end and a realisation attaining the other. Exit 0
    when the certificate verifies, 1 when not."""
    from ..io.outputs import check_output_file

    th = parse_vector(theta, "--theta")  # trivially bad input before the library loads
    require_file(file)
    check_theta_length(file, th)
    if out_path is not None:
        check_output_file(out_path, "--out")
    from ..certify import certify_robust, write_certificate
    from ..certify.robust.are import RICCATI_MAX_ND
    from ..model import Topology
    from ..model.load import load
    from ..reports.terminal import print_table

    top = load(file)
    if out_path is not None and isinstance(top, Topology) and top.nd > RICCATI_MAX_ND:
        raise InputError(
            f"a robust certificate is issued up to Nd = {RICCATI_MAX_ND} (this network: "
            f"Nd = {top.nd}); without --out the sparse bounds are proven and printed",
            field="--out",
        )
    try:
        res = certify_robust(top, th, radius, margin)
    except InputError as exc:  # the library names fields; here they are flags
        flags = {
            **flags_of("robust", {"radius": 1, "theta": 1, "margin": 1}),
            "topology": str(file),
        }
        raise blame(exc, None, flags, advice=FLAGS["robust"]) from None
    rep, doc, ver, ok = res.report, res.certificate, res.verification, res.valid
    if out_path is not None and doc is None:
        ok = False  # asked for a certificate; none to write (the reason is printed below)
    if out_path is not None and doc is not None and ok:
        write_certificate(doc, out_path)
    if as_json:
        print(json_text({**rep.to_dict(), "valid": ok}))
    else:
        print_table(rep.table())
        if ver is not None:
            print(f"certificate: {'valid' if ver.valid else 'NOT valid'} ({ver.method})")
            results = doc["results"] if doc is not None else {}
            kept = [
                f"{label} {results[key]['lower']:.6g}"
                for key, label, shown in (("decay", "α", rep.decay.lower),
                                          ("margin", "ρ", rep.margin.lower))
                if key in results and shown is not None and results[key]["lower"] < shown
            ]  # fmt: skip
            if kept:
                print(f"the certificate carries {', '.join(kept)} (what it re-proves); the "
                      "printed lower ends are proven here by block dominance")  # fmt: skip
        elif rep.design.topology.nd <= RICCATI_MAX_ND:
            print("no certificate: the search for one proved no margin radius (a bound "
                  "above, if any, is proven in this process only)")  # fmt: skip
        else:
            print(f"proven here (sparse dominance); no certificate above Nd = {RICCATI_MAX_ND}")
        if out_path is not None and ok:
            print(f"wrote {out_path}")
    if not ok:
        raise typer.Exit(1)


def export_cmd(
    file: Annotated[
        Path, typer.Argument(help="A scenario (YAML/JSON) or a certificate (JSON) to export.")
    ],
    out_dir: Annotated[Path, typer.Option("--out", help="The folder to write (all or nothing).")],
    lang: Annotated[
        str, typer.Option(help="c (C99: ntc_protocol.h/.c, ntc_replay.c) or python.")
    ] = "c",
    period: PeriodOpt = None,
    delay: DelayOpt = None,
    gain: Annotated[
        str | None,
        typer.Option(
            help="c(t), or a schedule CSV (default: the scenario's or the certificate's, else "
            "1/(1+t))."
        ),
    ] = None,
    noise_sigma: Annotated[
        float | None,
        typer.Option(
            "--noise-sigma",
            help="Additive noise intensity σ on every edge (default: the file's, else 0.4).",
        ),
    ] = None,
    noise_f: Annotated[
        float | None,
        typer.Option("--noise-f", help="f(x) = f·x (default: the file's, else 0.3)."),
    ] = None,
    old_sigma: Annotated[
        float | None, typer.Option("--sigma", hidden=True, help="Deprecated: --noise-sigma.")
    ] = None,
    old_f: Annotated[
        float | None, typer.Option("--f", hidden=True, help="Deprecated: --noise-f.")
    ] = None,
    agent: Annotated[
        str | None,
        typer.Option(
            "--agent", help="One agent's label: its tables only (C; for its own program)."
        ),
    ] = None,
    loss: LossOpt = None,
    loss_policy: LossPolicyOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Write the code each agent runs (the digital protocol of a certified design) as
    dependency-free C99 or Python, with a replay program that reads x(0), K and the
    normals on stdin and prints x_K, bit for bit as the toolkit's replay. The design is
    certified (or the certificate verified) first; nothing is written when it is not."""
    # one vocabulary with ntc certify; the old spellings still work, with a note
    # (each value checked before the imports and the certificate)
    sigma_flag, noise_sigma = renamed_flag(
        "--sigma", old_sigma, "--noise-sigma", noise_sigma, _non_negative
    )
    f_flag, noise_f = renamed_flag("--f", old_f, "--noise-f", noise_f, require_number)
    check_digital_flags(period, delay)
    from ..protocol.loss import require_loss, require_policy

    if loss is not None:
        require_loss("--loss", loss)
    policy = require_policy("--loss-policy", loss_policy) if loss_policy is not None else None
    require_file(file)
    from ..export.run import export
    from ..export.source import ExportOptions
    from ..present.rows import counted

    try:
        options = ExportOptions(period, delay, gain, noise_sigma, noise_f, loss, policy)
        res = export(file, cast("Language", lang), out_dir, options, agent)
    except InputError as exc:  # the library's names for the noise flags
        given = {"out": out_dir, "lang": lang, "period": period, "delay": delay, "gain": gain}
        given |= {"sigma": noise_sigma, "f": noise_f, "agent": agent, "loss": loss}
        flags = flags_of("export", {**given, "policy": loss_policy}, sigma=sigma_flag, f=f_flag)
        raise blame(exc, None, flags, advice=FLAGS["export"]) from None
    law = res.source.law
    if as_json:
        print(
            json_text(
                {
                    "ok": True,
                    "folder": str(res.folder),
                    "files": list(res.files),
                    "source": res.source.source,
                    "kind": res.source.kind,
                    "period": law.digital.period,
                    "delay": law.digital.delay,
                    "gain": law.gain.label,
                    "agents": law.n,
                    "modes": [m.name for m in law.modes],
                    "loss_policy": law.policy,
                }
            )
        )
        return
    for note in res.source.notes:
        print(one_line(note))
    # the network's name and the folder are the user's text: one line, escapes shown
    print(
        f"exported {one_line(law.name)} ({counted(law.n, 'agent')}, d = {law.dim}, "
        f"{counted(len(law.modes), 'mode')}; h = {law.digital.period:g}, "
        f"D = {law.digital.delay}, c(t) = {one_line(law.gain.label)}) as {lang} to "
        f"{one_line(str(res.folder))}: {', '.join(res.files)}"
    )
    print(f"build and check: see {one_line(str(res.folder / 'README.txt'))}")


def _non_negative(flag: str, value: float) -> float:
    return require_number(flag, value, minimum=0.0)


def examples(
    copy: Annotated[
        Path | None,
        typer.Option(
            "--copy", help="Copy the examples into this folder (new, or existing and empty)."
        ),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """The bundled example files (topologies, scenarios, sweeps) and where they are
    installed; with --copy, a copy of them to edit and run (no checkout needed)."""
    from ..model.paper import copy_examples, example_files, example_path

    root = example_path()
    names = example_files()
    written = copy_examples(copy) if copy is not None else None
    if as_json:
        doc = {"folder": str(root), "files": names}
        if written is not None:
            doc["copied_to"] = str(copy)
        print(json_text(doc))
        return
    if written is None:
        print(f"the bundled examples are in {root}:")
        for name in names:
            print(f"  {name}")
        print("copy them to a folder of your own with: ntc examples --copy DIR")
    else:
        print(f"copied {len(written)} example files to {copy} (e.g. ntc check {copy}/g1.yaml)")
