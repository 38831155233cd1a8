"""The report of a sweep directory (``ntc report DIR`` on ``ntc sweep --out DIR``): the
table of points, the final mean-square error against each swept key (one line per
combination of the other keys), every point's curve overlaid, and links to the tables.
One self-contained HTML file; the figures are also written to DIR/figures."""

from __future__ import annotations

import base64
import itertools
import json
import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..outputs import check_output_file, write_atomic
from ..rows import fmt
from .html import render

MAX_CURVES = 200  # curves drawn in the overlay (every point is still in curves.parquet)
MAX_ROWS = 2000  # rows of the HTML table (every point is in results.csv)


def _figure(png: bytes, alt: str) -> dict:
    return {"alt": alt, "png_b64": base64.b64encode(png).decode()}


def _save(fig, stem: Path) -> bytes:
    """stem.png in DIR/figures; the PNG bytes for inlining."""
    import io

    import matplotlib.pyplot as plt

    stem.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    stem.with_suffix(".png").write_bytes(buf.getvalue())
    return buf.getvalue()


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
    except (OSError, ValueError, AttributeError):
        return False


def _load(d: Path):
    import pandas as pd

    for name in ("sweep.json", "results.parquet", "curves.parquet"):
        if not (d / name).is_file():
            raise InputError(f"{d}: {name}: missing (run ntc sweep ... --out {d} first)")
    try:
        man = json.loads((d / "sweep.json").read_text(encoding="utf-8"))
        res = pd.read_parquet(d / "results.parquet")
        curves = pd.read_parquet(d / "curves.parquet")
    except (OSError, ValueError) as exc:
        raise InputError(f"{d}: cannot read the sweep tables ({exc.__class__.__name__})") from None
    keys = man.get("keys")
    if not isinstance(keys, list) or any(k not in res.columns for k in keys):
        raise InputError(f"{d}: sweep.json: keys do not match results.parquet")
    return man, res, curves, [str(k) for k in keys]


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


def ms_against_key(res, keys: list[str], key: str):
    """Final MS error (MC solid, exact dashed) against ``key``, one line per combination
    of the other keys' values."""
    import matplotlib.pyplot as plt

    others = [k for k in keys if k != key and res[k].nunique(dropna=False) > 1]
    pos, ticks = _positions(list(res[key]))
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    groups = res.groupby(others, sort=False, dropna=False) if others else [((), res)]
    colours = itertools.cycle(plt.rcParams["axes.prop_cycle"].by_key()["color"])
    ys: list[float] = []
    for n_line, (vals, g) in enumerate(groups):
        if n_line >= 20:
            break
        c = next(colours)
        vals = vals if isinstance(vals, tuple) else (vals,)
        label = ", ".join(f"{k}={v}" for k, v in zip(others, vals, strict=True)) or "MC"
        g = g.assign(_x=[pos[v] for v in g[key]]).sort_values("_x")
        for col, ls, suffix in (("ms_final_mc", "-", ""), ("ms_final_exact", "--", " (exact)")):
            y = g[col].astype(float).to_numpy()
            ok = np.isfinite(y)
            if ok.any():
                ys += y[ok].tolist()
                ax.plot(
                    g["_x"].to_numpy()[ok],
                    y[ok],
                    ls,
                    marker="o",
                    ms=4,
                    color=c,
                    label=(label + suffix) if (others or suffix) else label,
                )
    if _log_scale(ys):
        ax.set_yscale("log")
    if ticks is not None:
        ax.set_xticks(range(len(ticks)), ticks, rotation=20, fontsize=8)
    ax.set_xlabel(key)
    ax.set_ylabel(r"$\sum_i E\|x_i(T)-\theta\|^2$")
    ax.set_title(f"final mean-square error against {key}", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig


def curves_overlay(curves, res, keys: list[str]):
    """Σ_i E‖x_i − θ‖² against t for every point (MC), on one axis."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    total = curves.groupby(["point", "t"], sort=False)["mc"].sum(min_count=1).reset_index()
    label_of = {r["point"]: ", ".join(f"{k}={r[k]}" for k in keys) for _, r in res.iterrows()}
    drawn, ys = 0, []
    for point, g in total.groupby("point", sort=False):
        if drawn >= MAX_CURVES:
            break
        y = g["mc"].to_numpy(dtype=float)
        ok = np.isfinite(y)
        if not ok.any():
            continue
        ys += [float(y[ok].min()), float(y[ok].max())]
        ax.plot(g["t"].to_numpy()[ok], y[ok], lw=1, alpha=0.8, label=label_of.get(point, point))
        drawn += 1
    if _log_scale(ys):
        ax.set_yscale("log")
    ax.set_xlabel("t")
    ax.set_ylabel(r"$\sum_i E\|x_i(t)-\theta\|^2$ (MC)")
    ax.set_title(f"mean-square error of {drawn} points", fontsize=10)
    ax.grid(alpha=0.3)
    if drawn <= 16:
        ax.legend(fontsize=6, frameon=False)
    fig.tight_layout()
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
    try:
        import pandas as pd

        if v is pd.NA:
            return "—"
    except ImportError:  # pragma: no cover
        pass
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
