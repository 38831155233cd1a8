"""Start-up and small answers (issue 30): wall time of fresh processes, the median of
several runs, beside `python -c pass` measured in the same run and the issue's targets.

    python benchmarks/bench_startup.py [--repeat 5]

Each command runs as `python -m ntc_design ...` (the installed `ntc` script is the same
code; a pyenv shim in front of it adds its own second). The certify rows compare the
decay rate by the shifted Lyapunov equation (default) with the LMI bisection
(`--rate-method lmi`, cvxpy + Clarabel).

The first run (issue 47, item 9): Quickstart's `ntc simulate` of G1 (1000 paths, T = 10)
with Numba's cache pointed at an empty folder (a fresh install compiles the kernel it
calls) and then again with that cache warm, in CPU seconds of the process and its workers
(wall time on a shared machine says little about compiling); target: the cold run at most
2.5× the warm one.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NTC = [sys.executable, "-m", "ntc_design"]
G1 = ["examples/g1.yaml"]
CASES = [
    ("python -c pass", [sys.executable, "-c", "pass"], None),
    ("import ntc_design", [sys.executable, "-c", "import ntc_design"], 0.3),
    ("ntc --help", [*NTC, "--help"], 0.3),
    ("ntc --version", [*NTC, "--version"], 0.3),
    ("ntc check g1", [*NTC, "check", *G1], 1.0),
    ("ntc certify g1 (Lyapunov α)", [*NTC, "certify", *G1, "--theta", "1,2,-1", "--gain", "1/(1+t)"], 1.5),
    (
        "ntc certify g1 (LMI α)",
        [*NTC, "certify", *G1, "--theta", "1,2,-1", "--gain", "1/(1+t)", "--rate-method", "lmi"],
        None,
    ),
]  # fmt: skip


def wall(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, capture_output=True, check=False)
    return time.perf_counter() - t0


def cpu(cmd: list[str], env: dict[str, str]) -> float:
    """CPU seconds (user + system) of a fresh process and its children."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, cwd=ROOT, capture_output=True, check=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def first_run(repeat: int) -> None:
    """Cold (an empty Numba cache) against warm `ntc simulate` of G1, CPU seconds."""
    sim = [*NTC, "simulate", "examples/scenarios/g1_fixed.yaml", "--out"]
    cold, warm = [], []
    for _ in range(repeat):  # alternated: each round its own empty cache
        with tempfile.TemporaryDirectory() as d:
            env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(d) / "numba")}
            cold.append(cpu([*sim, f"{d}/cold"], env))
            warm.append(cpu([*sim, f"{d}/warm"], env))
    c, w = statistics.median(cold), statistics.median(warm)
    print(f"\nntc simulate g1_fixed.yaml (1000 paths, T = 10), CPU s, median of {repeat}:")
    print(f"{'cold Numba cache (first run)':<30} {c:9.2f}   ({min(cold):.2f}-{max(cold):.2f})")
    print(f"{'warm Numba cache':<30} {w:9.2f}   ({min(warm):.2f}-{max(warm):.2f})")
    print(f"{'cold / warm':<30} {c / w:9.2f}   (target <= 2.5)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--first-run-only", action="store_true", help="only the cold/warm rows")
    args = ap.parse_args()
    if args.first_run_only:
        first_run(max(1, args.repeat))
        return
    wall(NTC + ["--version"])  # warm the file cache and Numba's
    print(f"{'command':<30} {'median s':>9} {'target s':>9} {'ratio':>7} {'× python':>9}")
    base = None
    for name, cmd, target in CASES:
        med = statistics.median(wall(cmd) for _ in range(args.repeat))
        base = base or med
        ratio = f"{med / target:7.2f}" if target else "      —"
        tgt = f"{target:9.1f}" if target else "        —"
        print(f"{name:<30} {med:9.2f} {tgt} {ratio} {med / base:9.1f}")
    first_run(max(1, args.repeat // 2))


if __name__ == "__main__":
    main()
