"""Tuning the gain for a deadline (issue 21): the time of `tune` on the paper's G1, the
switching set and a 300-agent network, and one objective evaluation beside SciPy's DOP853
on the same moment equations (the peer: what a user would write by hand).

    python benchmarks/bench_tune.py [--skip-large] [--evaluations 160]

G1 and the switching set: the scenarios in examples/scenarios (σ = 0.4, f(x) = 0.3x,
x(0) uniform on [−3, 3], seed 1), T = 10, the default search (a grid, then bounded
Nelder–Mead), the contour map and the certificate included. The 300-agent network:
`ntc generate --agents 300 --dim 1` (δ in the hundreds, so L_B is stiff and the tuner integrates
by Crank–Nicolson), σ = 0.4, f = 0.05, T = 5, a budget of 40 evaluations, no contour map.
Wall times on a shared machine are noisy: CPU time is printed beside them.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from ntc_design.model.generate import random_network
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.simulate.moments import MomentRhs
from ntc_design.simulate.scenario import load_scenario
from ntc_design.tune import BASELINE, ExactObjective, PowerOptions, tune

ROOT = Path(__file__).resolve().parents[1]


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def dop853_value(obj: ExactObjective, gain) -> float:
    """E Σ‖x_i(T) − θ‖² by SciPy's DOP853 on the same right-hand side (rtol 1e-8)."""
    pm = obj.prepared(None)[0]
    (a, b, mode), *rest = pm.segments
    assert not rest, "one topology"
    f = MomentRhs(pm.systems[mode], pm.n, pm.d)
    nd_ = pm.n * pm.d

    def rhs(t, y):
        dm, ds = f(float(gain(np.array([t]))[0]), y[:nd_], y[nd_:].reshape(nd_, nd_))
        return np.concatenate([dm, ds.ravel()])

    y0 = np.concatenate([pm.eps0, np.outer(pm.eps0, pm.eps0).ravel()])
    sol = solve_ivp(rhs, (a, b), y0, method="DOP853", rtol=1e-8, atol=1e-10, t_eval=[b])
    return float(np.trace(sol.y[nd_:, -1].reshape(nd_, nd_)))


def case(name, top, spec, horizon, evaluations, landscape):
    res, wall, cpu = timed(
        lambda: tune(
            top, spec, horizon, PowerOptions(max_evaluations=evaluations, landscape=landscape)
        )
    )
    ms = res.ms_error_T
    print(
        f"{name:<22} N·d = {top.n * top.dim:>4}  tune {wall:7.1f} s wall / {cpu:7.1f} s CPU  "
        f"{res.evaluations:>3} evaluations ({wall / res.evaluations:.3f} s each)  "
        f"{res.tuned.text:<24} {ms['tuned']:.4g} vs baseline {ms['baseline']:.4g} "
        f"(×{ms['baseline'] / ms['tuned']:.2f})  certified: {res.certified}  [{res.method}]"
    )
    st = res.stage_seconds  # where the time went (the step check: spectra, no path drawn)
    print(f"{'':<22} {'; '.join(f'{k} {v:.2f} s' for k, v in st.items())}")
    return res


def peer(name, top, spec, horizon):
    obj = ExactObjective(top, spec, horizon)
    obj.prepared(None)
    ours, w1, _ = timed(lambda: obj.value(BASELINE))
    ref, w2, _ = timed(lambda: dop853_value(obj, BASELINE))
    print(
        f"{name:<22} one evaluation: tune's {w1:.3f} s ({obj.describe()}) vs SciPy DOP853 "
        f"{w2:.3f} s: ×{w2 / w1:.1f}; values {ours:.6g} / {ref:.6g} (rel. diff {abs(ours / ref - 1):.1e})"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-large", action="store_true", help="leave out the 300-agent network")
    ap.add_argument(
        "--evaluations", type=int, default=160, help="search budget for G1 and switching"
    )
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    sc = ROOT / "examples" / "scenarios"
    g1, g1_spec, _ = load_scenario(sc / "g1_fixed.yaml")
    sw, sw_spec, _ = load_scenario(sc / "switching.yaml")
    print("tuning c(t) = a·(b + t)^(−γ) for the deadline T (exact moments):")
    case("G1 (T = 10)", g1, g1_spec, 10.0, args.evaluations, True)
    case("switching (T = 10)", sw, sw_spec, 10.0, args.evaluations, True)
    big = None
    if not args.skip_large:
        big = random_network(300, 1, seed=1)
        x0 = np.random.default_rng(np.random.SeedSequence(2)).uniform(-3, 3, 300)
        big_spec = SimulationSpec.build([1.0], noise=NoiseModel(0.4, 0.05), initial=x0)
        case("random 300 (T = 5)", big, big_spec, 5.0, 40, False)
    print("\none objective evaluation against SciPy's DOP853 on the same equations:")
    peer("G1 (T = 10)", g1, g1_spec, 10.0)
    if big is not None:
        peer("random 300 (T = 5)", big, big_spec, 5.0)
    print(
        "\ncost: an evaluation is O(steps·(Nd)³); RK4's steps grow with c·ρ(L_B), "
        "Crank–Nicolson's with ∫c dt and the noise only (chosen per candidate)."
    )


if __name__ == "__main__":
    main()
