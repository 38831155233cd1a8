"""The optimal gain schedule (issue 28): `tune(..., ScheduleOptions())` on the paper's G1
(x(0) = linspace(−3, 3, 21), T = 10) and on a generated 20-agent network (Nd = 60, the
largest size accepted), with the refinement table, beside one objective evaluation and one
gradient (the peer: a finite-difference gradient costs K + 1 evaluations).

    python benchmarks/bench_schedule.py [--skip-large]

Cost grows as (Nd)⁴ × RK4 steps per evaluation: the table prints Nd, the half-vectorised
state size and the time per evaluation so the growth can be read off.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

import ntc_design as nd
from ntc_design.model.generate import random_network
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.simulate.prepare import prepare_modes
from ntc_design.tune import ScheduleOptions, tune
from ntc_design.tune.problem import ScheduleProblem

ROOT = Path(__file__).resolve().parents[1]


def case(name: str, top, theta, x0, horizon: float, paths: int) -> None:
    spec = SimulationSpec.build(theta, noise=NoiseModel(0.4, 0.3), initial=x0, paths=paths)
    pm = prepare_modes(top, spec.replace(T=horizon, method="exact"), lambda t: 1 + 0 * t)
    t0 = time.perf_counter()
    prob = ScheduleProblem(pm, horizon)
    build = time.perf_counter() - t0
    c = 1 / (1 + np.linspace(0, horizon, 51))
    plan = prob.plan(c)
    t0 = time.perf_counter()
    prob.forward(c, plan, store=False)
    one = time.perf_counter() - t0
    t0 = time.perf_counter()
    st = prob.forward(c, plan)
    prob.adjoint(plan, st)
    grad = time.perf_counter() - t0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w, cpu = time.perf_counter(), time.process_time()
        r = tune(top, spec, horizon, ScheduleOptions(check_paths=paths))
        wall, cpu = time.perf_counter() - w, time.process_time() - cpu
    ms = r.ms_error_T
    print(f"\n{name}: N·d = {top.n * top.dim}, state {prob.ns}, operators built in {build:.2f} s")
    print(
        f"  one evaluation {one * 1e3:.0f} ms ({plan.steps} RK4 steps); value + exact gradient "
        f"{grad * 1e3:.0f} ms = {grad / one:.1f} evaluations (finite differences: {c.size + 1})"
    )
    print(f"  tune --schedule optimal: {wall:.1f} s wall, {cpu:.1f} s CPU")
    print(
        f"  E Σ‖x_i(T) − θ‖²: optimal {ms['optimal']:.6g}, power {ms['power']:.6g} "
        f"({ms['power'] / ms['optimal']:.2f}×), 1/(1+t) {ms['baseline']:.6g} "
        f"({ms['baseline'] / ms['optimal']:.2f}×)"
    )
    for lv in r.solution.levels:
        print(
            f"  {lv.pieces:4d} pieces: {lv.value:.6g} ({lv.evaluations} evaluations, {lv.seconds:.1f} s)"
        )
    print(f"  optimality {r.solution.optimality:.1e}; re-evaluation gap {r.agreement:.1e}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-large", action="store_true", help="G1 only")
    args = ap.parse_args()
    case(
        "G1, T = 10",
        nd.load(ROOT / "examples" / "g1.yaml"),
        [1, 2, -1],
        np.linspace(-3, 3, 21),
        10.0,
        200,
    )
    if not args.skip_large:
        top = random_network(20, 3, seed=1)
        rng = np.random.default_rng(np.random.SeedSequence(5))
        case("generated 20 agents, T = 5", top, [1, 2, -1], rng.uniform(-3, 3, 60), 5.0, 100)


if __name__ == "__main__":
    main()
