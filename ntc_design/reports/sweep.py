"""The report of a sweep directory (``ntc report DIR`` on the output folder of ``ntc sweep``): the
table of points, the final mean-square error against each swept key (one line per
combination of the other keys), every point's curve overlaid, and links to the tables.
One self-contained HTML file; the figures are also written to DIR/figures."""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from ..errors import InputError
from ..io.outputs import check_output_file, write_atomic
from ..present.rows import fmt
from ..sweep.store import tables_module
from .html import render
from .style import MARKERS, TWO_COLUMN, agent_style, markevery, paper_style, save

MAX_CURVES = 200  # curves drawn in the overlay (every point is still in curves.parquet)
MAX_ROWS = 2000  # rows of the HTML table (every point is in results.csv)


def _figure(png: bytes, alt: str) -> dict:
    return {"alt": alt, "png_b64": base64.b64encode(png).decode()}


#: How a swept key reads on an axis (mathtext); other keys are shown as written.
KEY_LABELS = {
    "noise.sigma": r"noise $\sigma$",
    "noise.f": r"$f$ in $f(x) = f\,x$",
    "margin": r"margin $\Delta C$",
    "T": r"horizon $T$",
    "dt": r"step $\Delta t$",
    "ds": r"step $\Delta s$",
    "paths": "Monte Carlo paths",
    "seed": "Monte Carlo seed",
    "gain": r"gain $c(t)$",
    "initial.seed": "seed of $x(0)$",
}
#: The same keys in a legend entry (``σ = 0.4``).
KEY_SYMBOLS = {"noise.sigma": "σ", "noise.f": "f", "margin": "ΔC", "dt": "Δt", "ds": "Δs"}
INTEGER_KEYS = {"seed", "paths", "initial.seed", "workers", "block_size", "store_paths"}


def _save(fig, stem: Path) -> bytes:
    """stem.png (300 dpi), .svg and .pdf in DIR/figures, in the one style; the PNG bytes
    for inlining."""
    return save(fig, stem).png


def is_sweep_dir(directory: str | Path) -> bool:
    """Whether ``directory`` holds the output of ``ntc sweep`` (its sweep.json).

    Parameters
    ----------
    directory : str or pathlib.Path
        A folder.

    Returns
    -------
    bool
    """
    p = Path(directory) / "sweep.json"
    if not p.is_file():
        return False
    try:
        return json.loads(p.read_text(encoding="utf-8")).get("kind") == "sweep"
    except (OSError, ValueError, AttributeError, RecursionError):
        return False


def _load(d: Path):
    pd = tables_module()

    for name in ("sweep.json", "results.csv", "results.parquet", "curves.parquet"):
        if not (d / name).is_file():
            raise InputError(f"missing (run ntc sweep ... --out {d} first)", field=f"{d}: {name}")
    try:
        man = json.loads((d / "sweep.json").read_text(encoding="utf-8"))
        res = pd.read_parquet(d / "results.parquet")
        curves = pd.read_parquet(d / "curves.parquet")
    except (OSError, ValueError, RecursionError) as exc:
        raise InputError(
            f"cannot read the sweep tables ({exc.__class__.__name__})", field=str(d)
        ) from None
    _check_results_csv(d / "results.csv", res)
    if not isinstance(man, dict):
        raise InputError("expected a mapping", field=f"{d}: sweep.json")
    if len(res) == 0:
        raise InputError(
            f"no points (the sweep has not run; run ntc sweep ... --out {d})",
            field=f"{d}: results.parquet",
        )
    keys = man.get("keys")
    if not isinstance(keys, list) or any(k not in res.columns for k in keys):
        raise InputError("keys do not match results.parquet", field=f"{d}: sweep.json")
    return man, res, curves, [str(k) for k in keys]


def _check_results_csv(path: Path, res) -> None:
    """results.csv, which the report links as the sweep's data, must be the table of
    results.parquet (the same columns and points): an empty or damaged copy is refused
    rather than linked."""
    pd = tables_module()

    try:
        csv = pd.read_csv(path)
    except (OSError, ValueError, UnicodeDecodeError) as exc:  # EmptyDataError, ParserError
        why = "empty" if isinstance(exc, pd.errors.EmptyDataError) else "not a results table"
        raise InputError(
            f"{why} ({exc.__class__.__name__}); re-run ntc sweep", field=str(path)
        ) from None
    if list(csv.columns) != [str(c) for c in res.columns]:
        raise InputError(
            "its columns are not those of results.parquet; re-run ntc sweep", field=str(path)
        )
    if len(csv) != len(res) or (
        "point" in res.columns
        and csv["point"].astype(str).tolist() != res["point"].astype(str).tolist()
    ):
        raise InputError(
            f"{len(csv)} rows, not the {len(res)} points of results.parquet; re-run ntc sweep",
            field=str(path),
        )


def _numeric(values) -> bool:
    return all(
        isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
        for v in values
    )


def _positions(values) -> tuple[dict, list | None]:
    """x position of each distinct value; tick labels when the values are not numbers."""
    uniq = list(dict.fromkeys(values))
    if _numeric(uniq):
        return {v: float(v) for v in uniq}, None
    return {v: float(i) for i, v in enumerate(uniq)}, [str(v) for v in uniq]


def _group_label(keys: list[str], vals: tuple) -> str:
    return ", ".join(f"{KEY_SYMBOLS.get(k, k)} = {v}" for k, v in zip(keys, vals, strict=True))


def ms_against_key(res, keys: list[str], key: str):
    """Final Σ_i E‖x_i(T) − θ‖² against ``key``: one colour per combination of the other
    keys (the seed aside), the exact moments as a line (they do not depend on the seed),
    Monte Carlo as markers, one marker shape per seed.

    Parameters
    ----------
    res : pandas.DataFrame
        results.csv.
    keys : list of str
        The swept keys.
    key : str
        The key on the x axis.

    Returns
    -------
    matplotlib.figure.Figure
    """
    others = [k for k in keys if k not in (key, "seed") and res[k].nunique(dropna=False) > 1]
    seeds = list(dict.fromkeys(res["seed"])) if "seed" in res and key != "seed" else [None]
    pos, ticks = _positions(list(res[key]))
    groups = res.groupby(others, sort=False, dropna=False) if others else [((), res)]
    ys: list[float] = []
    with paper_style():
        fig, ax = plt.subplots(figsize=(TWO_COLUMN, 2.8), layout="constrained")
        handles = []
        for n_line, (vals, g) in enumerate(groups):
            if n_line >= 12:
                break
            st = agent_style(n_line)
            vals = vals if isinstance(vals, tuple) else (vals,)
            g = g.assign(_x=[pos[v] for v in g[key]]).sort_values("_x")
            ex = g.drop_duplicates("_x")
            y = ex["ms_final_exact"].astype(float).to_numpy()
            ok = np.isfinite(y)
            if ok.any():
                ys += y[ok].tolist()
                ax.plot(ex["_x"].to_numpy()[ok], y[ok], color=st.colour, ls=st.linestyle, lw=1.2)
            for k, seed in enumerate(seeds):
                sg = g if seed is None else g[g["seed"] == seed]
                y = sg["ms_final_mc"].astype(float).to_numpy()
                ok = np.isfinite(y)
                if ok.any():
                    ys += y[ok].tolist()
                    ax.plot(sg["_x"].to_numpy()[ok], y[ok], ls="none", marker=MARKERS[k % len(MARKERS)],
                            ms=4, mfc="none", color=st.colour)  # fmt: skip
            handles.append(
                Line2D(
                    [],
                    [],
                    color=st.colour,
                    ls=st.linestyle,
                    label=_group_label(others, vals) or "all points",
                )
            )
        handles.append(Line2D([], [], color="0.3", lw=1.2, label="exact moments (line)"))
        for k, seed in enumerate(seeds):
            name = "Monte Carlo" if seed is None else f"Monte Carlo, seed = {seed}"
            handles.append(
                Line2D(
                    [],
                    [],
                    color="0.3",
                    ls="none",
                    marker=MARKERS[k % len(MARKERS)],
                    mfc="none",
                    label=name,
                )
            )
        if _log_scale(ys):
            ax.set_yscale("log")
        if ticks is not None:
            ax.set_xticks(range(len(ticks)), ticks, rotation=20)
        elif key in INTEGER_KEYS:
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_xlabel(KEY_LABELS.get(key, key))
        ax.set_ylabel(r"$\sum_i E\,\|x_i(T)-\theta\|^2$")
        fig.legend(handles=handles, loc="outside right center", frameon=False)
    return fig


def curves_overlay(curves, res, keys: list[str]):
    """Σ_i E‖x_i(t) − θ‖² (Monte Carlo) for every point on one axis, each point with its
    own colour, line style and marker (a legend outside the axes up to 16 points).

    Parameters
    ----------
    curves : pandas.DataFrame
        curves.parquet.
    res : pandas.DataFrame
        results.csv.
    keys : list of str
        The swept keys.

    Returns
    -------
    matplotlib.figure.Figure
    """
    total = curves.groupby(["point", "t"], sort=False)["mc"].sum(min_count=1).reset_index()
    label_of = {
        r["point"]: _group_label(keys, tuple(r[k] for k in keys)) for _, r in res.iterrows()
    }
    drawn, ys = 0, []
    with paper_style():
        fig, ax = plt.subplots(figsize=(TWO_COLUMN, 3.0), layout="constrained")
        for point, g in total.groupby("point", sort=False):
            if drawn >= MAX_CURVES:
                break
            y = g["mc"].to_numpy(dtype=float)
            ok = np.isfinite(y)
            if not ok.any():
                continue
            ys += [float(y[ok].min()), float(y[ok].max())]
            st = agent_style(drawn)
            t = g["t"].to_numpy()[ok]
            ax.plot(t, y[ok], color=st.colour, ls=st.linestyle, marker=st.marker, ms=3,
                    markevery=markevery(drawn, t.size), lw=1.0, label=label_of.get(point, point))  # fmt: skip
            drawn += 1
        if _log_scale(ys):
            ax.set_yscale("log")
        ax.set_xlabel("$t$")
        ax.set_ylabel(r"$\sum_i E\,\|x_i(t)-\theta\|^2$ (Monte Carlo)")
        if drawn <= 16:
            fig.legend(loc="outside right center", frameon=False, fontsize=7)
    return fig


def _log_scale(ys: list[float]) -> bool:
    """Log axis when every value is positive and they span more than a factor 20."""
    return bool(ys) and min(ys) > 0 and max(ys) / min(ys) > 20


def _cell(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if isinstance(v, (np.bool_, bool)):
        return fmt(bool(v))
    if isinstance(v, (np.floating, float)):
        return fmt(float(v), 5)
    if type(v).__name__ == "NAType":  # pandas' missing value (a table read back)
        return "—"
    return str(v)


def write_sweep_report(directory: str | Path) -> Path:
    """`ntc report DIR` on a sweep directory: DIR/report.html (and DIR/figures/sweep_*).

    Parameters
    ----------
    directory
        The ``--out`` directory of ``ntc sweep``.

    Returns
    -------
    Path
        The report file.

    Raises
    ------
    InputError
        When the directory lacks sweep.json or the tables, or they do not match.
    """
    d = Path(directory)
    man, res, curves, keys = _load(d)
    check_output_file(d / "report.html", "report")  # before the figures
    figdir = d / "figures"
    figs = []
    for k in keys:
        if res[k].nunique(dropna=True) < 2:
            continue
        safe = "".join(ch if ch.isalnum() else "_" for ch in k)
        png = _save(ms_against_key(res, keys, k), figdir / f"sweep_ms_vs_{safe}")
        figs.append(_figure(png, f"final mean-square error against {k}"))
    png = _save(curves_overlay(curves, res, keys), figdir / "sweep_curves")
    figs.append(_figure(png, "mean-square error of every point (Monte Carlo)"))
    cols = [
        *keys,
        *(
            c
            for c in (
                "delta",
                "certified",
                "ms_guaranteed",
                "ms_final_mc",
                "ms_final_exact",
                "wall_seconds",
                "worker",
                "error",
                "point",
            )
            if c not in keys
        ),
    ]
    rows = [[_cell(r[c]) for c in cols] for _, r in res.head(MAX_ROWS).iterrows()]
    html = render(
        "sweep.html",
        title=f"ntc-design sweep: {man.get('name', d.name)}",
        toc=[
            {"id": "final", "title": "Final mean-square error"},
            {"id": "points", "title": "Points"},
        ],
        interactive=False,
        n_points=len(res),
        keys=keys,
        base=str(man.get("base", "")),
        n_failed=int(res["error"].notna().sum()),
        data_files=("results.csv", "results.parquet", "curves.parquet", "sweep.json"),
        figures=figs,
        points={"id": "points-table", "headers": cols, "rows": rows},
        truncated=len(res) > MAX_ROWS,
    )
    out = d / "report.html"
    write_atomic(out, html, "report")
    return out


__all__ = ["is_sweep_dir", "write_sweep_report"]
