"""The ``ntc`` command line: parse, call the library, print. Bad input: one line on
stderr, exit code 2."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from .design import ProtocolDesign, SwitchingDesign, design, structure_report
from .errors import InputError
from .model import SwitchingTopology, load

app = typer.Typer(
    add_completion=False,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
    help="Certify, design and validate non-trivial consensus protocols on signed "
    "matrix-weighted networks with compound measurement noise.",
)
out = Console(highlight=False)

FileArg = Annotated[Path, typer.Argument(help="A topology or switching file (YAML/JSON).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Machine-readable JSON output.")]


def parse_vector(text: str, field: str) -> list[float]:
    """``"1,2,-1"`` -> ``[1.0, 2.0, -1.0]``; one clear error otherwise."""
    try:
        vals = [float(x) for x in text.replace(" ", "").strip("[]").split(",") if x != ""]
    except ValueError:
        raise InputError(f"{field}: expected comma-separated numbers, got {text!r}") from None
    if not vals:
        raise InputError(f"{field}: expected comma-separated numbers, got {text!r}")
    return vals


def _json(obj) -> str:
    def clean(x):
        if isinstance(x, float) and not math.isfinite(x):
            return None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        if isinstance(x, np.generic):
            return x.item()
        return x

    return json.dumps(clean(obj), indent=2, ensure_ascii=False)


def _fmt(x, digits: int = 4) -> str:
    if x is None:
        return "—"
    if isinstance(x, float):
        return f"{x:.{digits}f}" if abs(x) < 1e6 else f"{x:.4g}"
    return str(x)


def _labels(xs) -> str:
    return "{" + ", ".join(str(x) for x in xs) + "}"


def _print_check(rep: dict, title: str) -> None:
    out.print(f"[bold]{title}[/bold]  d = {rep['dim']}, N = {len(rep['agents'])}")
    et = Table(title="edges (j -> i carries A_ij)")
    for c in ("edge", "class"):
        et.add_column(c)
    for e in rep["edges"]:
        et.add_row(f"{e['from']} -> {e['to']}", e["class"])
    out.print(et)
    at = Table(title=f"agents (U = {_labels(rep['U'])})")
    for c in ("agent", "N_i", "N'_i", "Ω_i", "in-degree-dominated", "C_i"):
        at.add_column(c)
    for a, info in rep["per_agent"].items():
        at.add_row(
            a,
            _labels(info["in_neighbours"]),
            _labels(info["out_neighbours"]),
            _labels(info["omega"]),
            "yes" if info["in_degree_dominated"] else "no",
            _fmt(info["C_i"]),
        )
    out.print(at)
    if rep["assumption_holds"]:
        out.print(f"Assumption 2 holds: V1 = {_labels(rep['V1'])}, V2 = {_labels(rep['V2'])}")
        for a, p in rep["paths"].items():
            out.print(f"  {a} reached by the positive-negative path {' -> '.join(map(str, p))}")
    else:
        out.print("[bold red]Assumption 2 fails:[/bold red]")
        for v in rep["violations"]:
            out.print(f"  agent {v['agent']}: {v['reason']}")


def _print_design(d: dict, title: str) -> None:
    t = Table(title=f"{title}: Lemma 1 design, θ = {d['theta']}, ΔC = {d['margin']}")
    t.add_column("quantity")
    t.add_column("value")
    t.add_row("Assumption 2", "holds" if d["assumption_holds"] else "FAILS")
    t.add_row("V1 / V2", f"{_labels(d['V1'])} / {_labels(d['V2'])}")
    t.add_row("C", _fmt(d["C"]))
    t.add_row("δ = C + ΔC", _fmt(d["delta"]))
    t.add_row("k1 = 1 + 2/δ", _fmt(d["k1"]))
    t.add_row("x0 = k1·θ", "[" + ", ".join(_fmt(v) for v in d["x0"]) + "]")
    t.add_row("informed V_I = U", _labels(d["informed"]))
    for a, b in d["B"].items():
        t.add_row(f"B_{a}", str(np.round(np.array(b), 4).tolist()))
    t.add_row("identity residual", f"{d['identity_residual']:.2e}")
    th = d["thresholds"]
    if th is not None:
        t.add_row("δ_H (−L_B Hurwitz ∀δ>δ_H)", _fmt(th["hurwitz"], 6))
        t.add_row("δ_S (L_B+L_Bᵀ ≻ 0 ∀δ>δ_S)", _fmt(th["symmetric"], 6))
        t.add_row("best decay rate", _fmt(th["best_rate"], 6))
        t.add_row("δ of best rate", _fmt(th["best_rate_delta"], 6))
    out.print(t)
    for v in d["violations"]:
        out.print(f"  violation, agent {v['agent']}: {v['reason']}")
    notes = list(d["notes"]) + (list(th["notes"]) if th else [])
    for n in notes:
        out.print(f"  note: {n}")


@app.command()
def check(file: FileArg, as_json: JsonOpt = False) -> None:
    """Edge classes, U, Ω_i, in-degree-domination and the Assumption 2 decomposition."""
    top = load(file)
    if isinstance(top, SwitchingTopology):
        rep = {"modes": {k: structure_report(m) for k, m in top.modes.items()}}
        if as_json:
            print(_json(rep))
        else:
            for k, r in rep["modes"].items():
                _print_check(r, f"mode {k}")
        return
    rep = structure_report(top)
    print(_json(rep)) if as_json else _print_check(rep, top.name or str(file))


@app.command("design")
def design_cmd(
    file: FileArg,
    theta: Annotated[str, typer.Option(help="Target consensus state θ ≠ 0, e.g. 1,2,-1.")],
    margin: Annotated[float, typer.Option(help="ΔC > 0: δ = C + ΔC.")] = 0.1,
    as_json: JsonOpt = False,
) -> None:
    """Lemma 1 protocol parameters with the exact critical couplings δ_H and δ_S."""
    th = parse_vector(theta, "--theta")
    res: ProtocolDesign | SwitchingDesign = design(load(file), th, margin)
    doc = res.to_dict()
    if as_json:
        print(_json(doc))
    elif isinstance(res, SwitchingDesign):
        for k, d in doc["modes"].items():
            _print_design(d, f"mode {k}")
    else:
        _print_design(doc, res.topology.name or str(file))


def main() -> None:
    try:
        app()
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
