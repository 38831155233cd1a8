"""Lossy links (issue 49): what the exact moments and the Monte Carlo cost on G1, beside
the lossless sampled protocol, as ratios.

    python benchmarks/bench_loss.py [--quick] [--gpu]

Rows:

- exact moments with loss on G1 (h = 0.1, D = 1, K = 100) for each policy (target
  <= 0.2 s), beside the lossless digital moments;
- Monte Carlo with loss (the compiled kernel of ``simulate/loss_kernels.py``, arrivals
  drawn in the kernel) against the lossless kernel, in path-steps/s on one process
  (target ratio >= 0.7);
- with ``--gpu`` (a machine with an NVIDIA GPU): the same runs with ``device: gpu`` (the
  GPU kernels of ``simulate/loss_cuda.py`` and the lossless one), beside the CPU kernel.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.digital import digital_grid, digital_moments
from ntc_design.simulate.loss import loss_moments
from ntc_design.simulate.moments import PreparedModes
from ntc_design.simulate.system import mode_system

X0 = np.linspace(-3, 3, 21)


def best(fn, repeat: int = 3) -> float:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--gpu", action="store_true", help="also the GPU kernels (device: gpu)")
    args = ap.parse_args()
    g1 = nd.model.paper.g1()
    s = mode_system(nd.design(g1, THETA, thresholds=False), NoiseModel(0.4, 0.3))
    eps0 = X0 - np.tile(THETA, 7)
    grid, _ = digital_grid(Digital(0.1, 1), 10.0, np.array([10.0]))

    def gain(t):
        return 1 / (1 + t)

    modes = PreparedModes.of([s], eps0)
    base = best(lambda: digital_moments(modes, grid, gain, 1))
    print(f"exact moments, G1, h = 0.1, D = 1, K = {grid.n_steps}")
    print(f"  lossless digital moments     {base:8.4f} s")
    loss = np.full(s.n_edges, 0.1)
    for policy in ("skip", "rescale", "hold"):
        sec = best(lambda p=policy: loss_moments(s, grid, gain, eps0, THETA, 1, loss, p))
        print(f"  loss 0.1, {policy:8s}           {sec:8.4f} s   ({sec / base:.2f}x lossless)")
    paths = 2000 if args.quick else 20000
    opts = dict(
        gain="1/(1+t)", noise=NoiseModel(0.4, 0.3), T=10.0, paths=paths, seed=1,
        save_every=10.0, method="mc", initial=X0.tolist(), workers=1,
    )  # fmt: skip
    simulate(g1, THETA, digital=Digital(0.1, 1), **{**opts, "paths": 8})  # compile/load
    simulate(g1, THETA, digital=Digital(0.1, 1, 0.1), **{**opts, "paths": 8})

    def rate(dg: Digital, device: str = "cpu", n: int = paths) -> float:
        run = {**opts, "device": device, "paths": n}
        return max(
            simulate(g1, THETA, digital=dg, **run).stats.path_steps_per_second for _ in range(3)
        )

    lossless = rate(Digital(0.1, 1))
    print(f"Monte Carlo, G1, {paths} paths × 100 steps, one process")
    print(f"  lossless kernel              {lossless:10.3g} path-steps/s")
    for policy in ("skip", "rescale", "hold"):
        r = rate(Digital(0.1, 1, 0.1, policy))
        print(f"  loss 0.1, {policy:8s}           {r:10.3g} path-steps/s   ({r / lossless:.2f}x)")

    if not args.gpu:
        return
    gpu_paths = 20 * paths  # one thread per path: a GPU needs many to fill
    simulate(g1, THETA, digital=Digital(0.1, 1), **{**opts, "paths": 64, "device": "gpu"})
    simulate(g1, THETA, digital=Digital(0.1, 1, 0.1), **{**opts, "paths": 64, "device": "gpu"})
    base_gpu = rate(Digital(0.1, 1), "gpu", gpu_paths)
    print(f"Monte Carlo on the GPU, G1, {gpu_paths} paths × 100 steps")
    print(f"  lossless GPU kernel          {base_gpu:10.3g} path-steps/s   "
          f"({base_gpu / lossless:.1f}x the CPU kernel)")  # fmt: skip
    for policy in ("skip", "rescale", "hold"):
        r = rate(Digital(0.1, 1, 0.1, policy), "gpu", gpu_paths)
        print(f"  loss 0.1, {policy:8s}           {r:10.3g} path-steps/s   "
              f"({r / base_gpu:.2f}x lossless GPU)")  # fmt: skip


if __name__ == "__main__":
    main()
