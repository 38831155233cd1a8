"""Figures and a report section for continuously time-varying topologies.

* λ_min(L_B(t) + L_B(t)ᵀ) over the certified domain (one period, or [0, constant_after]),
  of the protocol as Lemma 1 gives it at each t, with the certified uniform bound Λ₂ and
  the per-interval certified lower bounds of the branch and bound;
* the weights over time: every entry of each weight that depends on t, and δ(t).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..protocol.timevarying import TimeVaryingDesign
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
    with style.paper_style():
        fig, ax = plt.subplots(figsize=(style.TWO_COLUMN, 2.8), layout="constrained")
        ax.plot(ts, lam, color=style.BLUE, lw=1.2, label="sampled")
        if intervals:
            xs = [q[0] for q in intervals] + [intervals[-1][1]]
            ys = [q[2] for q in intervals] + [intervals[-1][2]]
            ax.step(
                xs, ys, where="post", color=style.GREY, lw=0.8, label="certified on each interval"
            )
        if lambda2 is not None:
            ax.axhline(
                lambda2, color=style.RED, ls="--", lw=1.2, label=rf"$\Lambda_2$ = {lambda2:.4g}"
            )
        ax.set_xlabel("$t$")
        ax.set_ylabel(r"$\lambda_{\min}(L_B(t) + L_B(t)^\top)$")
        fig.legend(loc="outside right center", frameon=False)
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
    d = tv.dim
    with style.paper_style():
        fig, axes = plt.subplots(
            panels, 1, figsize=(style.TWO_COLUMN, 1.6 * panels + 0.4), sharex=True,
            layout="constrained",
        )  # fmt: skip
        axes = np.atleast_1d(axes)
        for ax, k in zip(axes, var, strict=False):
            e = tv.edges[k]
            n_line = 0
            for r in range(d):
                for c in range(r, d):
                    if np.ptp(w[:, k, r, c]) > 0 or np.any(w[:, k, r, c]):
                        st = style.agent_style(n_line)
                        ax.plot(ts, w[:, k, r, c], color=st.colour, ls=st.linestyle, lw=1.0,
                                label=f"entry ({r + 1}, {c + 1})")  # fmt: skip
                        n_line += 1
            i, j = tv.labels[e.i], tv.labels[e.j]
            ax.set_ylabel(rf"$A_{{{i}{j}}}(t)$" + f"\n({e.cls.value})")
            ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False, fontsize=7)
        batch = des.at(ts)
        axes[-1].plot(ts, batch.delta, color=style.RED, lw=1.2)
        axes[-1].set_ylabel(r"$\delta(t) = C(t) + \Delta C$")
        axes[-1].set_xlabel("$t$")
    return fig


__all__ = ["lambda_min_figure", "weights_figure"]
