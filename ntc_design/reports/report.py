"""Self-contained HTML reports (``ntc report DIR``), rendered from the Jinja2 templates in
``templates/`` with autoescaping: a table of contents, the design with its matrices, the
coupling figure (decay rate and λ_min(L_B + L_Bᵀ) against δ), the certificate, gain and
theorem verdicts, a convergence table (fitted against predicted decay exponent), the
figures (PNG inline; PNG, SVG and PDF linked), final errors, links to every data file, the
parameters as a table and a re-run command."""

from __future__ import annotations

import base64
import csv
import io
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape
from markupsafe import Markup, escape

from ntc_design.certify.format import package_versions

from ..certify import certify, verify_file, write_certificate
from ..certify.theorems import theorem_table
from ..design import ProtocolDesign, SwitchingDesign
from ..errors import InputError, require_number, require_positive
from ..files import parse_topology
from ..model import SwitchingTopology, Topology
from ..outputs import check_output_file, write_atomic
from ..rows import Table as RowsTable
from ..rows import fmt
from ..simulate.result import MeanSquareBand
from . import figures

REQUIRED = ("summary.json", "ms_error.csv", "paths.npz")


@dataclass
class RunData:
    """A simulation run as ``ntc report`` reads it: summary.json, the curves table and the
    paths, checked against each other once by :func:`load_run`."""

    path: Path
    summary: dict
    t: np.ndarray
    table: dict[str, np.ndarray]
    npz: dict[str, np.ndarray]

    @property
    def labels(self) -> list[str]:
        """The agent labels, as text."""
        return [str(a) for a in self.npz["labels"]]

    @property
    def theta(self) -> np.ndarray:
        """The target θ of the run."""
        return np.asarray(self.summary["parameters"]["theta"], dtype=float)

    def topology(self) -> Topology | SwitchingTopology:
        """The run's topology (or switching set), rebuilt from summary.json.

        Returns
        -------
        Topology or SwitchingTopology

        Raises
        ------
        InputError
            A malformed topology or schedule, or a run over a time-varying topology.
        """
        where = f"{self.path}/summary.json"
        tops = {}
        for k, v in self.summary["topologies"].items():
            if not isinstance(v, dict):
                raise InputError(
                    f"{where}: topologies.{k}: expected a topology; {_rerun(self.path)}"
                )
            tops[k] = Topology.from_data(parse_topology(v, f"{where}: topologies.{k}"))
        sched = self.summary["parameters"].get("schedule")
        if sched is not None:  # a switching run: [{mode, duration}, ...] over the topologies
            ok = isinstance(sched, list) and all(
                isinstance(s, dict)
                and isinstance(s.get("mode"), str)
                and isinstance(s.get("duration"), (int, float))
                and not isinstance(s.get("duration"), bool)
                for s in sched
            )
            if not ok:
                raise InputError(
                    f"{where}: parameters.schedule: expected a list of {{mode, duration}}; "
                    f"{_rerun(self.path)}"
                )
            return SwitchingTopology(
                tops,
                tuple((s["mode"], float(s["duration"])) for s in sched),
                source=f"{where}: parameters",
            )
        if len(tops) != 1:
            raise InputError(
                f"{self.path}: a run over a topology given as functions of t has no single topology to certify"
            )
        return next(iter(tops.values()))

    def ms(self, kind: str) -> np.ndarray | None:
        """The per-agent E‖x_i − θ‖² curves of one kind.

        Parameters
        ----------
        kind : str
            ``mc``, ``lo``, ``hi`` or ``exact``: the column prefix in ms_error.csv.

        Returns
        -------
        numpy.ndarray or None
            Shape (save times, N); None when the run has no such curves.
        """
        cols = [f"{kind}_{a}" for a in self.labels]
        if not all(c in self.table for c in cols):
            return None
        return np.column_stack([self.table[c] for c in cols])


MAX_TEXT_BYTES = 256 * 2**20  # summary.json / ms_error.csv larger than this are refused
#: A report draws every agent (topology figure, per-agent curves and tables): refused above.
REPORT_MAX_AGENTS = 200
NPZ_KEYS = ("t", "paths", "labels", "theta")


def _rerun(d: Path) -> str:
    return f"re-run: ntc simulate SCENARIO --out {d}"


def _read_text(path: Path, d: Path) -> str:
    try:
        if path.stat().st_size > MAX_TEXT_BYTES:
            raise InputError(f"{path}: larger than {MAX_TEXT_BYTES // 2**20} MiB; {_rerun(d)}")
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: unreadable ({exc.__class__.__name__}); {_rerun(d)}") from None


def _read_npz(path: Path, d: Path) -> dict[str, np.ndarray]:
    """paths.npz, refusing a corrupt, empty or oversized (decompression bomb) archive."""
    import zipfile

    from ..errors import format_bytes
    from ..simulate.budget import MEMORY_FRACTION, available_memory

    try:
        with zipfile.ZipFile(path) as zf:
            size = sum(i.file_size for i in zf.infolist())
        limit = MEMORY_FRACTION * available_memory()
        if size > limit:
            raise InputError(
                f"{path}: unpacks to {format_bytes(size)}, more than {format_bytes(limit)}; {_rerun(d)}"
            )
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in NPZ_KEYS if k not in z.files]
            if missing:
                raise InputError(f"{path}: missing array {missing[0]!r}; {_rerun(d)}")
            npz = {k: z[k] for k in z.files}
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - BadZipFile, EOFError, zlib.error, ValueError...
        raise InputError(
            f"{path}: not a readable .npz archive ({exc.__class__.__name__}); {_rerun(d)}"
        ) from None
    if npz["paths"].ndim != 3 or npz["t"].ndim != 1 or npz["labels"].ndim != 1:
        raise InputError(f"{path}: arrays of the wrong shape; {_rerun(d)}")
    if npz["labels"].dtype.kind not in "UO" and npz["labels"].size:
        raise InputError(f"{path}: labels are not text; {_rerun(d)}")
    for k in ("t", "paths", "theta"):
        if npz[k].dtype.kind not in "fiu":
            raise InputError(f"{path}: array {k!r} is not numeric; {_rerun(d)}")
    return npz


def load_run(directory: str | Path) -> RunData:
    """Read a simulation output directory; name what is missing or malformed and how to
    make it again.

    Parameters
    ----------
    directory : str or Path
        A folder written by ``ntc simulate --out``.

    Returns
    -------
    RunData

    Raises
    ------
    InputError
        One line naming the file and what is wrong.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InputError(f"{d}: no such directory; make it with: ntc simulate SCENARIO --out {d}")
    for name in REQUIRED:
        if not (d / name).is_file():
            raise InputError(f"{d}: missing {name}; make it with: ntc simulate SCENARIO --out {d}")
    try:
        summary = json.loads(_read_text(d / "summary.json", d))
    except (json.JSONDecodeError, RecursionError, ValueError) as exc:
        raise InputError(
            f"{d}/summary.json: not valid JSON ({exc.__class__.__name__}); {_rerun(d)}"
        ) from None
    if not isinstance(summary, dict):
        raise InputError(f"{d}/summary.json: expected a mapping; {_rerun(d)}")
    for key in ("parameters", "topologies"):
        if not isinstance(summary.get(key), dict) or not summary[key]:
            raise InputError(f"{d}/summary.json: missing field '{key}'; {_rerun(d)}")
    for key in ("theta", "margin", "gain"):
        if key not in summary["parameters"]:
            raise InputError(f"{d}/summary.json: missing field 'parameters.{key}'; {_rerun(d)}")
    rows = list(csv.reader(io.StringIO(_read_text(d / "ms_error.csv", d))))
    if len(rows) < 2:
        raise InputError(f"{d}/ms_error.csv: no data rows; {_rerun(d)}")
    header = rows[0]
    if not header or header[0] != "t" or len(set(header)) != len(header):
        raise InputError(
            f"{d}/ms_error.csv: the header must start with 't' (unique columns); {_rerun(d)}"
        )
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(
                f"{d}/ms_error.csv: line {k} has {len(r)} values, the header {len(header)}; {_rerun(d)}"
            )
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:]])
    except ValueError:
        raise InputError(f"{d}/ms_error.csv: a value is not a number; {_rerun(d)}") from None
    if not np.all(np.isfinite(data[:, 0])) or np.any(np.diff(data[:, 0]) <= 0):
        raise InputError(f"{d}/ms_error.csv: times are not finite and increasing; {_rerun(d)}")
    npz = _read_npz(d / "paths.npz", d)
    if npz["t"].shape[0] != data.shape[0]:
        raise InputError(
            f"{d}: paths.npz has {npz['t'].shape[0]} save times, ms_error.csv {data.shape[0]} "
            f"(files from different runs?); {_rerun(d)}"
        )
    table = {h: data[:, k] for k, h in enumerate(header)}
    run = RunData(d, summary, table["t"], table, npz)
    _check_run(run)
    return run


def _check_run(run: RunData) -> None:
    """The fields of summary.json and paths.npz that the report reads, checked against each
    other before anything is written (certificate, figures, report.html): a damaged run, or
    files from different runs, is one line naming the file and the field rather than a
    TypeError or a failed reshape halfway through the figures."""
    d = run.path
    where = f"{d}/summary.json"

    def bad(field: str, what: str, file: str = where) -> InputError:
        return InputError(f"{file}: {field}: {what}; {_rerun(d)}")

    p = run.summary["parameters"]
    theta = p["theta"]
    if not isinstance(theta, list) or not theta:
        raise bad("parameters.theta", "expected a list of numbers")
    try:
        for k, v in enumerate(theta):
            require_number(f"parameters.theta[{k}]", v)
        require_positive("parameters.margin", p["margin"])
    except InputError as exc:
        raise InputError(f"{where}: {exc}; {_rerun(d)}") from None
    if not isinstance(p["gain"], str):
        raise bad("parameters.gain", "expected an expression in t (text)")
    from ..gain import parse_gain

    try:
        parse_gain(p["gain"])
    except InputError as exc:  # "gain: ..." from the parser
        raise InputError(f"{where}: parameters.{exc}; {_rerun(d)}") from None
    for key in ("noise", "time_varying"):
        if p.get(key) is not None and not isinstance(p[key], dict):
            raise bad(f"parameters.{key}", "expected a mapping")
    for key in ("run", "sample_paths"):
        if not isinstance(run.summary.get(key, {}), dict):
            raise bad(key, "expected a mapping")
    if not isinstance(run.summary.get("scenario", ""), str):
        raise bad("scenario", "expected a file name")
    sp_ = run.summary.get("sample_paths", {})
    if sp_.get("stored"):
        window = sp_.get("late_window")
        numbers = [sp_.get(k) for k in SPREAD_KEYS] + (window if isinstance(window, list) else [])
        if not (isinstance(window, list) and len(window) == 2) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in numbers
        ):
            raise bad("sample_paths", f"expected numbers {', '.join(SPREAD_KEYS)}, late_window")
    top = run.topology()
    labels = [str(a) for a in top.labels]
    npz_file = f"{d}/paths.npz"
    if run.labels != labels:
        raise bad(
            "labels",
            f"{len(run.labels)} agents {_few(run.labels)}, summary.json's topology has "
            f"{len(labels)} {_few(labels)} (files from different runs?)",
            npz_file,
        )
    if len(theta) != top.dim:
        raise bad("parameters.theta", f"{len(theta)} numbers, the topology has d = {top.dim}")
    if np.asarray(run.npz["theta"]).shape != (top.dim,):
        raise bad(
            "theta", f"shape {np.asarray(run.npz['theta']).shape}, expected ({top.dim},)", npz_file
        )
    paths = run.npz["paths"]
    if paths.size and paths.shape[1:] != (run.t.size, top.n * top.dim):
        raise bad(
            "paths",
            f"shape {paths.shape}, expected (paths, {run.t.size} save times, N·d = "
            f"{top.n * top.dim})",
            npz_file,
        )
    if run.ms("mc") is None and run.ms("exact") is None:
        raise bad(
            "header",
            f"no mc_<agent> or exact_<agent> column for every agent {_few(labels)}",
            f"{d}/ms_error.csv",
        )
    if run.ms("mc") is not None and not all(
        f"mc_{a}_{b}" in run.table for a in labels for b in ("lo", "hi")
    ):
        raise bad("header", "an mc_<agent> column without its _lo and _hi", f"{d}/ms_error.csv")


SPREAD_KEYS = (
    "late_fluctuation_mean",
    "late_fluctuation_max",
    "final_error_norm_mean",
)


def _few(labels: list[str]) -> str:
    shown = ", ".join(labels[:4]) + (", …" if len(labels) > 4 else "")
    return f"[{shown}]"


# ------------------------------------------------------------------------- rendering


@dataclass(frozen=True)
class Table:
    """A table for the templates: header texts and rows of cells; a cell is text or a
    mapping ``{"matrix": rows}``, ``{"verdict": bool|None, "text": ...}``, ``{"mark": bool}``,
    ``{"code": ...}``, ``{"lines": [...]}`` or ``{"href": ..., "text": ...}``."""

    headers: tuple[str, ...]
    rows: list
    id: str | None = None


@dataclass(frozen=True)
class Figure:
    id: str
    caption: str
    alt: str
    png_b64: str
    width_px: int
    links: tuple[tuple[str, str], ...]
    svg: Markup | None = None


@dataclass(frozen=True)
class RunSection:
    key: str
    title: str
    rerun: str
    designs: list
    coupling: Figure
    certificate: Table
    checks: Table
    gain: Table
    gain_figure: Figure | None
    theorems: Table
    ms_figure: Figure
    convergence_note: str
    convergence: Table
    topology_figures: list
    path_figures: list
    final: Table
    spread: str
    data_links: list
    parameters: Table
    versions: Table
    interactive_agents: list

    def toc(self) -> dict:
        sub = [
            ("design", "Protocol design"),
            ("coupling", "Coupling δ"),
            ("certificate", "Certificate"),
            ("gain", "Gain"),
            ("theorems", "Theorems"),
            ("convergence", "Convergence"),
            ("figures", "Topology and sample paths"),
            ("final", "Final errors"),
            ("data", "Data files"),
            ("parameters", "Parameters"),
        ]
        return {
            "id": self.key,
            "title": self.title,
            "children": [{"id": f"{self.key}-{k}", "title": t} for k, t in sub],
        }


ENV = Environment(
    loader=PackageLoader("ntc_design.reports", "templates"),
    autoescape=select_autoescape(["html"]),
    undefined=StrictUndefined,
    trim_blocks=True,
    lstrip_blocks=True,
)


def render(template: str, **context) -> str:
    """Render one of the package's Jinja2 templates (autoescaped)."""
    return ENV.get_template(template).render(**context)


def write_html(path: Path, text: str) -> None:
    """Write atomically (:func:`ntc_design.outputs.write_atomic`: no temporary file is left
    when the write fails)."""
    write_atomic(path, text, option="report")


def matrix(m, digits: int = 4) -> dict:
    """A matrix cell: entries rounded for display (−0 shown as 0)."""
    a = np.atleast_2d(np.asarray(m, dtype=float))
    return {"matrix": [[f"{v + 0.0:.{digits}g}" for v in row] for row in a]}


def rel(path: Path, base: Path) -> str:
    """A link from a report in ``base`` to ``path`` (relative, forward slashes)."""
    return Path(os.path.relpath(path, base)).as_posix()


def _figure(
    saved: figures.SavedFigure,
    fid: str,
    caption: str,
    base: Path,
    width_in: float,
    interactive: bool = False,
) -> Figure:
    links = tuple((f.upper(), rel(p, base)) for f, p in saved.files.items())
    svg = None
    if interactive and "svg" in saved.files:
        text = saved.files["svg"].read_text(encoding="utf-8")
        svg = Markup(text[text.index("<svg") :])  # our own matplotlib output
    return Figure(
        fid,
        caption,
        caption,
        base64.b64encode(saved.png).decode(),
        int(round(width_in * 110)),
        links,
        svg,
    )


# --------------------------------------------------------------------------- sections


def _modes(des: ProtocolDesign | SwitchingDesign) -> dict[str, ProtocolDesign]:
    if isinstance(des, SwitchingDesign):
        return dict(des.modes)
    return {des.topology.name or "topology": des}


def html_table(t: RowsTable, table_id: str | None = None) -> Table:
    """A presentation table (:mod:`ntc_design.rows`) for the templates: the same labels
    and cells as the terminal, each cell rendered once by :meth:`ntc_design.rows.Cell.html`.

    Parameters
    ----------
    t : ntc_design.rows.Table
        The table.
    table_id : str, optional
        An ``id`` for the table element.

    Returns
    -------
    Table
    """
    rows = [tuple(Markup(c.html()) for c in r) for r in t.rows]
    rows += [
        (Markup(f'<span class="note">note: {escape(n)}</span>'), *[""] * (len(t.columns) - 1))
        for n in t.notes
    ]
    return Table(t.columns, rows, table_id)


def design_tables(des: ProtocolDesign | SwitchingDesign) -> tuple[list, dict]:
    """The Lemma 1 parameters as one table with a column per mode (the design's own
    table); and the designs' dict forms."""
    docs = {name: d.to_dict() for name, d in _modes(des).items()}
    return [("", html_table(des.table()))], docs


def certificate_tables(res, cert_path: Path, base: Path) -> tuple[Table, Table, dict]:
    """Write the certificate, re-verify it from the file; summary and checks tables."""
    write_certificate(res.certificate, cert_path)
    ver = verify_file(cert_path)
    r = res.certificate["results"]
    rows = [
        (
            "certificate",
            {
                "href": rel(cert_path, base),
                "text": f"{cert_path.name} ({res.certificate['kind']}, {res.certificate['digest'][:23]}…)",
            },
        ),
        (
            "re-verified from the file (no SDP solver)",
            {
                "verdict": ver.valid,
                "text": f"— {ver.method}, {sum(c.ok for c in ver.checks)}/{len(ver.checks)} checks",
            },
        ),
    ]
    rows += list(html_table(res.results_table()).rows)
    checks = html_table(ver.table())
    return Table(("property", "result"), rows), checks, {"valid": ver.valid, "results": r}


# ------------------------------------------------------------------------ convergence


def fitted_exponent(t: np.ndarray, y: np.ndarray, t_from: float) -> float | None:
    """p in y ≈ K (1+t)^(−p), least squares of log y on log(1+t) over t >= t_from."""
    sel = (t >= t_from) & (y > 0) & np.isfinite(y)
    if sel.sum() < 5:
        return None
    slope = np.polyfit(np.log1p(t[sel]), np.log(y[sel]), 1)[0]
    return float(-slope)


def predicted_exponent(gain: str, rate: float) -> tuple[float | None, str]:
    """The decay exponent p of E‖x − 1⊗θ‖² ~ t^(−p) that the moment equations give for a
    gain c ~ t^(−β) (the second-moment ODE of the error dynamics, Niu & Wu, eq. (12):
    dΣ/dt = −c(L_BΣ + ΣL_Bᵀ) + c²(…) with a constant additive-noise term): β for
    0 < β < 1 (Σ follows c/2 times the noise covariance), min(1, 2α) for β = 1 (α the decay
    rate of −L_B), 0 for β > 1 (∫c < ∞: the error stalls) and 0 when c does not tend to 0.
    None when c is not a power of t."""
    import sympy as sp

    from ..gain import T, limit_at_infinity, parse_gain

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
    gain = run.summary["parameters"]["gain"]
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


def _flatten(prefix: str, v, out: list) -> None:
    if isinstance(v, dict) and v:
        for k, w in v.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), w, out)
    else:
        out.append((prefix, v))


def parameter_table(p: dict, n: int, d: int, run_info: dict) -> Table:
    rows = []
    for k, v in p.items():
        if k == "initial" and isinstance(v, list) and len(v) == n * d:
            rows.append(("initial x(0) (agents × d)", matrix(np.reshape(v, (n, d)))))
        elif k == "schedule" and isinstance(v, list):
            rows.append(
                ("schedule (one period)", ", ".join(f"{s['mode']} {s['duration']:g}" for s in v))
            )
        elif isinstance(v, dict):
            flat: list = []
            _flatten(k, v, flat)
            rows += [(a, fmt(b) if b not in ({}, [], None) else "—") for a, b in flat]
        else:
            rows.append((k, fmt(v)))
    for k in ("steps", "path_steps", "mc_seconds", "path_steps_per_second", "exact_seconds"):
        if k in run_info:
            v = run_info[k]
            rows.append((f"run.{k}", f"{v:.4g}" if isinstance(v, float) else str(v)))
    return Table(("parameter", "value"), rows)


def _time_varying(run: RunData, p: dict, figdir: Path) -> tuple:
    """For a run over weights given as expressions of t: its time-varying certificate
    (:mod:`ntc_design.certify.time_varying`) and the figures of
    :mod:`ntc_design.reports.timevarying`; (None, []) otherwise."""
    tvp = p.get("time_varying")
    if not isinstance(tvp, dict) or not isinstance(tvp.get("topology"), dict):
        return None, []
    from ..timevarying import from_document
    from .timevarying import lambda_min_figure, weights_figure

    tv = from_document(tvp["topology"], f"{run.path}/summary.json: time_varying")
    noise = p.get("noise") or {}
    f = noise.get("f", 0.3)
    res = certify(
        tv,
        p["theta"],
        p["margin"],
        p["gain"],
        noise_sigma=float(noise.get("sigma", 0.4)),
        noise_f=f if isinstance(f, (int, float, list)) else 0.3,
    )
    r = res.certificate["results"]["time_varying"]
    return res, [
        (
            "lambda_min",
            f"λ_min(L_B(t) + L_B(t)ᵀ) over {r['domain_text']} for Lemma 1 at each t, with the "
            f"certified uniform bound Λ₂ = {r['lambda2']:.6g} (dashed) and the bound proven on "
            "each t-interval (grey).",
            lambda_min_figure(res.design, r["lambda2"], res.certificate["intervals"]),
        ),
        (
            "weights",
            "The time-varying weights (every entry) and δ(t) = C(t) + ΔC; the design tables "
            "above show t = 0.",
            weights_figure(res.design),
        ),
    ]


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
    ``base``), and the facts a summary table needs. ``fine`` optionally holds sample
    paths at a finer decimation (``{"t", "paths"}``) for the states figure."""
    base = base or run.path
    p = run.summary["parameters"]
    top = run.topology()
    if top.n > REPORT_MAX_AGENTS:  # per-agent figures and tables: refused, not half-drawn
        raise InputError(
            f"{run.path}: N = {top.n} agents; the report draws every agent (figures, tables) "
            f"up to N = {REPORT_MAX_AGENTS}: use summary.json and ms_error_long.csv, and "
            "ntc certify for the certificate"
        )
    res = certify(top, p["theta"], p["margin"], p["gain"])
    designs, des_docs = design_tables(res.design)
    # weights as expressions of t: the design tables show t = 0, the certificate and the
    # theorems are the time-varying ones (uniform Λ₂), with two figures over a period
    tv_res, tv_figs = _time_varying(run, p, figdir)
    cert_res = tv_res or res
    cert_tab, checks, cert = certificate_tables(cert_res, run.path / "certificate.json", base)
    doc = cert_res.to_dict()
    labels = run.labels
    segs = top.segments(float(run.t[-1])) if isinstance(top, SwitchingTopology) else None
    modes = _modes(res.design)

    def fig(f, stem: str, caption: str, width: float, fid: str) -> Figure:
        return _figure(figures.save(f, figdir / stem), fid, caption, base, width, interactive)

    coupling = fig(
        figures.coupling_figure([figures.coupling_curve(m) for m in modes.values()]),
        f"{key}_coupling",
        "Decay rate −max Re λ(−L_B(δ)) (left) and λ_min(L_B + L_Bᵀ)(δ) (right) against the "
        "coupling δ, with B_i and the informed agents fixed: Lemma 1's δ (circle) is sufficient, "
        "δ_H and δ_S (triangle, square) are the exact thresholds and the star the best δ.",
        figures.TWO_COLUMN,
        f"{key}-fig-coupling",
    )
    topo = [
        fig(
            figures.topology_figure(m.topology, m.informed, m.B),
            f"{key}_topology_{name}",
            f"Ĝ of {name}: the agents and, outside their circle, vertex 0 (the external signal "
            "x0) with its edges to the informed agents.",
            figures.ONE_COLUMN,
            f"{key}-fig-topology-{name}",
        )
        for name, m in modes.items()
    ]
    for stem, caption, f in tv_figs:
        topo.append(fig(f, f"{key}_{stem}", caption, figures.TWO_COLUMN, f"{key}-fig-{stem}"))
    if isinstance(top, SwitchingTopology):
        topo.append(
            fig(
                figures.schedule_figure(top.schedule),
                f"{key}_schedule",
                f"The switching schedule, one period of {top.period:g}; it repeats up to "
                f"T = {run.t[-1]:g}.",
                figures.ONE_COLUMN,
                f"{key}-fig-schedule",
            )
        )
    mc = None
    if run.ms("mc") is not None:
        mc = MeanSquareBand(
            mean=run.ms("mc"),
            lo=np.column_stack([run.table[f"mc_{a}_lo"] for a in labels]),
            hi=np.column_stack([run.table[f"mc_{a}_hi"] for a in labels]),
        )
    exact = run.ms("exact")
    what = " and ".join(
        w
        for w, x in (("Monte Carlo (solid, 95% band)", mc), ("exact moments (dashed)", exact))
        if x is not None
    )
    ms_fig = fig(
        figures.ms_error_figure(
            run.t, mc, exact, labels, segments=segs, gid=key if interactive else None
        ),
        f"{key}_ms_error",
        f"E‖x_i − θ‖² per agent, {what}"
        + ("; the strip under the axis shows the active mode." if segs else "."),
        figures.TWO_COLUMN,
        f"{key}-fig-ms",
    )
    paths_fig = []
    if fine is not None and fine["paths"].size:
        t_p, path0, dec = fine["t"], fine["paths"][0], "a finer decimation than the statistics"
    elif run.npz["paths"].size:
        t_p, path0, dec = run.npz["t"], run.npz["paths"][0], "the statistics' save times"
    else:
        t_p = None
    if t_p is not None:
        paths_fig.append(
            fig(
                figures.states_figure(
                    t_p, path0, run.theta, labels, segments=segs, gid=key if interactive else None
                ),
                f"{key}_states",
                f"One sample path: the states of all agents per dimension, θ dashed; stored at "
                f"{dec} ({t_p.size} points).",
                figures.TWO_COLUMN,
                f"{key}-fig-states",
            )
        )
    gain_fig = None
    try:
        gain_fig = fig(
            figures.gain_figure(p["gain"], float(run.t[-1])),
            f"{key}_gain",
            "The gain c(t) and its integrals ∫c (infinite: the cumulative effect needed for "
            "consensus) and ∫c² (finite: the noise energy that almost-sure consensus needs).",
            figures.TWO_COLUMN,
            f"{key}-fig-gain",
        )
    except InputError:
        pass  # a callable gain: nothing to plot
    conv_note, conv, conv_facts = convergence_table(run, mc, exact, _average_rate(res.design, top))
    rows = []
    for k, a in enumerate(labels):
        rows.append(
            (
                a,
                fmt(float(mc.mean[-1, k]), 5) if mc is not None else "—",
                f"[{fmt(float(mc.lo[-1, k]), 5)}, {fmt(float(mc.hi[-1, k]), 5)}]"
                if mc is not None and np.isfinite(mc.lo[-1, k])
                else ("none (fewer than 2 paths)" if mc is not None else "—"),
                fmt(float(exact[-1, k]), 5) if exact is not None else "—",
                fmt(float(exact[0, k]), 5)
                if exact is not None
                else (fmt(float(mc.mean[0, k]), 5) if mc is not None else "—"),
            )
        )
    final = Table(
        ("agent", f"MC E‖x_i − θ‖² at t = {run.t[-1]:g}", "95% band", "exact", "at t = 0"), rows
    )
    sp_ = run.summary.get("sample_paths", {})
    spread = ""
    if sp_.get("stored"):
        spread = (
            f"Stored sample paths ({sp_['stored']}): over t ∈ [{sp_['late_window'][0]:g}, {sp_['late_window'][1]:g}] "
            f"‖x(t) − 1⊗θ‖ still moves by {sp_['late_fluctuation_mean']:.4f} on average (max {sp_['late_fluctuation_max']:.4f}); "
            f"at t = {run.t[-1]:g} its mean is {sp_['final_error_norm_mean']:.4f} with spread {fmt(sp_['final_error_norm_spread'])}."
        )
    data = [
        (f.name, rel(f, base))
        for f in sorted(run.path.iterdir())
        if f.is_file() and f.suffix in (".json", ".csv", ".npz") and not f.name.startswith(".")
    ]
    data += [
        (f.name, rel(f, base))
        for f in sorted(figdir.glob(f"{key}_*"))
        if f.suffix in (".png", ".svg", ".pdf")
    ]
    versions = package_versions()
    section = RunSection(
        key=key,
        title=title,
        rerun=rerun
        or f"ntc simulate {run.summary.get('scenario', 'SCENARIO')} --out {run.path} && ntc report {run.path}",
        designs=designs,
        coupling=coupling,
        certificate=cert_tab,
        checks=checks,
        gain=html_table(cert_res.gain.table())
        if cert_res.gain is not None
        else Table(("condition", "holds", "reason"), [("no gain was given", "—", "")]),
        gain_figure=gain_fig,
        theorems=html_table(theorem_table(cert_res.theorems)),
        ms_figure=ms_fig,
        convergence_note=conv_note,
        convergence=conv,
        topology_figures=topo,
        path_figures=paths_fig,
        final=final,
        spread=spread,
        data_links=data,
        parameters=parameter_table(p, len(labels), run.theta.size, run.summary.get("run", {})),
        versions=Table(("package", "version"), sorted(versions.items())),
        interactive_agents=[(a, f"{key}-ag{i}") for i, a in enumerate(labels)]
        if interactive
        else [],
    )
    facts = {
        "designs": des_docs,
        "certificate": cert,
        "gain": doc["gain"],
        "theorems": doc["theorems"],
        "exact_first": exact[0].sum() if exact is not None else None,
        "exact_last": exact[-1].sum() if exact is not None else None,
        "exact_curve": exact.sum(axis=1) if exact is not None else None,
        "mc_last": mc.mean[-1].sum() if mc is not None else None,
        "sample_paths": sp_,
        "T": float(run.t[-1]),
        "convergence": conv_facts,
    }
    return section, facts


def write_report(directory: str | Path, interactive: bool = False) -> Path:
    """`ntc report DIR`: DIR/report.html for one simulation output directory.

    Parameters
    ----------
    directory
        A simulation output directory (``ntc simulate --out``).
    interactive
        Embed the figures as SVG with per-agent toggles instead of PNG images (the page
        stays one self-contained file either way).

    Returns
    -------
    Path
        The written report.

    Raises
    ------
    InputError
        A missing or unreadable output file (named).
    """
    run = load_run(directory)
    check_output_file(run.path / "report.html", "report")  # before the certificate and figures
    scen = run.summary.get("scenario") or str(run.path)
    title = f"Run {Path(scen).stem}"
    section, _ = run_section(
        run, run.path / "figures", title, "run", run.path, interactive=interactive
    )
    out = run.path / "report.html"
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
    "RunData",
    "load_run",
    "write_report",
]
