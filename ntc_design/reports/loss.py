"""A report's lossy-link section (a run whose ``digital:`` block loses messages): the exact
error at T and the mean's offset ‖x* − 1⊗θ‖ against the loss p, for each policy, and what
the certificate proves (:mod:`ntc_design.certify.kinds.digital_loss`)."""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from ..errors import InputError
from ..model import Topology
from ..present.rows import fmt
from ..protocol.loss import POLICIES
from ..simulate.loss import loss_moments
from ..simulate.prepare import make_gain, prepare_modes, sampled_grid
from .figlist import Drawn
from .html import Table
from .rundata import RunData
from .style import TWO_COLUMN, paper_style

#: Losses drawn: evenly from 0 to this many times the run's p (at most MAX_P).
SPAN = 3.0
POINTS = 9
MAX_P = 0.9


@dataclass(frozen=True)
class LossFacts:
    """What the lossy-link section shows: the run's loss and policy, the curves error(p)
    and offset(p) per policy, and the certificate's statement (or why there is none)."""

    loss: float
    policy: str
    losses: np.ndarray
    final: dict[str, np.ndarray]
    offset: dict[str, np.ndarray]
    certified: str
    note: str

    def table(self) -> Table:
        """The section's table: one row per loss, the error at T per policy and the offset
        under skip.

        Returns
        -------
        Table
        """
        rows = [
            (
                fmt(float(p)),
                *(fmt(float(self.final[k][m])) for k in POLICIES),
                fmt(float(self.offset["skip"][m])),
            )
            for m, p in enumerate(self.losses)
        ]
        cols = ("loss p", *(f"{k}: Σ_i E‖x_i(T) − θ‖²" for k in POLICIES), "skip: ‖x* − 1⊗θ‖")
        return Table(cols, rows)


def loss_facts(run: RunData, certificate: dict) -> LossFacts | None:
    """The lossy-link section of a run, or None when no message is lost.

    Parameters
    ----------
    run : RunData
        The run.
    certificate : dict
        Its certificate (kind ``digital_loss`` states what is proven).

    Returns
    -------
    LossFacts or None
    """
    dg = run.digital
    if dg is None or not dg.lossy:
        return None
    res = certificate.get("results", {}).get("digital", {})
    if certificate.get("kind") != "digital_loss":
        certified = "not certified (the certificate is not of kind digital_loss)"
    elif "k0" in res:
        where = f"to x* at {fmt(res['offset'])} from 1⊗θ" if "offset" in res else "to 1⊗θ"
        certified = (
            f"certified: E‖x − x*‖² contracts from step k₀ = {res['k0']} (c(t) < κ = "
            f"{fmt(res['kappa'])}); the mean goes {where}"
        )
    else:
        certified = f"not certified: {res.get('stopped', 'no lossy section')}"
    losses = np.unique(np.append(np.linspace(0.0, min(SPAN * dg.loss, MAX_P), POINTS), dg.loss))
    final = {k: np.full(losses.size, np.nan) for k in POLICIES}
    offset = {k: np.full(losses.size, np.nan) for k in POLICIES}
    note = ""
    top = run.topology()
    try:
        if not isinstance(top, Topology):
            raise InputError("lossy links are modelled on one fixed topology")
        spec = run.design_spec()
        t_end = float(run.t[-1])
        gain = make_gain(run.gain)[0]
        pm = prepare_modes(top, spec.replace(T=t_end, method="exact"), gain)
        s = pm.systems[0]
        grid = sampled_grid(top, pm, dg, t_end, np.array([t_end]))  # h and D: its loss aside
        for k in POLICIES:
            for m, q in enumerate(losses):
                with np.errstate(all="ignore"):
                    lm = loss_moments(
                        s, grid, gain, pm.eps0, pm.theta, dg.delay, np.full(s.n_edges, q), k
                    )
                final[k][m] = float(lm.moments.ms_error[-1].sum())
                offset[k][m] = lm.offset
    except InputError as exc:
        note = f"the loss curves are not computed: {exc}"
    return LossFacts(dg.loss, dg.policy, losses, final, offset, certified, note)


def loss_figure(f: LossFacts):
    """E Σ‖x_i(T) − θ‖² against the loss for each policy (left) and the offset under skip
    (right), with the run's own loss.

    Parameters
    ----------
    f : LossFacts
        The section's facts.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with paper_style():
        fig, axes = plt.subplots(1, 2, figsize=(TWO_COLUMN, 2.5), layout="constrained")
        for k, ls in zip(POLICIES, ("-", "--", ":"), strict=True):
            axes[0].plot(f.losses, f.final[k], ls, marker="o", ms=2.5, label=k)
        axes[1].plot(f.losses, f.offset["skip"], "-", marker="o", ms=2.5, label="skip")
        for ax in axes:
            ax.axvline(f.loss, color="0.6", lw=0.8, ls="-.", label="this run's p")
            ax.set_xlabel("loss p")
        axes[0].set_yscale("log")
        axes[0].set_ylabel("E Σ‖x_i(T) − θ‖²")
        axes[1].set_ylabel("‖x* − 1⊗θ‖")
        axes[0].legend(fontsize=6.5, loc="best")
    return fig


def loss_drawings(f: LossFacts | None) -> list[Drawn]:
    """The section's figure (none without loss).

    Parameters
    ----------
    f : LossFacts or None
        The section's facts.

    Returns
    -------
    list of Drawn
    """
    if f is None:
        return []
    return [
        Drawn(
            "loss_curves",
            "loss-curves",
            "The exact error at T against the loss p for each policy (left) and, under skip, "
            "the distance of the mean's limit x* from 1⊗θ (right).",
            loss_figure(f),
        )
    ]


__all__ = ["LossFacts", "loss_drawings", "loss_facts", "loss_figure"]
