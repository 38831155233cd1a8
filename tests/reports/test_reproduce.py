"""Tests of :mod:`ntc_design.reports.reproduce`."""

import json

import numpy as np
import pytest

from ntc_design.reports.reproduce import reproduce_paper
from tests.support.reports import _assert_links_resolve, _links, stand_in_save


def _rows(html: str) -> list[str]:
    body = html.split('<h2 id="summary">Summary', 1)[1].split("</table>", 1)[0]
    return body.split("<tr>")[2:]


@pytest.mark.slow
def test_reproduce_paper_summary_matches(paper_run):
    out, path, ok, wall = paper_run
    html = path.read_text()
    rows = _rows(html)
    assert len(rows) == 17
    assert all('class="ok">✓' in r for r in rows), [r for r in rows if "✓" not in r]
    assert ok
    for s in (
        "7.1440",
        "7.2440",
        "7.0495",
        "3.1000",
        "[1.2761, 2.5522, -1.2761]",
        "[1.6452, 3.2903, -1.6452]",
    ):
        assert s in html
    for key in ("g1", "switching", "gain_vanishing", "gain_energy"):
        for name in ("summary.json", "ms_error.csv", "paths.npz", "certificate.json"):
            assert (out / key / name).is_file()
    for stem in (
        "g1_ms_error",
        "g1_states",
        "g1_coupling",
        "g1_gain",
        "switching_topology_G2",
        "switching_schedule",
        "gain_energy_states",
    ):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 10_000
        assert (out / "figures" / f"{stem}.svg").read_text().lstrip().startswith("<?xml")
        assert (out / "figures" / f"{stem}.pdf").read_bytes().startswith(b"%PDF")
    assert wall < 900  # a gross-regression guard only: speed is measured in benchmarks/


@pytest.mark.slow
def test_reproduce_report_structure(paper_run):
    """The α(δ) figure, the table of contents, data links that resolve, a re-run command that
    runs, parameters as a table, no empty table header."""
    out, path, _, _ = paper_run
    html = path.read_text()
    assert html.count('<nav class="toc"') == 1
    toc = html.split('<nav class="toc"', 1)[1].split("</nav>", 1)[0]
    for key in ("summary", "g1", "switching", "gain_vanishing", "gain_energy"):
        assert f'href="#{key}"' in toc
    for sub in ("coupling", "convergence", "data", "parameters"):
        assert f'href="#g1-{sub}"' in toc
    for key in ("g1", "switching", "gain_vanishing", "gain_energy"):
        assert f'id="{key}-fig-coupling"' in html
        assert f'href="figures/{key}_coupling.pdf"' in html
        for name in ("summary.json", "ms_error.csv", "ms_error_long.csv", "certificate.json"):
            assert f'href="{key}/{name}"' in html
    assert "decay rate −max Re λ(−L_B(δ))" in html.replace("Decay rate", "decay rate")
    assert _assert_links_resolve(path) > 80
    assert "<th></th>" not in html and "<pre>" not in html
    assert html.count("ntc reproduce paper --out " + str(out)) >= 5
    assert "ntc simulate ntc reproduce" not in html
    assert '<table class="matrix">' in html
    # convergence: the fitted decay exponent of the exact curve against the prediction
    doc = json.loads((out / "paper_summary.json").read_text())
    conv = doc["convergence"]
    assert conv["g1"]["predicted"] == 1.0
    assert abs(conv["g1"]["fits"]["all (Σ_i)"]["exact"] - 1.0) < 0.15
    assert abs(conv["gain_energy"]["predicted"] - 1 / 3) < 1e-12
    assert abs(conv["gain_energy"]["fits"]["all (Σ_i)"]["exact"] - 1 / 3) < 0.1
    assert conv["gain_vanishing"]["predicted"] == 0.0
    assert abs(conv["gain_vanishing"]["fits"]["all (Σ_i)"]["exact"]) < 0.1  # E → E∞ + K/(1+t)
    assert len(doc["rows"]) == 17 and all(r["match"] for r in doc["rows"])
    fine = np.load(out / "gain_energy" / "paths_fine.npz")
    coarse = np.load(out / "gain_energy" / "paths.npz")
    assert fine["t"].size > 4 * coarse["t"].size


def test_a_short_reproduction_in_the_fast_lane(tmp_path, monkeypatch):
    """The paper's Section 5 at T = 2 with 40 paths: every design and certification row
    matches at any horizon; only the three rows about the limit t → ∞ need the full T.
    Only the figure whose pixels are read is drawn (PNG at 72 dpi); the others are empty
    stand-in files, so the links to them resolve (drawing them is the slow full-size
    run's check, test_reproduce_paper_summary_matches)."""
    saved = stand_in_save(monkeypatch, draw=("switching_schedule",))
    path, ok, _ = reproduce_paper(tmp_path, T=2.0, paths=40, workers=1)
    doc = json.loads((tmp_path / "paper_summary.json").read_text())
    missed = [r["quantity"] for r in doc["rows"] if not r["match"]]
    assert len(doc["rows"]) == 17 and not ok
    assert len(missed) == 3 and all("→" in q or "no consensus" in q for q in missed), missed
    html = path.read_text()
    for s in ("7.1440", "7.2440", "[1.2761, 2.5522, -1.2761]"):
        assert s in html
    hrefs, ids = _links(path)
    files = [h for h in hrefs if not h.startswith("#") and not h.endswith((".svg", ".pdf"))]
    assert len(files) > 40 and all((path.parent / h).is_file() for h in files)
    assert all(h[1:] in ids for h in hrefs if h.startswith("#"))
    assert html.count("ntc reproduce paper --out " + str(tmp_path)) >= 5
    # the switching figure is drawn, not blank: a tenth of its pixels are ink
    import matplotlib.image

    # every section's figures were drawn (built; saved as stand-ins), 23 in all
    keys = ("g1", "switching", "gain_vanishing", "gain_energy")
    assert len(saved) == 23 and [s.name for s in saved if s.name.endswith("_coupling")] == [
        f"{k}_coupling" for k in keys
    ]
    img = matplotlib.image.imread(tmp_path / "figures" / "switching_schedule.png")
    assert np.mean(img[..., :3].min(axis=-1) < 0.9) > 0.1
