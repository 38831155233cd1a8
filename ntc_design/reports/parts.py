"""Pieces every run section has, whatever its size: the certificate written and
re-verified from its file, the parameters, the Monte Carlo band read back, the data links
and the fitted decay exponent."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..certify import CertifyResult, certify, verify_file, write_certificate
from ..errors import InputError
from ..gain.schedule import schedule_from_document
from ..present.rows import Cell, fmt, verdict
from ..present.rows import Table as RowsTable
from ..present.rows import matrix as rows_matrix
from ..simulate import MonteCarlo, SaveAt, SimulationDiverged, SimulationSpec, simulate
from ..simulate.result import MeanSquareBand
from .html import Table, html_table, rel
from .rundata import RunData


def certify_run(run: RunData) -> CertifyResult:
    """Certify a run's own topology, θ, margin and gain (summary.json's parameters).

    Parameters
    ----------
    run : RunData
        The run.

    Returns
    -------
    CertifyResult

    Raises
    ------
    InputError
        A malformed topology, θ or gain in the run.
    """
    spec = run.spec
    theta = spec.theta.tolist()
    if run.digital is None:
        return certify(run.topology(), theta, spec.margin, run.gain)
    noise = spec.noise
    if not noise.linear:
        raise InputError("the digital certificate needs a linear f", field=str(run.path))
    return certify(
        run.topology(),
        theta,
        spec.margin,
        run.gain,
        delta=spec.delta,
        noise_sigma=noise.sigma,
        noise_f=noise.f,
        digital=run.digital,
        sigma_edges={(str(a), str(b)): v for (a, b), v in noise.sigma_edges.items()},
    )


def certificate_tables(res, cert_path: Path, base: Path) -> tuple[Table, Table, dict]:
    """Write the certificate, re-verify it from the file; the summary and checks tables.

    Parameters
    ----------
    res : CertifyResult
        The result whose certificate is shown.
    cert_path : pathlib.Path
        Where the certificate is written.
    base : pathlib.Path
        The folder links are relative to.

    Returns
    -------
    (Table, Table, dict)
        The summary, the checks, and ``{"valid", "results"}``.

    Raises
    ------
    InputError
        The certificate cannot be written or read back.
    """
    write_certificate(res.certificate, cert_path, "report")
    ver = verify_file(cert_path)
    r = res.certificate["results"]
    head = RowsTable.build(
        "",
        ("property", "result"),
        [
            (
                "certificate",
                Cell(
                    text=f"{cert_path.name} ({res.certificate['kind']}, "
                    f"{res.certificate['digest'][:23]}…)",
                    href=rel(cert_path, base),
                ),
            ),
            (
                "re-verified from the file (no SDP solver)",
                verdict(
                    ver.valid,
                    f"— {ver.method}, {sum(c.ok for c in ver.checks)}/{len(ver.checks)} checks",
                ),
            ),
        ],
    )
    rows = html_table(head).rows + html_table(res.results_table()).rows
    checks = html_table(ver.table())
    return Table(("property", "result"), rows), checks, {"valid": ver.valid, "results": r}


def window_warning(t_from: float, t_end: float) -> str:
    """The caution a fitted decay exponent needs when its window is short: the predicted
    exponent describes t → ∞, and under one decade of 1 + t the fit sees the transient.

    Parameters
    ----------
    t_from, t_end : float
        The fitted window.

    Returns
    -------
    str
        The warning (with a leading space), or "" for a window of a decade or more.
    """
    decades = float(np.log10((1 + t_end) / (1 + t_from)))
    if decades >= 1.0:
        return ""
    return (
        # at most 0.99: a window of 0.996 decades must not read "only 1.00"
        f" The window spans only {min(round(decades, 2), 0.99):.2f} decades of 1 + t: too "
        "short for the fitted "
        "exponent to test a prediction (which describes t → ∞); take it as indicative."
    )


def fitted_exponent(t: np.ndarray, y: np.ndarray, t_from: float) -> float | None:
    """p in y ≈ K (1+t)^(−p), least squares of log y on log(1+t) over t >= t_from.

    Parameters
    ----------
    t : numpy.ndarray
        Times.
    y : numpy.ndarray
        Positive values at those times.
    t_from : float
        The start of the fitted window.

    Returns
    -------
    float or None
        p; None with fewer than five positive points in the window (a slope from fewer
        says little about a decay).
    """
    sel = (t >= t_from) & (y > 0) & np.isfinite(y)
    if sel.sum() < 5:
        return None
    slope = np.polyfit(np.log1p(t[sel]), np.log(y[sel]), 1)[0]
    return float(-slope)


def _flatten(prefix: str, v, out: list) -> None:
    if isinstance(v, dict) and v:
        for k, w in v.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), w, out)
    else:
        out.append((prefix, v))


def parameter_table(p: dict, n: int, d: int, run_info: dict) -> Table:
    """The run's parameters as a table (the initial state as a matrix for a few agents,
    as its range for many).

    Parameters
    ----------
    p : dict
        summary.json's parameters.
    n, d : int
        Agents and state dimension.
    run_info : dict
        summary.json's run statistics.

    Returns
    -------
    Table

    Raises
    ------
    InputError
        A recorded schedule gain that is malformed (``load_run`` checks it first).
    """
    rows: list[tuple] = []
    for k, v in p.items():
        if k == "initial" and isinstance(v, list) and len(v) == n * d and n > 20:
            a = np.asarray(v, dtype=float)
            rows.append(
                (
                    "initial x(0)",
                    f"{n} × {d} values in summary.json, in [{fmt(a.min())}, {fmt(a.max())}]",
                )
            )
        elif k == "initial" and isinstance(v, list) and len(v) == n * d:
            rows.append(("initial x(0) (agents × d)", rows_matrix(np.reshape(v, (n, d)))))
        elif k == "gain" and isinstance(v, dict):  # a schedule: its label, not its table
            rows.append(("gain", schedule_from_document(v, "parameters.gain").text))
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
            rows.append((f"run.{k}", v))
    return html_table(RowsTable.build("parameters", ("parameter", "value"), rows))


def mc_band(run: RunData) -> MeanSquareBand | None:
    """The Monte Carlo curves with their band, read back from ms_error.csv.

    Parameters
    ----------
    run : RunData
        The run.

    Returns
    -------
    MeanSquareBand or None
        None when the run has no Monte Carlo curves.
    """
    mean = run.ms("mc")
    if mean is None:
        return None
    return MeanSquareBand(
        mean=mean,
        lo=np.column_stack([run.table[f"mc_{a}_lo"] for a in run.labels]),
        hi=np.column_stack([run.table[f"mc_{a}_hi"] for a in run.labels]),
    )


def data_links(run: RunData, figdir: Path, key: str, base: Path) -> list[tuple[str, str]]:
    """Links to the run's data files and to this section's figures.

    Parameters
    ----------
    run : RunData
        The run.
    figdir : pathlib.Path
        The figures' folder.
    key : str
        The section's figure prefix.
    base : pathlib.Path
        The folder links are relative to.

    Returns
    -------
    list of (str, str)
        (file name, link).
    """
    data = [
        (f.name, rel(f, base))
        for f in sorted(run.path.iterdir())
        if f.is_file() and f.suffix in (".json", ".csv", ".npz") and not f.name.startswith(".")
    ]
    return data + [
        (f.name, rel(f, base))
        for f in sorted(figdir.glob(f"{key}_*"))
        if f.suffix in (".png", ".svg", ".pdf")
    ]


FINE_POINTS = 2000  # save times of the companion sample paths drawn in a report
COMPANION_MAX_STEPS = 2_000_000  # path-steps a report may spend on them


def companion_paths(run: RunData, top) -> dict | None:
    """Two sample paths of the run's own scenario (same noise, gain, initial state, step
    and seed) saved at FINE_POINTS times, for the states figure: the run's stored paths
    are kept only at the statistics' save times, too coarse to show a path.

    Parameters
    ----------
    run : RunData
        The run.
    top : Topology or SwitchingTopology
        Its topology.

    Returns
    -------
    dict or None
        ``{"t", "paths"}``; None when the run cannot be repeated from its summary (a
        callable gain or noise) or the paths would cost more than COMPANION_MAX_STEPS.
    """
    s = run.spec
    if callable(s.noise.f):  # the run's f is not recorded
        return None
    steps = s.T / (s.stepping.dt or s.stepping.ds or 1.0)
    if 2 * steps > COMPANION_MAX_STEPS:
        return None
    # the run's scenario, continuous, two paths finely saved (the run's seed, the default rng)
    mc = MonteCarlo(paths=2, store_paths=2, block_size=2, workers=1, seed=s.mc.seed)
    spec = SimulationSpec(
        theta=s.theta,
        T=s.T,
        margin=s.margin,
        gain=s.gain,
        noise=s.noise,
        initial=s.initial,
        save=SaveAt(every=s.T / FINE_POINTS),
        stepping=s.stepping,
        mc=mc,
        method="mc",
    )
    try:
        res = simulate(top, spec)
    except (InputError, SimulationDiverged):
        return None
    return {"t": res.save_times, "paths": res.mc.paths} if res.mc is not None else None


__all__ = [
    "certificate_tables",
    "companion_paths",
    "data_links",
    "fitted_exponent",
    "window_warning",
    "mc_band",
    "parameter_table",
]
