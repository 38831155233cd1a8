"""Start-up and small answers (issue 30): wall time of fresh processes, the median of
several runs, beside `python -c pass` measured in the same run and the issue's targets.

    python benchmarks/bench_startup.py [--repeat 5]

Each command runs as `python -m ntc_design ...` (the installed `ntc` script is the same
code; a pyenv shim in front of it adds its own second). The certify rows compare the
decay rate by the shifted Lyapunov equation (default) with the LMI bisection
(`--rate-method lmi`, cvxpy + Clarabel).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    wall(NTC + ["--version"])  # warm the file cache and Numba's
    print(f"{'command':<30} {'median s':>9} {'target s':>9} {'ratio':>7} {'× python':>9}")
    base = None
    for name, cmd, target in CASES:
        med = statistics.median(wall(cmd) for _ in range(args.repeat))
        base = base or med
        ratio = f"{med / target:7.2f}" if target else "      —"
        tgt = f"{target:9.1f}" if target else "        —"
        print(f"{name:<30} {med:9.2f} {tgt} {ratio} {med / base:9.1f}")


if __name__ == "__main__":
    main()
