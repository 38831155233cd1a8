"""The digital certificate's tightness and cost (issue 46, part 1): on G1 (θ = 1, 2, −1,
σ = 0.4, f = 0.3, c = 1/(1+t)) for D = 0, 1, 2 and h = 0.05, 0.1, 0.2, the certified level
κ beside the mean-square limit c_true (the largest constant gain at which the sampled
second-moment map contracts), κ / c_true, the first certified time k₀·h and the time to
certify, the Razumikhin bound ("old", :func:`ntc_design.certify.digital.plan`) beside the
delay line's functional ("new", :mod:`ntc_design.certify.delayline`), and a generated
network.

    python benchmarks/bench_digital_certificate.py [--quick]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.certify import digital as dg
from ntc_design.model.generate import random_network
from ntc_design.protocol.digital import Digital

THETA = [1.0, 2.0, -1.0]


def _old(top, theta, h: float, delay: int) -> tuple[float, float | None]:
    """The Razumikhin (D > 0) or no-delay level and k₀·h, as before issue 46."""
    des = nd.design(top, theta, thresholds=False)
    lap = des.grounded_laplacian()
    d = top.dim
    edges = dg.edge_noises(top, 0.3 * np.eye(d), 0.4)
    pl = dg.plan([lap], [edges], d, h, delay, None)
    if pl is None:
        return 0.0, None
    t0, _ = dg.gain_t0("1/(1+t)", pl.kappa)
    return pl.kappa, None if t0 is None else dg.first_step(t0, h, delay) * h


def row(name: str, top, theta, h: float, delay: int) -> None:
    old_k, old_t = _old(top, theta, h, delay)
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cert = certify(top, theta, gain="1/(1+t)", digital=Digital(h, delay)).certificate
    secs = time.perf_counter() - t
    r = cert["results"]["digital"]
    ct = r.get("c_true")
    k, k0h = r.get("kappa", 0.0), r.get("k0", 0) * h
    old_txt = f"{old_k:.4f} ({old_k / ct:5.1%}), k₀h = {old_t}" if ct else f"{old_k:.4f}"
    print(
        f"{name:10s} h = {h:<5g} D = {delay}: c_true = {ct:.4f}  new κ = {k:.4f} "
        f"({k / ct:5.1%}, {r.get('bound', 'no delay')}), k₀·h = {k0h:.2f} s, "
        f"certify {secs:.1f} s | old κ = {old_txt}",
        flush=True,
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="h = 0.1 only, D = 0 and 1")
    args = ap.parse_args()
    g1 = nd.load("examples/g1.yaml")
    hs = (0.1,) if args.quick else (0.05, 0.1, 0.2)
    ds = (0, 1) if args.quick else (0, 1, 2)
    for h in hs:
        for delay in ds:
            row("G1", g1, THETA, h, delay)
    gen = random_network(4, 2, seed=1)
    for delay in (0, 1) if args.quick else (0, 1, 2):
        row("generated", gen, [1.0, -1.0], 0.1, delay)


if __name__ == "__main__":
    main()
