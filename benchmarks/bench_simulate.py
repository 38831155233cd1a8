"""Simulation speed on the paper's G1 problem, ntc-design beside torchsde and sdeint in
one run (peers from the optional `bench` extra: pip install -e ".[bench]").

Problem: G1 with the Lemma 1 design, θ = [1, 2, -1], σ = 0.4, f(x) = 0.3x,
c(t) = 1/(1+t), Euler–Maruyama with dt = 1e-3, 1000 paths, 16 Brownian motions per path.
Prints path-steps per second and the ratios, the machine's random-number floor, the time
of the exact mean-square curves for T = 100, and (with --paper) the full paper-sized run
(1e8 path-steps) with its peak memory.

Run: python benchmarks/bench_simulate.py [--paper]
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

import ntc_design as nd
from ntc_design.simulate import NoiseModel, mode_system, simulate

ROOT = Path(__file__).resolve().parent.parent
THETA = [1.0, 2.0, -1.0]


def problem():
    top = nd.load(ROOT / "examples" / "g1.yaml")
    des = nd.design(top, THETA, thresholds=False)
    x0 = np.random.default_rng(np.random.SeedSequence(1)).uniform(-3, 3, size=21)
    return top, des, x0


def bench_ntc(top, x0, t_end=10.0, workers=2) -> float:
    res = simulate(
        top, THETA, T=t_end, dt=1e-3, paths=1000, seed=0, initial=x0, method="mc", workers=workers
    )
    return res.stats["path_steps_per_second"]


def drift_diffusion(des):
    """f and g of dX = f dt + g dW for the peers: W has 16 components (2 per edge)."""
    s = mode_system(des, NoiseModel(0.4, 0.3))
    lap_b, u, g_add, dmat, wmat, e_n = s.lap_b, s.u, s.g, s.dmat, s.wmat, s.n_edges

    def f(x, t):
        return (u - lap_b @ x) / (1.0 + t)

    def g(x, t):
        diff = (dmat @ x).reshape(e_n, 3)
        mult = np.stack([wmat[:, 3 * e : 3 * e + 3] @ diff[e] for e in range(e_n)], axis=1)
        return np.hstack([g_add, mult]) / (1.0 + t)

    return f, g, s


def bench_sdeint(des, x0, n_steps=5000) -> float | None:
    try:
        import sdeint
    except ImportError:
        return None
    f, g, _ = drift_diffusion(des)
    tspan = np.linspace(0.0, n_steps * 1e-3, n_steps + 1)
    t0 = time.perf_counter()
    sdeint.itoEuler(f, g, x0, tspan, generator=np.random.default_rng(0))
    return n_steps / (time.perf_counter() - t0)


def bench_torchsde(des, x0, n_steps=1000, batch=1000) -> float | None:
    try:
        import torch
        import torchsde
    except ImportError:
        return None
    torch.set_num_threads(2)
    _, _, s = drift_diffusion(des)
    lap = torch.tensor(s.lap_b)
    u = torch.tensor(s.u)
    gadd = torch.tensor(s.g)
    dmat = torch.tensor(s.dmat)
    w = torch.tensor(s.wmat).reshape(21, s.n_edges, 3)

    class SDE(torch.nn.Module):
        noise_type = "general"
        sde_type = "ito"

        def f(self, t, y):
            return (u - y @ lap.T) / (1.0 + t)

        def g(self, t, y):
            diff = (y @ dmat.T).reshape(y.shape[0], -1, 3)  # (B, E, 3)
            mult = torch.einsum("iec,bec->bie", w, diff)  # (B, 21, E)
            add = gadd.expand(y.shape[0], -1, -1)
            return torch.cat([add, mult], dim=2) / (1.0 + t)

    y0 = torch.tensor(x0).expand(batch, -1).clone()
    ts = torch.tensor([0.0, n_steps * 1e-3])
    t0 = time.perf_counter()
    with torch.no_grad():
        torchsde.sdeint(SDE(), y0, ts, method="euler", dt=1e-3)
    return n_steps * batch / (time.perf_counter() - t0)


def rng_floor() -> float:
    rng = np.random.default_rng(0)
    buf = np.empty((64, 1000, 16))
    t0 = time.perf_counter()
    for _ in range(40):
        rng.standard_normal(out=buf)
    return 40 * buf.size / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "--paper", action="store_true", help="also run the paper-sized T = 100 (1e8 path-steps)"
    )
    args = ap.parse_args()
    top, des, x0 = problem()
    floor = rng_floor()
    ours1 = bench_ntc(top, x0, workers=1)
    ours = bench_ntc(top, x0, workers=2)
    sde = bench_sdeint(des, x0)
    tsde = bench_torchsde(des, x0)
    print("G1, 1000 paths, dt = 1e-3, 16 normal draws per path-step")
    print(f"{'implementation':<44} {'path-steps/s':>14} {'ntc-design is':>14}")
    rows = [
        ("ntc-design, 2 workers", ours),
        ("ntc-design, 1 worker", ours1),
        ("torchsde batch Euler, general noise, 2 threads", tsde),
        ("sdeint itoEuler, one path at a time", sde),
    ]
    for name, v in rows:
        ratio = "" if v is None or v == ours else f"{ours / v:>13.1f}x"
        val = "not installed" if v is None else f"{v:.3g}"
        print(f"{name:<44} {val:>14} {ratio:>14}")
    print(f"{'RNG floor: float64 normals/s on one core':<44} {floor:>14.3g}")
    print(
        f"{'  -> path-steps/s if only drawing, 2 cores':<44} {2 * floor / 16:>14.3g} {ours / (2 * floor / 16):>13.2f}x of it"
    )
    t0 = time.perf_counter()
    simulate(top, THETA, T=100.0, initial=x0, method="exact", save_every=0.1)
    print(f"exact mean-square curves, T = 100, 1001 save times: {time.perf_counter() - t0:.2f} s")
    if args.paper:
        t0 = time.perf_counter()
        res = simulate(
            top, THETA, T=100.0, dt=1e-3, paths=1000, seed=0, initial=x0, method="both", workers=2
        )
        wall = time.perf_counter() - t0
        rss = max(
            resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
            resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,
        )
        print(
            f"paper run (T = 100, 1e8 path-steps, MC + exact): {wall:.1f} s, "
            f"{res.stats['path_steps_per_second']:.3g} path-steps/s, peak RSS of one process {rss / 1024:.0f} MB"
        )


if __name__ == "__main__":
    main()
