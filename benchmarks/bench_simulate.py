"""Simulation speed: the paper's G1 problem beside torchsde, sdeint and diffrax (JAX, CPU),
the random-number floor, the step kernels side by side, and the scaling to N = 1,000 and
10,000 agents, in one run (peers from the optional `bench` extra:
pip install -e ".[bench]" with a CPU PyTorch, see the README).

G1: the Lemma 1 design, θ = [1, 2, -1], σ = 0.4, f(x) = 0.3x, c(t) = 1/(1+t),
Euler–Maruyama with dt = 1e-3, 1000 paths, 16 Brownian motions per path (2 per edge).

The floor: a path-step needs 2E standard normals (E edges), so no Euler–Maruyama code
using NumPy's generator can exceed ``normals/s × cores / 2E`` path-steps per second;
the tables give each figure as a fraction of that floor. The scaling figure
path-steps/s × edges says whether the cost per path-step grows with the edges only.

Large networks: a ring of antagonistic edges plus 10% random edges with PD weights of
log-normal scale (Assumption 2 holds: every agent has a PD antagonistic in-weight, so
V1 = V); δ comes out large (hundreds), so L_B is stiff and the explicit step is taken
at half the guard's limit. The design is computed here from the edge arrays (the dense
design layer does not reach N = 10,000).

The kernel against the previous release: the fused kernel's path-steps per second of CPU
on one core (G1, 1000 paths) beside :data:`PREVIOUS_RELEASE`, the same figure measured with
the release before the digital protocol and the GPU work, so that a drop shows as a ratio
below 1. With ``--previous DIR`` (a checkout of that commit, e.g. ``git worktree add
/tmp/old 9a16b0f``) both trees are measured here, in alternating fresh processes (the
machine may be shared: medians of the rounds).

Run: python benchmarks/bench_simulate.py [--paper] [--skip-large] [--previous DIR]
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

import numpy as np

import ntc_design as nd
from ntc_design.model.paper import THETA
from ntc_design.protocol import Decomposition, ProtocolDesign
from ntc_design.simulate import NoiseModel, mode_system, simulate
from ntc_design.simulate.grid import build_grid
from ntc_design.simulate.kernels import em_steps, kernel_arrays, numpy_step, tile_width
from ntc_design.simulate.modes import FixedModes
from ntc_design.simulate.montecarlo import MonteCarloSpec, run
from ntc_design.simulate.system import check_step_size

ROOT = Path(__file__).resolve().parent.parent

CORES = min(2, os.cpu_count() or 1)

# The fused kernel of the release before the digital protocol and the GPU work, measured as
# kernel_rate() measures it (CPU time, one core, G1, 1000 paths), alternating with this
# tree's in one shell on the shared 2-core machine of figures.json (issue 47: the delay
# ring's slice had made today's 1.07-1.14e7, 1.7x slower; after the fix 1.89-2.03e7).
PREVIOUS_RELEASE = {"commit": "9a16b0f", "kernel_path_steps_per_s": 1.95e7, "date": "2026-11-28"}

# One tree's kernel rate in a fresh process (works with the previous release's API too):
# path-steps per second of CPU time, the median of three runs of 2,000 steps.
KERNEL_PROBE = """
import statistics, sys, time
from pathlib import Path
import numpy as np
import ntc_design as nd
try:
    from ntc_design.model.paper import THETA
except ImportError:
    from ntc_design.paper import THETA
from ntc_design.simulate import NoiseModel, mode_system
from ntc_design.simulate.kernels import em_steps_rng, kernel_arrays, tile_width
from ntc_design.simulate.rng import NormalSource
root = Path(nd.__file__).resolve().parent.parent
des = nd.design(nd.load(root / "examples" / "g1.yaml"), THETA, thresholds=False)
s = mode_system(des, NoiseModel(0.4, 0.3))
args, p, k = kernel_arrays(s), 1000, int(sys.argv[1])
c = 1.0 / (1.0 + np.arange(k) * 1e-3)
ch, cs = c * 1e-3, c * np.sqrt(1e-3)
src = NormalSource("xoshiro", 0, 0, p)
x0 = np.zeros((p, s.nd))  # every path from 0 (x(0) = 0, as the paper)
x = x0.copy()
em_steps_rng(x, src.states, 2 * s.n_edges, 0, 10, ch, cs, *args, True, tile_width(p, s.nd))
rates = []
for _ in range(3):
    x = x0.copy()
    t0 = time.process_time()
    em_steps_rng(x, src.states, 2 * s.n_edges, 0, k, ch, cs, *args, True, tile_width(p, s.nd))
    rates.append(k * p / (time.process_time() - t0))
print(statistics.median(rates))
"""


def kernel_rate(tree: Path = ROOT, steps: int = 2000) -> float:
    """The fused kernel's path-steps per second of CPU time on one core (G1, 1000 paths), in
    a fresh process importing ``tree`` (this checkout, or another commit's)."""
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(tree)}
    r = subprocess.run(
        [sys.executable, "-c", KERNEL_PROBE, str(steps)],
        env=env, cwd=tree, capture_output=True, text=True, check=True,
    )  # fmt: skip
    return float(r.stdout.split()[-1])


def against_previous(previous: Path | None, rounds: int = 5) -> None:
    """Print this tree's kernel rate beside the stored previous release's, and with
    ``previous`` (a checkout) both measured here in alternating rounds."""
    import statistics

    kernel_rate(ROOT, 20)  # compile or load both first
    ref = PREVIOUS_RELEASE["kernel_path_steps_per_s"]
    print(
        f"\nfused kernel, one core, G1, 1000 paths (path-steps per CPU second), vs {PREVIOUS_RELEASE['commit']}:"
    )
    if previous is None:
        now = statistics.median(kernel_rate() for _ in range(3))
        print(f"{'this tree':<40} {now:>11.3g}")
        print(f"{'previous release, stored':<40} {ref:>11.3g}   this tree is {now / ref:.2f}x")
        return
    kernel_rate(previous, 20)
    ours, theirs = [], []
    for _ in range(rounds):
        ours.append(kernel_rate())
        theirs.append(kernel_rate(previous))
    a, b = statistics.median(ours), statistics.median(theirs)
    print(
        f"{'this tree (median of ' + str(rounds) + ' alternated)':<40} {a:>11.3g}   ({min(ours):.3g}-{max(ours):.3g})"
    )
    print(f"{'previous release, here':<40} {b:>11.3g}   ({min(theirs):.3g}-{max(theirs):.3g})")
    print(f"{'previous release, stored':<40} {ref:>11.3g}")
    print(
        f"this tree is {a / b:.2f}x the previous release measured here, {a / ref:.2f}x the stored figure"
    )


def problem():
    top = nd.load(ROOT / "examples" / "g1.yaml")
    des = nd.design(top, THETA, thresholds=False)
    x0 = np.random.default_rng(np.random.SeedSequence(1)).uniform(-3, 3, size=21)
    return top, des, x0


def bench_ntc(top, x0, t_end=10.0, workers=2, rng="xoshiro") -> float:
    res = simulate(
        top, THETA, T=t_end, dt=1e-3, paths=1000, seed=0, initial=x0, method="mc",
        workers=workers, rng=rng,
    )  # fmt: skip
    return res.stats.path_steps_per_second


def bench_cli(paths: int = 5000, t_end: float = 10.0) -> float:
    """G1 end to end through the CLI, start-up and writing included: path-steps per
    second of wall time (5e7 path-steps by default)."""
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        cmd = [
            sys.executable, "-m", "ntc_design", "simulate",
            str(ROOT / "examples" / "scenarios" / "g1_fixed.yaml"), "--out", f"{d}/o",
            "--paths", str(paths), "--horizon", str(t_end), "--method", "mc",
        ]  # fmt: skip
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        return paths * t_end / 1e-3 / (time.perf_counter() - t0)


def kernel_rng_rate() -> float:
    """Normals per second of the in-kernel generator (xoshiro256** + ziggurat), one core."""
    from ntc_design.simulate.rng import NormalSource

    src = NormalSource("xoshiro", 0, 0, 1000)
    buf = np.empty((64, 1000, 16))
    src.fill(buf)
    best = 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(15):
            src.fill(buf)
        best = max(best, 15 * buf.size / (time.perf_counter() - t0))
    return best


def drift_diffusion(des):
    """f and g of dX = f dt + g dW for the peers: W has 16 components (2 per edge)."""
    s = mode_system(des, NoiseModel(0.4, 0.3))
    lap_b, u, g_add = s.lap_b.toarray(), s.u, s.g.toarray()
    dmat, wmat, e_n = s.dmat.toarray(), s.wmat.toarray(), s.n_edges

    def f(x, t):
        return (u - lap_b @ x) / (1.0 + t)

    def g(x, t):
        diff = (dmat @ x).reshape(e_n, 3)
        mult = np.stack([wmat[:, 3 * e : 3 * e + 3] @ diff[e] for e in range(e_n)], axis=1)
        return np.hstack([g_add, mult]) / (1.0 + t)

    return f, g, (lap_b, u, g_add, dmat, wmat, e_n)


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


def bench_torchsde(des, x0, n_steps=200, batch=1000) -> float | None:
    try:
        import torch
        import torchsde
    except ImportError:
        return None
    torch.set_num_threads(CORES)
    _, _, (lap_b, u_, gadd_, dmat_, wmat_, e_n) = drift_diffusion(des)
    lap, u, gadd, dmat = (torch.tensor(a) for a in (lap_b, u_, gadd_, dmat_))
    w = torch.tensor(wmat_).reshape(21, e_n, 3)

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


def bench_diffrax(des, x0, n_steps=1000, batch=1000) -> float | None:
    """diffrax Euler on the same SDE, vmapped over 1000 paths, JIT-compiled (the compile
    is excluded: one warm-up solve first), float64, CPU."""
    try:
        import jax

        jax.config.update("jax_enable_x64", True)
        import diffrax
        import jax.numpy as jnp
    except ImportError:
        return None
    _, _, (lap_b, u_, gadd_, dmat_, wmat_, e_n) = drift_diffusion(des)
    lap, u, gadd, dmat = (jnp.asarray(a) for a in (lap_b, u_, gadd_, dmat_))
    w = jnp.asarray(wmat_).reshape(21, e_n, 3)

    def drift(t, y, args):
        return (u - lap @ y) / (1.0 + t)

    def diffusion(t, y, args):
        diff = (dmat @ y).reshape(e_n, 3)
        mult = jnp.einsum("iec,ec->ie", w, diff)
        return jnp.concatenate([gadd, mult], axis=1) / (1.0 + t)

    t1 = n_steps * 1e-3

    def solve(key):
        bm = diffrax.UnsafeBrownianPath(shape=(2 * e_n,), key=key)
        terms = diffrax.MultiTerm(diffrax.ODETerm(drift), diffrax.ControlTerm(diffusion, bm))
        sol = diffrax.diffeqsolve(
            terms,
            diffrax.Euler(),
            0.0,
            t1,
            1e-3,
            jnp.asarray(x0),
            saveat=diffrax.SaveAt(t1=True),
            max_steps=n_steps + 10,
            adjoint=diffrax.ForwardMode(),
        )
        return sol.ys

    fn = jax.jit(jax.vmap(solve))
    keys = jax.random.split(jax.random.PRNGKey(0), batch)
    fn(keys).block_until_ready()
    t0 = time.perf_counter()
    fn(keys).block_until_ready()
    return n_steps * batch / (time.perf_counter() - t0)


def rng_floor() -> float:
    """float64 standard normals per second on one core (NumPy's PCG64, as the kernel)."""
    rng = np.random.default_rng(0)
    buf = np.empty((64, 1000, 16))
    best = 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(15):
            rng.standard_normal(out=buf)
        best = max(best, 15 * buf.size / (time.perf_counter() - t0))
    return best


# -- large random networks -------------------------------------------------------------


def random_network(n: int, d: int = 3, seed: int = 0) -> nd.Topology:
    """Ring of antagonistic edges + 10% random edges, PD weights, log-normal scale."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    pairs = [(i, (i + 1) % n) for i in range(n)]
    seen = set(pairs)
    while len(pairs) < n + n // 10:
        a, b = (int(v) for v in rng.integers(0, n, 2))
        if a != b and (a, b) not in seen:
            seen.add((a, b))
            pairs.append((a, b))
    edges = []
    for a, b in pairs:
        q = rng.normal(size=(d, d))
        w = (q @ q.T / d + 0.2 * np.eye(d)) * np.exp(rng.normal())
        neg = b == (a + 1) % n or rng.random() < 0.5
        edges.append((a + 1, b + 1, -w if neg else w))
    return nd.Topology.from_edges(n, d, edges)


def edge_design(top: nd.Topology, margin: float = 0.1) -> ProtocolDesign:
    """Lemma 1 with V1 = V (every agent has a PD antagonistic in-weight), from the edge
    arrays: C_i = ½ λ_max(S_i^{-1}(out_i − in_i)), S_i = Σ_{Ω_i}|A_ij|."""
    import scipy.linalg as sla

    n, d = top.n, top.dim
    s_in = np.zeros((n, d, d))
    deg_in = np.zeros((n, d, d))
    deg_out = np.zeros((n, d, d))
    for i, j in top.edges:
        a = top.abs_weight(i, j)
        deg_in[i] += a
        deg_out[j] += a
        if top.sign(i, j) < 0:
            s_in[i] += a
    coef = {
        i: 0.5 * float(sla.eigh(deg_out[i] - deg_in[i], s_in[i], eigvals_only=True)[-1])
        for i in range(n)
    }
    c = max(coef.values())
    delta = c + margin
    th = np.array(THETA[:d])
    k1 = 1 + 2 / delta
    dec = Decomposition(True, tuple(range(n)), (), coef, (), {})
    b = {i: s_in[i] for i in range(n)}
    return ProtocolDesign(
        topology=top,
        theta=th,
        margin=margin,
        decomposition=dec,
        C=c,
        delta=delta,
        k1=k1,
        x0=k1 * th,
        informed=tuple(range(n)),
        B=b,
        identity_residual=float("nan"),
        thresholds=None,
    )


def large_case(
    n: int, paths: int = 1000, steps: int = 40, workers: int = 2, rng: str = "xoshiro"
) -> dict:
    t0 = time.perf_counter()
    top = random_network(n)
    des = edge_design(top)
    s = mode_system(des, NoiseModel(0.4, 0.3))
    setup = time.perf_counter() - t0
    gain = lambda t: 1.0 / (1.0 + np.asarray(t, dtype=float))  # noqa: E731
    probe = build_grid(1.0, 1.0, [0, 1.0])
    try:
        check_step_size([s], probe, gain(probe.t[:-1]))
        h_lim = 1.0
    except nd.InputError as exc:
        h_lim = float(str(exc).split("use dt < ")[1].split(",")[0])
    dt = 0.5 * h_lim
    grid = build_grid(steps * dt, dt, [0.0, steps * dt])
    x0 = np.tile(des.x0 * 0 + THETA[: top.dim], n) + 0.5
    spec = MonteCarloSpec(
        modes=FixedModes((s,)), grid=grid, gain=gain, theta=des.theta, x_init=x0, n_agents=n,
        dim=top.dim, paths=paths, seed=0, block_size=500, store_paths=0, rng=rng,
    )  # fmt: skip
    t0 = time.perf_counter()
    run(spec, workers=workers)
    sec = time.perf_counter() - t0
    out = {
        "n": n,
        "edges": s.n_edges,
        "delta": des.delta,
        "rho": s.spectral_radius,
        "dt": dt,
        "setup_s": setup,
        "ps": grid.n_steps * paths / sec,
    }
    # the implicit scheme at a step 20× the explicit limit (one sparse LU, reused)
    ig = build_grid(steps * 20 * dt, 20 * dt, [0.0, steps * 20 * dt])
    ispec = MonteCarloSpec(
        modes=FixedModes((s,)), grid=ig, gain=lambda t: np.ones_like(np.asarray(t, float)),
        theta=des.theta, x_init=x0, n_agents=n, dim=top.dim, paths=paths, seed=0,
        block_size=500, store_paths=0, scheme="implicit", rng=rng,
    )  # fmt: skip
    t0 = time.perf_counter()
    part = run(ispec, workers=workers)
    out["ps_implicit"] = ig.n_steps * paths / (time.perf_counter() - t0)
    out["implicit_finite"] = bool(np.all(np.isfinite(part.sq)))
    return out


def step_variants(s, p: int = 500, k_n: int = 8) -> dict:
    """One block's steps three ways: the compiled edge kernel, SciPy sparse products
    (CSR @ dense) and NumPy gather/scatter (einsum on stacked blocks + np.add.at)."""
    rng = np.random.default_rng(0)
    x = np.tile(np.tile(THETA[: s.dim], s.n_agents), (p, 1))
    xi = rng.standard_normal((k_n, p, 2 * s.n_edges))
    ch = np.full(k_n, 1e-5)
    cs = np.sqrt(ch)
    lap = s.lap_b.tocsr()
    args = kernel_arrays(s)
    tile = tile_width(p, s.nd)
    ne, d = s.n_edges, s.dim

    def gather_scatter(x, xi_k):
        x3 = x.reshape(p, s.n_agents, d)
        diff = (x3[:, s.src] - x3[:, s.dst]) * xi_k[:, ne:, None]
        inc = np.einsum("eab,peb->pea", s.k_blocks, diff) + s.g_edge * xi_k[:, :ne, None]
        out = np.zeros((p, s.n_agents, d))
        np.add.at(out, (slice(None), s.dst), inc)
        x += 1e-5 * (s.u - (lap @ x.T).T) + np.sqrt(1e-5) * out.reshape(p, -1)

    runs = {
        "compiled edge kernel": lambda: em_steps(x, xi, 0, k_n, ch, cs, *args, True, tile),
        "SciPy sparse products": lambda: [
            numpy_step(x, xi[k], ch[k], cs[k], s) for k in range(k_n)
        ],
        "NumPy gather/scatter": lambda: [gather_scatter(x, xi[k]) for k in range(k_n)],
    }
    out = {}
    for name, f in runs.items():
        f()
        t0 = time.perf_counter()
        f()
        out[name] = k_n * p / (time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "--paper", action="store_true", help="also run the paper-sized T = 100 (1e8 path-steps)"
    )
    ap.add_argument("--skip-large", action="store_true", help="skip N = 1,000 and 10,000")
    ap.add_argument(
        "--previous", type=Path, help="a checkout of the previous release, measured beside this"
    )
    ap.add_argument(
        "--kernel-only", action="store_true", help="only the kernel against the previous release"
    )
    args = ap.parse_args()
    if args.kernel_only:
        against_previous(args.previous)
        return
    top, des, x0 = problem()
    g1s = mode_system(des, NoiseModel())
    floor = rng_floor()
    g1_floor = floor * CORES / (2 * g1s.n_edges)
    bench_ntc(top, x0, t_end=0.1, workers=1)  # compile (or load) the kernels first
    ours1 = bench_ntc(top, x0, workers=1)
    ours = bench_ntc(top, x0, workers=2)
    ours_np = bench_ntc(top, x0, workers=2, rng="numpy")
    cli = bench_cli()
    kernel_rng = kernel_rng_rate()
    floor2 = rng_floor()  # the machine is shared: the floor before and after
    # the large runs fork workers: before JAX (multithreaded) is imported by diffrax
    sizes = ((1000, 60), (10000, 8))
    large = [] if args.skip_large else [large_case(n, steps=k) for n, k in sizes]
    large_np = [] if args.skip_large else [large_case(1000, steps=60, rng="numpy")]
    sde = bench_sdeint(des, x0)
    tsde = bench_torchsde(des, x0)
    dfx = bench_diffrax(des, x0)
    print(f"G1, 1000 paths, dt = 1e-3, {2 * g1s.n_edges} normal draws per path-step")
    print(f"{'implementation':<48} {'path-steps/s':>13} {'ntc is':>8} {'of floor':>9}")
    rows = [
        (f"ntc-design, {CORES} workers (normals in the kernel)", ours),
        ("ntc-design, 1 worker (normals in the kernel)", ours1),
        (f"ntc-design, {CORES} workers, --rng numpy", ours_np),
        ("ntc simulate CLI, 5e7 path-steps, start-up incl.", cli),
        (f"torchsde batch Euler, general noise, {CORES} threads", tsde),
        ("diffrax Euler, vmap over paths, JIT, CPU", dfx),
        ("sdeint itoEuler, one path at a time", sde),
    ]
    for name, v in rows:
        if v is None:
            print(f"{name:<48} {'not installed':>13}")
            continue
        ratio = "" if v == ours else f"{ours / v:.1f}x"
        print(f"{name:<48} {v:>13.3g} {ratio:>8} {v / g1_floor:>9.2f}")
    print(
        f"{'RNG floor: float64 normals/s, one core':<48} {floor:>13.3g}   (after the runs: {floor2:.3g})"
    )
    print(f"{f'  -> path-steps/s if only drawing, {CORES} cores':<48} {g1_floor:>13.3g}")
    print(
        f"{'in-kernel generator: normals/s, one core':<48} {kernel_rng:>13.3g}   ({kernel_rng / floor:.2f}x NumPy's)"
    )
    print("(targets: the CLI row >= 1.5 of the floor; N = 1,000 >= 5e4 path-steps/s)")

    print("\nkernels, one block of 500 paths (one core):")
    cases = [("G1", g1s)]
    if not args.skip_large:
        for n in (1000, 10000):
            s = mode_system(edge_design(random_network(n)), NoiseModel())
            cases.append((f"N = {n}", s))
    print(f"{'':<24}" + "".join(f"{name:>14}" for name, _ in cases))
    var = [step_variants(s, k_n=64 if s.nd < 100 else 4) for _, s in cases]
    for key in var[0]:
        print(f"{key:<24}" + "".join(f"{v[key]:>14.3g}" for v in var))

    against_previous(args.previous)

    t0 = time.perf_counter()
    simulate(top, THETA, T=100.0, initial=x0, method="exact", save_every=0.1)
    print(f"\nexact mean-square curves, T = 100, 1001 save times: {time.perf_counter() - t0:.2f} s")

    if not args.skip_large:
        print(f"\nscaling (1000 paths, {CORES} workers; explicit dt = half the guard's limit):")
        head = f"{'network':<10} {'edges':>6} {'delta':>7} {'rho(L_B)':>9} {'dt':>9} {'path-steps/s':>13} {'x edges':>9} {'vs G1':>6} {'of floor':>9} {'implicit 20·dt':>15}"
        print(head)
        g1_pe = ours * g1s.n_edges
        print(
            f"{'G1':<10} {g1s.n_edges:>6} {des.delta:>7.4g} {g1s.spectral_radius:>9.4g} {1e-3:>9.3g} "
            f"{ours:>13.3g} {g1_pe:>9.3g} {1.0:>6.2f} {ours / g1_floor:>9.2f}"
        )
        for r in large:
            n = r["n"]
            fl = floor * CORES / (2 * r["edges"])
            pe = r["ps"] * r["edges"]
            print(
                f"{'N = ' + str(n):<10} {r['edges']:>6} {r['delta']:>7.4g} {r['rho']:>9.4g} {r['dt']:>9.3g} "
                f"{r['ps']:>13.3g} {pe:>9.3g} {pe / g1_pe:>6.2f} {r['ps'] / fl:>9.2f} {r['ps_implicit']:>15.3g}"
            )
        for r in large_np:
            fl = floor * CORES / (2 * r["edges"])
            print(
                f"{'N = 1000, --rng numpy':<24} path-steps/s {r['ps']:.3g} ({r['ps'] / fl:.2f} of floor); "
                f"in-kernel normals: {large[0]['ps'] / r['ps']:.2f}x"
            )
        print("(targets: N = 1,000 >= 5e4 path-steps/s; path-steps/s × edges within 3× of G1's)")

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
            f"{res.stats.path_steps_per_second:.3g} path-steps/s, peak RSS of one process {rss / 1024:.0f} MB"
        )


if __name__ == "__main__":
    main()
