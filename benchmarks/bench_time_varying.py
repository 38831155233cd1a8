"""Time-varying topologies: certification time and tightness of Λ₂, and Monte Carlo
throughput with A(t) against the fixed topology.

    python benchmarks/bench_time_varying.py [--skip-large] [--paths 1000]

Targets (issue 11): the 7-agent example certified within 1 % of the sampled infimum in
<= 10 s; N = 100 agents with 20 time-varying edges in <= 60 s; Monte Carlo with A(t) at
least half the path-steps/s of the fixed topology. Wall times on a shared machine are noisy:
the script prints CPU time beside them.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import ntc_design as nd
from ntc_design.certify.time_varying import certify_lambda2
from ntc_design.model.timevarying import from_document
from ntc_design.protocol.timevarying import TimeVaryingDesign
from ntc_design.simulate import NoiseModel, simulate

ROOT = Path(__file__).resolve().parents[1]


def dense_infimum(tv, margin: float = 0.1, k: int = 4000) -> float:
    des = TimeVaryingDesign(tv, np.ones(tv.dim), margin)
    a, b = tv.domain
    lam = []
    for chunk in np.array_split(np.linspace(a, b, k), max(1, k // 200)):
        lap = des.at(chunk).lap_b(des.structure)
        lam.append(np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0])
    return float(np.min(np.concatenate(lam)))


def large_document(n: int = 100, dim: int = 3, varying: int = 20, seed: int = 0) -> dict:
    """An undirected signed network (so L_B + L_Bᵀ ≻ 0, paper's Remark after Theorem 3):
    a ring plus random chords, a few antagonistic pairs, and ``varying`` directed edges
    (``varying/2`` undirected pairs) whose weights are s_k(t)·W with period 2π."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    pairs = {(k, (k + 1) % n) for k in range(n)}
    while len(pairs) < 3 * n:
        a, b = sorted(rng.choice(n, 2, replace=False).tolist())
        pairs.add((a, b))
    pairs = sorted(pairs)
    neg = set(rng.choice(len(pairs), 6, replace=False).tolist())
    var = set(
        rng.choice(
            [k for k in range(len(pairs)) if k not in neg], varying // 2, replace=False
        ).tolist()
    )
    edges = []
    for k, (a, b) in enumerate(pairs):
        m = rng.normal(size=(dim, dim))
        w = (m @ m.T / dim + np.eye(dim)).round(3)
        sgn = -1 if k in neg else 1
        if k in var:
            f = int(rng.integers(1, 4))
            weight = {"matrix": f"W{k}", "scale": f"{sgn} * (1 + 0.4*sin({f}*t + {k % 5}))"}
        else:
            weight = (sgn * w).tolist()
        for i, j in ((a, b), (b, a)):
            edges.append({"from": j + 1, "to": i + 1, "weight": weight})
    mats = {}
    for k in var:
        m = rng.normal(size=(dim, dim))
        mats[f"W{k}"] = (m @ m.T / dim + np.eye(dim)).round(3).tolist()
    return {
        "name": f"N{n}-tv",
        "dim": dim,
        "agents": n,
        "period": "2*pi",
        "matrices": mats,
        "edges": edges,
    }


def bench_certify(name: str, tv) -> None:
    c0, w0 = time.process_time(), time.perf_counter()
    b = certify_lambda2(tv, 0.1)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    inf = dense_infimum(tv)
    print(
        f"{name:<22} Nd = {tv.nd:4d}: Λ₂ = {b.lambda2:.6g}, dense sampled inf = {inf:.6g} "
        f"(gap {100 * (inf - b.lambda2) / inf:.2f} %), {len(b.leaves)} intervals, "
        f"{wall:.1f} s wall, {cpu:.1f} s CPU"
    )


def bench_mc(paths: int) -> None:
    tv = nd.load(ROOT / "examples" / "g1_tv.yaml")
    fixed = nd.load(ROOT / "examples" / "g1.yaml")
    x0 = np.random.default_rng(1).uniform(-3, 3, 21)
    kw = dict(
        gain="1/(1+t)",
        noise=NoiseModel(0.4, 0.3),
        initial=x0,
        T=2.0,
        dt=1e-3,
        paths=paths,
        seed=0,
        workers=1,
        method="mc",
        save_every=0.1,
    )
    rates = {}
    for name, top in (("fixed G1", fixed), ("time-varying G1", tv)):
        best = 0.0
        for _ in range(2):
            r = simulate(top, [1, 2, -1], **kw)
            best = max(best, r.stats.path_steps_per_second)
        rates[name] = best
        print(f"{name:<22} Monte Carlo: {best:.3g} path-steps/s (best of 2, 1 worker)")
    print(f"ratio time-varying / fixed = {rates['time-varying G1'] / rates['fixed G1']:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--paths", type=int, default=1000)
    args = ap.parse_args()
    bench_certify("G1-tv (7 agents)", nd.load(ROOT / "examples" / "g1_tv.yaml"))
    if not args.skip_large:
        bench_certify("N = 100, 20 tv edges", from_document(large_document(), "large"))
    bench_mc(args.paths)


if __name__ == "__main__":
    main()
