"""The ``ntc`` commands that run a study and write a folder: ``simulate``, ``tune``,
``sweep``, ``report`` and ``reproduce`` (registered on :data:`ntc_design.cli.app.app`;
:mod:`ntc_design.cli.commands` imports this module after its own commands, so ``ntc --help`` lists
them in this order after those)."""

from __future__ import annotations

import contextlib
import json
import sys
import warnings
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import (
    NUMBER_TEXT,
    AssumptionWarning,
    InputError,
    blame,
    one_line,
    require_horizon,
)
from .app import (
    DelayOpt,
    JsonOpt,
    LossOpt,
    LossPolicyOpt,
    PeriodOpt,
    SchedulerOpt,
    check_digital_flags,
    command_line,
    digital_option,
    json_text,
    require_file,
)
from .flags import FLAGS, digital_flags, flags_of

OUTPUT_NOTE_BYTES = 100 * 2**20  # ntc simulate says how big its outputs will be above this


def simulate(
    scenario: Annotated[Path, typer.Argument(help="A scenario file (YAML/JSON).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")],
    workers: Annotated[
        int | None, typer.Option(help="Worker processes (default: the scenario's, or 2).")
    ] = None,
    paths: Annotated[
        int | None, typer.Option(help="Monte Carlo paths (overrides the scenario).")
    ] = None,
    horizon: Annotated[
        float | None, typer.Option("--horizon", "--T", help="Horizon T (overrides the scenario).")
    ] = None,
    dt: Annotated[
        float | None, typer.Option(help="Euler–Maruyama step (overrides the scenario).")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Monte Carlo seed (overrides the scenario).")
    ] = None,
    method: Annotated[
        str | None,
        typer.Option(
            help="Which curves: mc (Monte Carlo paths), exact (the moment equations) or both, "
            "to compare them (overrides the scenario). ntc tune's --method instead picks its "
            "one objective: auto, exact or mc."
        ),
    ] = None,
    rng: Annotated[
        str | None,
        typer.Option(
            help="Normals: xoshiro (one xoshiro256** stream per path, drawn in the compiled "
            "kernel; default) or numpy (NumPy's PCG64 per block). Overrides the scenario."
        ),
    ] = None,
    device: Annotated[
        str | None,
        typer.Option(
            help="Where the Monte Carlo paths run: cpu (default) or gpu (an NVIDIA GPU, "
            "installed with the gpu extra; the same paths to rounding). Overrides the scenario."
        ),
    ] = None,
    period: PeriodOpt = None,
    delay: DelayOpt = None,
    loss: LossOpt = None,
    loss_policy: LossPolicyOpt = None,
    scheduler: SchedulerOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Monte Carlo Euler–Maruyama and exact mean-square curves for a scenario; writes
    summary.json, ms_error.csv (wide), ms_error_long.csv (tidy) and paths.npz to --out (all
    or nothing)."""
    if horizon is not None:  # trivially bad input before the library's layers load
        require_horizon("--horizon", horizon)
    check_digital_flags(period, delay)
    require_file(scenario)
    from ..errors import format_bytes
    from ..io.files import parse_scenario
    from ..reports.terminal import Progress, out
    from ..simulate import SimulationDiverged
    from ..simulate import simulate as run
    from ..simulate.driver import device_engine
    from ..simulate.options import MonteCarlo, check_workers
    from ..simulate.scenario import (
        REPLACEABLE,
        check_output,
        load_scenario,
        result_output_bytes,
        write_outputs,
    )
    from ..sweep.engines import DaskEngine

    given = {
        "paths": paths,
        "T": horizon,
        "dt": dt,
        "seed": seed,
        "method": method,
        "rng": rng,
        "device": device,
    }
    overrides: dict[str, Any] = {k: v for k, v in given.items() if v is not None}
    sc = parse_scenario(scenario)
    # the flags over the file's block: one Digital, passed as itself (the spec checks h <= T)
    sampled = digital_option(period, delay, sc.document.get("digital"), None, loss, loss_policy)
    if sampled is not None:
        overrides["digital"] = sampled.to_dict()  # as summary.json records the command
    # the fields the flags gave (an error about one names the flag, not the file)
    flags = {**flags_of("simulate", overrides), **digital_flags(period, delay)}
    if period is None:  # the file's period: its errors name the file, not --period
        flags.pop("digital", None)
    passed = {**overrides, "digital": sampled} if sampled is not None else overrides
    top, spec, sc = load_scenario(scenario, passed, sc, flags)
    # summary.json records the command as typed: the report's re-run line keeps the overrides
    recorded = {"scenario": str(scenario), "command": command_line(), "overrides": overrides}
    if workers is not None:
        check_workers(workers, "--workers")
        spec = spec.replace(mc=MonteCarlo(**{**spec.mc.__dict__, "workers": workers}))
    check_output(out_dir)  # before the run, not after it
    if any((out_dir / name).is_file() for name in REPLACEABLE):  # said, not done in silence
        print(f"note: replacing the run in {one_line(str(out_dir))}", file=sys.stderr)
    # "" is a malformed address (refused by connect), not "no scheduler"
    dask = DaskEngine.connect(scheduler) if scheduler is not None else None
    try:  # the device before any progress line: a refusal is the only line printed
        engine = device_engine(spec, dask)
    except InputError as exc:
        if dask is not None:
            dask.close()
        raise blame(exc, sc.source, flags, values=overrides, advice=FLAGS["simulate"]) from None
    with contextlib.ExitStack() as stack, Progress("ntc simulate") as prog:
        if dask is not None:
            stack.callback(dask.close)
        prog.stage(f"simulating {scenario}")
        try:
            res = run(
                top,
                spec,
                progress=lambda done, total: prog.tick("simulating", done, total),
                engine=engine,
            )
        except InputError as exc:  # a field of the scenario, or of a flag: name it
            raise blame(exc, sc.source, flags, values=overrides, advice=FLAGS["simulate"]) from None
        except SimulationDiverged as exc:
            written = write_outputs(exc.result, out_dir, recorded)
            if as_json:
                print(
                    json_text({"ok": False, "error": str(exc), "files": [str(p) for p in written]})
                )
            print(f"error: {one_line(str(exc))}", file=sys.stderr)
            raise typer.Exit(1) from None
    study = None
    if spec.robust is not None:  # weight realisations with the nominal protocol
        from ..sweep.robust import robust_study

        with Progress("ntc simulate") as prog, warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the brackets' solver notes; every end is proven
            prog.stage(f"simulating {spec.robust.realizations} weight realisations")
            study = robust_study(top, spec, progress=lambda k, n: prog.tick("realisations", k, n))
        recorded["robust"] = study.to_dict()
    size = result_output_bytes(res, top)
    if size > OUTPUT_NOTE_BYTES and not as_json:
        print(
            f"note: writing about {format_bytes(size)} to {one_line(str(out_dir))}", file=sys.stderr
        )
    written = write_outputs(
        res, out_dir, recorded, {"robust.csv": study.csv()} if study is not None else None
    )
    st = res.stats
    if as_json:
        summary = res.summary()
        print(
            json_text(
                {
                    "ok": True,
                    "out": str(out_dir),
                    "files": [str(p) for p in written],
                    "stats": st.to_dict(),
                    "notes": list(res.notes),
                    **{
                        k: summary[k]
                        for k in (
                            "final_ms_error_mc",
                            "final_ms_error_exact",
                            "sample_paths",
                            "digital",
                        )
                        if k in summary
                    },
                }
            )
        )
        return
    rate = (
        f", {st.path_steps_per_second:.3g} path-steps/s"
        if st.path_steps_per_second is not None
        else ""
    )
    parts = []
    if st.mc_seconds is not None:
        eng = st.engine or {}
        where = f" on {eng['device']}" if eng.get("engine") == "gpu" else ""
        parts.append(f"{st.path_steps:.3g} path-steps in {st.mc_seconds:.1f} s{rate}{where}")
    if st.exact_seconds is not None:
        parts.append(f"exact moments {st.exact_seconds:.2f} s")
    out.print("; ".join(parts))
    for n in res.notes:
        out.print(f"note: {n}")
    if study is not None:
        from ..sweep.robust import study_sentence

        out.print(study_sentence(study.to_dict()))
    out.print(f"wrote {', '.join(str(p) for p in written)}", soft_wrap=True)


def tune(
    scenario: Annotated[Path, typer.Argument(help="A scenario file (YAML/JSON).")],
    horizon: Annotated[
        float | None,
        typer.Option(
            "--horizon",
            "--T",
            help="The deadline T: minimise E Σ‖x_i(T) − θ‖² (default: the scenario's T).",
        ),
    ] = None,
    schedule: Annotated[
        str,
        typer.Option(
            help="power: the family a·(b + t)^(−γ); optimal: the best schedule c(t) on "
            "[0, T] by optimal control of the exact moments, with an admissible tail after T."
        ),
    ] = "power",
    family: Annotated[
        str | None,
        typer.Option(hidden=True, help="Deprecated: --schedule power (the power family)."),
    ] = None,
    require: Annotated[
        str,
        typer.Option(
            help="Theorems the gain must satisfy: both (γ in [0.51, 1]) or mean-square "
            "(γ in [0.05, 1])."
        ),
    ] = "both",
    tune_delta: Annotated[
        bool, typer.Option("--tune-delta", help="Also tune a common coupling δ (certified).")
    ] = False,
    eps: Annotated[
        float | None, typer.Option(help="Report when each gain first reaches E Σ‖x_i − θ‖² ≤ ε.")
    ] = None,
    method: Annotated[
        str,
        typer.Option(
            help="How the objective is computed: exact (the moment equations), mc (Monte "
            "Carlo, common random numbers) or auto (exact where they apply, else mc). One "
            "objective, so no 'both' (ntc simulate --method both draws the two curves)."
        ),
    ] = "auto",
    evaluations: Annotated[int, typer.Option(help="Search budget (objective evaluations).")] = 160,
    max_gain: Annotated[
        float | None,
        typer.Option(help="--schedule optimal: the upper bound on c(t) (default 50)."),
    ] = None,
    max_peak: Annotated[
        float | None,
        typer.Option(help="--schedule optimal: keep sup_t E Σ‖x_i(t) − θ‖² <= this."),
    ] = None,
    check_paths: Annotated[
        int | None,
        typer.Option(
            help="--schedule optimal: Monte Carlo paths of the evidence (0: none; default 200)."
        ),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            help="Write tuned.yaml (the scenario with the tuned gain), tune.json, "
            "certificate.json, tune.html and its figures here (and schedule.csv).",
        ),
    ] = None,
    period: Annotated[
        str | None,
        typer.Option(
            "--period",
            help="The digital protocol's sampling period h: tune the gain for the sampled "
            "recursion; or 'auto': find the longest period whose exact error at T stays "
            "within --tolerance of the continuous design's (and its peak within --max-peak).",
        ),
    ] = None,
    delay: DelayOpt = None,
    tolerance: Annotated[
        float,
        typer.Option(
            help="--period auto / --loss auto: allowed relative excess over the continuous "
            "(or lossless sampled) error."
        ),
    ] = 0.1,
    loss: Annotated[
        str | None,
        typer.Option(
            "--loss",
            help="'auto': find the largest uniform message loss whose exact error at T, and "
            "every smaller loss's, stays within --tolerance of the lossless sampled "
            "protocol's (at --period or the scenario's digital period).",
        ),
    ] = None,
    loss_policy: LossPolicyOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Tune the gain c(t) = a·(b + t)^(−γ) (and with --tune-delta the coupling δ) to bring
    the agents closest to θ by the deadline T (the scenario's, or --horizon) under the
    scenario's noise, initial state and topology, by the exact moment equations (Monte
    Carlo with common random numbers where they do not apply); --schedule optimal finds the
    best schedule c(t) instead. Prints the tuned gain beside 1/(1 + t). Exit 0 when the
    tuned gain satisfies the required theorems and its design's certificate verifies, 1
    otherwise."""
    schedule = _schedule_option(schedule, family)
    if horizon is not None:  # trivially bad input before the library's layers load
        require_horizon("--horizon", horizon)
    value: float | None = None  # --period as a number (ASCII numerals, as every number flag)
    if period not in (None, "auto"):
        if not NUMBER_TEXT.fullmatch(period):
            raise InputError(f"expected a number or auto, got {period[:40]!r}", field="--period")
        value = float(period)
        check_digital_flags(value, delay)
    require_file(scenario)
    from ..io.files import parse_scenario
    from ..io.outputs import check_output_folder
    from ..reports.terminal import Progress, out, print_table
    from ..reports.tune import TUNE_FILES, write_tune_outputs
    from ..simulate.scenario import load_scenario
    from ..tune import options_for
    from ..tune import tune as run

    sc0 = parse_scenario(scenario)
    # the flags given (an error about one names it); the deadline defaults to the file's T
    given = {"horizon": horizon, "eps": eps, "max_gain": max_gain, "check_paths": check_paths}
    flags = {
        k: f
        for k, f in FLAGS["tune"].items()
        if not k.startswith("digital") and given.get(k, k) is not None
    }
    fields = {"horizon": "T"} if horizon is None else None
    if schedule != "optimal":
        for name, value in (("--max-gain", max_gain), ("--check-paths", check_paths)):
            if value is not None:
                raise InputError("applies to --schedule optimal", field=name)
    if loss is not None or loss_policy is not None:
        _tune_loss(
            scenario, sc0, horizon, period, delay, loss, loss_policy, tolerance, out_dir, as_json
        )
        return
    if period == "auto":
        _tune_period(scenario, sc0, horizon, delay, tolerance, max_peak, out_dir, as_json)
        return
    overrides: dict[str, Any] = {}
    if period is not None or delay is not None:
        t_doc = horizon if horizon is not None else sc0.document.get("T")
        overrides["digital"] = digital_option(value, delay, sc0.document.get("digital"), t_doc)
    top, spec, sc = load_scenario(scenario, overrides, sc0, {"digital": "--period"})
    if out_dir is not None:
        check_output_folder(out_dir, TUNE_FILES)  # before the run, not after it
    with warnings.catch_warnings(), Progress("ntc tune") as prog:
        warnings.simplefilter("ignore", AssumptionWarning)  # the certificate says it
        deadline = spec.T if horizon is None else horizon
        prog.stage(f"tuning {scenario} for T = {deadline:g}")
        opts: dict[str, Any] = dict(require=require, tune_delta=tune_delta, eps=eps)
        if schedule == "optimal":  # the defaults of the options where a flag is not given
            opts["max_peak"] = max_peak
            opts.update({k: given[k] for k in ("max_gain", "check_paths") if given[k] is not None})
        else:
            opts.update(max_evaluations=evaluations, max_peak=max_peak)
        try:
            res = run(top, spec, deadline, options_for(schedule, method, **opts), prog.stage)
        except InputError as exc:
            raise blame(exc, sc.source, flags, fields, advice=FLAGS["tune"]) from None
    doc = res.to_dict()
    written: list[str] = []
    if out_dir is not None:
        written = write_tune_outputs(res, sc, out_dir)
        doc["out"] = str(out_dir)
    if as_json:
        print(json_text(doc))
    else:
        for t in getattr(res, "tables", lambda: [res.table()])():
            print_table(t)
        if out_dir is not None:
            rest = ", ".join(f for f in written if f != "tuned.yaml")
            out.print(
                f"written to {out_dir}: tuned.yaml (check it by Monte Carlo: ntc simulate "
                f"{out_dir / 'tuned.yaml'} --out {out_dir}-mc), {rest}"
            )
    if not res.certified:
        msg = "not proven: the tuned design is not certified for the required theorems"
        print(msg, file=sys.stderr)
        raise typer.Exit(1)


def _tune_loss(
    scenario, sc0, horizon, period, delay, loss, policy, tolerance, out_dir, as_json
) -> None:
    """``ntc tune --loss auto``: the largest tolerable loss, its curve, loss.json."""
    from ..io.outputs import check_output_folder
    from ..protocol.digital import Digital
    from ..reports.terminal import Progress
    from ..simulate.scenario import load_scenario
    from ..tune.loss import largest_tolerable_loss

    if loss != "auto":
        raise InputError(
            f"expected auto (the largest tolerable loss), got {loss!r:.40}", field="--loss"
        )
    if period == "auto":
        raise InputError(
            "give a number with --loss auto (the loss is tuned at one h)", field="--period"
        )
    try:
        h = float(period) if period is not None else None
    except ValueError:
        raise InputError(f"expected a number, got {period!r:.40}", field="--period") from None
    given = sc0.document.get("digital")
    t_doc = horizon if horizon is not None else sc0.document.get("T")
    dg = digital_option(h, delay, given, t_doc, None, policy)
    if dg is None:
        if not isinstance(given, dict):
            raise InputError("needs --period (or a digital block in the scenario)", field="--loss")
        dg = Digital.from_document(given)
    top, spec, sc = load_scenario(scenario, None, sc0)
    if out_dir is not None:
        check_output_folder(out_dir, ("loss.json",))
    with warnings.catch_warnings(), Progress("ntc tune") as prog:
        warnings.simplefilter("ignore", AssumptionWarning)
        prog.stage(f"the largest tolerable loss of {scenario} ({dg.policy}, h = {dg.period:g})")
        deadline = spec.T if horizon is None else horizon
        try:
            res = largest_tolerable_loss(top, spec, deadline, dg, dg.policy, tolerance)
        except InputError as exc:  # its options are the flags; the rest is the file's
            named = flags_of("tune", dict.fromkeys(("horizon", "tolerance", "loss", "policy"), 1))
            raise blame(exc, sc.source, named, advice=FLAGS["tune"]) from None
    _write_and_show(res, out_dir, "loss.json", as_json)
    if res.loss is None:
        print("not found: no positive loss keeps the error within the tolerance", file=sys.stderr)
        raise typer.Exit(1)


def _schedule_option(schedule: str, family: str | None) -> str:
    """``--schedule``, with the deprecated ``--family`` read as its alias: ``--family
    power`` is ``--schedule power`` (the only family), anything else is refused."""
    if family is None:
        return schedule
    if family != "power":
        raise InputError(
            f"replaced by --schedule power|optimal (power is a·(b + t)^(−γ)), got {family!r}",
            field="--family",
        )
    if schedule != "power":
        raise InputError(
            f"power contradicts --schedule {schedule}; give --schedule only", field="--family"
        )
    print("note: --family is deprecated; it is --schedule power", file=sys.stderr)
    return "power"


def _tune_period(scenario, sc0, horizon, delay, tolerance, max_peak, out_dir, as_json) -> None:
    """``ntc tune --period auto``: the longest safe period, its curve, period.json."""
    from ..io.outputs import check_output_folder
    from ..reports.terminal import Progress
    from ..simulate.scenario import load_scenario
    from ..tune.period import longest_safe_period

    given = sc0.document.get("digital")
    d = delay if delay is not None else (given.get("delay", 0) if isinstance(given, dict) else 0)
    top, spec, sc = load_scenario(scenario, None, sc0)
    if out_dir is not None:
        check_output_folder(out_dir, ("period.json",))
    with warnings.catch_warnings(), Progress("ntc tune") as prog:
        warnings.simplefilter("ignore", AssumptionWarning)
        prog.stage(f"the longest safe period of {scenario} (delay D = {d})")
        deadline = spec.T if horizon is None else horizon
        try:
            res = longest_safe_period(
                top, spec, deadline, delay=d, tolerance=tolerance, max_peak=max_peak
            )
        except InputError as exc:
            # its options are the flags; the defaulted T is the file's
            given = {"horizon": horizon, "delay": 1, "tolerance": 1, "max_peak": 1, "period": 1}
            fields = {"horizon": "T"} if horizon is None else None
            named = flags_of("tune", given)
            raise blame(exc, sc.source, named, fields, advice=FLAGS["tune"]) from None
    if res.diverged is not None:  # one line, no period: nothing is safe against it
        if as_json:
            print(json_text(res.to_dict()))
        print(f"{sc.source}: {res.diverged}", file=sys.stderr)
        raise typer.Exit(1)
    _write_and_show(res, out_dir, "period.json", as_json)
    if res.period is None:
        print("not found: no period meets the bounds", file=sys.stderr)
        raise typer.Exit(1)


def sweep(
    sweep_file: Annotated[Path, typer.Argument(help="A sweep file (YAML/JSON).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")],
    scheduler: SchedulerOpt = None,
    workers: Annotated[
        int | None,
        typer.Option(help="Local processes per point without --scheduler (default: 2)."),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Design, certify and simulate every point of a sweep (a grid or a list of points over
    a base scenario); points already in --out are reused. Writes results.csv,
    results.parquet, curves.parquet and points/. Exit 1 when some point failed."""
    require_file(sweep_file)  # before the library's layers load
    from ..reports.terminal import out, sweep_progress
    from ..sweep import load_sweep, run_sweep
    from ..sweep.store import tables_module

    pd = tables_module()  # the extra, before any work
    sw = load_sweep(sweep_file)
    callback, ctx = sweep_progress()
    with ctx:
        res = run_sweep(sw, out_dir, scheduler=scheduler, workers=workers, progress=callback)

    table = pd.read_csv(out_dir / "results.csv")
    failed = table[table["error"].notna()]
    if as_json:
        print(
            json_text(
                {
                    "ok": not res.failed,
                    "out": str(out_dir),
                    "points": res.points,
                    "computed": res.computed,
                    "reused": res.reused,
                    "failed": res.failed,
                    "seconds": res.seconds,
                    "files": [str(f) for f in res.files],
                    "failures": [
                        {"point": r["point"], **{k: r[k] for k in sw.keys}, "error": r["error"]}
                        for _, r in failed.iterrows()
                    ],
                }
            )
        )
    else:
        out.print(
            f"{res.points} points in {res.seconds:.1f} s: {res.computed} computed, "
            f"{res.reused} reused, {res.failed} failed"
        )
        for _, row in failed.head(10).iterrows():
            vals = ", ".join(f"{k}={row[k]}" for k in sw.keys)
            out.print(f"  failed: {vals}: {row['error']}", soft_wrap=True)
        out.print(
            f"wrote {out_dir}/results.csv, results.parquet, curves.parquet "
            f"(report: ntc report {out_dir})",
            soft_wrap=True,
        )
    if res.failed:
        raise typer.Exit(1)


def report(
    directory: Annotated[
        Path,
        typer.Argument(help="A simulation or sweep output directory (ntc simulate/sweep --out)."),
    ],
    interactive: Annotated[
        bool,
        typer.Option(
            help="Embed SVG figures with per-agent toggles, as report_interactive.html "
            "(the static report.html is kept).",
            metavar="",
        ),
    ] = False,
    period: PeriodOpt = None,
    delay: DelayOpt = None,
    loss: LossOpt = None,
    loss_policy: LossPolicyOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Turn a simulation or sweep output directory into one self-contained report.html
    (figures also in DIR/figures). A run of the digital protocol (or --period, --delay)
    adds its digital section: the error and the peak against the period for delays 0, 1
    and 2, the certified k₀ and the continuous curve beside the sampled one; with a loss
    (--loss, or the run's digital.loss), the lossy-link section."""
    sampled = digital_option(
        period, delay, None, None, loss, loss_policy
    )  # before the library loads
    from ..reports.report import write_report
    from ..reports.sweep import is_sweep_dir, write_sweep_report
    from ..reports.terminal import out

    if is_sweep_dir(directory):
        if sampled is not None:
            raise InputError("applies to a run's report, not a sweep's", field="--period")
        out.print(f"wrote {write_sweep_report(directory)}", soft_wrap=True)
        return
    try:
        path = write_report(
            directory,
            interactive=interactive,
            digital=sampled,
        )
    except InputError as exc:  # h > T, too many steps, the delay's memory: name the flag
        raise blame(exc, None, digital_flags(period, delay)) from None
    if as_json:
        figs = sorted(str(p) for p in (path.parent / "figures").glob("*") if p.is_file())
        print(
            json_text(
                {
                    "report": str(path),
                    "certificate": str(path.parent / "certificate.json"),
                    "figures": figs,
                }
            )
        )
        return
    out.print(f"wrote {path}", soft_wrap=True)


def reproduce(
    what: Annotated[str, typer.Argument(help="What to reproduce: 'paper' (its Section 5).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")],
    t_end: Annotated[float, typer.Option("--horizon", "--T", help="Horizon T.")] = 100.0,
    paths: Annotated[int, typer.Option(help="Sample paths per run.")] = 1000,
    dt: Annotated[
        float, typer.Option(help="Euler–Maruyama step (ds for intrinsic stepping).")
    ] = 1e-3,
    stepping: Annotated[
        str, typer.Option(help="intrinsic (validated fast path) or uniform.")
    ] = "intrinsic",
    workers: Annotated[int, typer.Option(help="Worker processes.")] = 2,
    seed: Annotated[int, typer.Option(help="Monte Carlo seed.")] = 0,
    interactive: Annotated[
        bool,
        typer.Option(
            help="Embed SVG figures with per-agent toggles, as report_interactive.html "
            "(the static report.html is kept).",
            metavar="",
        ),
    ] = False,
    as_json: JsonOpt = False,
) -> None:
    """Run the paper's Section 5 end to end and write one report beside its numbers."""
    from ..reports.reproduce import reproduce_paper
    from ..reports.terminal import Progress, out

    if what != "paper":
        raise InputError(f"unknown target {what!r} (known: paper)", field="reproduce")
    from ..errors import MAX_SEED, require_int, require_positive
    from ..io.outputs import check_output_folder
    from ..simulate.options import check_workers

    # each flag checked and named before the run (not as the scenario field it becomes)
    require_positive("--horizon", t_end)
    require_positive("--paths", paths, integer=True)
    require_positive("--dt", dt)
    if stepping not in ("intrinsic", "uniform"):
        raise InputError(f"must be uniform or intrinsic, got {stepping!r}", field="--stepping")
    require_int("--seed", seed, minimum=0, maximum=MAX_SEED)
    check_workers(workers, "--workers")
    require_horizon("--horizon", t_end)
    check_output_folder(out_dir, replaceable=None)  # before a long run, not after it
    with Progress("ntc reproduce") as prog:
        try:
            path, ok, wall = reproduce_paper(
                out_dir,
                t_end,
                paths,
                dt,
                stepping,
                workers,
                seed,
                progress=prog.tick,
                status=prog.stage,
                interactive=interactive,
            )
        except InputError as exc:  # a limit a flag's value breaks: name the flag
            raise blame(exc, None, FLAGS["reproduce"]) from None
    if as_json:
        doc = json.loads((path.parent / "paper_summary.json").read_text(encoding="utf-8"))
        print(json_text({"report": str(path), "all_match": ok, "wall_seconds": wall, **doc}))
    else:
        out.print(
            f"wrote {path} in {wall:.0f} s; every row matches the paper: {'yes' if ok else 'NO'}",
            soft_wrap=True,
        )
    if not ok:
        raise typer.Exit(1)


def _write_and_show(res, out_dir: Path | None, name: str, as_json: bool) -> None:
    """A search's result (``--loss auto``, ``--period auto``): its document into
    ``out_dir/name`` when asked, then as JSON or as its table."""
    from ..io.outputs import output_folder
    from ..reports.terminal import out, print_table

    doc = res.to_dict()
    if out_dir is not None:
        with output_folder(out_dir, (name,)) as tmp:
            (tmp / name).write_text(json_text(doc) + "\n", encoding="utf-8")
        doc["out"] = str(out_dir)
    if as_json:
        print(json_text(doc))
    else:
        print_table(res.table())
        if out_dir is not None:
            out.print(f"written to {out_dir}: {name}")
