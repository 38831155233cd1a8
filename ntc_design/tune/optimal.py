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
from typing import Any

import numpy as np

from ..errors import InputError, Option, require_number
from .family import PowerGain
from .problem import (
    BIG,
    C_MIN,
    DEFAULT_MAX_GAIN,
    KAPPA,
    LEVELS,
    MAX_MAX_GAIN,
    REFINE_RTOL,
    Forward,
    MomentProblem,
    ks_aggregate,
)


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
        One line naming ``max_gain``.
    """
    v = require_number("max_gain", max_gain)
    if not C_MIN < v <= MAX_MAX_GAIN:
        raise InputError(
            f"expected a number in ({C_MIN:g}, {MAX_MAX_GAIN:g}] (the optimiser "
            f"searches c(t) in [{C_MIN:g}, ",
            Option("max_gain"),
            f"]), got {max_gain!r}",
            field="max_gain",
        )
    return v


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
            "the optimum left RK4's stable range (lower ",
            Option("max_gain"),
            ")",
            field="schedule",
            value="optimal",
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
    "Level",
    "NodeLogs",
    "PowerNodes",
    "ScheduleSolution",
    "Solved",
    "check_max_gain",
    "fit_power",
    "optimise_schedule",
    "solve",
]
