"""Sweeps and Monte Carlo on a Dask cluster, against the targets of issue 10, in one run.

1. A 16-point sweep of G1 (examples/sweeps/g1_noise.yaml: 1000 paths, T = 10, dt = 1e-3)
   on a local cluster of 2 worker processes (LocalCluster, threads_per_worker=1) against
   1 worker: target >= 1.7x the throughput (points per second).
2. Per-task overhead, from empty tasks: the round trip of one task at a time and the
   cost per task of a batch on one worker: target <= 50 ms.
3. `ntc simulate examples/scenarios/g1_fixed.yaml` through `--scheduler` on a local
   2-worker cluster against the local run (2 processes): target within 15 % wall time
   (each a fresh `ntc` process; the cluster is started beforehand, as a user's would be).
4. On paper: tasks, bytes moved per task, and the projected time of a 10,000-point sweep
   on 100 workers.

Both clusters are warmed up (ntc_design imported on every worker) before timing. Timings
on a shared machine are noisy: run it on an idle one.

Run: python benchmarks/bench_distributed.py [--points 16] [--paths 1000] [--T 10]
"""

from __future__ import annotations

import argparse
import math
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cloudpickle
import yaml

from ntc_design.sweep import load_sweep, run_point, run_sweep
from ntc_design.sweep.engines import DaskEngine

ROOT = Path(__file__).resolve().parent.parent
SWEEP = ROOT / "examples" / "sweeps" / "g1_noise.yaml"
SCENARIO = ROOT / "examples" / "scenarios" / "g1_fixed.yaml"


def cluster(n_workers: int):
    from distributed import Client, LocalCluster

    cl = LocalCluster(
        n_workers=n_workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
        silence_logs=40,
    )
    client = Client(cl)
    client.run(lambda: __import__("ntc_design.sweep"))  # warm: imports on every worker
    return cl, client


def sweep_file(tmp: Path, points: int, paths: int, t_end: float) -> Path:
    """The example sweep, cut to ``points`` points and scaled to ``paths`` / ``t_end``."""
    doc = yaml.safe_load(SWEEP.read_text())
    doc["base"] = str(SCENARIO)
    grid = doc["grid"]
    keys = list(grid)
    n = math.prod(len(v) for v in grid.values())
    while n > points:  # drop values from the last keys first
        k = next(k for k in reversed(keys) if len(grid[k]) > 1)
        n = n // len(grid[k]) * (len(grid[k]) - 1)
        grid[k] = grid[k][:-1]
    base = yaml.safe_load(SCENARIO.read_text())
    for key, value in (("paths", paths), ("T", t_end)):
        if value != base[key]:  # the example's own points (and hashes) otherwise
            grid[key] = [value]
    path = tmp / "sweep.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def time_sweep(path: Path, out: Path, n_workers: int) -> tuple[float, int]:
    """Wall time of the sweep on a fresh, warm local cluster of ``n_workers``."""
    cl, client = cluster(n_workers)
    try:
        t0 = time.perf_counter()
        with DaskEngine(client) as eng:
            res = run_sweep(path, out, engine=eng)
        return time.perf_counter() - t0, res.points
    finally:
        client.close()
        cl.close()


def noop(x):
    return x


def task_overhead(client, n: int = 200) -> tuple[float, float]:
    """(round trip of one empty task at a time, cost per task of n empty tasks), seconds."""
    client.submit(noop, -1, pure=False).result()
    t0 = time.perf_counter()
    for i in range(20):
        client.submit(noop, i, pure=False).result()
    latency = (time.perf_counter() - t0) / 20
    t0 = time.perf_counter()
    client.gather(client.map(noop, range(n), pure=False))
    return latency, (time.perf_counter() - t0) / n


def ntc_simulate(out: Path, scheduler: str | None) -> tuple[float, float]:
    """(wall time of the `ntc simulate` process, its Monte Carlo seconds as printed)."""
    cmd = [sys.executable, "-m", "ntc_design", "simulate", str(SCENARIO), "--out", str(out)]
    if scheduler:
        cmd += ["--scheduler", scheduler]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {done.returncode}: {done.stderr.strip()}")
    m = re.search(r"path-steps in ([0-9.]+) s", done.stdout)
    return wall, float(m.group(1)) if m else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=16)
    ap.add_argument("--paths", type=int, default=1000)
    ap.add_argument("--T", dest="t_end", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=1, help="ntc simulate runs (best of)")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-distributed-"))
    try:
        sw = sweep_file(tmp, args.points, args.paths, args.t_end)
        print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
        # 1. throughput, 1 vs 2 workers (fresh output directories: nothing reused)
        t1, n = time_sweep(sw, tmp / "w1", 1)
        t2, _ = time_sweep(sw, tmp / "w2", 2)
        same = (tmp / "w1" / "results.csv").read_text().count("\n") == n + 1
        # 2-3. overheads and ntc simulate, on one 2-worker cluster
        cl, client = cluster(2)
        try:
            lat, per_task = task_overhead(client)
            addr = client.scheduler.address
            local, local_mc = min(ntc_simulate(tmp / f"local{i}", None) for i in range(args.repeat))
            remote, remote_mc = min(
                ntc_simulate(tmp / f"dask{i}", addr) for i in range(args.repeat)
            )
            identical = (tmp / "local0" / "ms_error.csv").read_bytes() == (
                tmp / "dask0" / "ms_error.csv"
            ).read_bytes()
            empty_rate = 1.0 / per_task
        finally:
            client.close()
            cl.close()
        # 4. on paper: what one point task moves, measured on the real objects
        sweep = load_sweep(sw)
        task = sweep.tasks()[0]
        t0 = time.perf_counter()
        res = run_point(task, remote=True)
        point_seconds = time.perf_counter() - t0
        bytes_in = len(cloudpickle.dumps(task))
        bytes_topology = len(pickle.dumps(task.topology_doc))
        bytes_out = len(pickle.dumps(res))
        n_big, w_big = 10_000, 100
        compute = math.ceil(n_big / w_big) * point_seconds
        sched = n_big * 1e-3  # ~1 ms of scheduler time per task (Dask's documented order)
        rows = [
            ("sweep: points", f"{n} (G1, {args.paths} paths, T = {args.t_end:g}, dt = 1e-3)", ""),
            ("sweep: 1 worker", f"{t1:.1f} s ({n / t1:.3f} points/s)", ""),
            ("sweep: 2 workers", f"{t2:.1f} s ({n / t2:.3f} points/s)", ""),
            ("sweep: throughput 2 vs 1", f"{t1 / t2:.2f}x", "target >= 1.7x"),
            ("task round trip (empty)", f"{lat * 1e3:.1f} ms", "target <= 50 ms"),
            ("task cost in a batch (empty)", f"{per_task * 1e3:.2f} ms", "target <= 50 ms"),
            (
                "ntc simulate G1, local (2 procs)",
                f"{local:.2f} s (Monte Carlo {local_mc:.2f} s)",
                "",
            ),
            ("ntc simulate G1, --scheduler", f"{remote:.2f} s (Monte Carlo {remote_mc:.2f} s)", ""),
            ("  ratio (process wall time)", f"{remote / local:.3f}", "target <= 1.15"),
            ("  ratio (Monte Carlo part)", f"{remote_mc / local_mc:.3f}", ""),
            ("  ms_error.csv identical", "yes" if identical else "NO", ""),
            ("tasks of a sweep", "1 per point (+1 scatter per topology)", ""),
            ("tasks of ntc simulate", "1 per block of 500 paths (+1 scatter)", ""),
            ("bytes to a point task", f"{bytes_in} (topology doc {bytes_topology}, once)", ""),
            ("bytes back from a point", f"{bytes_out}", ""),
            ("one G1 point, one process", f"{point_seconds:.1f} s", ""),
            (
                f"projected {n_big} points on {w_big} workers",
                f"{(compute + sched) / 60:.1f} min ({n_big // w_big} points per worker "
                f"x {point_seconds:.1f} s + ~{sched:.0f} s scheduler), "
                f"{n_big * (bytes_in + bytes_out) / 1e6:.0f} MB moved",
                "",
            ),
            ("empty-task throughput (2 workers)", f"{empty_rate:.0f} tasks/s", ""),
            ("results rows", "ok" if same else "MISSING", ""),
        ]
        w = max(len(r[0]) for r in rows)
        v = max(len(r[1]) for r in rows)
        for a, b, c in rows:
            print(f"{a:<{w}}  {b:<{v}}  {c}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
