"""Proven figures at the deadline (issue 46, part 2): B_T / exact and B_peak / exact and
the time, on G1 (examples/scenarios/g1_deadline.yaml, T = 10): the continuous protocol
and the sampled one at h = 0.1 with D = 0, 1, 2.

    python benchmarks/bench_deadline.py [--quick]

"exact" is the toolkit's floating-point figure, computed independently of the bound:
``simulate(method="exact")`` (the sampled recursion of simulate/digital.py; the continuous
moment equations by RK4 at dt = 0.001, peak over its save times every 0.01).
``--quick`` takes T = 2.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from ntc_design.certify.deadline import deadline_bound
from ntc_design.certify.deadline_subject import build_problem
from ntc_design.model.paper import example_path
from ntc_design.protocol import design
from ntc_design.protocol.digital import Digital
from ntc_design.rigorous.exact import Dyadic
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import load_scenario
from ntc_design.simulate.spec import SaveAt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="T = 2 instead of 10")
    t_end = 2.0 if ap.parse_args().quick else 10.0
    warnings.simplefilter("ignore")
    top, spec, _ = load_scenario(example_path() / "scenarios" / "g1_deadline.yaml")
    spec = spec.replace(T=t_end, method="exact", save=SaveAt(every=0.01))
    des = design(top, spec.theta, spec.margin)
    lap = des.grounded_laplacian()
    x0, _ = spec.initial_state(top.n, top.dim)
    print(f"G1, T = {t_end:g}, c(t) = {spec.gain}, σ = 0.4, f = 0.3")
    print(f"{'protocol':<22}{'B_T':>12}{'B_T/exact':>12}{'B_peak':>12}{'B_peak/exact':>14}{'s':>8}")
    for period, delay in ((None, 0), (0.1, 0), (0.1, 1), (0.1, 2)):
        run = spec.replace(digital=Digital(period, delay) if period else None)
        res = simulate(top, run)
        exact_t = float(res.exact.ms_error[-1].sum())
        if period:
            exact_peak = float(res.digital.ms_error_peak)
        else:
            exact_peak = float(res.exact.ms_error.sum(axis=1).max())
        section = {
            "T": t_end,
            "period": period,
            "delay": delay,
            "gain": spec.gain,
            "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
            "initial": {"x0": x0.tolist()},
        }
        t0 = time.perf_counter()
        pb = build_problem(
            {"G1": (top, lap, np.zeros_like(lap), Dyadic.of(lap))}, None, section, spec.theta
        )
        b = deadline_bound(pb)
        secs = time.perf_counter() - t0
        name = "continuous" if period is None else f"h = {period:g}, D = {delay}"
        print(
            f"{name:<22}{b.ms_error_bound:>12.7g}{b.ms_error_bound / exact_t:>12.8f}"
            f"{b.peak_bound:>12.7g}{b.peak_bound / exact_peak:>14.8f}{secs:>8.1f}"
        )


if __name__ == "__main__":
    main()
