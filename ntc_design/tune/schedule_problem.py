"""The schedule optimisation's problem (:mod:`.optimal` states the method): the moment
equations of the piecewise-linear gain on a grid, stepped by RK4 forward and by its
discrete adjoint backward, and the smooth maximum the peak constraint uses. Its constants
are the optimiser's too."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..errors import InputError, Option, format_bytes
from ..simulate.prepare import PreparedModes
from .operators import MomentOperators

#: The largest N·d optimised (dense operators of (Nd(Nd+1)/2)² entries; 60 → 1830).
OPTIMAL_MAX_ND = 60
#: RK4's h·ρ per step while optimising (measured on G1: 2e-7 relative against the
#: matrix exponential of each piece).
KAPPA = 1.5
#: A step whose h·ρ exceeds this (a trial point far from the plan) scores +∞.
STABLE = 2.5
#: A piece's steps are planned for this much more than its largest node value.
PLAN_MARGIN = 1.25
LEVELS = (25, 50, 100, 200, 400, 800)
MAX_PIECES = 800
REFINE_RTOL = 1e-3
C_MIN = 1e-6
DEFAULT_MAX_GAIN = 50.0
#: The largest ``max_gain`` accepted.
MAX_MAX_GAIN = 1e6
#: Stored stage derivatives above this many bytes are refused (the adjoint needs them).
MAX_STORE = 2 * 2**30
#: The peak constraint's aggregation parameter (on tr S / M): the aggregate exceeds the
#: maximum by at most log(steps) / KS_RHO.
KS_RHO = 2000.0
BIG = 1e10


class MomentProblem(Protocol):
    """What :func:`solve` and :func:`optimise_schedule` need of a problem: the moment
    equations (:class:`ScheduleProblem`) or the sampled recursion
    (:class:`~ntc_design.tune.sampled.SampledScheduleProblem`)."""

    horizon: float
    initial: float
    evaluations: int

    def node_times(self, pieces: int) -> np.ndarray:
        """The K + 1 node times of K equal pieces of [0, T].

        Parameters
        ----------
        pieces : int
            K.

        Returns
        -------
        numpy.ndarray
        """
        return np.linspace(0.0, self.horizon, pieces + 1)

    def plan(self, c: np.ndarray, kappa: float = ...) -> Any:
        """The steps for node values ``c``.

        Parameters
        ----------
        c : numpy.ndarray
            Node values.
        kappa : float, optional
            The step control (RK4's h·ρ), where there is one.

        Returns
        -------
        Any
        """
        ...

    def forward(self, c: np.ndarray, plan: Any, store: bool = ...) -> Forward | None:
        """J and the traces after every step; None when the run leaves its range.

        Parameters
        ----------
        c : numpy.ndarray
            Node values.
        plan : Any
            The steps.
        store : bool, optional
            Keep what the adjoint needs.

        Returns
        -------
        Forward or None
        """
        ...

    def adjoint(self, plan: Any, fwd: Forward, sources: np.ndarray | None = ...) -> np.ndarray:
        """The gradient of Σ_j sources_j·(trace after step j) with respect to the nodes.

        Parameters
        ----------
        plan : Any
            The steps.
        fwd : Forward
            The forward run.
        sources : numpy.ndarray, optional
            Weights on the traces (default: the last alone).

        Returns
        -------
        numpy.ndarray
        """
        ...


@dataclass(frozen=True, eq=False)
class Plan:
    """The RK4 steps: per step its mode, the node interval k it lies in, its length and
    the positions θ ∈ [0, 1] of its three stage times inside [t_k, t_{k+1}]."""

    mode: np.ndarray
    k: np.ndarray
    h: np.ndarray
    theta: np.ndarray  # (steps, 3)
    t_end: np.ndarray  # step ends
    pieces: np.ndarray  # steps planned per node interval (the largest over its segments)
    nodes: int  # K + 1

    @property
    def steps(self) -> int:
        """The number of RK4 steps."""
        return int(self.h.size)


class ScheduleProblem(MomentProblem):
    """J(c) = tr S(T) for a piecewise-linear c on K pieces, its exact gradient, and the
    peak aggregate (see the module).

    Parameters
    ----------
    prepared : PreparedModes
        The designs, systems and segments (of a fixed, switching or sampled topology).
    horizon : float
        T.
    """

    def __init__(
        self,
        prepared: PreparedModes,
        horizon: float,
    ) -> None:
        n, d = prepared.n, prepared.d
        self.check_size(n * d)
        self.horizon = float(horizon)
        self.ops = [MomentOperators.build(s, n, d) for s in prepared.systems]
        self.diag = MomentOperators.diagonal(n * d)
        eps0 = prepared.eps0
        self.s0 = MomentOperators.pack(np.outer(eps0, eps0))
        self.ns = self.s0.size
        self.segments = [(float(a), float(b), int(m)) for a, b, m in prepared.segments]
        self.initial = float(eps0 @ eps0)
        self.rho = np.array([[op.rho1, op.rho2] for op in self.ops])  # (modes, 2)
        self.evaluations = 0

    @staticmethod
    def check_size(nd_: int) -> None:
        """Refuse N·d above ``OPTIMAL_MAX_ND`` in one line, with why.

        Parameters
        ----------
        nd_ : int
            N·d.

        Raises
        ------
        InputError
            Above the limit.
        """
        if nd_ > OPTIMAL_MAX_ND:
            raise InputError(
                f"N·d = {nd_} is above {OPTIMAL_MAX_ND} (an evaluation "
                "grows as (Nd)³ per RK4 step and the steps with ρ(L_B); a search takes "
                "hundreds); use ",
                Option("schedule", "power"),
                field="schedule",
                value="optimal",
            )

    # ------------------------------------------------------------------ the step plan
    def plan(self, c: np.ndarray, kappa: float = KAPPA) -> Plan:
        """Steps for node values ``c`` (K + 1 of them): each piece ∩ segment is cut in
        equal steps with h·ρ(PLAN_MARGIN·max(c_k, c_{k+1})) <= κ.

        Parameters
        ----------
        c : numpy.ndarray
            Node values.
        kappa : float, optional
            h·ρ per step.

        Returns
        -------
        Plan

        Raises
        ------
        InputError
            More steps than the adjoint's memory allows.
        """
        kk = c.size - 1
        nodes = self.node_times(kk)
        parts: list[tuple[float, float, int, int, int]] = []  # (lo, hi, mode, k, steps)
        seg = self.segments
        si = 0
        for k in range(kk):
            a, b = nodes[k], nodes[k + 1]
            cbar = PLAN_MARGIN * max(c[k], c[k + 1])
            while si < len(seg) - 1 and seg[si][1] <= a + 1e-14 * max(1.0, a):
                si += 1
            j = si
            lo = a
            while lo < b - 1e-14 * max(1.0, b):
                mode = seg[j][2] if j < len(seg) else seg[-1][2]
                hi = min(b, seg[j][1]) if j < len(seg) else b
                if hi > lo:
                    rho = float(max(self.ops[mode].radius(cbar), 1e-12))
                    parts.append((lo, hi, mode, k, max(1, math.ceil((hi - lo) * rho / kappa))))
                    lo = hi
                j += 1
        steps = sum(p[4] for p in parts)
        need = steps * 4 * self.ns * 8  # refused before any array of that many steps exists
        if need > MAX_STORE:
            raise InputError(
                f"{steps:.3g} RK4 steps would store {format_bytes(need)} "
                f"for the adjoint (limit {format_bytes(MAX_STORE)}); lower ",
                Option("max_gain"),
                " or T",
                field="schedule",
                value="optimal",
            )
        per = np.zeros(kk, dtype=np.int64)
        modes, ks, hs, th, ends = [], [], [], [], []
        for lo, hi, mode, k, m in parts:
            per[k] = max(per[k], m)
            edges = np.linspace(lo, hi, m + 1)
            h = np.diff(edges)
            starts = edges[:-1]
            modes.append(np.full(m, mode))
            ks.append(np.full(m, k))
            hs.append(h)
            width = nodes[k + 1] - nodes[k]
            th.append((np.stack([starts, starts + h / 2, starts + h], axis=1) - nodes[k]) / width)
            ends.append(edges[1:])
        plan = Plan(
            np.concatenate(modes),
            np.concatenate(ks),
            np.concatenate(hs),
            np.clip(np.concatenate(th), 0.0, 1.0),
            np.concatenate(ends),
            per,
            c.size,
        )
        return plan

    # ------------------------------------------------------------ forward and adjoint
    def _stage_gains(self, c: np.ndarray, plan: Plan) -> np.ndarray:
        ck, ck1 = c[plan.k], c[plan.k + 1]
        return ck[:, None] * (1 - plan.theta) + ck1[:, None] * plan.theta

    def forward(self, c: np.ndarray, plan: Plan, store: bool = True) -> Forward | None:
        """Integrate from S(0) = ε(0)ε(0)ᵀ; None when a step leaves RK4's stable range
        (h·ρ > ``STABLE``: a trial point far from the plan) or the moments overflow.

        Parameters
        ----------
        c : numpy.ndarray
            Node values.
        plan : Plan
            The steps.
        store : bool, optional
            Keep ∂k/∂c of every stage (the adjoint needs them).

        Returns
        -------
        Forward or None
        """
        self.evaluations += 1
        cs = self._stage_gains(c, plan)
        top = cs.max(axis=1)
        rho = self.rho[plan.mode]
        if np.any(plan.h * (rho[:, 0] * top + rho[:, 1] * top * top) > STABLE):
            return None
        ns = self.ns
        s = self.s0.copy()
        traces = np.empty(plan.steps)
        g = np.empty((plan.steps, 4, ns)) if store else None
        with np.errstate(all="ignore"):
            for j in range(plan.steps):
                op = self.ops[plan.mode[j]]
                h = plan.h[j]
                ks = []
                y = s
                for st, (col, frac) in enumerate(_STAGES):
                    cc = cs[j, col]
                    a1y, a2y = op.products(y)
                    zq = a2y + op.q
                    ks.append(cc * a1y + cc * cc * zq)
                    if g is not None:
                        g[j, st] = a1y + 2 * cc * zq
                    y = s + (frac * h) * ks[-1]
                s = s + (h / 6) * (ks[0] + 2 * ks[1] + 2 * ks[2] + ks[3])
                traces[j] = s[self.diag].sum()
            if not np.all(np.isfinite(traces)) or traces.max() > BIG * max(self.initial, 1.0):
                return None
        return Forward(float(traces[-1]), traces, g, cs)

    def adjoint(self, plan: Plan, fwd: Forward, sources: np.ndarray | None = None) -> np.ndarray:
        """The gradient, with respect to the node values, of Σ_j sources_j·tr S(t_j) over
        the step ends (default: tr S(T) alone), by the discrete adjoint of the forward
        RK4 recursion [1]_.

        Parameters
        ----------
        plan : Plan
            The steps.
        fwd : Forward
            What :meth:`forward` returned (with ``store=True``).
        sources : numpy.ndarray, optional
            Weights on the step-end traces.

        Returns
        -------
        numpy.ndarray
            ∂/∂c_k, k = 0 … K.
        """
        g, cs = fwd.stages, fwd.gains
        assert g is not None, "forward(..., store=True) keeps what the adjoint needs"
        ns = self.ns
        if sources is None:
            sources = np.zeros(plan.steps)
            sources[-1] = 1.0
        lam = np.zeros(ns)
        grad_stage = np.zeros((plan.steps, 3))
        for j in range(plan.steps - 1, -1, -1):
            lam[self.diag] += sources[j]
            bt = self.ops[plan.mode[j]].transpose  # Bᵀμ, B = c𝓐₁ + c²𝓐₂
            h = plan.h[j]
            c1, c2, c4 = cs[j]

            mu4 = (h / 6) * lam
            a4 = bt(mu4, c4)
            mu3 = (h / 3) * lam + h * a4
            a3 = bt(mu3, c2)
            mu2 = (h / 3) * lam + (h / 2) * a3
            a2 = bt(mu2, c2)
            mu1 = (h / 6) * lam + (h / 2) * a2
            a1 = bt(mu1, c1)
            grad_stage[j] = (mu1 @ g[j, 0], mu2 @ g[j, 1] + mu3 @ g[j, 2], mu4 @ g[j, 3])
            lam = lam + a1 + a2 + a3 + a4
        out = np.zeros(plan.nodes)
        np.add.at(out, plan.k, np.sum(grad_stage * (1 - plan.theta), axis=1))
        np.add.at(out, plan.k + 1, np.sum(grad_stage * plan.theta, axis=1))
        return out


#: RK4's stages: which of the step's three gains (t, t + h/2, t + h) each uses, and the
#: fraction of h at which the next stage's input is taken.
_STAGES = ((0, 0.5), (1, 0.5), (1, 1.0), (2, 0.0))


@dataclass(frozen=True, eq=False)
class Forward:
    """One integration: tr S(T), tr S at every step end, ∂k/∂c of every RK4 stage (None
    unless stored) and the stages' gains."""

    value: float
    traces: np.ndarray
    stages: np.ndarray | None
    gains: np.ndarray


def ks_aggregate(traces: np.ndarray, bound: float) -> tuple[float, np.ndarray]:
    """The Kreisselmeier–Steinhauser aggregate of tr S(t_j)/M over the step ends (t = 0's
    value is fixed, so not included) and its weights: KS >= max_j tr S(t_j)/M, and at
    most log(steps)/``KS_RHO`` above it.

    Parameters
    ----------
    traces : numpy.ndarray
        tr S at the step ends.
    bound : float
        M.

    Returns
    -------
    (float, numpy.ndarray)
        KS and ∂KS/∂tr S(t_j).
    """
    v = traces / bound
    top = float(v.max())
    e = np.exp(KS_RHO * (v - top))
    tot = float(e.sum())
    return top + math.log(tot) / KS_RHO, e / tot / bound


__all__ = [
    "BIG",
    "C_MIN",
    "DEFAULT_MAX_GAIN",
    "KAPPA",
    "KS_RHO",
    "LEVELS",
    "MAX_MAX_GAIN",
    "MAX_PIECES",
    "MAX_STORE",
    "OPTIMAL_MAX_ND",
    "PLAN_MARGIN",
    "REFINE_RTOL",
    "STABLE",
    "Forward",
    "MomentProblem",
    "Plan",
    "ScheduleProblem",
    "ks_aggregate",
]
