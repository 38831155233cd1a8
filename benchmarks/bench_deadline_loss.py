"""Proven figures at the deadline on lossy links: B_T / exact and B_peak / exact and the
time to prove them, on G1 (examples/scenarios/g1_deadline.yaml, T = 10, h = 0.1) for
D = 0 and 1, p = 0.1 and 0.3 and each policy (skip, rescale, hold).

    python benchmarks/bench_deadline_loss.py [--quick]

"exact" is the toolkit's floating-point figure, computed independently of the bound:
``simulate(method="exact")`` on lossy links (the float recursion of simulate/loss.py; its
peak over the samples is the peak over [0, T]: between samples E‖e‖² is a convex
quadratic). ``--quick`` takes T = 2.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from ntc_design.certify.deadline_loss import loss_section
from ntc_design.certify.deadline_subject import section_bound
from ntc_design.model.paper import example_path
from ntc_design.protocol import design
from ntc_design.protocol.digital import Digital
from ntc_design.rigorous.exact import Dyadic
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import load_scenario


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="T = 2 instead of 10")
    t_end = 2.0 if ap.parse_args().quick else 10.0
    warnings.simplefilter("ignore")
    top, spec, _ = load_scenario(example_path() / "scenarios" / "g1_deadline.yaml")
    spec = spec.replace(T=t_end, method="exact")
    des = design(top, spec.theta, spec.margin)
    lap = des.grounded_laplacian()
    modes = {"G1": (top, lap, np.zeros_like(lap), Dyadic.of(lap))}
    x0, _ = spec.initial_state(top.n, top.dim)
    print(f"G1, T = {t_end:g}, h = 0.1, c(t) = {spec.gain}, σ = 0.4, f = 0.3")
    print(
        f"{'D':>2}{'p':>5}  {'policy':<8}{'B_T':>12}{'B_T/exact-1':>14}{'B_peak':>12}"
        f"{'B_peak/exact-1':>16}{'s':>7}"
    )
    for delay in (0, 1):
        for p in (0.1, 0.3):
            for policy in ("skip", "rescale", "hold"):
                run = spec.replace(digital=Digital(0.1, delay, p, policy))
                res = simulate(top, run)
                exact_t = float(res.exact.ms_error[-1].sum())
                exact_peak = max(float(res.digital.ms_error_peak), exact_t)
                section = {
                    "T": t_end,
                    "period": 0.1,
                    "delay": delay,
                    "gain": spec.gain,
                    "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
                    "initial": {"x0": x0.tolist()},
                    "loss": loss_section(top, p, policy),
                }
                t0 = time.perf_counter()
                b = section_bound(modes, None, section, np.asarray(spec.theta, dtype=float))
                secs = time.perf_counter() - t0
                print(
                    f"{delay:>2}{p:>5g}  {policy:<8}{b.ms_error_bound:>12.7g}"
                    f"{b.ms_error_bound / exact_t - 1:>14.2e}{b.peak_bound:>12.7g}"
                    f"{b.peak_bound / exact_peak - 1:>16.2e}{secs:>7.1f}"
                )


if __name__ == "__main__":
    main()
