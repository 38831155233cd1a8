"""The measured figures the documentation states, kept in one place (issue 43, item A).

``docs/_generated/figures.json`` holds every performance figure that README.md and the
guide state (throughputs, timings, the install, the test counts, the first command's
residual), each with the benchmark that re-measures it; ``docs/_generated/figures.md`` is
its rendering, which the guide's benchmarks page includes. The benchmarks that measure a
figure rewrite its entry (``python benchmarks/bench_readme.py --all --write``); nothing
else edits either file by hand, and ``tests/system/test_doc_figures.py`` checks that every
figure the pages state is one of these.

    python benchmarks/figures.py          # re-render figures.md from figures.json
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
JSON = ROOT / "docs" / "_generated" / "figures.json"
MARKDOWN = ROOT / "docs" / "_generated" / "figures.md"

HEADER = (
    "<!-- generated from figures.json by benchmarks/figures.py: do not edit by hand;\n"
    "     the benchmark named in each row re-measures it -->\n"
)


def load() -> dict:
    """The figures document: ``{"machine": ..., "figures": [{key, group, what, figure, by}]}``."""
    return json.loads(JSON.read_text(encoding="utf-8"))


def entry(doc: dict, key: str) -> dict:
    """The entry named ``key``."""
    for e in doc["figures"]:
        if e["key"] == key:
            return e
    raise KeyError(key)


def render(doc: dict) -> str:
    """figures.md: one table per group, in the order of first appearance."""
    groups: dict[str, list[dict]] = {}
    for e in doc["figures"]:
        groups.setdefault(e["group"], []).append(e)
    out = [HEADER, doc["machine"], ""]
    for group, rows in groups.items():
        out += [f"**{group}**", "", "| what | figure | re-measured by |", "|---|---|---|"]
        out += [f"| {e['what']} | {e['figure']} | `{e['by']}` |" for e in rows]
        out.append("")
    return "\n".join(out)


def save(doc: dict) -> None:
    """Write figures.json and its rendering figures.md."""
    JSON.write_text(json.dumps(doc, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    MARKDOWN.write_text(render(doc), encoding="utf-8")


def update(figures: dict[str, str]) -> None:
    """Replace the ``figure`` text of the entries named (a benchmark's new measurements)."""
    doc = load()
    for key, text in figures.items():
        entry(doc, key)["figure"] = text
    save(doc)


if __name__ == "__main__":
    save(load())
