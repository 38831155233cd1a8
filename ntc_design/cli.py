"""The ``ntc`` command line: parse, call the library, print. Bad input: one line on
stderr, exit code 2."""

from __future__ import annotations

import json
import re
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from .cli_base import (
    ARGS,
    DelayOpt,
    FileArg,
    JsonOpt,
    PeriodOpt,
    app,
    digital_option,
    flags_named,
    json_text,
    parse_vector,
)
from .errors import AssumptionWarning, InputError, interrupt_seen, note_interrupt, one_line
from .outputs import exit_process

if TYPE_CHECKING:
    from .design import ProtocolDesign, SwitchingDesign

# Everything else loads in the command that needs it: `ntc --help` and a mistyped option
# answer without importing NumPy, SciPy, SymPy or the library's layers.


@app.command(epilog="Example: ntc check examples/g1.yaml")
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
    from .design import (
        SUMMARY_ABOVE,
        structure_report,
        structure_summary,
        structure_tables,
        summary_table,
    )
    from .loader import load
    from .model import SwitchingTopology, Topology
    from .reports.terminal import print_table

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


@app.command("design", epilog="Example: ntc design examples/g1.yaml --theta 1,2,-1")
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
    import numpy as np

    from .design import SwitchingDesign, design
    from .loader import load
    from .outputs import check_output_file
    from .reports.terminal import out, print_table
    from .timevarying import ExpressionTopology

    th = parse_vector(theta, "--theta")
    if out_path is not None:
        check_output_file(out_path, "--out", (".mat", ".json"))
    top = load(file)
    if isinstance(top, ExpressionTopology):
        from .timevarying import TimeVaryingDesign

        with flags_named(theta="--theta"):
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
        with flags_named(theta="--theta"):
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


def _exit_if_uninformed(modes: list, out_path: Path | None) -> None:
    """Exit 1 when a design (a mode's, or None for the only one) has no informed agent:
    L_B = L then does not depend on δ and nothing draws the agents to θ, so Lemma 1
    designs nothing (one line on stderr, with the fix)."""
    if not modes:
        return
    where = (
        f"mode(s) {', '.join(one_line(str(k)) for k in modes)} have"
        if modes != [None]
        else "the network has"
    )
    kept = f"; nothing written to {one_line(str(out_path))}" if out_path is not None else ""
    print(
        f"not designed: {where} no informed agent (U is empty), so L_B = L does not depend "
        "on δ and Lemma 1 cannot bring the agents to θ; an antagonistic edge (A_ij negative "
        f"definite) into an agent makes it informed{kept}",
        file=sys.stderr,
    )
    raise typer.Exit(1)


def _write_design(res: ProtocolDesign | SwitchingDesign, path: Path) -> list[Path]:
    """The design as .mat (one file per mode for a switching set: NAME_MODE.mat) or .json;
    the files written."""
    from .design import SwitchingDesign
    from .outputs import write_atomic

    if path.suffix.lower() == ".json":
        return [write_atomic(path, json_text(res.to_dict()) + "\n")]
    if isinstance(res, SwitchingDesign):
        from .outputs import check_output_file

        # one file per mode, the mode's name made a safe file name; all checked first
        paths = [
            path.with_name(f"{path.stem}_{re.sub(r'[^A-Za-z0-9._-]', '_', str(k))}{path.suffix}")
            for k in res.modes
        ]
        if len(set(paths)) != len(paths):
            raise InputError(f"--out: two modes give the same file name beside {path.name}")
        for q in paths:
            check_output_file(q, "--out")
        for q, d in zip(paths, res.modes.values(), strict=True):
            d.to_mat(q)
        return paths
    res.to_mat(path)
    return [path]


@app.command(epilog="Example: ntc generate --n 1000 --d 3 --out runs/net.npz")
def generate(
    n: Annotated[int, typer.Option("--n", help="Number of agents N (>= 2).")],
    out_path: Annotated[
        Path, typer.Option("--out", help="Output file: .npz (compact), .json or .yaml.")
    ],
    d: Annotated[int, typer.Option("--d", help="State dimension d.")] = 3,
    seed: Annotated[int, typer.Option(help="Seed (numpy SeedSequence).")] = 0,
    family: Annotated[
        str, typer.Option(help="random, ring, grid, small-world or scale-free.")
    ] = "random",
    p_negative: Annotated[float, typer.Option(help="Probability of an antagonistic edge.")] = 0.3,
    as_json: JsonOpt = False,
) -> None:
    """Write a random directed signed matrix-weighted network that satisfies Assumption 2
    by construction (seeded; see ntc_design.generate)."""
    from .generate import TOPOLOGY_SUFFIXES, random_network, write_topology
    from .outputs import check_output_file
    from .reports.terminal import Progress, out

    check_output_file(out_path, "--out", TOPOLOGY_SUFFIXES)  # before the work
    with Progress("ntc generate") as prog:
        prog.stage(f"drawing {n} agents ({family})")
        top = random_network(n, d, seed, family, p_negative=p_negative)
        prog.stage(f"writing {len(top.weights)} edges to {one_line(str(out_path))}")
        write_topology(top, out_path)
    if as_json:
        doc = {"file": str(out_path), "name": top.name, "N": top.n, "d": top.dim}
        print(json_text({**doc, "edges": len(top.weights), "seed": seed, "family": family}))
        return
    out.print(f"wrote {out_path}: {top.name}, N = {top.n}, d = {top.dim}, {len(top.weights)} edges")


@app.command(epilog="Example: ntc gain '1/(1+t)'")
def gain(
    expr: Annotated[str, typer.Argument(help="c(t), e.g. '1/(1+t)' or '(1+t)^(-1/3)'.")],
    as_json: JsonOpt = False,
) -> None:
    """Decide the gain conditions of Theorems 1-4 for c(t). Exit 0 when the conditions of
    some theorem hold (mean square at least), 1 when none do or they are undetermined."""
    from .gain import analyse_gain
    from .reports.terminal import print_table

    analysis = analyse_gain(expr)
    print(json_text(analysis.to_dict())) if as_json else print_table(analysis.table())
    if analysis.mean_square is not True:  # no theorem's conditions on c hold (as certify)
        raise typer.Exit(1)


@app.command(
    epilog="Example: ntc certify examples/g1.yaml --theta 1,2,-1 --gain '1/(1+t)' --out runs/g1.json"
)
def certify(
    file: FileArg,
    theta: Annotated[str, typer.Option(help="Target consensus state θ ≠ 0, e.g. 1,2,-1.")],
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
    as_json: JsonOpt = False,
) -> None:
    """Certify the Lemma 1 design (Lyapunov equation + LMI, or per-mode L_B + L_Bᵀ ≻ 0 and a
    common P), re-verify it exactly, and say which of Theorems 1-4 is guaranteed.
    With --period (and --delay) the sampled protocol is certified too: the step k₀ from
    which it contracts in mean square and the sampled analogues of the theorems.
    Exit 0 when one is (the sampled ones with --period; or, without --gain, when the
    certificate is valid), 1 when none is; --out is written only when the certificate is
    valid."""
    from .certify import certify as run
    from .certify import write_certificate
    from .design.digital import Digital
    from .loader import load
    from .outputs import check_output_file
    from .schedule import gain_from_option

    th = parse_vector(theta, "--theta")
    if rate_method not in ("lyapunov", "lmi"):  # before any work
        raise InputError(f"--rate-method: expected lyapunov or lmi, got {rate_method!r}")
    sampled = digital_option(period, delay)
    if out_path is not None:
        check_output_file(out_path, "--out")
    with warnings.catch_warnings(), flags_named(theta="--theta"):
        warnings.simplefilter("ignore", AssumptionWarning)  # printed in the verdicts
        res = run(
            load(file),
            th,
            margin,
            gain_from_option(gain, "--gain"),
            noise_sigma=noise_sigma,
            noise_f=noise_f,
            rate_method=rate_method,
            digital=Digital.from_document(sampled) if sampled is not None else None,
        )
    doc = res.to_dict()  # every step that can fail runs before anything is written
    written = out_path is not None and res.verification.valid
    if out_path is not None and written:
        write_certificate(res.certificate, out_path)
    if as_json:
        print(json_text(doc))
    else:
        _print_certify(res, out_path if written else None)
    if out_path is not None and not written:
        print(f"not proven: no certificate written to {out_path}", file=sys.stderr)
    if not res.proven:
        if out_path is None or written:
            print("not proven: no theorem is guaranteed", file=sys.stderr)
        raise typer.Exit(1)


def _print_certify(res, written: Path | None) -> None:
    from .reports.terminal import out, print_table

    for t in res.tables():  # the HTML report and notebooks show the same tables
        print_table(t)
    if written is not None:
        out.print(f"certificate written to {written} (re-check with: ntc verify {written})")


@app.command(epilog="Example: ntc verify runs/g1.json --topology examples/g1.yaml --theta 1,2,-1")
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
    from .certify import verify_file
    from .loader import load
    from .reports.terminal import print_verification

    top = load(topology) if topology is not None else None
    th = parse_vector(theta, "--theta") if theta is not None else None
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


@app.command(epilog="Example: ntc robust examples/g1.yaml --theta 1,2,-1 --radius 0.05")
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
    from .certify import verify, write_certificate
    from .certify.kinds.robust import robust_certificate
    from .certify.robust import check_radius, check_robust_work
    from .certify.robust import robust as run
    from .certify.robust_are import RICCATI_MAX_ND
    from .design import ProtocolDesign, design
    from .loader import load
    from .model import Topology
    from .outputs import check_output_file
    from .reports.terminal import print_table

    th = parse_vector(theta, "--theta")
    rho = check_radius(radius)
    if out_path is not None:
        check_output_file(out_path, "--out")
    top = load(file)
    if not isinstance(top, Topology):
        raise InputError(
            f"{file}: robust needs one fixed topology (not a switching or time-varying one)"
        )
    dense = top.nd <= RICCATI_MAX_ND
    if out_path is not None and not dense:
        raise InputError(
            f"--out: a robust certificate is issued up to Nd = {RICCATI_MAX_ND} (this network: "
            f"Nd = {top.nd}); without --out the sparse bounds are proven and printed"
        )
    doc, ver = None, None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the certificate says whether Assumption 2 holds
        with flags_named(theta="--theta"):
            des = design(top, th, margin, thresholds=False)
    assert isinstance(des, ProtocolDesign)  # a fixed topology's design
    check_robust_work(des)  # the estimate, before the work (a warning line past a minute)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solver chatter; the verification decides
        rep = run(des, rho)
        if dense and rep.proofs.get("margin") is not None:
            doc = robust_certificate(rep)
            ver = verify(json.loads(json.dumps(doc)), "the robust certificate")
    ok = ver.valid if ver is not None else rep.margin.lower is not None
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
            res = doc["results"] if doc is not None else {}
            kept = [
                f"{label} {res[key]['lower']:.6g}"
                for key, label, shown in (("decay", "α", rep.decay.lower),
                                          ("margin", "ρ", rep.margin.lower))
                if key in res and shown is not None and res[key]["lower"] < shown
            ]  # fmt: skip
            if kept:
                print(f"the certificate carries {', '.join(kept)} (what it re-proves); the "
                      "printed lower ends are proven here by block dominance")  # fmt: skip
        elif dense:
            print("no certificate: the search for one proved no margin radius (a bound "
                  "above, if any, is proven in this process only)")  # fmt: skip
        else:
            print(f"proven here (sparse dominance); no certificate above Nd = {RICCATI_MAX_ND}")
        if out_path is not None and ok:
            print(f"wrote {out_path}")
    if not ok:
        raise typer.Exit(1)


@app.command(
    "export",
    epilog="Example: ntc export examples/scenarios/g1_deadline.yaml --lang c --out runs/g1-c "
    "--period 0.1 --delay 1",
)
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
    sigma: Annotated[
        float | None,
        typer.Option("--sigma", help="Additive noise σ (default: the file's, else 0.4)."),
    ] = None,
    noise_f: Annotated[
        float | None, typer.Option("--f", help="f(x) = f·x (default: the file's, else 0.3).")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Write the code each agent runs (the digital protocol of a certified design) as
    dependency-free C99 or Python, with a replay program that reads x(0), K and the
    normals on stdin and prints x_K, bit for bit as the toolkit's replay. The design is
    certified (or the certificate verified) first; nothing is written when it is not."""
    from .export.run import export

    res = export(file, lang, out_dir, period, delay, gain, sigma, noise_f)
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
                }
            )
        )
        return
    for note in res.source.notes:
        print(note)
    print(
        f"exported {law.name} ({law.n} agents, d = {law.dim}, {len(law.modes)} mode(s); "
        f"h = {law.digital.period:g}, D = {law.digital.delay}, c(t) = {law.gain.label}) "
        f"as {lang} to {res.folder}: {', '.join(res.files)}"
    )
    print(f"build and check: see {res.folder / 'README.txt'}")


@app.command(epilog="Example: ntc examples --copy my-examples")
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
    from .paper import copy_examples, example_files, example_path

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


# the commands that run a study register after the ones above (``ntc --help`` order)
from . import cli_runs  # noqa: E402, F401


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line on stderr (``warning: ...``), without the source line."""
    print(f"warning: {one_line(str(message))}", file=sys.stderr)


def _argv(args: list[str]) -> list[str]:
    """A value that starts with a minus sign (``ntc gain "-1/(1+t)"``, ``--gain "-1"``)
    is a value, not an option. Option values are taken as they are by click; a positional
    one (a minus sign followed by a digit, ``(`` or ``.``) is moved after ``--`` at the end
    (every command has at most one such positional argument)."""
    if "--" in args:
        return list(args)
    rest: list[str] = []
    negative: list[str] = []
    for k, tok in enumerate(args):
        prev = args[k - 1] if k else ""
        looks_negative = len(tok) > 1 and tok[0] == "-" and (tok[1].isdigit() or tok[1] in "(.")
        takes_value = prev.startswith("-") and "=" not in prev and prev not in _FLAGS
        (negative if looks_negative and not takes_value else rest).append(tok)
    return rest + ["--", *negative] if negative else rest


_FLAGS = {"--json", "--help", "--version"}  # options that take no value


def _error_exit(message: str, args: list[str], code: int = 2) -> int:
    """An error exit: ``error: ...`` on stderr, and with --json ``{"error": ...}`` on
    stdout too (a script reading stdout gets JSON for every error exit: bad input, memory,
    an unreadable file, an interrupt, an internal error). Returns ``code`` (2: bad
    input)."""
    print(f"error: {message}", file=sys.stderr)
    if "--json" in args[: args.index("--")] if "--" in args else "--json" in args:
        try:
            print(
                json.dumps({"ok": False, "error": message, "exit_code": code}, ensure_ascii=False)
            )
        except OSError:  # stdout itself is gone (a closed pipe): stderr has said it
            pass
    return code


def main(argv: list[str] | None = None) -> None:
    """Run the CLI: one line ``error: ...`` on stderr for every user error (exit 2), for
    an interrupt (exit 130); warnings as ``warning: ...`` lines.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).
    """
    import os
    import warnings

    try:  # typer >= 0.20 vendors click; its exceptions are what the commands raise
        from typer._click import exceptions as click
    except ImportError:  # pragma: no cover - older typer
        from click import exceptions as click  # type: ignore[no-redef]

    args = sys.argv[1:] if argv is None else list(argv)
    ARGS[:] = args
    # figures are written to files: no display, whatever the machine has (a GUI backend
    # would open windows or fail without one); set before matplotlib is ever imported
    os.environ.setdefault("MPLBACKEND", "Agg")
    warnings.showwarning = _warning_line
    warnings.simplefilter("ignore", RuntimeWarning)  # numerical trouble is checked, not warned
    warnings.simplefilter("once", AssumptionWarning)  # one line per network, not per mode
    code = 0
    try:
        try:
            rv = app(args=_argv(args), prog_name="ntc", standalone_mode=False)
        except click.NoArgsIsHelpError as exc:
            print(exc.format_message())
            code = 2
        else:
            code = rv if isinstance(rv, int) else 0
            if code == 0 and interrupt_seen():  # Ctrl-C came, its exception was lost
                code = 130
            if code == 130:  # typer turns KeyboardInterrupt into Exit(130)
                _error_exit("interrupted", args, 130)
    except InputError as exc:
        code = _error_exit(one_line(str(exc)), args)
    except click.UsageError as exc:
        where = f" (see: {exc.ctx.command_path} --help)" if exc.ctx is not None else ""
        code = _error_exit(f"{one_line(exc.format_message())}{where}", args)
    except click.ClickException as exc:  # e.g. an unreadable file argument
        code = _error_exit(one_line(exc.format_message()), args)
    except (KeyboardInterrupt, typer.Abort):
        code = _error_exit("interrupted", args, 130)
    except MemoryError:
        code = _error_exit(
            "out of memory: the input asks for more memory than the machine has", args
        )
    except BrokenPipeError:
        code = 1
    except OSError as exc:  # a file or folder the user named cannot be read or written
        where = f"{one_line(str(exc.filename))!r}: " if exc.filename else ""
        code = _error_exit(f"{where}{exc.strerror or exc.__class__.__name__}", args)
    except Exception as exc:  # a bug: one line, the traceback with NTC_DEBUG=1
        if os.environ.get("NTC_DEBUG"):
            raise
        code = _error_exit(
            f"internal error ({exc.__class__.__name__}: {one_line(str(exc))[:300]}); "
            "re-run with NTC_DEBUG=1 for the traceback",
            args,
            1,
        )
    sys.exit(code)


def run() -> None:
    """The ``ntc`` program: :func:`main`, then an exit that skips the interpreter's
    teardown of its modules (about 0.3 s once Numba and SciPy are loaded). The exit
    handlers still run and the streams are flushed first; with another thread or a child
    process still alive, or under a profiler or tracer, the ordinary exit is taken.
    """
    import signal

    # Ctrl-C raises KeyboardInterrupt as always, and is noted (errors.note_interrupt): one
    # raised inside a finaliser is dropped by Python, the note is not. An ignored SIGINT
    # (a background job) stays ignored, as Python leaves it.
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, note_interrupt)
    try:
        main()
        code: str | int | None = 0
    except SystemExit as exc:
        code = exc.code
    exit_process(code)
