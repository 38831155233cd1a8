"""The digital (sampled, delayed) protocol (issue 40): what each of its jobs costs beside
its continuous counterpart, in one run, as ratios, and how it grows with the delay D and
with N·d.

    python benchmarks/bench_digital.py [--quick]

Rows:

- exact moments of the sampled recursion (augmented state, ((D+1)·Nd)² numbers) against the
  continuous moment equations (RK4) on G1, for D = 0, 1, 2, 4, and on generated networks of
  growing N·d (cost ∝ K·(D+1)·Nd² per step);
- Monte Carlo of the sampled recursion against the continuous Euler–Maruyama at dt = h
  (D = 0 is the same recursion; a delay adds a ring of D + 1 states, not work per step);
- the certificate with ``--period`` against the plain one;
- ``--period auto`` (the longest safe period);
- the exported agents' code: the C replay, the Python module and the toolkit's replay, per
  step of G1.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.model.generate import random_network
from ntc_design.protocol.digital import Digital
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.digital import digital_grid, digital_moments
from ntc_design.simulate.prepare import make_gain, prepare_modes
from ntc_design.simulate.spec import SimulationSpec
from ntc_design.tune.period import longest_safe_period

ROOT = Path(__file__).resolve().parents[1]
THETA = [1.0, 2.0, -1.0]
NOISE = NoiseModel(0.4, 0.3)


def best(fn, repeat: int = 3) -> float:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def moments_rows(top, theta, label: str, t_end: float, h: float, delays) -> None:
    spec = SimulationSpec.build(theta, noise=NOISE, initial=np.linspace(-3, 3, top.nd).tolist())
    gain = make_gain(spec.gain)[0]
    pm = prepare_modes(top, spec.replace(T=t_end, method="exact"), gain)
    cont = best(lambda: pm.moments(gain, np.array([0.0, t_end])))
    print(
        f"\n{label} (N·d = {top.nd}, T = {t_end:g}, h = {h:g}): continuous RK4 {cont * 1e3:.1f} ms"
    )
    for d in delays:
        grid, _ = digital_grid(Digital(h, d), t_end, np.array([t_end]))
        sec = best(lambda grid=grid, d=d: digital_moments(pm, grid, gain, d))
        per = sec / grid.n_steps * 1e6
        print(
            f"  D = {d}: exact sampled moments {sec * 1e3:7.1f} ms ({grid.n_steps} steps, "
            f"{per:.0f} µs/step, augmented {(d + 1) * top.nd}²) = {sec / cont:.2f}× continuous"
        )


def monte_carlo_rows(g1, paths: int) -> None:
    kw = dict(T=2.0, paths=paths, seed=0, noise=NOISE, method="mc", save_every=0.5, workers=2)
    simulate(g1, THETA, dt=0.01, **kw)  # compile
    t0 = time.perf_counter()
    simulate(g1, THETA, dt=0.01, **kw)
    cont = time.perf_counter() - t0
    print(f"\nMonte Carlo, G1, {paths} paths × 200 steps: continuous EM at dt = 0.01 {cont:.2f} s")
    for d in (0, 1, 2, 10, 100):
        simulate(g1, THETA, digital={"period": 0.01, "delay": d}, **kw)
        t0 = time.perf_counter()
        simulate(g1, THETA, digital={"period": 0.01, "delay": d}, **kw)
        sec = time.perf_counter() - t0
        rate = paths * 200 / sec
        print(f"  sampled, D = {d:3d}: {sec:.2f} s ({rate:.3g} path-steps/s) = {sec / cont:.2f}×")


def certificate_rows(g1) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = best(lambda: certify(g1, THETA, gain="1/(1+t)"), 2)
        print(f"\ncertify G1: {base:.2f} s")
        for d in (0, 1):
            sec = best(lambda d=d: certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, d)), 2)
            print(f"  with --period 0.1 --delay {d}: {sec:.2f} s = {sec / base:.2f}×")


def period_rows() -> None:
    from ntc_design.simulate.scenario import load_scenario

    top, spec, _ = load_scenario(ROOT / "examples" / "scenarios" / "g1_deadline.yaml")
    print("\nntc tune --period auto on G1 (T = 10, tolerance 0.1):")
    for d in (0, 1, 2):
        t0 = time.perf_counter()
        r = longest_safe_period(top, spec, 10.0, delay=d, tolerance=0.1)
        sec = time.perf_counter() - t0
        ev = r.evidence.periods if r.evidence is not None else 0
        print(
            f"  D = {d}: h = {r.period:.4g} in {sec:.2f} s ({len(r.curve)} periods scanned "
            f"and bisected, {ev} verified up to h)"
        )


def export_rows(g1, steps: int) -> None:
    from ntc_design.export.run import export
    from ntc_design.export.source import ExportOptions
    from ntc_design.protocol.agents import agent_law
    from ntc_design.simulate.replay import replay

    cc = shutil.which("cc")
    des = nd.design(g1, THETA, thresholds=False)
    law = agent_law(des, Digital(0.01, 1), "1/(1+t)", 0.4, 0.3)
    rng = np.random.default_rng(0)
    x0 = np.linspace(-3, 3, 21)
    normals = rng.standard_normal((steps, 2 * len(law.modes[0].dst)))
    sec_py = best(lambda: replay(law, x0, normals.ravel(), steps), 2)
    print(f"\nexported agents' code, G1, {steps} steps (h = 0.01, D = 1):")
    print(f"  toolkit replay (NumPy, bit for bit with the code): {sec_py * 1e3:.0f} ms")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            export(
                ROOT / "examples" / "scenarios" / "g1_deadline.yaml",
                "c",
                out,
                ExportOptions(0.01, 1),
            )
            export(
                ROOT / "examples" / "scenarios" / "g1_deadline.yaml",
                "python",
                Path(tmp) / "py",
                ExportOptions(0.01, 1),
            )
        text = (
            " ".join(map(repr, x0.tolist()))
            + f" {steps} "
            + " ".join(map(repr, normals.ravel().tolist()))
        )
        if cc is None:
            print("  C: no C compiler here, skipped")
        else:
            exe = out / "ntc_replay"
            subprocess.run(
                [
                    cc,
                    "-std=c99",
                    "-O2",
                    "-ffp-contract=off",
                    "-o",
                    str(exe),
                    str(out / "ntc_replay.c"),
                    str(out / "ntc_protocol.c"),
                    "-lm",
                ],
                check=True,
            )
            sec_c = best(
                lambda: subprocess.run(
                    [str(exe)], input=text, capture_output=True, text=True, check=True
                ),
                2,
            )
            print(
                f"  C replay (process start and parsing included): {sec_c * 1e3:.0f} ms = {sec_py / sec_c:.1f}× faster than the toolkit's"
            )
        import sys

        mod = Path(tmp) / "py" / "ntc_protocol.py"
        sec_m = best(
            lambda: subprocess.run(
                [sys.executable, str(mod)], input=text, capture_output=True, text=True, check=True
            ),
            2,
        )
        print(
            f"  Python module (interpreter start included): {sec_m * 1e3:.0f} ms = {sec_m / sec_py:.1f}× the toolkit's"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes")
    args = ap.parse_args()
    g1 = nd.load(ROOT / "examples" / "g1.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        moments_rows(g1, THETA, "G1", 10.0, 0.1, (0, 1, 2, 4))
        sizes = (10, 20) if args.quick else (10, 20, 40, 80)
        for n in sizes:
            top = random_network(n, 3, seed=1)
            moments_rows(top, THETA, f"generated, N = {n}", 1.0, 0.01, (0, 1))
    monte_carlo_rows(g1, 200 if args.quick else 2000)
    certificate_rows(g1)
    period_rows()
    export_rows(g1, 200 if args.quick else 1000)


if __name__ == "__main__":
    main()
