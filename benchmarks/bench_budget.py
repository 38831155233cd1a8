"""How good is the size-before-allocation estimate, and how fast does Ctrl-C stop a run?

For a few runs (the paper's G1 run, many save times with many stored paths, a larger random
network, exact moments only) this runs ``simulate`` in a fresh process with one worker,
measures the growth of the peak resident memory (ru_maxrss after the run minus before it)
and prints it beside :func:`ntc_design.simulate.budget.estimate`'s total. The estimate is
meant to be an upper bound within a small factor (it guards against requests that are
orders of magnitude too big). Then it starts ``ntc simulate`` on a ~20 s scenario with 2
workers, sends SIGINT after 3 s and prints how long the process took to exit.

Run: python benchmarks/bench_budget.py
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ntc_design.model.paper import THETA

ROOT = Path(__file__).resolve().parent.parent

CASES = {
    "G1 (T=2, 1000 paths, 21 saves)": dict(top="g1", T=2.0, paths=1000, save_every=0.1),
    "G1, 20 001 saves, 200 stored paths": dict(
        top="g1", T=2.0, paths=200, save_every=1e-4, store_paths=200, method="mc"
    ),
    "random N=150, d=2 (Nd=300), both": dict(top="random", T=0.2, paths=200, save_every=0.05),
    "random N=250, d=2 (Nd=500), exact": dict(
        top="random500", T=0.2, paths=1, save_every=0.05, method="exact"
    ),
}


def _topology(kind: str):
    import numpy as np

    import ntc_design as nd

    if kind == "g1":
        return nd.load(ROOT / "examples" / "g1.yaml"), THETA
    n = 150 if kind == "random" else 250
    rng = np.random.default_rng(0)
    edges = [(i % n + 1, (i + 1) % n + 1, np.eye(2)) for i in range(n)]
    edges += [
        (int(a) + 1, int(b) + 1, -0.1 * np.eye(2))
        for a, b in rng.integers(0, n, size=(n // 5, 2))
        if a != b and (b - a) % n != 1
    ]
    seen, uniq = set(), []
    for j, i, w in edges:
        if (j, i) not in seen:
            seen.add((j, i))
            uniq.append((j, i, w))
    return nd.Topology.from_edges(n, 2, uniq), [1.0, -1.0]


def _child(case: dict, conn) -> None:
    import ntc_design.simulate.prepare as drv
    from ntc_design.simulate import simulate

    captured = {}
    orig = drv.check_budget

    def spy(est):
        captured["est"] = est
        orig(est)

    drv.check_budget = spy
    kw = dict(case)
    try:
        top, theta = _topology(kw.pop("top"))
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        t0 = time.perf_counter()
        simulate(top, theta, dt=1e-3, workers=1, seed=0, **kw)
        sec = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        est = captured["est"]
        conn.send((est.total, after - before, sec, est.largest()[0]))
    except Exception as exc:  # noqa: BLE001 - reported by the parent
        conn.send(exc.__class__.__name__ + ": " + str(exc))


def memory_table() -> None:
    ctx = mp.get_context("spawn")
    print(
        f"{'run':45s} {'estimate':>10s} {'measured':>10s} {'ratio':>6s}  seconds  largest part",
        flush=True,
    )
    for name, case in CASES.items():
        a, b = ctx.Pipe()
        p = ctx.Process(target=_child, args=(case, b))
        p.start()
        got = a.recv() if a.poll(600) else "no answer in 600 s"
        p.join(timeout=5)
        if isinstance(got, str):
            print(f"{name:45s} failed: {got}", flush=True)
            continue
        total, grown, sec, part = got
        print(
            f"{name:45s} {total / 2**20:8.1f}MB {grown / 2**20:8.1f}MB "
            f"{total / max(grown, 1):6.1f}  {sec:7.1f}  {part}",
            flush=True,
        )


def interrupt_latency(repeats: int = 3) -> None:
    with tempfile.TemporaryDirectory() as d:
        sc = Path(d) / "sc.json"
        sc.write_text(
            json.dumps(
                {
                    "topology": str(ROOT / "examples" / "g1.yaml"),
                    "theta": THETA,
                    "T": 10,
                    "paths": 2000,
                    "block_size": 100,
                    "method": "mc",
                    "workers": 2,
                }
            )
        )
        for _ in range(repeats):
            proc = subprocess.Popen(
                [sys.executable, "-m", "ntc_design", "simulate", str(sc), "--out", f"{d}/o"],
                env={**os.environ, "PYTHONPATH": str(ROOT)},
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
            )
            time.sleep(3.0)
            proc.send_signal(signal.SIGINT)
            t0 = time.monotonic()
            proc.wait(timeout=60)
            print(
                f"Ctrl-C after 3 s (2 workers): exit {proc.returncode} in "
                f"{time.monotonic() - t0:.2f} s; output folder present: {Path(d, 'o').exists()}",
                flush=True,
            )


if __name__ == "__main__":
    memory_table()
    interrupt_latency()
