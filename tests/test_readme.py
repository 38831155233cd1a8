"""The Python blocks of the README and of the user guide (docs/guide/*.md) paste and run as
they are, each on its own, from a checkout (examples/ beside them, runs/ to write into)."""

import re
import subprocess
import sys

import pytest

from .conftest import ROOT

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
