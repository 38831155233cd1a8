"""Monte Carlo on a GPU (``device: gpu``) beside the CPU kernel, hand-written JAX and
diffrax, in one run, with the ratios (issue 42's table).

G1: the Lemma 1 design, θ = [1, 2, -1], σ = 0.4, f(x) = 0.3x, c(t) = 1/(1+t),
Euler–Maruyama with dt = 1e-3, float64; path-steps per second. A large network: the
random ring of bench_simulate.py at N = 1e5 agents (d = 3), in agent-path-steps per
second (N × paths × steps / s). On the GPU the paths are the CPU's: the run also prints
the largest relative gap between a few GPU paths and the same paths on the CPU (the
CPU kernel is the reference; the GPU contracts a·b + c into fused multiply-adds).

Without a usable GPU (no driver, no numba-cuda, not installed with the gpu extra, or
only numba-cuda's simulator asked for) the GPU rows say "no GPU: skipped" and why; the
CPU rows and the peers installed (the `bench` extra: jax, diffrax) still run. Targets
on an H100/H200: >= 1.5e9 path-steps/s on G1 with 1e6 paths; >= 5e8
agent-path-steps/s at N = 1e5.

It also times the dense products of the exact moment equations on the CPU (issue 42,
item 5: why the exact moments stay on the CPU; docs/guide/simulate.md).

Run: python benchmarks/bench_gpu.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_simulate import edge_design, problem, random_network  # noqa: E402

from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel, mode_system, simulate  # noqa: E402
from ntc_design.simulate.grid import build_grid  # noqa: E402
from ntc_design.simulate.modes import FixedModes  # noqa: E402
from ntc_design.simulate.montecarlo import MonteCarloSpec, run  # noqa: E402
from ntc_design.simulate.system import check_step_size  # noqa: E402

NOISE = NoiseModel(0.4, 0.3)
GAIN = "1/(1+t)"


def gpu_status() -> tuple[bool, str]:
    """(usable, the device's name or why not); the simulator does not count."""
    from ntc_design.simulate.gpu import gpu_available, simulator_requested

    if simulator_requested():
        return False, "NTC_CUDA_SIMULATOR=1 asks for the simulator, which is for tests"
    return gpu_available()


def g1_rate(top, x0, paths: int, t_end: float, device: str, workers: int = 2) -> float:
    res = simulate(
        top, THETA, gain=GAIN, noise=NOISE, T=t_end, dt=1e-3, paths=paths, seed=0,
        initial=x0, method="mc", workers=workers, device=device, block_size=500,
        store_paths=0,
    )  # fmt: skip
    return res.stats.path_steps_per_second


def agreement(top, x0, paths: int = 64, t_end: float = 1.0) -> float:
    """max relative gap between the GPU's and the CPU's stored paths (1,000 steps)."""
    opts = dict(
        gain=GAIN, noise=NOISE, T=t_end, dt=1e-3, paths=paths, seed=7, initial=x0,
        method="mc", workers=2, store_paths=paths, save_every=t_end / 4,
    )  # fmt: skip
    a = simulate(top, THETA, device="cpu", **opts).mc.paths
    b = simulate(top, THETA, device="gpu", **opts).mc.paths
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-12)))


def large_system(n: int) -> tuple:
    """The random ring at N agents (built once: ARPACK's step bound takes seconds at
    N = 1e5), with dt half the explicit guard's limit."""
    top = random_network(n)
    des = edge_design(top)
    s = mode_system(des, NOISE)
    probe = build_grid(1.0, 1.0, [0, 1.0])
    try:
        check_step_size([s], probe, 1.0 / (1.0 + probe.t[:-1]))
        dt = 0.5
    except Exception as exc:  # the guard names the limit
        dt = 0.5 * float(str(exc).split("use dt < ")[1].split(",")[0])
    x0 = np.tile(np.asarray(THETA[: top.dim], dtype=float), n) + 0.5
    return s, des, dt, x0


def large_spec(system: tuple, paths: int, steps: int) -> MonteCarloSpec:
    """``paths`` paths of ``steps`` steps on :func:`large_system`'s network."""
    s, des, dt, x0 = system
    grid = build_grid(steps * dt, dt, [0.0, steps * dt])
    return MonteCarloSpec(
        modes=FixedModes((s,)), grid=grid, gain=lambda t: 1.0 / (1.0 + np.asarray(t, dtype=float)),
        theta=des.theta, x_init=x0, n_agents=s.n_agents, dim=s.dim, paths=paths, seed=0,
        block_size=500, store_paths=0,
    )  # fmt: skip


def large_rate(spec: MonteCarloSpec, device: str) -> float:
    """agent-path-steps/s of one run of ``spec``."""
    t0 = time.perf_counter()
    if device == "gpu":
        from ntc_design.simulate.gpu import GpuEngine

        GpuEngine().run_mc(spec)
    else:
        run(spec, workers=2)
    return spec.n_agents * spec.paths * spec.grid.n_steps / (time.perf_counter() - t0)


def jax_rate(des, x0, paths: int, n_steps: int) -> tuple[float | None, str]:
    """Hand-written JAX: Euler–Maruyama as a lax.scan over steps, the paths as a batch
    (jax.random normals), JIT-compiled (compile excluded), float64, on JAX's default
    device."""
    try:
        import jax

        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp
    except ImportError:
        return None, "not installed"
    s = mode_system(des, NOISE)
    lap, u, gadd = jnp.asarray(s.lap_b.toarray()), jnp.asarray(s.u), jnp.asarray(s.g.toarray())
    dmat, wmat, e_n = jnp.asarray(s.dmat.toarray()), jnp.asarray(s.wmat.toarray()), s.n_edges
    dt = 1e-3

    def step(carry, k):
        x, key = carry
        key, sub = jax.random.split(key)
        xi = jax.random.normal(sub, (paths, 2 * e_n))
        c = 1.0 / (1.0 + k * dt)
        diff = (x @ dmat.T).reshape(paths, e_n, 3) * xi[:, e_n:, None]
        noise = xi[:, :e_n] @ gadd.T + diff.reshape(paths, -1) @ wmat.T
        x = x + c * dt * (u - x @ lap.T) + c * np.sqrt(dt) * noise
        return (x, key), None

    @jax.jit
    def solve(key):
        x = jnp.tile(jnp.asarray(x0), (paths, 1))
        return jax.lax.scan(step, (x, key), jnp.arange(n_steps))[0][0]

    solve(jax.random.PRNGKey(0)).block_until_ready()
    t0 = time.perf_counter()
    solve(jax.random.PRNGKey(1)).block_until_ready()
    return paths * n_steps / (time.perf_counter() - t0), str(jax.devices()[0].platform)


def diffrax_rate(des, x0, paths: int, n_steps: int) -> float | None:
    """diffrax Euler vmapped over the paths (bench_simulate.bench_diffrax)."""
    from bench_simulate import bench_diffrax

    return bench_diffrax(des, x0, n_steps=n_steps, batch=paths)


def dense_products() -> list[tuple[int, float]]:
    """Seconds of one dense Nd×Nd product on one CPU core (BLAS, best of 3): an RK4 stage
    of the exact moment equations costs a few (L S, S Lᵀ, the noise terms)."""
    from threadpoolctl import threadpool_limits

    out = []
    rng = np.random.default_rng(0)
    with threadpool_limits(1):
        for nd in (60, 300, 1000, 3000):
            a, b = rng.normal(size=(nd, nd)), rng.normal(size=(nd, nd))
            a @ b
            reps = max(1, int(2e8 // nd**3))
            best = np.inf
            for _ in range(3):
                t0 = time.perf_counter()
                for _ in range(reps):
                    a @ b
                best = min(best, (time.perf_counter() - t0) / reps)
            out.append((nd, best))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="smaller runs (a check, not a figure)")
    args = ap.parse_args()
    quick = args.quick
    top, des, x0 = problem()
    ok, device = gpu_status()
    print(f"GPU: {device}" if ok else f"no GPU: skipped ({device})")
    rows: list[tuple[str, float | None, str]] = []

    # the CPU kernel: compile (or load from the cache) first
    g1_rate(top, x0, 20, 0.05, "cpu")
    cpu = g1_rate(top, x0, 1000, 0.5 if quick else 5.0, "cpu")
    rows.append((f"ntc CPU kernel, {min(2, os.cpu_count() or 1)} workers, 1e3 paths", cpu, ""))
    gpu6 = None
    if ok:
        g1_rate(top, x0, 64, 0.01, "gpu")  # compile
        for paths in (10**5, 10**6):
            r = g1_rate(top, x0, paths // (10 if quick else 1), 1.0, "gpu")
            rows.append((f"ntc GPU kernel, {paths:.0e} paths", r, ""))
            gpu6 = r
        gap = agreement(top, x0, 16 if quick else 64)
        rows.append(("GPU paths vs CPU paths, max relative gap", None, f"{gap:.2e}"))
    else:
        rows.append(("ntc GPU kernel, 1e6 paths", None, "no GPU: skipped"))
    jr, where = jax_rate(des, x0, 10**5 if ok else 1000, 1000 if ok else 200)
    rows.append((f"hand-written JAX ({where})", jr, "" if jr else where))
    dr = diffrax_rate(des, x0, 1000, 200)
    rows.append(("diffrax Euler, vmap, JIT", dr, "" if dr else "not installed"))

    ref = gpu6 or cpu
    print(
        f"\nG1, dt = 1e-3, float64 (ratios: {'the GPU kernel at 1e6 paths' if gpu6 else 'the CPU kernel'} / row)"
    )
    print(f"{'implementation':<44} {'path-steps/s':>13} {'ratio':>8}")
    for name, v, note in rows:
        if v is None:
            print(f"{name:<44} {note:>13}")
        else:
            print(f"{name:<44} {v:>13.3g} {ref / v:>7.1f}x")
    print("(target on an H100/H200: the GPU kernel >= 1.5e9 path-steps/s at 1e6 paths)")

    n_big = 10**4 if quick else 10**5
    print(f"\nN = {n_big:.0e} agents, d = 3 (agent-path-steps/s)")
    big_sys = large_system(n_big)
    cpu_big = large_rate(large_spec(big_sys, 20, 2), "cpu")
    print(f"{'ntc CPU kernel, 2 workers, 20 paths':<44} {cpu_big:>13.3g}")
    if ok:
        spec = large_spec(big_sys, 1000, 10)
        large_rate(large_spec(big_sys, 8, 1), "gpu")  # compile
        big = large_rate(spec, "gpu")
        print(
            f"{'ntc GPU kernel (sparse), 1000 paths':<44} {big:>13.3g} {big / cpu_big:>7.1f}x the CPU"
        )
        print("(target on an H100/H200: >= 5e8 agent-path-steps/s at N = 1e5)")
    else:
        print(f"{'ntc GPU kernel (sparse)':<44} {'no GPU: skipped':>13}")

    print("\nexact moments stay on the CPU: one dense Nd×Nd product (BLAS, one core)")
    for nd, sec in dense_products():
        print(f"  Nd = {nd:>5}: {sec * 1e3:9.3f} ms")


if __name__ == "__main__":
    main()
