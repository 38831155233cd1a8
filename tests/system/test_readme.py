"""The Python blocks of the README and of the user guide (docs/guide/*.md) paste and run as
they are, each on its own, from a checkout (examples/ beside them, runs/ to write into)."""

import os
import re
import subprocess
import sys

import pytest

from tests.conftest import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]
BLOCKS = [
    b
    for page in PAGES
    for b in re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.S)
]


def test_the_readme_and_the_guide_have_python_blocks():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "```python" in readme and len(BLOCKS) >= 5
    assert len(readme.splitlines()) <= 250  # the README fits on a screen; the guide has the rest


@pytest.mark.slow
@pytest.mark.parametrize("k", range(len(BLOCKS)))
def test_readme_python_block_runs_on_its_own(k, tmp_path):
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "runs").mkdir()
    r = subprocess.run(
        [sys.executable, "-c", BLOCKS[k]], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert r.returncode == 0, r.stderr[-2000:]


README = (ROOT / "README.md").read_text(encoding="utf-8")


def _said(pattern: str) -> str:
    m = re.search(pattern, README, re.S)
    assert m, pattern
    return m.group(1)


def test_readme_numbers_of_the_first_command(g1, theta):
    # every figure the Quickstart states about G1, recomputed
    import ntc_design as nd
    from ntc_design.certify import certify

    res = certify(g1, theta, gain="1/(1+t)")
    assert res.proven
    assert int(_said(r"table of the (\d+) certificate checks")) == len(res.verification.checks)
    alpha = res.certificate["results"]["lmi"]["alpha"]
    assert _said(r"decay rate: α = ([\d.]+)") == f"{alpha:.6f}"
    des = nd.design(g1, theta, margin=0.1)
    assert _said(r"C = ([\d.]+),\nδ") == f"{des.C:.4f}"
    assert _said(r"δ_S = ([\d.]+):") == f"{des.thresholds.symmetric:.4f}"
    x0 = ", ".join(f"{v:.3f}" for v in des.x0)
    assert f"x0 = [{x0}]" in README
    minors = int(_said(r"all (\d+) leading minors"))
    assert minors == g1.n * g1.dim


@pytest.mark.slow  # ~11 s: it collects the whole suite in a second pytest
def test_readme_test_counts_are_those_collected():
    # one collection gives both: "2845/2872 tests collected (27 deselected)"
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"],
        cwd=ROOT, capture_output=True, text=True,
        env={k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"},  # CI's coverage
    ).stdout  # fmt: skip
    m = re.search(r"(\d+)/(\d+) tests collected", out)
    assert m, out[-500:]
    fast_now, total_now = int(m.group(1)), int(m.group(2))
    total = int(_said(r"([\d,]+) tests, \d+ min").replace(",", ""))
    fast = int(_said(r"slow ones out\n?\s*\(([\d,]+) tests").replace(",", ""))
    # within 5 %: the README is re-measured when the suite grows by more
    assert abs(total_now - total) <= 0.05 * total
    assert abs(fast_now - fast) <= 0.05 * fast
