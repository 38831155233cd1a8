"""Figures and a report section for continuously time-varying topologies.

* λ_min(L_B(t) + L_B(t)ᵀ) over the certified domain (one period, or [0, constant_after]),
  of the protocol as Lemma 1 gives it at each t, with the certified uniform bound Λ₂ and
  the per-interval certified lower bounds of the branch and bound;
* the weights over time: every entry of each weight that depends on t, and δ(t).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..timevarying import TimeVaryingDesign
from . import style


def lambda_min_figure(
    des: TimeVaryingDesign,
    lambda2: float | None = None,
    intervals: list | None = None,
    samples: int = 1500,
):
    """λ_min(L_B(t) + L_B(t)ᵀ) over the domain with Λ₂ marked (and the certified bound on
    each branch-and-bound interval, as a step curve).

    Parameters
    ----------
    des : TimeVaryingDesign
        The design.
    lambda2 : float, optional
        The certified Λ₂.
    intervals : list, optional
        The certificate's [a, b, bound] intervals.
    samples : int, optional
        Times sampled.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tv = des.topology
    a, b = tv.domain or (0.0, 10.0)
    ts = np.linspace(a, b, samples)
    batch = des.at(ts)
    lap = batch.lap_b(des.structure)
    lam = np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0]
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    ax.plot(ts, lam, color=style.BLUE, lw=1.4, label="λ_min(L_B(t) + L_B(t)ᵀ), sampled")
    if intervals:
        xs = [q[0] for q in intervals] + [intervals[-1][1]]
        ys = [q[2] for q in intervals] + [intervals[-1][2]]
        ax.step(xs, ys, where="post", color="#888888", lw=0.8, label="certified on each interval")
    if lambda2 is not None:
        ax.axhline(lambda2, color=style.RED, ls="--", lw=1.2, label=f"Λ₂ = {lambda2:.4g}")
    ax.set_xlabel("t")
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def weights_figure(des: TimeVaryingDesign, samples: int = 1000):
    """Every entry of each time-varying weight over the domain, and δ(t) = C(t) + ΔC.

    Parameters
    ----------
    des : TimeVaryingDesign
        The design.
    samples : int, optional
        Times sampled.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tv = des.topology
    a, b = tv.domain or (0.0, 10.0)
    ts = np.linspace(a, b, samples)
    w = tv.weights_at(ts)
    var = [k for k, e in enumerate(tv.edges) if not e.weight.constant]
    panels = len(var) + 1
    fig, axes = plt.subplots(panels, 1, figsize=(7.5, 2.1 * panels), sharex=True)
    axes = np.atleast_1d(axes)
    d = tv.dim
    for ax, k in zip(axes, var, strict=False):
        e = tv.edges[k]
        for r in range(d):
            for c in range(r, d):
                if np.ptp(w[:, k, r, c]) > 0 or np.any(w[:, k, r, c]):
                    ax.plot(ts, w[:, k, r, c], lw=1.0, label=f"[{r + 1},{c + 1}]")
        ax.set_ylabel(f"A {tv.labels[e.i]}{tv.labels[e.j]}")
        ax.set_title(f"{e.field} ({e.cls.value})", fontsize=9)
        ax.legend(fontsize=7, ncol=6, loc="upper right")
        ax.grid(alpha=0.3)
    batch = des.at(ts)
    axes[-1].plot(ts, batch.delta, color=style.RED, lw=1.2, label="δ(t) = C(t) + ΔC")
    axes[-1].set_ylabel("δ(t)")
    axes[-1].set_xlabel("t")
    axes[-1].legend(fontsize=8)
    axes[-1].grid(alpha=0.3)
    fig.tight_layout()
    return fig


__all__ = ["lambda_min_figure", "weights_figure"]
