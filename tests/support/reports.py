"""The paper's Section 5 run once at full size for the report tests, and the checks that
a report's links and anchors resolve."""

import re
from pathlib import Path

import pytest

from ntc_design.reports.reproduce import reproduce_paper
from tests.support.shared import once_per_run


@pytest.fixture(scope="session")
def paper_run(tmp_path_factory):
    """The paper's Section 5 at its settings (1000 paths, ds = dt = 1e-3, T = 100): run once
    per test run, whichever xdist worker asks first (the others read its folder)."""

    def build():
        out = tmp_path_factory.mktemp("paper")
        path, ok, wall = reproduce_paper(out)
        return [str(out), str(path), ok, wall]

    out, path, ok, wall = once_per_run(tmp_path_factory, "paper_run", build)
    return Path(out), Path(path), ok, wall


def _links(path: Path) -> tuple[list[str], set[str]]:
    """Every href of a report and every id it defines."""
    html = path.read_text()
    return re.findall(r'href="([^"]+)"', html), set(re.findall(r'id="([^"]+)"', html))


def _assert_links_resolve(path: Path) -> int:
    hrefs, ids = _links(path)
    files = [h for h in hrefs if not h.startswith("#")]
    for h in hrefs:
        if h.startswith("#"):
            assert h[1:] in ids, h
        else:
            assert "://" not in h, h
            assert (path.parent / h).is_file(), h
    return len(files)


def stand_in_save(monkeypatch, draw: tuple[str, ...] = (), formats=("png",)) -> list[Path]:
    """Replace ``style.save`` by one that draws nothing: each figure is closed and its
    files (``formats``) are empty stand-ins, so links to them resolve; the stems ending in
    one of ``draw`` are drawn for real (``formats``, PNG at 72 dpi) for the tests that
    read them. Drawing is the slow part of a report (about 0.4 s a figure); the full-size runs and
    tests/reports/test_style.py draw every format. Returns the stems saved, in order."""
    import matplotlib.pyplot as plt

    from ntc_design.reports import style

    real = style.save
    got: list[Path] = []

    def save(fig, stem, **_):
        got.append(stem)
        if draw and stem.name.endswith(draw):
            return real(fig, stem, formats=formats, dpi=72)
        plt.close(fig)
        stem.parent.mkdir(parents=True, exist_ok=True)
        files = {f: stem.with_suffix(f".{f}") for f in formats}
        for p in files.values():
            p.write_bytes(b"")
        return style.SavedFigure(stem, files, b"")

    monkeypatch.setattr(style, "save", save)
    return got
