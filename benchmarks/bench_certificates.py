"""Certificate scaling on this machine, ntc-design's structured search beside the naive
dense formulation, in one run.

1. Common Lyapunov matrix for 3 modes at Nd = 21, 60, 150, on mode sets where a
   block-diagonal certificate exists (modes similar, through T = blockdiag(t_i·I_d), to
   matrices with positive definite symmetric part, so P = TᵀT works and P = I does not).
   ntc-design tries P = I, then block-diagonal P; the naive formulation is one dense
   Nd×Nd P (skipped above --naive-max, where it takes minutes to hours).
2. A single-topology Hurwitz certificate via the Lyapunov equation at Nd = 3000
   (a 1000-agent, d = 3 signed network designed by Lemma 1), proven by the rigorous
   floating-point test, beside SciPy's solve_continuous_lyapunov (with --scipy-3000; it
   takes minutes here) or at Nd = 1000 by default.

Run: python benchmarks/bench_certificates.py [--naive-max 60] [--scipy-3000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.linalg as sla

import ntc_design as nd
from ntc_design.certify.dense import prove_hurwitz
from ntc_design.certify.lyapunov import common_lyapunov


def similar_modes(nd_size: int, d: int = 3, modes: int = 3, seed: int = 0) -> dict[str, np.ndarray]:
    """Sparse block matrices (each agent coupled to 3 others per mode) with positive
    definite symmetric part, made similar through T = blockdiag(t_i·I_d)."""
    rng = np.random.default_rng(seed)
    n = nd_size // d
    tvec = np.repeat(rng.uniform(0.3, 4.0, size=n), d)
    out = {}
    for k in range(modes):
        base = np.zeros((nd_size, nd_size))
        for i in range(n):
            for j in rng.choice([x for x in range(n) if x != i], size=3, replace=False):
                w = rng.normal(size=(d, d)) * 0.5
                base[i * d : (i + 1) * d, j * d : (j + 1) * d] += w
                base[j * d : (j + 1) * d, i * d : (i + 1) * d] -= w.T  # skew coupling
        base += np.eye(nd_size)  # symmetric part I, so the untransformed mode is easy
        out[f"M{k}"] = (tvec[:, None] * base) / tvec[None, :]
    return out


def large_network(n_agents: int = 1000, d: int = 3, seed: int = 1) -> nd.Topology:
    """Random sparse signed network: each agent hears 2 cooperative PD neighbours; a third
    of them also hear one antagonistic ND neighbour (and so are informed)."""
    rng = np.random.default_rng(seed)
    edges = []
    for i in range(n_agents):
        others = rng.choice([j for j in range(n_agents) if j != i], size=3, replace=False)
        for j in others[:2]:
            m = rng.normal(size=(d, d))
            edges.append((int(j) + 1, i + 1, m @ m.T / d + 0.5 * np.eye(d)))
        if rng.random() < 1 / 3:
            m = rng.normal(size=(d, d))
            edges.append((int(others[2]) + 1, i + 1, -(m @ m.T / d + 0.5 * np.eye(d))))
    return nd.Topology.from_edges(n_agents, d, edges)


def timed(fn):
    t0 = time.perf_counter()
    res = fn()
    return res, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--naive-max", type=int, default=60)
    ap.add_argument("--scipy-3000", action="store_true")
    args = ap.parse_args()
    print("== common Lyapunov matrix, 3 modes (block-diagonal certificate exists)")
    print(
        f"{'Nd':>5} {'ntc-design [s]':>15} {'structure':>15} {'naive dense [s]':>16} {'ratio':>7}"
    )
    for size in (21, 60, 150):
        mats = similar_modes(size)
        res, t_s = timed(lambda mats=mats: common_lyapunov(mats, 3))
        if size <= args.naive_max:
            naive, t_n = timed(lambda mats=mats: common_lyapunov(mats, 3, structures=("dense",)))
            ok = "" if naive.p is not None else " (no P)"
            print(
                f"{size:>5} {t_s:>15.2f} {res.structure!s:>15} {t_n:>16.2f}{ok} {t_n / t_s:>7.1f}x"
            )
        else:
            print(f"{size:>5} {t_s:>15.2f} {res.structure!s:>15} {'skipped':>16} {'—':>7}")
    print(
        "\n== Hurwitz certificate via the Lyapunov equation (P L_B + L_Bᵀ P = I, proven P ≻ 0 and PL_B + L_BᵀP ≻ 0)"
    )
    top, t_build = timed(lambda: large_network())
    des, t_des = timed(lambda: nd.design(top, [1.0, 2.0, -1.0]))
    lap_b = des.grounded_laplacian()
    print(f"network: N = {top.n}, d = {top.dim}, Nd = {lap_b.shape[0]}; design {t_des:.1f} s")
    proof, t_p = timed(lambda: prove_hurwitz(lap_b))
    print(
        f"ntc-design Nd={lap_b.shape[0]}: {t_p:.1f} s, proven = {proof.holds} ({proof.lyapunov_pd.method})"
    )
    if args.scipy_3000:
        _, t_sp = timed(lambda: sla.solve_continuous_lyapunov(lap_b.T, np.eye(lap_b.shape[0])))
        print(
            f"scipy solve_continuous_lyapunov Nd={lap_b.shape[0]}: {t_sp:.1f} s (solve only); ratio {t_sp / t_p:.1f}x"
        )
    sub = lap_b[:1002, :1002] + 5 * np.eye(1002)
    _, t_ours = timed(lambda: prove_hurwitz(sub))
    _, t_sp = timed(lambda: sla.solve_continuous_lyapunov(sub.T, np.eye(1002)))
    print(
        f"Nd=1002: ntc-design {t_ours:.2f} s (solve + proof), scipy {t_sp:.2f} s (solve only), ratio {t_sp / t_ours:.1f}x"
    )


if __name__ == "__main__":
    main()
