"""Self-contained HTML reports: design, certificate, gain and theorem verdicts, figures,
final errors, and every parameter needed to re-run (``ntc report DIR``)."""

from __future__ import annotations

import base64
import csv
import html
import io
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..certify import certify, verify_file, write_certificate
from ..certify.certificate import package_versions
from ..design import ProtocolDesign, SwitchingDesign
from ..errors import InputError
from ..files import parse_topology
from ..model import SwitchingTopology, Topology
from . import figures

REQUIRED = ("summary.json", "ms_error.csv", "paths.npz")


@dataclass
class RunData:
    path: Path
    summary: dict
    t: np.ndarray
    table: dict[str, np.ndarray]
    npz: dict[str, np.ndarray]

    @property
    def labels(self) -> list[str]:
        return [str(a) for a in self.npz["labels"]]

    @property
    def theta(self) -> np.ndarray:
        return np.asarray(self.summary["parameters"]["theta"], dtype=float)

    def topology(self) -> Topology | SwitchingTopology:
        tops = {
            k: Topology.from_data(parse_topology(v, f"{self.path}/summary.json: topologies.{k}"))
            for k, v in self.summary["topologies"].items()
        }
        sched = self.summary["parameters"].get("schedule")
        if sched:
            return SwitchingTopology(tops, tuple((s["mode"], float(s["duration"])) for s in sched))
        if len(tops) != 1:
            raise InputError(
                f"{self.path}: a run over a topology given as functions of t has no single topology to certify"
            )
        return next(iter(tops.values()))

    def ms(self, kind: str) -> np.ndarray | None:
        cols = [f"{kind}_{a}" for a in self.labels]
        if not all(c in self.table for c in cols):
            return None
        return np.column_stack([self.table[c] for c in cols])


MAX_TEXT_BYTES = 256 * 2**20  # summary.json / ms_error.csv larger than this are refused
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
    return RunData(d, summary, table["t"], table, npz)


# ------------------------------------------------------------------------- HTML bits


def esc(x) -> str:
    return html.escape(str(x))


def fmt(x, digits: int = 4) -> str:
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return f"{x:.{digits}f}" if 1e-3 <= abs(x) < 1e6 or x == 0 else f"{x:.{digits}g}"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(fmt(v, digits) for v in x) + "]"
    return esc(x)


def table(headers, rows, cls: str = "") -> str:
    head = "".join(f"<th>{esc(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def img(png: bytes, alt: str) -> str:
    return f'<figure><img alt="{esc(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode()}"><figcaption>{esc(alt)}</figcaption></figure>'


def verdict(v) -> str:
    return {
        True: '<span class="ok">yes</span>',
        False: '<span class="bad">no</span>',
        None: '<span class="und">undetermined</span>',
    }[v]


CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{border-bottom:2px solid #1f5fbf;padding-bottom:.2em;margin-top:2em}h3{margin-top:1.4em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}
th{background:#f0f4fa}.ok{color:#1a7f37;font-weight:600}.bad{color:#c8322d;font-weight:600}.und{color:#9a6700}
figure{margin:1em 0}img{max-width:100%;border:1px solid #eee}figcaption{font-size:.85em;color:#555}
.grid{display:flex;flex-wrap:wrap;gap:1em}.grid figure{flex:1 1 320px}pre{background:#f7f7f7;padding:.6em;overflow-x:auto;font-size:.8em}
"""

SCRIPT = """<script>
window.addEventListener('load', function () {
  var im = document.images, ok = 0;
  for (var i = 0; i < im.length; i++) { if (im[i].complete && im[i].naturalWidth > 0) ok++; }
  document.body.setAttribute('data-images-loaded', ok + '/' + im.length);
});
</script>"""


def page(title: str, body: str) -> str:
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{esc(title)}</title>'
        f"<style>{CSS}</style></head><body><h1>{esc(title)}</h1>{body}{SCRIPT}</body></html>\n"
    )


# --------------------------------------------------------------------------- sections


def _modes(des: ProtocolDesign | SwitchingDesign) -> dict[str, ProtocolDesign]:
    if isinstance(des, SwitchingDesign):
        return dict(des.modes)
    return {des.topology.name or "topology": des}


def design_tables(des: ProtocolDesign | SwitchingDesign) -> tuple[str, dict]:
    docs = {name: d.to_dict() for name, d in _modes(des).items()}
    out = []
    for name, d in docs.items():
        th = d["thresholds"] or {}
        rows = [
            (
                "Assumption 2",
                verdict(d["assumption_holds"])
                + "".join(
                    f"<br>agent {esc(v['agent'])}: {esc(v['reason'])}" for v in d["violations"]
                ),
            ),
            ("V1 / V2", f"{fmt(d['V1'])} / {fmt(d['V2'])}"),
            ("C", fmt(d["C"])),
            ("δ = C + ΔC", fmt(d["delta"])),
            ("k1 = 1 + 2/δ", fmt(d["k1"])),
            ("x0 = k1·θ", fmt(d["x0"])),
            ("informed agents V_I = U", fmt(d["informed"])),
            *[(f"B_{a}", fmt(np.round(np.array(b), 4).tolist())) for a, b in d["B"].items()],
            ("identity residual", f"{d['identity_residual']:.2e}"),
            ("δ_H (−L_B Hurwitz for δ > δ_H)", fmt(th.get("hurwitz"), 6)),
            ("δ_S (L_B + L_Bᵀ ≻ 0 for δ > δ_S)", fmt(th.get("symmetric"), 6)),
            (
                "best decay rate / at δ",
                f"{fmt(th.get('best_rate'), 6)} / {fmt(th.get('best_rate_delta'), 6)}",
            ),
        ]
        out.append(f"<h4>mode {esc(name)}</h4>" + table(["quantity", "value"], rows))
    return "".join(out), docs


def certificate_section(res, cert_path: Path) -> tuple[str, dict]:
    write_certificate(res.certificate, cert_path)
    ver = verify_file(cert_path)
    r = res.certificate["results"]
    lines = [
        (
            "certificate",
            f"{esc(cert_path.name)} ({esc(res.certificate['kind'])}, {esc(res.certificate['digest'][:23])}…)",
        ),
        (
            "re-verified from the file (no SDP solver)",
            verdict(ver.valid)
            + f" — {esc(ver.method)}, {sum(c.ok for c in ver.checks)}/{len(ver.checks)} checks",
        ),
    ]
    if "lmi" in r:
        lines += [
            (
                "−L_B Hurwitz: Lyapunov equation",
                f"P ≻ 0 proven, residual {r['lyapunov']['residual']:.1e}",
            ),
            (
                "decay rate: LMI α vs eigenvalue bound",
                f"{r['lmi']['alpha']:.6f} vs {r['lmi']['eig_bound']:.6f} (gap {r['lmi']['gap']:.1e})",
            ),
        ]
    if "symmetric_part_min_eig" in r:
        lines.append(
            (
                "λ_min(L_B + L_Bᵀ) per mode",
                ", ".join(f"{esc(k)}: {v:.6f}" for k, v in r["symmetric_part_min_eig"].items()),
            )
        )
        cl = r["common_lyapunov"]
        lines.append(("common Lyapunov matrix", esc(cl["structure"] or "none found")))
    checks = table(
        ["claim", "holds", "proof"],
        [(esc(c.name), verdict(c.ok), esc(c.detail)) for c in ver.checks],
    )
    return table(
        ["", ""], lines
    ) + "<details><summary>all checks</summary>" + checks + "</details>", {
        "valid": ver.valid,
        "results": r,
    }


def gain_section(g: dict | None) -> str:
    if g is None:
        return "<p>No gain was given.</p>"
    names = {
        "continuous_nonnegative": "c continuous, ≥ 0 on [0, ∞)",
        "integral_diverges": "∫₀^∞ c dt = ∞",
        "tends_to_zero": "c(t) → 0",
        "square_integrable": "∫₀^∞ c² dt < ∞",
    }
    rows = [(esc(v), verdict(g[k]["value"]), esc(g[k]["reason"])) for k, v in names.items()]
    rows += [
        ("mean square (Theorems 1, 3)", verdict(g["mean_square"]), ""),
        ("almost sure (Theorems 2, 4)", verdict(g["almost_sure"]), ""),
    ]
    return f"<p>c(t) = <code>{esc(g['parsed'])}</code></p>" + table(
        ["condition", "holds", "reason"], rows
    )


def theorem_section(ths: list[dict]) -> str:
    rows = []
    for th in ths:
        why = "<br>".join(f"fails: {esc(p['premise'])} — {esc(p['detail'])}" for p in th["failing"])
        why += "<br>".join(f"undetermined: {esc(p['premise'])}" for p in th["undetermined"])
        rows.append(
            (
                f"Theorem {th['theorem']}",
                esc(th["sense"]),
                verdict(th["guaranteed"]),
                why or "all premises hold",
            )
        )
    return table(["theorem", "sense", "guaranteed", "why"], rows)


def run_section(run: RunData, figdir: Path, title: str, key: str) -> tuple[str, dict]:
    """One run's section of a report, and the facts a summary table needs."""
    p = run.summary["parameters"]
    top = run.topology()
    res = certify(top, p["theta"], p["margin"], p["gain"])
    des_html, des_docs = design_tables(res.design)  # the design certify made
    cert_html, cert = certificate_section(res, run.path / "certificate.json")
    doc = res.to_dict()
    labels = run.labels
    segs = None
    if isinstance(top, SwitchingTopology):
        segs = top.segments(float(run.t[-1]))
    figs = []
    for name, d_m in _modes(res.design).items():
        _, _, png = figures.save(
            figures.topology_figure(
                d_m.topology, d_m.informed, d_m.B, f"Ĝ of {name}: vertex 0 is x0"
            ),
            figdir / f"{key}_topology_{name}",
        )
        figs.append(img(png, f"{title}: topology {name} with the external signal (vertex 0)"))
    mc = None
    if run.ms("mc") is not None:
        mc = {
            "mean": run.ms("mc"),
            "lo": np.column_stack([run.table[f"mc_{a}_lo"] for a in labels]),
            "hi": np.column_stack([run.table[f"mc_{a}_hi"] for a in labels]),
        }
    exact = run.ms("exact")
    _, _, png = figures.save(
        figures.ms_error_figure(run.t, mc, exact, labels, f"{title}: mean-square error", segs),
        figdir / f"{key}_ms_error",
    )
    figs_ts = [img(png, f"{title}: E‖x_i − θ‖² per agent")]
    if run.npz["paths"].size:
        _, _, png = figures.save(
            figures.states_figure(
                run.npz["t"],
                run.npz["paths"][0],
                run.theta,
                labels,
                f"{title}: states of one sample path",
                segs,
            ),
            figdir / f"{key}_states",
        )
        figs_ts.append(img(png, f"{title}: states of all agents (one sample path), θ dashed"))
    rows = []
    for k, a in enumerate(labels):
        rows.append(
            (
                esc(a),
                fmt(float(mc["mean"][-1, k]), 5) if mc is not None else "—",
                f"[{fmt(float(mc['lo'][-1, k]), 5)}, {fmt(float(mc['hi'][-1, k]), 5)}]"
                if mc is not None and np.isfinite(mc["lo"][-1, k])
                else ("none (fewer than 2 paths)" if mc is not None else "—"),
                fmt(float(exact[-1, k]), 5) if exact is not None else "—",
                fmt(float(exact[0, k]), 5)
                if exact is not None
                else (fmt(float(mc["mean"][0, k]), 5) if mc is not None else "—"),
            )
        )
    final = table(
        ["agent", f"MC E‖x_i − θ‖² at t = {run.t[-1]:g}", "95% band", "exact", "at t = 0"], rows
    )
    sp = run.summary.get("sample_paths", {})
    spread = ""
    if sp.get("stored"):
        spread = (
            f"<p>Stored sample paths ({sp['stored']}): over t ∈ [{sp['late_window'][0]:g}, {sp['late_window'][1]:g}] "
            f"‖x(t) − 1⊗θ‖ still moves by {sp['late_fluctuation_mean']:.4f} on average (max {sp['late_fluctuation_max']:.4f}); "
            f"at t = {run.t[-1]:g} its mean is {sp['final_error_norm_mean']:.4f} with spread {fmt(sp['final_error_norm_spread'])}.</p>"
        )
    run_info = run.summary.get("run", {})
    params = {
        **p,
        "run": run_info,
        "versions": package_versions(),
        "rerun": f"ntc simulate {run.summary.get('scenario', 'SCENARIO')} --out {run.path}",
    }
    body = (
        f"<h2>{esc(title)}</h2>"
        f"<h3>Protocol design (Lemma 1) and critical couplings</h3>{des_html}"
        f"<h3>Certificate</h3>{cert_html}"
        f"<h3>Gain</h3>{gain_section(doc['gain'])}"
        f"<h3>Theorems</h3>{theorem_section(doc['theorems'])}"
        f"<h3>Figures</h3><div class='grid'>{''.join(figs)}</div>{''.join(figs_ts)}"
        f"<h3>Final errors</h3>{final}{spread}"
        f"<h3>Parameters, seed and versions</h3><pre>{esc(json.dumps(params, indent=1, ensure_ascii=False))}</pre>"
    )
    facts = {
        "designs": des_docs,
        "certificate": cert,
        "gain": doc["gain"],
        "theorems": doc["theorems"],
        "exact_first": exact[0].sum() if exact is not None else None,
        "exact_last": exact[-1].sum() if exact is not None else None,
        "exact_curve": exact.sum(axis=1) if exact is not None else None,
        "mc_last": mc["mean"][-1].sum() if mc is not None else None,
        "sample_paths": sp,
        "T": float(run.t[-1]),
    }
    return body, facts


def write_report(directory: str | Path) -> Path:
    """`ntc report DIR`: DIR/report.html for one simulation output directory."""
    run = load_run(directory)
    title = run.summary.get("scenario") or str(run.path)
    body, _ = run_section(run, run.path / "figures", f"Run {Path(title).stem}", "run")
    out = run.path / "report.html"
    tmp = out.with_suffix(".html.tmp")
    tmp.write_text(page(f"ntc-design report: {Path(title).name}", body), encoding="utf-8")
    tmp.replace(out)
    return out
