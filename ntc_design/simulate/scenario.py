"""Scenario files -> :func:`ntc_design.simulate.simulate` arguments, and the outputs of a run
(summary.json, ms_error.csv, paths.npz), written atomically."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import ScenarioData, jsonable, parse_scenario
from ..interop import simulation_frame
from ..model import SwitchingTopology, load
from .system import NoiseModel


def scenario_arguments(path: str | Path) -> tuple[object, dict, ScenarioData]:
    """(topology, keyword arguments of simulate(), parsed scenario)."""
    sc = parse_scenario(path)
    top = load(sc.topology)
    n, d = top.n, top.dim
    kw = dict(sc.values)
    kw.pop("name", None)
    kw.pop("description", None)
    theta = kw.pop("theta")
    noise = NoiseModel(
        sigma=float(sc.noise.get("sigma", 0.4)),
        f=np.asarray(sc.noise["f"], dtype=float)
        if isinstance(sc.noise.get("f"), list)
        else float(sc.noise.get("f", 0.3)),
        sigma_edges={
            (e["from"], e["to"]): float(e["sigma"]) for e in sc.noise.get("sigma_edges", []) or []
        },
    )
    kw["noise"] = noise
    ini = sc.initial
    if isinstance(ini, dict):
        if (
            set(ini) != {"uniform", "seed"}
            or not isinstance(ini["uniform"], list)
            or len(ini["uniform"]) != 2
        ):
            raise InputError(
                f"{sc.source}: initial: expected {{uniform: [lo, hi], seed: S}} or a list of {n} states"
            )
        lo, hi = (float(v) for v in ini["uniform"])
        if not lo < hi:
            raise InputError(f"{sc.source}: initial.uniform: need lo < hi")
        kw["initial"] = np.random.default_rng(np.random.SeedSequence(int(ini["seed"]))).uniform(
            lo, hi, size=n * d
        )
    elif isinstance(ini, list):
        try:
            arr = np.asarray(ini, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{sc.source}: initial: expected numbers") from None
        if arr.size != n * d:
            raise InputError(
                f"{sc.source}: initial: expected {n} states of {d} numbers ({n * d} values), got {arr.size}"
            )
        kw["initial"] = arr
    elif ini is not None:
        raise InputError(
            f"{sc.source}: initial: expected {{uniform: [lo, hi], seed: S}} or a list of {n} states"
        )
    if isinstance(top, SwitchingTopology):
        kw.pop("resample", None)
    return top, {"theta": theta, **kw}, sc


def ms_error_table(res) -> tuple[list[str], np.ndarray]:
    """Columns t, mc_a, mc_a_lo, mc_a_hi, exact_a (a = agent label)."""
    cols = ["t"]
    data = [res.save_times]
    for k, a in enumerate(res.labels):
        if res.mc is not None:
            cols += [f"mc_{a}", f"mc_{a}_lo", f"mc_{a}_hi"]
            data += [res.mc["mean"][:, k], res.mc["lo"][:, k], res.mc["hi"][:, k]]
        if res.exact is not None:
            cols.append(f"exact_{a}")
            data.append(res.exact.ms_error[:, k])
    return cols, np.column_stack(data)


def write_outputs(res, out_dir: str | Path, extra: dict | None = None) -> list[Path]:
    """Write summary.json, ms_error.csv (wide), ms_error_long.csv (tidy) and paths.npz (each
    via a temporary file)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = res.summary()
    if extra:
        summary.update(extra)
    cols, table = ms_error_table(res)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(cols)
    for row in table:
        w.writerow([repr(float(v)) for v in row])
    files = {
        "summary.json": json.dumps(jsonable(summary), indent=1, ensure_ascii=False) + "\n",
        "ms_error.csv": buf.getvalue(),
        # the same numbers in tidy long form (t, agent, mc, lo, hi, exact), as to_pandas()
        "ms_error_long.csv": simulation_frame(res).to_csv(index=False),
    }
    written = []
    for name, text in files.items():
        tmp = out / (name + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(out / name)
        written.append(out / name)
    tmp = out / "paths.tmp.npz"
    np.savez_compressed(
        tmp,
        t=res.save_times,
        paths=res.mc["paths"] if res.mc is not None else np.zeros((0, res.save_times.size, 0)),
        mean_state=res.mc["mean_state"] if res.mc is not None else np.zeros((0, 0)),
        exact_mean=(res.exact.mean + np.tile(res.theta, len(res.labels)))
        if res.exact is not None
        else np.zeros((0, 0)),
        labels=np.array([str(a) for a in res.labels]),
        theta=res.theta,
    )
    tmp.replace(out / "paths.npz")
    written.append(out / "paths.npz")
    return written
