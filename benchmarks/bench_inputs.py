"""How fast are the guarded readers: files, expressions and the gain analysis?

1. A random topology file with E edges (3x3 weights, flow style) read by
   :func:`ntc_design.io.documents.read_document` (libyaml events, an iterative composer with the
   depth and alias limits, PyYAML's safe constructor), against ``yaml.safe_load`` (pure
   Python, the reader before issue 8) and ``yaml.load(..., CSafeLoader)`` (no limits).
2. Hostile documents refused: billion laughs, 10⁵ levels of nesting, a 5000-digit integer.
3. ``parse_expression`` on typical and hostile gains, and ``analyse_gain`` wall time
   (forked, with a hard limit) on a few gains.

4. Three styles of a generated N-agent topology (issue 30: flow mappings with nested flow
   lists, PyYAML's block style, JSON text) read by :func:`read_document` (which hands a
   text of 1 MiB or more to yaml-rs), beside the compiled peers yaml-rs, ryaml (serde_yaml)
   and libyaml's CSafeLoader (no limits), and the guarded PyYAML path it replaced.

Run: python benchmarks/bench_inputs.py [EDGES] [--styles N]   (default 20000; N = 100000)
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from ntc_design.errors import InputError
from ntc_design.expr.symbolic import parse_expression
from ntc_design.gain.conditions import analyse_gain
from ntc_design.io.documents import read_document


def topology_text(edges: int, agents: int, seed: int = 0) -> str:
    rng = np.random.default_rng(seed)
    lines = ["dim: 3", f"agents: {agents}", "edges:"]
    seen = set()
    while len(seen) < edges:
        j, i = (int(x) for x in rng.integers(1, agents + 1, 2))
        if i == j or (j, i) in seen:
            continue
        seen.add((j, i))
        w = round(float(rng.uniform(0.5, 2.0)), 3)
        lines.append(f"  - {{from: {j}, to: {i}, weight: [[{w}, 0, 0], [0, 1, 0], [0, 0, 2]]}}")
    return "\n".join(lines) + "\n"


def timed(fn) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main(edges: int) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "big.yaml"
        p.write_text(topology_text(edges, max(100, edges // 5)))
        text = p.read_text()
        print(f"topology file: {edges} edges, {len(text) / 1e6:.2f} MB")
        t_ours, doc = timed(lambda: read_document(p))
        t_c, doc_c = timed(lambda: yaml.load(text, Loader=yaml.CSafeLoader))  # noqa: S506
        t_py, _ = timed(lambda: yaml.safe_load(text))
        assert doc == doc_c
        print(f"  read_document {t_ours:.2f} s | CSafeLoader {t_c:.2f} s | safe_load {t_py:.2f} s")

        attacks = {
            "billion laughs": 'a0: &a0 ["lol"]\n'
            + "".join(
                f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]\n" for k in range(1, 10)
            ),
            "nesting 1e5": "x: " + "[" * 100_000 + "]" * 100_000 + "\n",
            "5000-digit int": "dim: " + "9" * 5000 + "\n",
        }
        for name, body in attacks.items():
            q = Path(d) / "attack.yaml"
            q.write_text(body)
            t0 = time.perf_counter()
            try:
                read_document(q)
                verdict = "ACCEPTED"
            except InputError as exc:
                verdict = str(exc).split(": ", 1)[1]
            print(f"  {name}: {1e3 * (time.perf_counter() - t0):.1f} ms: {verdict}")

    for e in ["1/(1+t)", "(2+sin(t))/(1+t)^(1/3)", "t**(10**10)", "sin((pi**1000)**1000)"]:
        t0 = time.perf_counter()
        try:
            parse_expression(e, "gain")
            verdict = "parsed"
        except InputError as exc:
            verdict = str(exc)
        print(f"parse {e!r}: {1e3 * (time.perf_counter() - t0):.2f} ms: {verdict}")
    for g in ["1/(1+t)", "1/log(2+t)", "sin(t)^2/(1+t)", "sin(t)^1000/(1+t)"]:
        t, a = timed(lambda g=g: analyse_gain(g))
        print(
            f"analyse_gain {g!r}: {t:.2f} s: ∫c=∞ {a.integral_diverges.value}, "
            f"c→0 {a.tends_to_zero.value}, ∫c²<∞ {a.square_integrable.value}"
        )


def styles(n: int) -> None:
    """Three machine-written styles of an n-agent topology, each read five ways."""
    import json

    from ntc_design.io import documents
    from ntc_design.model.generate import random_network

    doc = random_network(n, 3, seed=0).to_dict()
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    texts = {
        "flow": yaml.dump(doc, Dumper=dumper, sort_keys=False, default_flow_style=None),
        "block": yaml.dump(doc, Dumper=dumper, sort_keys=False, default_flow_style=False),
        "json": json.dumps(doc),
    }
    peers = {"read_document": None, "yaml-rs": None, "ryaml": None, "CSafeLoader": None}
    try:
        import yaml_rs

        peers["yaml-rs"] = yaml_rs.loads
    except ImportError:
        pass
    try:
        import ryaml  # type: ignore[import-not-found]

        peers["ryaml"] = ryaml.loads
    except ImportError:
        pass
    peers["CSafeLoader"] = lambda t: yaml.load(t, Loader=yaml.CSafeLoader)  # noqa: S506
    print(f"\n{n} agents, {len(doc['edges'])} edges: seconds (ratio to read_document)")
    print(f"{'style':<7} {'MB':>6} " + " ".join(f"{k:>18}" for k in peers) + " guarded PyYAML")
    with tempfile.TemporaryDirectory() as d:
        for style, text in texts.items():
            p = Path(d) / f"{style}.yaml"
            p.write_text(text)
            t_ours, got = timed(lambda p=p: read_document(p))
            assert got == doc, style
            cells = [f"{t_ours:>18.2f}"]
            for fn in list(peers.values())[1:]:
                if fn is None:
                    cells.append(f"{'not installed':>18}")
                    continue
                t, _ = timed(lambda fn=fn, text=text: fn(text))
                cells.append(f"{t:>11.2f} ({t / t_ours:4.2f})")
            # what a file took before yaml-rs: the guarded composer (first 10 % only: ~linear)
            part = text if style == "json" else text[: len(text) // 10]
            if style != "json":
                part = part[: part.rfind("\n  - ")] + "\n"
            old = documents.COMPILED_YAML_MIN_CHARS
            documents.COMPILED_YAML_MIN_CHARS = 1 << 62
            try:
                t_py, _ = timed(lambda part=part, p=p: documents._load_yaml(part, p))
            finally:
                documents.COMPILED_YAML_MIN_CHARS = old
            scale = len(text) / len(part)
            print(
                f"{style:<7} {len(text) / 1e6:>6.1f} " + " ".join(cells) + f" ~{t_py * scale:.0f}"
            )


if __name__ == "__main__":
    args = sys.argv[1:]
    if "--styles" in args:
        k = args.index("--styles")
        styles(int(args[k + 1]) if len(args) > k + 1 else 100_000)
    else:
        main(int(args[0]) if args else 20_000)
