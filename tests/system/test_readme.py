"""The README and the user guide (docs/guide/*.md): their Python blocks paste and run as
they are, each on its own, from a checkout (examples/ beside them, runs/ to write into);
the numbers the README states are recomputed; every measured figure they state is one of
docs/_generated/figures.json's (issue 43: one generated place, no two values of a figure);
the README's layout (the first example near the top, sentences of at most 40 words)."""

import importlib.util
import json
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
    assert _said(r"C = ([\d.]+),\s+δ") == f"{des.C:.4f}"
    assert _said(r"δ_S = (\d+\.\d+)") == f"{des.thresholds.symmetric:.4f}"
    x0 = ", ".join(f"{v:.3f}" for v in des.x0)
    assert f"x0 = [{x0}]" in README
    minors = int(_said(r"all (\d+) leading minors"))
    assert minors == g1.n * g1.dim


@pytest.mark.slow  # ~11 s when it collects the whole suite in a second pytest
def test_readme_test_counts_are_those_collected(request):
    from tests.conftest import WHOLE_SUITE_COUNTS

    counted = request.config.stash.get(WHOLE_SUITE_COUNTS, None)
    if counted is not None:  # this run collected the whole suite: its own counts
        total_now, fast_now = counted
    else:  # one collection gives both: "2845/2872 tests collected (27 deselected)"
        out = subprocess.run(
            [sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"],
            cwd=ROOT, capture_output=True, text=True,
            env={k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"},  # CI's coverage
        ).stdout  # fmt: skip
        m = re.search(r"(\d+)/(\d+) tests collected", out)
        assert m, out[-500:]
        fast_now, total_now = int(m.group(1)), int(m.group(2))
    # the one place that states them: docs/_generated/figures.json (bench_readme.py --write)
    total, fast = _stated_test_counts()
    # within 5 %: the figures are re-measured when the suite grows by more
    assert abs(total_now - total) <= 0.05 * total
    assert abs(fast_now - fast) <= 0.05 * fast


# -- the measured figures: one generated place ------------------------------------------

GENERATED = ROOT / "docs" / "_generated"
FIGURES = json.loads((GENERATED / "figures.json").read_text(encoding="utf-8"))


def _figure(key: str) -> str:
    return next(e["figure"] for e in FIGURES["figures"] if e["key"] == key)


def _stated_test_counts() -> tuple[int, int]:
    m = re.fullmatch(r"([\d,]+) tests; ([\d,]+) in the fast lane", _figure("tests"))
    assert m, _figure("tests")
    return int(m.group(1).replace(",", "")), int(m.group(2).replace(",", ""))


def _number(text: str) -> float:
    return float(text.replace(",", ""))


# what a page states as a measured figure: a throughput, a residual, a test count, an
# install size or a duration in minutes
STATED = [
    re.compile(r"(\d[\d,.]*(?:e[+-]?\d+)?) (?:agent-)?(?:path-steps|normals)/s"),
    re.compile(r"[Rr]esidual (\d[\d.]*e-\d+)"),
    re.compile(r"(\d[\d,]*) (?:tests|fast-lane tests)\b"),
    re.compile(r"(\d[\d.]*) GB in \d+ distributions"),
    re.compile(r"(\d+ min(?: \d+ s)?)\b"),
]


def test_the_generated_figures_page_is_the_rendering_of_figures_json():
    spec = importlib.util.spec_from_file_location("figures", ROOT / "benchmarks" / "figures.py")
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    assert (GENERATED / "figures.md").read_text(encoding="utf-8") == figures.render(FIGURES)
    keys = [e["key"] for e in FIGURES["figures"]]
    assert len(keys) == len(set(keys))
    for e in FIGURES["figures"]:  # each names the benchmark that re-measures it
        assert (ROOT / "benchmarks" / e["by"].split()[0]).is_file(), e
    size = next(e["figure"] for e in FIGURES["figures"] if e["key"] == "install_size")
    # the core install, at most 60 % of the 1,307 MB it was (.ci/installed_wheel re-measures)
    assert int(re.search(r"\((\d+) MB", size).group(1)) <= 784
    benchmarks = (ROOT / "docs" / "guide" / "benchmarks.md").read_text(encoding="utf-8")
    assert "```{include} ../_generated/figures.md" in benchmarks


def test_every_figure_the_pages_state_is_a_generated_one():
    generated = " ".join(e["figure"] for e in FIGURES["figures"])
    values = {_number(x) for x in re.findall(r"\d[\d,]*\.?\d*(?:e[+-]?\d+)?", generated)}
    bad = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for pattern in STATED:
            for m in pattern.finditer(text):
                said = m.group(1)
                known = said in generated if " min" in said else _number(said) in values
                if not known:
                    bad.append(f"{page.name}: {m.group(0)!r}")
    assert not bad, "figures stated outside docs/_generated/figures.json:\n" + "\n".join(bad)
    # the first command's output, as the README and the certify guide show it
    for page in (ROOT / "README.md", ROOT / "docs" / "guide" / "certify.md"):
        said = re.search(r"Lyapunov residual (\S+)", page.read_text(encoding="utf-8"))
        assert said and said.group(1) == _figure("residual"), page.name


# -- the README's layout ------------------------------------------------------------------


def test_the_readme_shows_its_first_example_near_the_top():
    lines = README.splitlines()
    first = next(k for k, line in enumerate(lines, 1) if line.startswith("```"))
    assert first <= 25
    assert lines[first] == (
        'python -m pip install . && ntc certify examples/g1.yaml --theta 1,2,-1 --gain "1/(1+t)"'
    )
    quickstart = README.split("## Quickstart")[1].split("\n## ")[0]
    assert 'python -m pip install -e ".[test]" && python -m pytest -q' in quickstart
    assert "docs/guide/robust.md" in README  # every guide page is listed
    for page in (ROOT / "docs" / "guide").glob("*.md"):
        assert page.stem == "index" or f"docs/guide/{page.name}" in README, page.name


def _sentences(markdown: str) -> list[str]:
    """The prose of a Markdown page, sentence by sentence: code blocks, tables and headings
    left out, inline code kept as words."""
    text = re.sub(r"```.*?```", "\n\n", markdown, flags=re.S)
    text = re.sub(r"\n\s*[-*] ", "\n\n", text)  # a list item stands on its own
    paragraphs = [
        " ".join(ln for ln in block.splitlines() if not ln.lstrip().startswith(("|", "#")))
        for block in re.split(r"\n\s*\n", text)
    ]
    out = []
    for para in paragraphs:
        para = re.sub(r"\b(e\.g|i\.e|etc|vs|cf)\.", r"\1", para)  # abbreviations end none
        out += [s for s in re.split(r"(?<=[.!?])\s+(?=[^a-z\s])", para) if s.strip()]
    return out


def test_sentences_are_split_as_a_reader_would():
    got = _sentences(
        "One, e.g. `a.b`. Two!\n\n```\nno. code.\n```\n| a. | b. |\nThree\nlines.\n- four\n- five"
    )
    assert got == ["One, e.g `a.b`.", "Two!", "Three lines.", "four", "five"]


def test_no_readme_sentence_is_over_40_words():
    long = [s for s in _sentences(README) if len(s.split()) > 40]
    assert not long, "\n\n".join(f"{len(s.split())} words: {s}" for s in long)


@pytest.mark.parametrize(
    "page", [p for p in PAGES[1:] if p.stem != "index"], ids=lambda p: p.stem
)  # fmt: skip
def test_each_guide_page_leads_with_what_you_get_and_one_command(page):
    lines = page.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# ") and lines[2].startswith("**What you get.**"), lines[:3]
    lead = "\n".join(lines[2:]).split("\n```bash\n", 1)
    assert "\n\n" not in lead[0], "the example follows the lead paragraph"
    command = lead[1].split("\n```", 1)[0].splitlines()
    assert len(command) == 1 and command[0].startswith(("ntc ", "python ")), command
