"""Proven figures at the deadline on lossy links: E Σ‖x_i(T) − θ‖² ≤ B_T and its peak over
[0, T] ≤ B_peak for the sampled protocol whose messages are lost (skip, rescale or hold;
any delay D ≥ 0), by the exact lossy moment recursion in ball arithmetic (python-flint's
arb), as :mod:`ntc_design.certify.deadline` does without loss.

The recursion is the one :mod:`ntc_design.simulate.loss` runs in floats (its docstring has
the model). On the augmented state z = (e_k, …, e_{k−D}, 1, y_1 … y_E) (the held
measurements y_e only for hold), with χ_e ~ Bernoulli(q_e), q_e = 1 − p_e, the edge's
multiplier's mean, variance and mean square μ_e, v_e, w_e (q, q(1 − q), q for skip and
hold; 1, (1 − q)/q, 1/q for rescale), r_e the d×W row block of the edge's measurement a_e
(minus y_e for hold), M̄ = M_y + τ M_τ the mean step (τ = h c_k) and R = Y + τ P its
placement of the edges' terms, the second moment Z = E[z zᵀ] (its constant's column is
the mean) follows exactly

    Z' = M̄ Z M̄ᵀ + R B Rᵀ,   B = blockdiag_e( v_e r_e Z r_eᵀ + w_e (g_e g_eᵀ + K_e Δ_e Z Δ_eᵀ K_eᵀ)/h ).

Between samples an agent integrates its held input, so with s in [0, h] the error
e(kh + s) is the step's e-rows at τ = c_k s: E‖e(kh + s)‖² = a + b s + q s² with
a = tr Z_ee, b = 2 c_k tr(M_τ,e Z E_eᵀ), q = c_k² (tr(M_τ,e Z M_τ,eᵀ) + tr B) (the
e-rows of M_y are E_e and those of Y are zero). K = ⌊T/h⌋ full steps and the partial
step s = T − K h give B_T; each step's quadratic's maximum over [0, h] gives B_peak.
Every matrix is built exactly from the subject's floats (p_e, the weights, θ, x(0)), and
every entry of the recursion is a ball.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from flint import arb, arb_mat, ctx

from ..errors import InputError, check_work, format_bytes
from ..numerics.memory import available_memory
from ..protocol.loss import loss_width, require_loss, require_policy
from .deadline import (
    ARB_FLOP_SECONDS,
    BUILD_BITS,
    MAX_BITS,
    MAX_SECONDS,
    PREC,
    RADIUS_RTOL,
    DeadlineBound,
    DeadlineProblem,
    deadline_steps,
    precision,
)
from .digital import EdgeNoise
from .fields import need, number
from .loss import LossEdge, loss_edges

#: The share of the available memory the ball recursion may take.
MEMORY_SHARE = 0.5
#: Ball matrices of W² entries alive during a step.
BALL_COPIES = 8
#: Bytes of one ball besides its midpoint's limbs.
BALL_BYTES = 64


@dataclass(frozen=True)
class LossSection:
    """``subject.deadline.loss`` as read: the policy and p_e by (i, j) (every edge of the
    topology, 0 where it is not listed)."""

    policy: str
    losses: dict[tuple[int, int], float]

    @property
    def p_max(self) -> float:
        """The largest p_e."""
        return max(self.losses.values(), default=0.0)

    def to_dict(self) -> dict:
        """What ``results.deadline.loss`` states.

        Returns
        -------
        dict
            ``policy`` and ``p_max``.
        """
        return {"policy": self.policy, "p_max": self.p_max}


def loss_section(top: Any, loss: float, policy: str) -> dict | None:
    """``subject.deadline.loss`` for a topology run with a uniform loss p (each edge's own
    ``loss:`` over it), None when no message is lost.

    Parameters
    ----------
    top : Topology
        The topology.
    loss : float
        The uniform p.
    policy : str
        ``skip``, ``rescale`` or ``hold``.

    Returns
    -------
    dict or None
        ``{policy, edges: [{from, to, p}]}``.
    """
    own = dict(getattr(top, "loss", {}) or {})
    losses = {k: float(own.get(k, loss)) for k in top.edges}
    if not any(p > 0 for p in losses.values()):
        return None
    lab = [str(x) for x in top.labels]
    return {
        "policy": policy,
        "edges": [{"from": lab[j], "to": lab[i], "p": p} for (i, j), p in losses.items()],
    }


def read_loss_section(section: Any, top: Any, where: str) -> LossSection:
    """Parse ``{policy, edges: [{from, to, p}]}`` against the topology.

    Parameters
    ----------
    section : dict
        The section.
    top : Topology
        The mode's topology.
    where : str
        Where it is written, for messages.

    Returns
    -------
    LossSection

    Raises
    ------
    InputError
        A missing or malformed field, an edge not in the topology or listed twice, a bad
        p or policy.
    """
    if not isinstance(section, dict):
        raise InputError("expected {policy, edges}", field=where)
    policy = require_policy(f"{where}.policy", section.get("policy"))
    index = {str(a): k for k, a in enumerate(top.labels)}
    edges = set(top.edges)
    losses: dict[tuple[int, int], float] = {}
    for k, e in enumerate(need(section, "edges", list, where)):
        w = f"{where}.edges[{k}]"
        if not isinstance(e, dict) or not all(isinstance(e.get(x), str) for x in ("from", "to")):
            raise InputError("expected {from, to, p}", field=w)
        key = (index.get(e["to"], -1), index.get(e["from"], -1))
        if key not in edges or key in losses:
            raise InputError(f"no edge {e['from']}->{e['to']} (or listed twice)", field=w)
        losses[key] = require_loss(f"{w}.p", e.get("p"))
    return LossSection(policy, {k: losses.get(k, 0.0) for k in top.edges})


def check_loss_work(
    nd_: int,
    n_edges: int,
    d: int,
    t_end: float,
    period: float,
    delay: int,
    policy: str,
    limit: float | None = None,
) -> None:
    """Refuse, before anything is built, a lossy ball recursion whose W² balls do not fit in
    memory or whose steps take past the limit (one line naming ``--deadline``).

    Parameters
    ----------
    nd_ : int
        N·d.
    n_edges : int
        E.
    d : int
        The state dimension.
    t_end, period : float
        T and h.
    delay : int
        D.
    policy : str
        The policy.
    limit : float, optional
        The longest work accepted (default :data:`~ntc_design.certify.deadline.MAX_SECONDS`).

    Raises
    ------
    InputError
        Past the memory or the time limit.
    """
    w = loss_width(nd_, delay, n_edges, d, policy)
    ed = n_edges * d
    need_bytes = BALL_COPIES * (w * w + 4 * ed * ed) * (BALL_BYTES + MAX_BITS / 16)
    avail = MEMORY_SHARE * available_memory()
    if need_bytes > avail:
        raise InputError(
            f"the proven moments with lossy links hold W² = {w}² balls, about "
            f"{format_bytes(need_bytes)}, more than {format_bytes(avail)}; lower the delay or "
            "use the exact moments of ntc simulate",
            field="deadline",
        )
    k_steps = deadline_steps(t_end, period)[0] + 1
    secs = k_steps * (6.0 * w**3 + 8.0 * ed * w * w) * ARB_FLOP_SECONDS
    check_work(
        secs,
        f"the proven moments on lossy links take K = {k_steps} steps of a "
        f"{w}×{w} ball recursion (N·d = {nd_}, D = {delay}, {policy}), roughly {secs:.3g} s",
        MAX_SECONDS if limit is None else limit,
        "raise the period, lower the delay or shorten T",
        field="deadline",
        option=True,
    )


@dataclass(frozen=True, eq=False)
class LossDeadlineProblem:
    """What the lossy figures depend on: the lossless problem (its one mode, gain, T, h
    and D), the edges with their p_e and noise, the policy, θ and the initial state.

    Attributes
    ----------
    base : DeadlineProblem
        One mode, with a period.
    edges : tuple of LossEdge
        In the topology's edge order.
    noises : tuple of EdgeNoise
        The same order.
    section : LossSection
        The policy and p_e.
    theta : numpy.ndarray
        θ.
    mean0, var0 : numpy.ndarray
        E x(0) and the variance of each component (zeros for a given state).
    """

    base: DeadlineProblem
    edges: tuple[LossEdge, ...]
    noises: tuple[EdgeNoise, ...]
    section: LossSection
    theta: np.ndarray
    mean0: np.ndarray
    var0: np.ndarray


def initial_parts(initial: Any, source: str) -> tuple[np.ndarray, np.ndarray]:
    """E x(0) and its components' variances from ``{x0}`` or ``{mean, variance}`` (already
    checked by :func:`~ntc_design.certify.deadline_subject.initial_moment`).

    Parameters
    ----------
    initial : dict
        ``subject.deadline.initial``.
    source : str
        Where it is written.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
    """
    key = "x0" if "x0" in initial else "mean"
    mean = np.array([number(v, f"{source}.{key}") for v in initial[key]], dtype=float)
    if key == "x0":
        return mean, np.zeros_like(mean)
    var = [number(v, f"{source}.variance") for v in initial["variance"]]
    return mean, np.array(var, dtype=float)


def loss_problem(
    base: DeadlineProblem,
    top: Any,
    noises: Sequence[EdgeNoise],
    section: dict,
    theta: np.ndarray,
    where: str,
    limit: float | None = None,
) -> LossDeadlineProblem:
    """The lossy problem from the lossless one and ``subject.deadline`` (its ``loss``).

    Parameters
    ----------
    base : DeadlineProblem
        The lossless problem (checked fields).
    top : Topology
        The one mode's topology.
    noises : sequence of EdgeNoise
        Its edges' noise (:func:`~ntc_design.certify.digital.edge_noises`).
    section : dict
        ``subject.deadline``.
    theta : numpy.ndarray
        θ.
    where : str
        Where the section is written, for messages.
    limit : float, optional
        The longest work accepted.

    Returns
    -------
    LossDeadlineProblem

    Raises
    ------
    InputError
        No period, more than one mode, a malformed ``loss``, or work past the limits.
    """
    if base.period is None:
        raise InputError("lossy links need a period (the sampled protocol)", field=f"{where}.loss")
    if len(base.modes) != 1 or base.schedule is not None:
        raise InputError("lossy links are modelled on one fixed topology", field=f"{where}.loss")
    sec = read_loss_section(section.get("loss"), top, f"{where}.loss")
    d, nd_ = top.dim, base.nd
    check_loss_work(nd_, len(top.edges), d, base.t_end, base.period, base.delay, sec.policy, limit)
    mean0, var0 = initial_parts(section["initial"], f"{where}.initial")
    return LossDeadlineProblem(
        base,
        tuple(loss_edges(top, sec.losses)),
        tuple(noises),
        sec,
        np.asarray(theta, dtype=float),
        mean0,
        var0,
    )


# -- the recursion ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _Balls:
    """The recursion's fixed matrices as balls (module docstring)."""

    m_y: arb_mat  # W×W
    m_tau: arb_mat  # W×W
    top: arb_mat  # W×Ed, P_i per edge
    ypl: arb_mat  # W×Ed, the y_e rows (hold)
    stack: arb_mat  # 2Ed×W: the r_e, then the K_e Δ_e
    var: list[arb]  # v_e
    sq: list[arb]  # w_e
    gg: list[arb_mat]  # g_e g_eᵀ
    z0: arb_mat  # E[z_0 z_0ᵀ]
    w: int


def _vec(a: np.ndarray) -> list[arb]:
    return [arb(float(v)) for v in np.ravel(a)]


def _balls(pb: LossDeadlineProblem) -> _Balls:
    base = pb.base
    (mode,) = base.modes
    d, nd_, delay, policy = mode.d, base.nd, base.delay, pb.section.policy
    ne, ed, hold = len(pb.edges), len(pb.edges) * d, pb.section.policy == "hold"
    w = loss_width(nd_, delay, ne, d, policy)
    one, lo = (delay + 1) * nd_, delay * nd_
    shift, t0 = arb_mat(w, w), arb_mat(w, w)
    for r in range(one):
        shift[r, r if r < nd_ else r - nd_] = 1
    shift[one, one] = 1
    ldelta = arb_mat(mode.lap)
    theta = _vec(pb.theta)
    r_mat, wk = arb_mat(ed, w), arb_mat(ed, w)
    top, ypl = arb_mat(w, ed), arb_mat(w, ed)
    var, sq, gg, mus = [], [], [], []
    for k, (e, nz) in enumerate(zip(pb.edges, pb.noises, strict=True)):
        i, j = e.i, e.j
        q = 1 - arb(e.p)
        if policy == "rescale":
            mu, v, m2 = arb(1), (1 - q) / q, 1 / q
        else:
            mu, v, m2 = q, q * (1 - q), q
        var.append(v)
        sq.append(m2)
        g = [arb(float(nz.sigma)) * sum(_vec(nz.absw[a]), arb(0)) for a in range(d)]
        gg.append(arb_mat([[g[a] * g[b] for b in range(d)] for a in range(d)]))
        for a in range(d):
            row = k * d + a
            b_e = sum(
                ((arb(float(e.signed[a, c])) - arb(float(e.absw[a, c]))) * theta[c])
                for c in range(d)
            )
            r_mat[row, one] = b_e
            t0[i * d + a, one] -= b_e
            top[i * d + a, row] = 1
            for c in range(d):
                s_ac, a_ac = arb(float(e.signed[a, c])), arb(float(e.absw[a, c]))
                r_mat[row, lo + j * d + c] += s_ac
                r_mat[row, lo + i * d + c] -= a_ac
                ldelta[i * d + a, j * d + c] += s_ac  # L_δ = L_B − Σ_e L_e
                ldelta[i * d + a, i * d + c] -= a_ac
            if hold:
                y = one + 1 + k * d + a
                r_mat[row, y] -= 1
                ypl[y, row] = 1
                shift[y, y] = 1
                t0[i * d + a, y] += 1
            for c in range(nd_):  # K_e Δ_e on the delayed block (mode.w: K_e S_e)
                assert mode.w is not None
                wk[row, lo + c] = mode.w[row, c]
        mus.append(mu)
    for a in range(nd_):
        for c in range(nd_):
            t0[a, lo + c] -= ldelta[a, c]
    mr, stack = arb_mat(ed, w), arb_mat(2 * ed, w)
    for row in range(ed):
        for c in range(w):
            mr[row, c] = mus[row // d] * r_mat[row, c]
            stack[row, c] = r_mat[row, c]
            stack[ed + row, c] = wk[row, c]
    return _Balls(
        shift + ypl * mr,
        t0 + top * mr,
        top,
        ypl,
        stack,
        var,
        sq,
        gg,
        _initial(pb, r_mat, w, one),
        w,
    )


def _initial(pb: LossDeadlineProblem, r_mat: arb_mat, w: int, one: int) -> arb_mat:
    """E[z_0 z_0ᵀ]: the history held at e(0), the constant 1 and, for hold, y_e at the
    noiseless a_e of the initial state (a linear map of the rest)."""
    nd_ = pb.base.nd
    theta = _vec(pb.theta)
    e = [arb(float(x)) - theta[c % len(theta)] for c, x in enumerate(pb.mean0)]
    zb = arb_mat(one + 1, one + 1)
    for a in range(one + 1):
        ea = e[a % nd_] if a < one else arb(1)
        for b in range(one + 1):
            eb = e[b % nd_] if b < one else arb(1)
            zb[a, b] = ea * eb
            if a < one and b < one and a % nd_ == b % nd_:
                zb[a, b] += arb(float(pb.var0[a % nd_]))
    if w == one + 1:
        return zb
    jm = arb_mat(w, one + 1)
    for a in range(one + 1):
        jm[a, a] = 1
    for y in range(one + 1, w):
        for c in range(one + 1):
            jm[y, c] = r_mat[y - one - 1, c]
    return jm * zb * jm.transpose()


def _upper(x: arb) -> float:
    u = float(x.upper())
    return u if u >= x.upper() else math.nextafter(u, math.inf)


def _quad_top(a: arb, b: arb, q: arb, s: arb) -> float:
    """A float at or above max over σ in [0, s] of a + bσ + qσ²: the larger end's upper
    bound when q ≥ 0 (no ball union: its radius carries only 30 bits), else the
    quadratic over the interval."""
    top = max(_upper(a), _upper(a + b * s + q * s * s))
    if q >= 0:
        return top
    sig = arb(0).union(s)
    return max(top, _upper(a + b * sig + q * sig * sig))


def _trace_prod(x: arb_mat, y: arb_mat, rows: int, cols: int) -> arb:
    """tr(X[:rows, :cols] · Y[:rows, :cols]ᵀ) = Σ X ∘ Y on that block."""
    out = arb(0)
    for a in range(rows):
        for c in range(cols):
            out += x[a, c] * y[a, c]
    return out


def loss_bound(pb: LossDeadlineProblem) -> DeadlineBound:
    """B_T and B_peak on lossy links (module docstring), from
    :data:`~ntc_design.certify.deadline.PREC` bits, doubled until the result's radius is
    below :data:`~ntc_design.certify.deadline.RADIUS_RTOL` of it (measured on G1, the radii
    stay near 2⁻¹²⁸ relative: flint's products bound the rounding, they do not wrap).

    Parameters
    ----------
    pb : LossDeadlineProblem
        The problem.

    Returns
    -------
    DeadlineBound
        With ``loss`` set.

    Raises
    ------
    InputError
        The moments overflow the balls (a diverging recursion).
    """
    with precision(BUILD_BITS):
        balls = _balls(pb)
    bits = PREC
    while True:
        out = _recursion(pb, balls, bits)
        if out.ms_error_bound - out.ms_error <= RADIUS_RTOL * abs(out.ms_error) or bits >= MAX_BITS:
            return out
        bits = min(2 * bits, MAX_BITS)


def _recursion(pb: LossDeadlineProblem, bl: _Balls, bits: int) -> DeadlineBound:
    base = pb.base
    assert base.period is not None
    h_f, nd_ = base.period, base.nd
    d = base.modes[0].d
    ne, ed = len(pb.edges), len(pb.edges) * d
    k_full, s_part = deadline_steps(base.t_end, h_f)
    old = ctx.prec
    ctx.prec = bits
    try:
        h = arb(h_f)
        z = bl.z0
        stack_t = bl.stack.transpose()
        tr0 = sum((z[a, a] for a in range(nd_)), arb(0))
        peak_hi, peak_mid, peak_t = _upper(tr0), float(tr0.mid()), 0.0
        final = tr0
        for k in range(k_full + (1 if s_part > 0 else 0)):
            c = base.gain.value(arb(k) * h)
            y = bl.stack * z * stack_t
            blk = arb_mat(ed, ed)
            tr_b = arb(0)
            for e in range(ne):
                for a in range(d):
                    for b in range(d):
                        ra, rb = e * d + a, e * d + b
                        v = (
                            bl.var[e] * y[ra, rb]
                            + bl.sq[e] * (bl.gg[e][a, b] + y[ed + ra, ed + rb]) / h
                        )
                        blk[ra, rb] = v
                        if a == b:
                            tr_b += v
            mtz = bl.m_tau * z
            a_ = sum((z[r, r] for r in range(nd_)), arb(0))
            b_ = 2 * c * sum((mtz[r, r] for r in range(nd_)), arb(0))
            q_ = c * c * (_trace_prod(mtz, bl.m_tau, nd_, bl.w) + tr_b)
            if k == k_full:  # the partial step to T
                s = arb(base.t_end) - arb(k) * h
                final = a_ + b_ * s + q_ * s * s
                peak_hi = max(peak_hi, _quad_top(a_, b_, q_, s))
                if float(final.mid()) > peak_mid:
                    peak_mid, peak_t = float(final.mid()), base.t_end
                break
            tau = c * h
            mbar = bl.m_y + tau * bl.m_tau
            place = bl.ypl + tau * bl.top
            z = mbar * z * mbar.transpose() + place * blk * place.transpose()
            peak_hi = max(peak_hi, _quad_top(a_, b_, q_, h))
            final = sum((z[r, r] for r in range(nd_)), arb(0))
            if not final.is_finite():
                break
            if float(final.mid()) > peak_mid:
                peak_mid, peak_t = float(final.mid()), (k + 1) * h_f
        if not final.is_finite() or not math.isfinite(peak_hi):
            raise InputError(
                "the second moments on lossy links overflow the balls (diverging)", field="deadline"
            )
        return DeadlineBound(
            base.t_end,
            _upper(final),
            peak_hi,
            peak_t,
            float(final.mid()),
            peak_mid,
            k_full,
            pb.section.to_dict(),
        )
    finally:
        ctx.prec = old


__all__ = [
    "LossDeadlineProblem",
    "LossSection",
    "check_loss_work",
    "initial_parts",
    "loss_bound",
    "loss_problem",
    "loss_section",
    "loss_width",
    "read_loss_section",
]
