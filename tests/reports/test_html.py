"""Tests of :mod:`ntc_design.reports.html`."""

import shutil
import subprocess

import pytest
from markupsafe import Markup

from ntc_design.reports.html import Table

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.mark.slow  # it opens the full-size paper report (the module's paper_run, ~40 s)
@pytest.mark.skipif(
    CHROMIUM is None, reason="Debian's chromium is not installed (.ci/run installs it where it can)"
)
def test_report_opens_in_headless_chromium(paper_run, tmp_path):
    _, path, _, _ = paper_run
    dom = subprocess.run(
        [
            CHROMIUM,
            *FLAGS,
            f"--user-data-dir={tmp_path / 'profile'}",
            "--virtual-time-budget=10000",
            "--dump-dom",
            path.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    n = path.read_text().count("<img ")
    assert n == 23
    assert f'data-images-loaded="{n}/{n}"' in dom
    shot = tmp_path / "shot.png"
    subprocess.run(
        [
            CHROMIUM,
            *FLAGS,
            f"--user-data-dir={tmp_path / 'profile2'}",
            "--window-size=1200,1600",
            f"--screenshot={shot}",
            path.as_uri(),
        ],
        capture_output=True,
        timeout=120,
    )
    assert shot.stat().st_size > 50_000


@pytest.mark.parametrize(
    "value",
    [{"href": "c.json", "text": "c.json"}, {"verdict": True, "text": "ok"}, True, None, 1.5],
    ids=["link dict", "verdict dict", "bool", "None", "float"],
)
def test_a_report_table_takes_only_text_cells(value):
    # a value the template would print as Python is refused where the table is built;
    # links and verdicts are rows.Cell, rendered by html_table
    with pytest.raises(TypeError, match="expected text or Markup"):
        Table(("property", "result"), [("certificate", value)])
    assert Table(("a",), [("text",), (Markup("<b>x</b>"),)]).rows[1][0] == "<b>x</b>"
