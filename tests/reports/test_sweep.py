"""Tests of :mod:`ntc_design.reports.sweep`."""

import pandas as pd
import pytest

from ntc_design.present.rows import fmt
from tests.cli_helpers import assert_input_error, run_cli


def test_report_of_a_sweep_directory(sweep_reference, capsys, monkeypatch):
    code, out, err = run_cli(["report", sweep_reference], capsys, monkeypatch)
    assert code == 0, err
    html = (sweep_reference / "report.html").read_text()
    for needle in ('href="results.csv"', 'href="results.parquet"', 'href="curves.parquet"'):
        assert needle in html
    assert html.count("data:image/png;base64,") == 3  # noise.sigma, seed, the overlay
    assert html.count("<tr>") == 1 + 8  # header + one row per point
    assert (sweep_reference / "figures" / "sweep_ms_vs_noise_sigma.png").is_file()


def test_sweep_report_shows_every_point(sweep_files, sweep_reference, tmp_path):
    """``ntc report`` on a sweep folder: one table row per point (its hash and its final
    error as in results.csv), a figure per swept key with two or more values plus the
    overlay, each also written to figures/."""
    import shutil

    from ntc_design.reports.sweep import write_sweep_report

    d = tmp_path / "sw"
    shutil.copytree(sweep_reference, d)
    out = write_sweep_report(d)
    page = out.read_text(encoding="utf-8")
    table = pd.read_csv(d / "results.csv")
    body = page.split('id="points-table"')[1]
    assert body.count("<tr>") == len(table) + 1  # the header and one row per point
    for point, ms in zip(table["point"], table["ms_final_mc"], strict=True):
        assert point in body and fmt(float(ms), 5) in body
    swept = [
        k for k in ("noise.sigma", "margin", "seed", "T") if k in table and table[k].nunique() > 1
    ]
    assert page.count("<img") == len(swept) + 1
    assert len(list((d / "figures").glob("sweep_*.png"))) == len(swept) + 1


def _empty(p):
    p.write_text("", encoding="utf-8")


def _garbage(p):
    p.write_bytes(b"\x00\xff garbage \x01\n\x02,\x03\n")


def _header_only(p):
    p.write_text(p.read_text(encoding="utf-8").splitlines()[0] + "\n", encoding="utf-8")


def _other_columns(p):
    p.write_text("a,b\n1,2\n", encoding="utf-8")


def _missing(p):
    p.unlink()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "damage, needle",
    [
        (_empty, "results.csv: empty"),
        (_garbage, "results.csv: "),
        (_header_only, "results.csv: 0 rows, not the 8 points of results.parquet"),
        (_other_columns, "results.csv: its columns are not those of results.parquet"),
        (_missing, "results.csv: missing"),
    ],
)
def test_a_damaged_results_csv_is_refused_not_linked(
    sweep_reference, tmp_path, capsys, monkeypatch, damage, needle
):
    import shutil

    d = tmp_path / "sw"
    shutil.copytree(sweep_reference, d)
    (d / "report.html").unlink(missing_ok=True)  # what another report test wrote there
    shutil.rmtree(d / "figures", ignore_errors=True)
    damage(d / "results.csv")
    assert_input_error(["report", d], capsys, monkeypatch, needle)
    assert not (d / "report.html").exists() and not (d / "figures").exists()
