"""Re-measure the figures README.md states about installing, testing and the docs, and
print each beside the README's value as a ratio (issue 29: a README figure is one a test
or a benchmark re-measures).

    python benchmarks/bench_readme.py            # the test count, the first command
    python benchmarks/bench_readme.py --all      # also the suite, the install, the docs

The README's numbers themselves (design, certificate, tune) are asserted by
tests/system/test_readme.py; this script measures what depends on the machine: times and sizes.
The install is timed in a fresh virtual environment from the configured package index.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def readme_figure(pattern: str) -> str:
    """The README's text matched by ``pattern`` (group 1)."""
    m = re.search(pattern, (ROOT / "README.md").read_text(), re.S)
    return m.group(1) if m else "?"


def timed(cmd: list[str], cwd: Path = ROOT, env: dict | None = None) -> tuple[float, str]:
    t0 = time.perf_counter()
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env)
    return time.perf_counter() - t0, out.stdout + out.stderr


def minutes(text: str) -> float:
    """'14 min', '1 min 53 s', '40 s' -> minutes."""
    m = re.search(r"(?:(\d+)\s*min)?\s*(?:(\d+)\s*s)?", text)
    if not m or not (m.group(1) or m.group(2)):
        return float("nan")
    return int(m.group(1) or 0) + int(m.group(2) or 0) / 60


def row(what: str, said: str, measured: str, ratio: float | None) -> None:
    r = f"{ratio:6.2f}" if ratio is not None else "     —"
    print(f"{what:<38} {said:>16} {measured:>16} {r}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--all", action="store_true", help="suite, install and docs too (~30 min)")
    args = ap.parse_args()
    print(f"{'figure':<38} {'README':>16} {'measured':>16} {'ratio'}")

    _, out = timed([sys.executable, "-m", "pytest", "--collect-only", "-q"])
    n = int(re.search(r"(\d+) tests? collected", out).group(1))
    said = readme_figure(r"([\d,]+) tests,")
    row("tests collected", said, f"{n:,}", n / float(said.replace(",", "")))
    _, out = timed([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"])
    m = re.search(r"(\d+)/\d+ tests collected|(\d+) tests? collected", out)
    fast = int(m.group(1) or m.group(2))
    said = readme_figure(r"slow ones out\s+\(([\d,]+) tests")  # across the line break
    row("fast-lane tests", said, f"{fast:,}", fast / float(said.replace(",", "")))

    secs, _ = timed(
        ["ntc", "certify", "examples/g1.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    )
    row("first command (certify G1), s", "—", f"{secs:.1f}", None)

    if not args.all:
        return
    secs, _ = timed([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"])
    said = readme_figure(r"tests, (\d+ min) in a fresh")
    row("whole suite, min", said, f"{secs / 60:.1f}", secs / 60 / minutes(said))
    with tempfile.TemporaryDirectory() as tmp:
        venv = Path(tmp) / "venv"
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        secs, _ = timed([str(venv / "bin" / "pip"), "install", "-q", str(ROOT)])
        said = readme_figure(r"Linux x86-64 wheels: (\d+ min(?: \d+ s)?)")
        row("install, min", said, f"{secs / 60:.1f}", secs / 60 / minutes(said))
        size = sum(f.stat().st_size for f in venv.rglob("*") if f.is_file()) / 2**30
        said = readme_figure(r"toolkit \(([\d.]+) GB")
        row("install size, GB", said, f"{size:.2f}", size / float(said))
        dists = len(list((venv / "lib").glob("python*/site-packages/*.dist-info")))
        said = readme_figure(r"GB in (\d+) distributions")
        row("distributions installed", said, str(dists), dists / float(said))
    secs, _ = timed([sys.executable, "-m", "sphinx", "-q", "-b", "html", "docs", f"{tmp}-docs"])
    said = readme_figure(
        r"\((\d+ min(?: \d+ s)?) with the install, in a fresh"
    )  # README's docs time
    row("docs build (no install), min", said, f"{secs / 60:.1f}", secs / 60 / minutes(said))


if __name__ == "__main__":
    main()
