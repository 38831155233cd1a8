"""Re-measure the figures of installing, testing and building the docs, and the first
command's residual, and print each beside the value docs/_generated/figures.json states,
as a ratio; with ``--write``, store the new figures there (and re-render figures.md, which
the guide's benchmarks page includes). A figure the documentation states is one a test or
a benchmark re-measures (issues 29 and 43).

    python benchmarks/bench_readme.py                  # the test counts, the first command
    python benchmarks/bench_readme.py --all            # also the suite, the install, the docs,
                                                       # ntc reproduce (~30 min)
    python benchmarks/bench_readme.py --all --write    # ... and store them

The README's design, certificate and tune numbers are asserted by tests/system/test_readme.py;
this script measures what depends on the machine: counts, times and sizes. The install is
timed in a fresh virtual environment from the configured package index.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import figures

ROOT = Path(__file__).resolve().parents[1]
ENV = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}  # CI's coverage options


def stated(key: str) -> str:
    """The figure text figures.json holds for ``key``."""
    return figures.entry(figures.load(), key)["figure"]


def timed(cmd: list[str], cwd: Path = ROOT) -> tuple[float, str]:
    t0 = time.perf_counter()
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=ENV)
    return time.perf_counter() - t0, out.stdout + out.stderr


def minutes(text: str) -> float:
    """The first '14 min', '1 min 53 s' or '40 s' in ``text``, in minutes."""
    m = re.search(r"(\d+) min(?: (\d+) s)?|(\d+) s\b", text)
    if not m:
        return float("nan")
    return int(m.group(1) or 0) + int(m.group(2) or m.group(3) or 0) / 60


def clock(secs: float) -> str:
    """Seconds as '1 min 40 s', '6 min' or '45 s'."""
    m, s = divmod(round(secs), 60)
    return f"{m} min {s:02d} s" if m and s else f"{m} min" if m else f"{s} s"


def row(what: str, said: float, measured: float, shown: str) -> None:
    print(f"{what:<38} {said:>12.4g} {shown:>16} {measured / said:6.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--all", action="store_true", help="suite, install, docs, reproduce (~30 min)")
    ap.add_argument("--write", action="store_true", help="store the figures in figures.json")
    args = ap.parse_args()
    new: dict[str, str] = {}
    print(f"{'figure':<38} {'stated':>12} {'measured':>16} {'ratio'}")

    _, out = timed([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"])
    fast, total = map(int, re.search(r"(\d+)/(\d+) tests collected", out).groups())
    said = re.search(r"([\d,]+) tests; ([\d,]+) in the fast lane", stated("tests"))
    said_total, said_fast = (int(x.replace(",", "")) for x in said.groups())
    row("tests collected", said_total, total, f"{total:,}")
    row("fast-lane tests", said_fast, fast, f"{fast:,}")
    new["tests"] = f"{total:,} tests; {fast:,} in the fast lane"

    _, out = timed(
        [
            sys.executable,
            "-m",
            "ntc_design",
            "certify",
            "examples/g1.yaml",
            "--theta",
            "1,2,-1",
            "--gain",
            "1/(1+t)",
        ]
    )
    residual = re.search(r"Lyapunov residual (\S+)", out).group(1)
    row("first command's residual", float(stated("residual")), float(residual), residual)
    new["residual"] = residual

    if args.all:
        # .ci/run's two pytest lanes, without its coverage (the fast lane's target: 4 min)
        lane = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m"]
        fsecs, _ = timed([*lane, "not slow"])
        ssecs, _ = timed([*lane, "slow"])
        said = stated("suite")
        row("fast lane, min", minutes(said.split("fast lane", 1)[1]), fsecs / 60, clock(fsecs))
        row("slow lane, min", minutes(said.split("slow lane", 1)[1]), ssecs / 60, clock(ssecs))
        new["suite"] = (
            f"the fast lane {clock(fsecs)} without coverage; the slow lane {clock(ssecs)}"
        )
        with tempfile.TemporaryDirectory() as tmp:
            times = []
            for k in (1, 2):  # a cold and a warm pip cache
                venv = Path(tmp) / f"venv{k}"
                subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
                t0 = time.perf_counter()
                subprocess.run([str(venv / "bin" / "pip"), "install", "-q", str(ROOT)], check=True)
                ntc = str(venv / "bin" / "ntc")
                subprocess.run([ntc, "certify", "examples/g1.yaml", "--theta", "1,2,-1"], cwd=ROOT)
                times.append(time.perf_counter() - t0)
            said = stated("install")
            row("install + first command, min", minutes(said), times[0] / 60, clock(times[0]))
            new["install"] = f"{clock(times[0])}; {clock(times[1])} with a warm pip cache"
            venv = Path(tmp) / "venv1"
            (site,) = (venv / "lib").glob("python*/site-packages")
            size = sum(f.stat().st_size for f in site.rglob("*") if f.is_file()) / 2**30
            dists = len(list((venv / "lib").glob("python*/site-packages/*.dist-info")))
            said = stated("install_size")
            row("install size, GB", float(said.split(" GB")[0]), size, f"{size:.2f}")
            row(
                "distributions",
                float(re.search(r"(\d+) distributions", said).group(1)),
                dists,
                str(dists),
            )
            rest = said.split("; ", 1)[1] if "; " in said else ""
            new["install_size"] = (
                f"{size:.2f} GB in {dists} distributions ({size * 1024:.0f} MB; was 1.3 GB in 69)"
                + (f"; {rest}" if rest else "")
            )
            docs = Path(tmp) / "docs-venv"
            subprocess.run([sys.executable, "-m", "venv", str(docs)], check=True)
            t0 = time.perf_counter()
            subprocess.run(
                [str(docs / "bin" / "pip"), "install", "-q", "-e", f"{ROOT}[docs]"], check=True
            )
            build = [str(docs / "bin" / "python"), "-m", "sphinx", "-q", "-b", "html", "docs"]
            subprocess.run([*build, f"{tmp}/html"], cwd=ROOT, check=True)
            secs = time.perf_counter() - t0
            row(
                "docs, install and build, min",
                minutes(stated("docs_build")),
                secs / 60,
                clock(secs),
            )
            new["docs_build"] = clock(secs)
            # the peak of the reproduce process alone: measured in a wrapper of its own
            wrap = (
                "import resource, subprocess, sys; r = subprocess.run(sys.argv[1:], text=True,"
                " capture_output=True); print(r.stdout + r.stderr);"
                " print('peak', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
            )
            cmd = [
                sys.executable,
                "-m",
                "ntc_design",
                "reproduce",
                "paper",
                "--out",
                f"{tmp}/paper",
            ]
            wall, out = timed([sys.executable, "-c", wrap, *cmd])
            peak = int(re.search(r"peak (\d+)", out).group(1)) / 1024  # KiB on Linux
            printed = re.search(r"report\.html in (\d+) s", out).group(1)
            row(
                "ntc reproduce paper, s", minutes(stated("reproduce")) * 60, float(printed), printed
            )
            new["reproduce"] = (
                f"{printed} s; {wall:.0f} s and {peak:.0f} MB peak for the whole process"
            )
    if args.write:
        figures.update(new)
        print(f"wrote {len(new)} figures into {figures.JSON.relative_to(ROOT)} and figures.md")


if __name__ == "__main__":
    main()
