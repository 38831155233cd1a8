"""The best gain schedule for a deadline: optimal control of the exact moment equations.

The problem: over continuous c(t) >= 0 on [0, T], minimise J = E Σ_i ‖x_i(T) − θ‖² =
tr S(T), where S = E[εεᵀ] obeys the exact second-moment equation of
:mod:`ntc_design.simulate.moments` (linear f),

    dS/dt = c 𝓐₁(S) + c² (𝓐₂(S) + Q),   𝓐₁(S) = −(L_B S + S L_Bᵀ),
    𝓐₂(S) = Σ_e G_e S G_eᵀ,  Q = G Gᵀ,

optionally subject to sup_{t <= T} tr S(t) <= M (a peak constraint).

**Transcription** (direct single shooting, a control parametrisation): c is piecewise
linear on K equal pieces of [0, T] (node values c_0 … c_K, so the schedule is continuous
as the theorems ask), S is flattened (:mod:`.operators`: L_B products and a sparse noise
map), and the equation is integrated by classical RK4 on a grid through every node and every
switching instant, with h·ρ(c𝓐₁ + c²𝓐₂) <= ``KAPPA`` on each step (the step count of a
piece is planned from its node values and kept while the optimiser runs, so J is a
smooth function of the nodes; after each run the plan is remade and the run repeated
until it holds). The gradient is the **exact discrete adjoint** of that RK4 recursion
(reverse accumulation through the four stages; a finite-difference test checks it to
1e-7), so the optimiser sees the exact derivative of the number it minimises.

**Solver**: with the state eliminated the NLP has K + 1 variables, u_k = log c_k, and
simple bounds (c_min <= c <= ``max_gain``): SciPy's L-BFGS-B [2]_. With a peak bound the
constraint is the Kreisselmeier–Steinhauser aggregate of tr S at every step end (an upper
bound of their maximum, so the constraint it enforces is conservative), and the solver is
SLSQP [3]_. CasADi + IPOPT was measured and not used: a direct transcription with S as
NLP variables needs a step of about 0.01 at c ≈ 2 for 0.1 % accuracy on G1, i.e. about
10⁵ states with dense 231×231 Jacobian blocks, and CasADi's symbolic evaluation of the
shooting recursion is slower than NumPy's BLAS products here; IPOPT's strength, sparse
large constrained problems, is not what is left after elimination.

**Refinement**: K = 25, 50, 100, … (each level starts from the last: a piecewise-linear
schedule on K pieces is exactly one on 2K), until the optimum changes by less than
``REFINE_RTOL`` (0.1 %), at most ``MAX_PIECES``.

Cost: an evaluation with its gradient is 8 stages of 2–3 products with L_B and one sparse
product per RK4 step, O((Nd)³ + E·d⁴) each, and the steps grow as ∫ c ρ(L_B) dt (a large
Lemma 1 δ makes L_B stiff); the adjoint stores 4 (Nd)² numbers per step. Above
``OPTIMAL_MAX_ND`` it is refused.

References
----------
.. [1] A. E. Bryson, Y.-C. Ho, *Applied Optimal Control*, Hemisphere, 1975, ch. 2
   (adjoint equations); A. Sandu, "On the properties of Runge–Kutta discrete adjoints",
   ICCS 2006 (the discrete adjoint of RK4).
.. [2] R. H. Byrd, P. Lu, J. Nocedal, C. Zhu, "A limited memory algorithm for bound
   constrained optimization", SIAM J. Sci. Comput. 16 (1995) 1190–1208.
.. [3] D. Kraft, "A software package for sequential quadratic programming", DFVLR-FB
   88-28, 1988.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Protocol

import numpy as np

from ..errors import InputError, format_bytes, require_number
from ..simulate.driver import PreparedModes
from .family import PowerGain
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
#: The largest --max-gain accepted.
MAX_MAX_GAIN = 1e6
#: Stored stage derivatives above this many bytes are refused (the adjoint needs them).
MAX_STORE = 2 * 2**30
#: The peak constraint's aggregation parameter (on tr S / M): the aggregate exceeds the
#: maximum by at most log(steps) / KS_RHO.
KS_RHO = 2000.0
BIG = 1e10


def check_max_gain(max_gain: float) -> float:
    """The upper bound on c(t): a number in (``C_MIN``, ``MAX_MAX_GAIN``] (the optimiser
    searches log c in [log C_MIN, log max_gain], empty below C_MIN).

    Parameters
    ----------
    max_gain : float
        The bound given (``--max-gain``).

    Returns
    -------
    float

    Raises
    ------
    InputError
        One line naming --max-gain.
    """
    v = require_number("--max-gain", max_gain)
    if not C_MIN < v <= MAX_MAX_GAIN:
        raise InputError(
            f"--max-gain: expected a number in ({C_MIN:g}, {MAX_MAX_GAIN:g}] (the optimiser "
            f"searches c(t) in [{C_MIN:g}, --max-gain]), got {max_gain!r}"
        )
    return v


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
        ...

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


class ScheduleProblem:
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
                f"--schedule optimal: N·d = {nd_} is above {OPTIMAL_MAX_ND} (an evaluation "
                "grows as (Nd)³ per RK4 step and the steps with ρ(L_B); a search takes "
                "hundreds); use --schedule power"
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
                f"--schedule optimal: {steps:.3g} RK4 steps would store {format_bytes(need)} "
                f"for the adjoint (limit {format_bytes(MAX_STORE)}); lower --max-gain or T"
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


class NodeLogs:
    """The schedule's parameters: x_k = log c_k at the K + 1 nodes (bounds on c become
    bounds on x; the chain rule is ∂J/∂x_k = c_k ∂J/∂c_k)."""

    def nodes(self, x: np.ndarray) -> np.ndarray:
        """The node values c for parameters x.

        Parameters
        ----------
        x : numpy.ndarray
            log c.

        Returns
        -------
        numpy.ndarray
        """
        return np.exp(x)

    def pullback(self, x: np.ndarray, c: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """∂J/∂x from ∂J/∂c.

        Parameters
        ----------
        x, c, grad : numpy.ndarray
            Parameters, node values and ∂J/∂c.

        Returns
        -------
        numpy.ndarray
        """
        return c * grad


class PowerNodes(NodeLogs):
    """A power law a·(b + t)^(−γ) sampled at the nodes ``t``: parameters (log a, log b, γ)."""

    def __init__(self, t: np.ndarray) -> None:
        self.t = t

    def nodes(self, x: np.ndarray) -> np.ndarray:  # noqa: D102 - as the base
        return np.exp(x[0]) * (np.exp(x[1]) + self.t) ** (-x[2])

    def pullback(self, x: np.ndarray, c: np.ndarray, grad: np.ndarray) -> np.ndarray:  # noqa: D102
        b = np.exp(x[1])
        dc = np.stack([c, -x[2] * c * b / (b + self.t), -c * np.log(b + self.t)])
        return dc @ grad


@dataclass(frozen=True)
class Level:
    """One row of the refinement table."""

    pieces: int
    value: float
    evaluations: int
    seconds: float
    steps: int


@dataclass(frozen=True, eq=False)
class ScheduleSolution:
    """The optimum on the finest level: node times and values, its value (the optimiser's
    own integration), the refinement table, the projected-gradient norm (of J with
    respect to log c_k, relative to J), whether the gain bound binds and the peak."""

    t: np.ndarray
    c: np.ndarray
    value: float
    levels: tuple[Level, ...]
    optimality: float
    max_gain: float
    binds: tuple[float, ...]
    peak: tuple[float, float]
    converged: bool
    message: str
    notes: tuple[str, ...] = field(default=())


@dataclass(frozen=True, eq=False)
class Solved:
    """What :func:`solve` found: parameters, node values, the plan and the integration at
    the optimum, ∂J/∂x there and the optimiser's message."""

    x: np.ndarray
    c: np.ndarray
    plan: Any
    fwd: Forward
    grad: np.ndarray
    message: str


def solve(
    prob: MomentProblem,
    param: NodeLogs,
    x0: np.ndarray,
    bounds: Sequence[tuple[float, float]],
    *,
    max_peak: float | None = None,
    kappa: float = KAPPA,
) -> Solved:
    """Minimise J over the parameters of ``param`` from ``x0``: L-BFGS-B (or SLSQP with
    the peak bound M ≥ the KS aggregate), with the exact adjoint gradient; the step plan
    is made from the start, kept while the optimiser runs (so J is smooth), and remade
    for the larger of every gain seen and the run repeated until the optimum needs no
    more steps (so the plan only grows and the loop ends).

    Parameters
    ----------
    prob : MomentProblem
        The moment equations, or the sampled recursion.
    param : NodeLogs
        How parameters map to node values.
    x0 : numpy.ndarray
        The start.
    bounds : sequence of (float, float)
        Per parameter.
    max_peak : float, optional
        M.
    kappa : float, optional
        RK4's h·ρ.

    Returns
    -------
    Solved

    Raises
    ------
    InputError
        The optimum leaves RK4's stable range, or a plan too large for memory.
    """
    from scipy.optimize import minimize

    lo = np.array([b[0] for b in bounds])
    hi = np.array([b[1] for b in bounds])
    x = np.clip(np.asarray(x0, dtype=float), lo, hi)
    scale = max(prob.initial, 1e-300)
    basis = param.nodes(x)  # the plan is made for gains up to these; it only grows
    plan = prob.plan(basis, kappa)
    peak = float(max_peak) if max_peak is not None else math.inf
    message = ""
    for _ in range(4):
        memo: dict[bytes, Forward | None] = {}

        def run(z: np.ndarray, plan: Any = plan, memo=memo) -> Forward | None:
            key = z.tobytes()
            if key not in memo:
                if len(memo) > 8:
                    memo.clear()
                memo[key] = prob.forward(param.nodes(z), plan)
            return memo[key]

        def grad(z: np.ndarray, fwd: Forward, sources=None, plan: Any = plan) -> np.ndarray:
            return param.pullback(z, param.nodes(z), prob.adjoint(plan, fwd, sources))

        def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
            fwd = run(z)
            if fwd is None:
                return BIG, np.zeros_like(z)
            return fwd.value / scale, grad(z, fwd) / scale

        if max_peak is None:
            r = minimize(
                objective,
                x,
                jac=True,
                method="L-BFGS-B",
                bounds=list(zip(lo, hi, strict=True)),
                options={"maxiter": 2000, "ftol": 1e-13, "gtol": 1e-10, "maxcor": 20},
            )
        else:

            def con(z: np.ndarray) -> float:
                fwd = run(z)
                return -BIG if fwd is None else 1.0 - ks_aggregate(fwd.traces, peak)[0]

            def con_jac(z: np.ndarray) -> np.ndarray:
                fwd = run(z)
                if fwd is None:
                    return np.zeros_like(z)
                return -grad(z, fwd, ks_aggregate(fwd.traces, peak)[1])

            r = minimize(
                lambda z: objective(z)[0],
                x,
                jac=lambda z: objective(z)[1],
                method="SLSQP",
                bounds=list(zip(lo, hi, strict=True)),
                constraints=[{"type": "ineq", "fun": con, "jac": con_jac}],
                options={"maxiter": 500, "ftol": 1e-12},
            )
        x = np.clip(r.x, lo, hi)
        message = str(r.message)
        basis = np.maximum(basis, param.nodes(x))
        new = prob.plan(basis, kappa)
        if np.array_equal(new.pieces, plan.pieces):
            break
        plan = new
    fwd = prob.forward(param.nodes(x), plan)
    if fwd is None:
        raise InputError(
            "--schedule optimal: the optimum left RK4's stable range (lower --max-gain)"
        )
    c = param.nodes(x)
    return Solved(x, c, plan, fwd, param.pullback(x, c, prob.adjoint(plan, fwd)), message)


def optimise_schedule(
    prob: MomentProblem,
    start: Callable[[np.ndarray], np.ndarray],
    *,
    max_gain: float = DEFAULT_MAX_GAIN,
    max_peak: float | None = None,
    levels: Sequence[int] = LEVELS,
    rtol: float = REFINE_RTOL,
    kappa: float = KAPPA,
    progress: Callable[[str], None] | None = None,
) -> ScheduleSolution:
    """Refine the optimal piecewise-linear schedule over ``levels`` until it changes by
    less than ``rtol`` (see the module); each level starts from the last one's schedule
    (exactly: a piecewise-linear c on K pieces is one on 2K).

    Parameters
    ----------
    prob : MomentProblem
        The moment equations, or the sampled recursion.
    start : callable
        c(t) to start the coarsest level from (e.g. the best power law).
    max_gain : float, optional
        The upper bound on c.
    max_peak : float, optional
        The bound M on sup_t tr S(t).
    levels : sequence of int, optional
        Pieces per level.
    rtol : float, optional
        The refinement's stopping tolerance.
    kappa : float, optional
        RK4's h·ρ.
    progress : callable, optional
        Called with a line per level.

    Returns
    -------
    ScheduleSolution

    Raises
    ------
    InputError
        A plan too large for the adjoint's memory, or an optimum outside RK4's stable
        range.
    """
    lo, hi = math.log(C_MIN), math.log(check_max_gain(max_gain))
    rows: list[Level] = []
    c_prev: Callable[..., Any] = start
    best: Solved | None = None
    converged = False
    for kk in levels:
        t0 = time.perf_counter()
        nodes = prob.node_times(kk)
        x0 = np.log(np.clip(np.asarray(c_prev(nodes), dtype=float), C_MIN, max_gain))
        ev0 = prob.evaluations
        sol = solve(prob, NodeLogs(), x0, [(lo, hi)] * x0.size, max_peak=max_peak, kappa=kappa)
        rows.append(
            Level(
                kk, sol.fwd.value, prob.evaluations - ev0, time.perf_counter() - t0, sol.plan.steps
            )
        )
        if progress is not None:
            progress(
                f"{kk} pieces: E Σ‖x_i(T) − θ‖² = {sol.fwd.value:.6g} ({sol.plan.steps} RK4 steps)"
            )
        previous, best = best, sol
        c_prev = partial(np.interp, xp=nodes, fp=sol.c)
        if previous is not None and abs(sol.fwd.value - previous.fwd.value) <= rtol * sol.fwd.value:
            converged = True
            break
    assert best is not None
    pg = best.grad.copy()
    pg[(best.x <= lo + 1e-9) & (pg > 0)] = 0.0  # the projected gradient: zero where a
    pg[(best.x >= hi - 1e-9) & (pg < 0)] = 0.0  # bound holds the descent back
    traces = np.concatenate([[prob.initial], best.fwd.traces])
    times = np.concatenate([[0.0], best.plan.t_end])
    k = int(np.argmax(traces))
    notes = []
    if not converged:
        notes.append(
            f"the refinement did not settle to {rtol:.1%} by {levels[-1]} pieces; the last "
            "level is reported"
        )
    nodes = prob.node_times(best.c.size - 1)
    return ScheduleSolution(
        nodes,
        best.c,
        best.fwd.value,
        tuple(rows),
        float(np.max(np.abs(pg)) / max(best.fwd.value, 1e-300)),
        max_gain,
        tuple(float(x) for x in nodes[best.x >= hi - 1e-6]),
        (float(traces[k]), float(times[k])),
        converged,
        best.message,
        tuple(notes),
    )


def fit_power(
    prob: MomentProblem,
    start: PowerGain,
    gamma: tuple[float, float],
    a_range: tuple[float, float],
    b_range: tuple[float, float],
    pieces: int = 800,
) -> PowerGain:
    """Polish a power law a·(b + t)^(−γ) by L-BFGS-B on (log a, log b, γ) with the exact
    gradient of the same discretised problem (c sampled at ``pieces`` + 1 nodes, linear
    between; :class:`PowerNodes`).

    Parameters
    ----------
    prob : MomentProblem
        The moment equations, or the sampled recursion.
    start : PowerGain
        Where to start (e.g. the coarse search's optimum).
    gamma, a_range, b_range : (float, float)
        The admissible box.
    pieces : int, optional
        Pieces of the sampled gain.

    Returns
    -------
    PowerGain

    Raises
    ------
    InputError
        A plan too large for the adjoint's memory.
    """
    box = [
        (math.log(a_range[0]), math.log(a_range[1])),
        (math.log(b_range[0]), math.log(b_range[1])),
        gamma,
    ]
    x0 = np.array([math.log(start.a), math.log(start.b), start.gamma])
    sol = solve(prob, PowerNodes(prob.node_times(pieces)), x0, box)
    return PowerGain(float(np.exp(sol.x[0])), float(np.exp(sol.x[1])), float(sol.x[2]))


__all__ = [
    "C_MIN",
    "MAX_MAX_GAIN",
    "check_max_gain",
    "DEFAULT_MAX_GAIN",
    "Forward",
    "Level",
    "MomentProblem",
    "NodeLogs",
    "OPTIMAL_MAX_ND",
    "Plan",
    "PowerNodes",
    "ScheduleProblem",
    "ScheduleSolution",
    "Solved",
    "fit_power",
    "ks_aggregate",
    "optimise_schedule",
    "solve",
]
