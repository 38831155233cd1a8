"""Proven figures at the deadline: E Σ‖x_i(T) − θ‖² ≤ B_T and max over t in [0, T] of
E Σ‖x_i(t) − θ‖² ≤ B_peak, for the sampled protocol and for the continuous one, in ball
arithmetic (python-flint's arb, :data:`PREC` bits).

Sampled protocol (period h, delay D; :mod:`ntc_design.protocol.digital`). The exact
second moment Z_k = E[z_k z_kᵀ] of z_k = (e_k, …, e_{k−D}) follows

    Z_{k+1} = M_k Z_k M_kᵀ + E_0ᵀ N_k E_0,  M_k = Shift − h c_k E_0ᵀ L_B E_D,
    N_k = h c_k² (Σ_e g_e g_eᵀ + G_e Z_DD G_eᵀ),

computed with every entry a ball. Between samples an agent integrates its held input:
with K = ⌊T/h⌋ (T snapped to K·h within :data:`~ntc_design.protocol.digital.WHOLE_RTOL`)
and s = T − K h, e(kh + s) = e_k − s c_k L_B e_{k−D} + (s/√h) c_k Σ_e (g_e ξ₁ + G_e
e_{k−D} ξ₂), so E‖e(kh + s)‖² = a + b s + q s² with a = tr Z_00, b = −2 c_k tr(L_B Z_D0)
and q = c_k² tr(L_B Z_DD L_Bᵀ) + c_k² tr(Σ g gᵀ + G Z_DD Gᵀ)/h. The peak over a step is
the quadratic's maximum on [0, h] (q ≥ 0: at an end).

Continuous protocol. dS/dt = c(t) 𝒜₁(S) + c(t)² (𝒜₂(S) + Q) with 𝒜₁(S) = −(L_B S +
S L_Bᵀ), 𝒜₂(S) = Σ_e G_e S G_eᵀ, Q = Σ_e g_e g_eᵀ (:mod:`ntc_design.simulate.moments`).
Each step [t_k, t_k + Δ] (cut at switching instants and schedule knots) is a Taylor
polynomial of degree :data:`ORDER` − 1 from the float matrix Ŝ_k, its coefficients by the
ODE's recursion with c's Taylor coefficients (arb_series), plus the Lagrange remainder,
bounded by a scalar majorant recursion from an a-priori bound of ‖S‖_F on the step. The
propagated error η_k ≥ ‖S(t_k) − Ŝ_k‖₂ grows by exp(∫ω) with ω = −c λ_min(L_B + L_Bᵀ) +
c² λ_max(Σ_e G_e G_eᵀ): the homogeneous flow Φ is positive, so ‖Φ[E]‖₂ ≤ ‖E‖₂ ‖Φ[I]‖₂
and d λ_max(Φ[I])/dt ≤ ω λ_max. A trace is within N d η of the computed one.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from flint import arb, arb_mat, ctx

from ..errors import InputError, check_work
from ..protocol.digital import WHOLE_RTOL, step_modes
from ..rigorous.exact import Dyadic
from ..rigorous.floatmat import FloatMat
from .deadline_gain import GainBalls
from .digital import EdgeNoise

#: Bits of the balls' midpoints.
PREC = 128
#: Taylor coefficients of a continuous step (the remainder is the next one).
ORDER = 20
#: A continuous step is at most this long, and Δ·(c̄‖𝒜₁‖ + c̄²‖𝒜₂‖) at most STEP_SCALE.
MAX_STEP = 0.05
STEP_SCALE = 1.0
#: Longest work accepted (seconds, estimated before it starts).
MAX_SECONDS = 600.0
#: Seconds per multiply-add of an arb matrix product (measured: 42³ in 0.75 ms).
ARB_FLOP_SECONDS = 1e-8
#: Bits at which the matrices are built from floats (their products and sums exactly).
BUILD_BITS = 1024
#: The most bits of a ball's midpoint (the sampled recursion's wrapping, see sampled_bits).
MAX_BITS = 8192
#: The sampled bound's radius is at most this share of the figure.
RADIUS_RTOL = 1e-11
#: Points of a step's trace polynomial sampled for its maximum.
PEAK_POINTS = 16


# -- the problem --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class DeadlineMode:
    """One mode's matrices as balls: L_B, the stacked W_e = K_e S_e ((E·d) × Nd, so that
    G_e S G_eᵀ puts W_e S W_eᵀ in agent i's block) and Q = Σ_e g_e g_eᵀ."""

    lap: arb_mat
    w: arb_mat | None
    agents: tuple[int, ...]
    q: arb_mat
    n: int
    d: int
    lam_sym: float  # a proven lower bound on λ_min(L_B + L_Bᵀ)
    lam_noise: arb  # an upper bound on λ_max(Σ_e G_e G_eᵀ)
    norm_l: arb  # ‖L_B‖_F
    norm_w: arb  # Σ_e ‖W_e‖_F²
    norm_q: arb  # ‖Q‖_F


@dataclass(frozen=True, eq=False)
class DeadlineProblem:
    """What the figures at the deadline depend on.

    Attributes
    ----------
    modes : tuple of DeadlineMode
        One per mode (in ``names``' order).
    names : tuple of str
        The modes' names.
    schedule : tuple of (str, float) or None
        The periodic schedule (None: one mode).
    gain : GainBalls
        c(t).
    t_end : float
        T.
    period : float or None
        h (None: the continuous protocol).
    delay : int
        D.
    moment0 : numpy.ndarray
        E[e(0) e(0)ᵀ], Nd × Nd.
    """

    modes: tuple[DeadlineMode, ...]
    names: tuple[str, ...]
    schedule: tuple[tuple[str, float], ...] | None
    gain: GainBalls
    t_end: float
    period: float | None
    delay: int
    moment0: np.ndarray

    @property
    def nd(self) -> int:
        """N·d."""
        return self.modes[0].n * self.modes[0].d

    def mode_at(self, times: np.ndarray, period: float | None = None) -> np.ndarray:
        """The mode index at each time: at the samples t_k = k·h by the exact rule the
        simulator uses (:func:`~ntc_design.protocol.digital.step_modes`), else (a time
        inside a segment between switching instants) by the cumulative durations.

        Parameters
        ----------
        times : numpy.ndarray
            Times.
        period : float, optional
            h, when the times are the samples k·h.

        Returns
        -------
        numpy.ndarray
        """
        t = np.asarray(times, dtype=float)
        if self.schedule is None:
            return np.zeros(len(t), dtype=np.int64)
        if period is not None:
            return step_modes(self.schedule, t, list(self.names), period)
        ends = np.cumsum([float(dur) for _, dur in self.schedule])
        slot = np.searchsorted(ends, np.mod(t, ends[-1]), side="right")
        slot = np.minimum(slot, len(self.schedule) - 1)
        index = {name: k for k, name in enumerate(self.names)}
        return np.array([index[self.schedule[int(k)][0]] for k in slot], dtype=np.int64)


@dataclass(frozen=True)
class DeadlineBound:
    """The proven figures and the computed ones (the balls' midpoints).

    Attributes
    ----------
    t_end : float
        T.
    ms_error_bound : float
        B_T ≥ E Σ‖x_i(T) − θ‖².
    peak_bound : float
        B_peak ≥ max over [0, T] of E Σ‖x_i(t) − θ‖².
    peak_time : float
        When the computed peak is reached.
    ms_error : float
        The computed E Σ‖x_i(T) − θ‖².
    peak : float
        The computed peak.
    steps : int
        Steps taken.
    """

    t_end: float
    ms_error_bound: float
    peak_bound: float
    peak_time: float
    ms_error: float
    peak: float
    steps: int
    loss: dict | None = None  # lossy links: {policy, p_max} (ntc_design.certify.deadline_loss)

    def to_dict(self) -> dict:
        """What a certificate's ``results.deadline`` and ``--json`` state.

        Returns
        -------
        dict
            ``T``, ``ms_error_bound``, ``peak_bound``, ``peak_time`` (and ``loss`` on
            lossy links).
        """
        out: dict = {
            "T": self.t_end,
            "ms_error_bound": self.ms_error_bound,
            "peak_bound": self.peak_bound,
            "peak_time": self.peak_time,
        }
        if self.loss is not None:
            out["loss"] = dict(self.loss)
        return out


@contextmanager
def precision(bits: int) -> Iterator[None]:
    """Ball arithmetic at ``bits`` bits within the block (python-flint's precision is
    global: restored on the way out).

    Parameters
    ----------
    bits : int
        The midpoints' bits.

    Yields
    ------
    None
    """
    old = ctx.prec
    ctx.prec = bits
    try:
        yield
    finally:
        ctx.prec = old


def dyadic_balls(exact: Dyadic) -> arb_mat:
    """An exact dyadic matrix as balls of radius 0 (at :data:`BUILD_BITS` bits).

    Parameters
    ----------
    exact : Dyadic
        ``num / 2**exp``.

    Returns
    -------
    flint.arb_mat
    """
    with precision(BUILD_BITS):
        scale = arb(2) ** (-exact.exp)
        rows, cols = exact.num.shape
        out = arb_mat(rows, cols)
        for i in range(rows):
            for j in range(cols):
                out[i, j] = arb(int(exact.num[i, j])) * scale
        return out


def _ball_matrix(a: np.ndarray, rad: np.ndarray | float = 0.0) -> arb_mat:
    r = np.broadcast_to(np.asarray(rad, dtype=float), a.shape)
    return arb_mat(
        [
            [arb(float(a[i, j]), float(r[i, j])) for j in range(a.shape[1])]
            for i in range(a.shape[0])
        ]
    )


def _upper(x: arb) -> float:
    """A float at or above every point of the ball."""
    u = float(x.upper())
    return u if u >= x.upper() else math.nextafter(u, math.inf)


def _lower(x: arb) -> float:
    """A float at or below every point of the ball."""
    v = float(x.lower())
    return v if v <= x.lower() else math.nextafter(v, -math.inf)


def _frob(m: arb_mat) -> arb:
    s = arb(0)
    for v in m.entries():
        s += v * v
    return s.sqrt()


def _lam_min_sym(lap: np.ndarray, err: np.ndarray) -> float:
    """A proven lower bound on λ_min(L + Lᵀ): a float estimate, backed off until
    L + Lᵀ − λI is proven positive definite in verified floats (else Gershgorin)."""
    m = lap + lap.T
    est = float(np.linalg.eigvalsh(m)[0])
    sym = FloatMat.of(lap, err) + FloatMat.of(lap, err).T
    for back in (1e-9, 1e-6, 1e-3, 1e-1):
        lam = est - back * max(1.0, abs(est))
        if sym.__sub__(FloatMat.of(lam * np.eye(m.shape[0]))).positive_definite().holds:
            return lam
    rows = np.abs(m).sum(axis=1) - np.abs(np.diag(m)) + 2 * err.sum(axis=1) * 2
    return float(np.min(np.diag(m) - rows)) * (1 + 1e-12) - 1e-300


def deadline_mode(
    lap: np.ndarray,
    err: np.ndarray,
    edges: Sequence[EdgeNoise],
    d: int,
    exact: Dyadic | None = None,
) -> DeadlineMode:
    """One mode's balls from L_B (with an entrywise bound on its error) and its edges.

    Parameters
    ----------
    lap : numpy.ndarray
        L_B, Nd × Nd.
    err : numpy.ndarray
        An entrywise bound on |L_B − lap| (0 when exact).
    edges : sequence of EdgeNoise
        The mode's noise terms (:func:`~ntc_design.certify.digital.edge_noises`).
    d : int
        The state dimension.
    exact : Dyadic, optional
        L_B exactly (then ``lap`` and ``err`` only estimate λ_min(L_B + L_Bᵀ)).

    Returns
    -------
    DeadlineMode
    """
    with precision(BUILD_BITS):
        return _mode(lap, err, edges, d, exact)


def _mode(
    lap: np.ndarray, err: np.ndarray, edges: Sequence[EdgeNoise], d: int, exact: Dyadic | None
) -> DeadlineMode:
    nd_ = lap.shape[0]
    w_rows, g_all, agents = [], np.zeros((nd_, len(edges))), []
    for k, e in enumerate(edges):
        w = np.zeros((d, nd_))
        w[:, e.j * d : e.j * d + d] += np.eye(d)
        w[:, e.i * d : e.i * d + d] -= np.eye(d)
        w_rows.append(w)
        g_all[e.i * d : e.i * d + d, k] = e.g
        agents.append(e.i)
    # K_e = |A_ij| F and g_e = σ|A_ij|1 as balls (their float products carry rounding)
    kmats = [_ball_matrix(e.absw) * _ball_matrix(e.f) for e in edges]
    gs = [_ball_matrix(e.absw) * arb_mat([[arb(e.sigma)] for _ in range(d)]) for e in edges]
    w_ball = None
    if edges:
        blocks = [km * _ball_matrix(w) for km, w in zip(kmats, w_rows, strict=True)]
        w_ball = arb_mat(len(edges) * d, nd_)
        for k, blk in enumerate(blocks):
            for a in range(d):
                for c in range(nd_):
                    w_ball[k * d + a, c] = blk[a, c]
    q = arb_mat(nd_, nd_)
    for e, g in zip(edges, gs, strict=True):
        for a in range(d):
            for b in range(d):
                q[e.i * d + a, e.i * d + b] += g[a, 0] * g[b, 0]
    # λ_max(Σ G_e G_eᵀ) <= max over agents of Σ_{e into i} 2 ‖K_e‖_F² (S_e S_eᵀ = 2 I)
    per_agent: dict[int, arb] = {}
    for e, km in zip(edges, kmats, strict=True):
        per_agent[e.i] = per_agent.get(e.i, arb(0)) + 2 * _frob(km) ** 2
    lam_noise = max((v for v in per_agent.values()), key=lambda v: float(v.upper()), default=arb(0))
    norm_w = arb(0)
    if w_ball is not None:
        for k in range(len(edges)):
            s = arb(0)
            for a in range(d):
                for c in range(nd_):
                    s += w_ball[k * d + a, c] ** 2
            norm_w += s
    lap_ball = dyadic_balls(exact) if exact is not None else _ball_matrix(lap, err)
    return DeadlineMode(
        lap_ball,
        w_ball,
        tuple(agents),
        q,
        nd_ // d,
        d,
        _lam_min_sym(lap, err),
        lam_noise,
        _frob(lap_ball),
        norm_w,
        _frob(q),
    )


def _noise(mode: DeadlineMode, s: arb_mat) -> arb_mat:
    """Σ_e G_e S G_eᵀ (without Q)."""
    nd_, d = mode.n * mode.d, mode.d
    out = arb_mat(nd_, nd_)
    if mode.w is None:
        return out
    y = mode.w * s * mode.w.transpose()
    for k, i in enumerate(mode.agents):
        for a in range(d):
            for b in range(d):
                out[i * d + a, i * d + b] += y[k * d + a, k * d + b]
    return out


# -- the sampled protocol ---------------------------------------------------------------


def deadline_steps(t_end: float, period: float) -> tuple[int, float]:
    """K = ⌊T/h⌋ full steps and the partial step s = T − K h (0 when T is a whole
    number of periods within :data:`~ntc_design.protocol.digital.WHOLE_RTOL`).

    Parameters
    ----------
    t_end, period : float
        T and h.

    Returns
    -------
    (int, float)
    """
    k = round(t_end / period)
    if k >= 1 and abs(k * period - t_end) <= WHOLE_RTOL * t_end:
        return k, 0.0
    k = math.floor(t_end / period)
    return k, max(t_end - k * period, 0.0)


def _quad_max(a: arb, b: arb, q: arb, s: arb) -> arb:
    """An enclosure of max over σ in [0, s] of a + bσ + qσ²."""
    end = a + b * s + q * s * s
    if q >= 0:  # convex: an end
        return a.union(end)
    sig = arb(0).union(s)
    return a.union(a + b * sig + q * sig * sig)


def sampled_bits(pb: DeadlineProblem) -> int:
    """The midpoints' bits for the sampled recursion: the entrywise radii grow by about
    |M_k| per step (the wrapping of ball arithmetic), about exp(2 Σ_k h c_k ‖|L_B|‖_∞)
    over the run, so that many more bits than :data:`PREC` keep the radii negligible.

    Parameters
    ----------
    pb : DeadlineProblem
        With a period.

    Returns
    -------
    int
    """
    assert pb.period is not None
    k_full, _ = deadline_steps(pb.t_end, pb.period)
    t = np.arange(k_full + 1, dtype=float) * pb.period
    c = np.array([abs(float(pb.gain.value(arb(x)).mid())) for x in t[:: max(1, k_full // 200)]])
    row = max(
        float(np.max(np.sum(np.abs(np.array(m.lap.mid().tolist(), dtype=float)), axis=1)))
        for m in pb.modes
    )
    growth = 2.0 * pb.period * row * float(np.mean(c)) * (k_full + 1) * 2.0
    return int(min(PREC + growth / math.log(2), MAX_BITS))


def sampled_bound(pb: DeadlineProblem) -> DeadlineBound:
    """B_T and B_peak of the sampled protocol (module docstring), with the bits doubled
    until the result's radius is below :data:`RADIUS_RTOL` of it.

    Parameters
    ----------
    pb : DeadlineProblem
        With a period.

    Returns
    -------
    DeadlineBound
    """
    bits = sampled_bits(pb)
    while True:
        out = _sampled(pb, bits)
        if out.ms_error_bound - out.ms_error <= RADIUS_RTOL * abs(out.ms_error) or bits >= MAX_BITS:
            return out
        bits = min(2 * bits, MAX_BITS)


def _sampled(pb: DeadlineProblem, bits: int) -> DeadlineBound:
    assert pb.period is not None
    h_f, delay, nd_ = pb.period, pb.delay, pb.nd
    k_full, s_part = deadline_steps(pb.t_end, h_f)
    w = (delay + 1) * nd_
    old = ctx.prec
    ctx.prec = bits
    try:
        h = arb(h_f)
        e0 = arb_mat(nd_, w)
        ed = arb_mat(nd_, w)
        shift = arb_mat(w, w)
        for r in range(nd_):
            e0[r, r] = 1
            ed[r, delay * nd_ + r] = 1
            shift[r, r] = 1
        for r in range(nd_, w):
            shift[r, r - nd_] = 1
        e0t = e0.transpose()
        le = [e0t * m.lap * ed for m in pb.modes]
        m0 = _ball_matrix(np.kron(np.ones((delay + 1, delay + 1)), pb.moment0))
        z = m0
        modes = pb.mode_at(np.arange(k_full + 1, dtype=float) * h_f, h_f)
        tr0 = (e0 * z * e0t).trace()
        peak_hi, peak_mid, peak_t = _upper(tr0), float(tr0.mid()), 0.0
        final = tr0
        for k in range(k_full + (1 if s_part > 0 else 0)):
            mode, lek = pb.modes[int(modes[k])], le[int(modes[k])]
            c = pb.gain.value(arb(k) * h)
            zdd = ed * z * ed.transpose()
            nraw = mode.q + _noise(mode, zdd)
            lz = lek * z
            a = (e0 * z * e0t).trace()
            b = -2 * c * lz.trace()
            q = c * c * (lz * lek.transpose()).trace() + c * c * nraw.trace() / h
            if k == k_full:  # the partial step to T
                s = arb(pb.t_end) - arb(k) * h
                final = a + b * s + q * s * s
                top = _quad_max(a, b, q, s)
                if _upper(top) > peak_hi:
                    peak_hi = _upper(top)
                if float(final.mid()) > peak_mid:
                    peak_mid, peak_t = float(final.mid()), pb.t_end
                break
            m = shift - (c * h) * lek
            z = m * z * m.transpose() + e0t * ((h * c * c) * nraw) * e0
            top = _quad_max(a, b, q, h)
            peak_hi = max(peak_hi, _upper(top))
            final = (e0 * z * e0t).trace()
            if float(final.mid()) > peak_mid:
                peak_mid, peak_t = float(final.mid()), (k + 1) * h_f
        if not final.is_finite():
            raise InputError("the second moments overflow the balls (diverging)", field="deadline")
        return DeadlineBound(
            pb.t_end,
            _upper(final),
            peak_hi,
            peak_t,
            float(final.mid()),
            peak_mid,
            k_full,
        )
    finally:
        ctx.prec = old


# -- the continuous protocol ------------------------------------------------------------


def _cuts(pb: DeadlineProblem) -> list[float]:
    """0, T, the schedule's knots and the switching instants in between, sorted."""
    cuts = {0.0, pb.t_end, *pb.gain.knots(pb.t_end)}
    if pb.schedule is not None:
        durations = [float(d) for _, d in pb.schedule]
        period = float(sum(durations))
        ends = np.cumsum(durations)
        m = 0
        while m * period < pb.t_end:
            cuts.update(float(m * period + e) for e in ends if 0 < m * period + e < pb.t_end)
            cuts.add(m * period) if m * period > 0 else None
            m += 1
    return sorted(cuts)


def _lam_min_proven(s: np.ndarray) -> float:
    """A lower bound on λ_min(s) proven in verified floats (0 when none is found)."""
    est = float(np.linalg.eigvalsh(s)[0])
    if not est > 0:
        return 0.0
    for share in (0.999, 0.9, 0.5):
        if (
            (FloatMat.of(s) - FloatMat.of(share * est * np.eye(s.shape[0])))
            .positive_definite()
            .holds
        ):
            return share * est
    return 0.0


def _square(a: Sequence[arb]) -> list[arb]:
    return [sum((a[i] * a[j - i] for i in range(j + 1)), arb(0)) for j in range(len(a))]


def _poly_max(coefs: Sequence[arb], dt: arb) -> tuple[arb, float, float]:
    """An upper bound of max over σ in [0, Δ] of Σ_j p_j σ^j (the polynomial at
    :data:`PEAK_POINTS` + 1 points, plus half a spacing times a bound on |p'|), the largest
    sampled midpoint value and its σ."""
    m = PEAK_POINTS
    best, best_mid, at = None, -math.inf, 0.0
    for i in range(m + 1):
        s = dt * i / m
        v = arb(0)
        for c in reversed(coefs):
            v = v * s + c
        best = v if best is None else best.union(v)
        if float(v.mid()) > best_mid:
            best_mid, at = float(v.mid()), float((dt * i / m).mid())
    slope = sum((abs(coefs[j]) * j * dt ** (j - 1) for j in range(1, len(coefs))), arb(0))
    assert best is not None
    return best + slope * dt / (2 * m), best_mid, at


def continuous_work(pb: DeadlineProblem) -> float:
    """Seconds the continuous enclosure takes (about), from the steps and the sizes.

    Parameters
    ----------
    pb : DeadlineProblem
        The problem.

    Returns
    -------
    float
    """
    nd_ = pb.nd
    ed = max((m.w.nrows() if m.w is not None else 0) for m in pb.modes)
    rate = max(float((2 * m.norm_l + m.norm_w).upper()) for m in pb.modes)
    c0 = abs(float(pb.gain.value(arb(0)).mid())) + 1.0
    steps = len(_cuts(pb)) + pb.t_end * max(1.0 / MAX_STEP, c0 * rate / STEP_SCALE)
    flops = ORDER * (2 * nd_**3 + ed * nd_ * (nd_ + ed) + ORDER * nd_ * nd_)
    return steps * flops * ARB_FLOP_SECONDS


def continuous_bound(pb: DeadlineProblem) -> DeadlineBound:
    """B_T and B_peak of the continuous protocol (module docstring).

    Parameters
    ----------
    pb : DeadlineProblem
        Without a period.

    Returns
    -------
    DeadlineBound

    Raises
    ------
    InputError
        The enclosure overflows (a diverging design).
    """
    nd_ = pb.nd
    cuts = _cuts(pb)
    old = ctx.prec
    ctx.prec = PREC
    try:
        s_hat = np.array(pb.moment0, dtype=float)
        eta = 0.0  # ‖S(t_k) − Ŝ_k‖₂ <= eta (the absolute form)
        rel: float | None = None  # −r S(t_k) ⪯ S(t_k) − Ŝ_k ⪯ r S(t_k) (the relative form)
        tr0 = float(np.trace(s_hat))
        peak_hi, peak_mid, peak_t = math.nextafter(tr0, math.inf), tr0, 0.0
        steps = 0
        sqrt_nd = arb(nd_).sqrt()
        for a_f, b_f in zip(cuts[:-1], cuts[1:], strict=True):
            mode = pb.modes[int(pb.mode_at(np.array([0.5 * (a_f + b_f)]))[0])]
            lt = mode.lap.transpose()
            alpha1, alpha2 = 2 * mode.norm_l, mode.norm_w
            t = a_f
            while t < b_f:
                cbar = abs(pb.gain.value(arb(t).union(arb(min(b_f, t + MAX_STEP)))))
                rate = float((cbar * alpha1 + cbar * cbar * alpha2).upper())
                step = min(MAX_STEP, STEP_SCALE / rate if rate > 0 else MAX_STEP)
                t1 = b_f if t + step >= b_f * (1 - 1e-12) else t + step
                ta, tb = arb(t), arb(t1)
                dt = tb - ta
                ca = pb.gain.series(ta, ORDER)
                cb = _square(ca)
                s_j = [_ball_matrix(s_hat)]
                a1: list[arb_mat] = []
                a2: list[arb_mat] = []
                for j in range(ORDER - 1):
                    a1.append(-(mode.lap * s_j[j] + s_j[j] * lt))
                    a2.append(_noise(mode, s_j[j]))
                    acc = mode.q * cb[j]
                    for i in range(j + 1):
                        acc = acc + a1[j - i] * ca[i] + a2[j - i] * cb[i]
                    s_j.append(acc * (arb(1) / (j + 1)))
                # the remainder: a scalar majorant of the ORDER-th coefficient over the step
                span = ta.union(tb)
                cs = [abs(x) for x in pb.gain.series(span, ORDER)]
                cs2 = [abs(x) for x in _square(pb.gain.series(span, ORDER))]
                c_hi = cs[0]
                norm0 = _frob(_ball_matrix(s_hat))
                rho = (norm0 + dt * c_hi * c_hi * mode.norm_q) * (
                    dt * (c_hi * alpha1 + c_hi * c_hi * alpha2)
                ).exp()
                sig = [rho]
                for j in range(ORDER):
                    tot = cs2[j] * mode.norm_q
                    for i in range(j + 1):
                        tot += (cs[i] * alpha1 + cs2[i] * alpha2) * sig[j - i]
                    sig.append(tot / (j + 1))
                rem = sig[ORDER] * dt**ORDER  # ‖R‖_F on the step
                # the step's end, its midpoint kept (symmetric) and the local error
                new = s_j[-1]
                for sj in reversed(s_j[:-1]):
                    new = new * dt + sj
                mid = np.array(new.mid().tolist(), dtype=float)
                mid = 0.5 * (mid + mid.T)
                eps = _frob(new - _ball_matrix(mid)) + rem
                cc = arb(0).union(c_hi)  # c on the step, within [0, c̄]
                omega = -cc * mode.lam_sym + cc * cc * mode.lam_noise
                grow = (dt * omega).exp() if omega.upper() > 0 else arb(1)
                # the peak on the step: the trace polynomial, its remainder, the error
                coefs = [sj.trace() for sj in s_j]
                top, top_mid, at = _poly_max(coefs, dt)
                if rel is None:
                    top = top + sqrt_nd * rem + nd_ * arb(eta) * grow
                else:  # tr S <= p + √(Nd)·|R| + r·tr S
                    top = (top + sqrt_nd * rem) / (1 - arb(rel))
                if _upper(top) > peak_hi:
                    peak_hi = _upper(top)
                if top_mid > peak_mid:
                    peak_mid, peak_t = top_mid, t + at
                lam_hat = _lam_min_proven(mid)
                if rel is None:
                    eta = _upper(grow * arb(eta) + eps)
                    lam = lam_hat - eta  # Weyl
                    if lam > 0:
                        rel = _upper(arb(eta) / lam)
                else:
                    # (1 + r) S(t_{k+1}) ⪰ Ŝ_{k+1} − ε I bounds λ_min(S(t_{k+1})) below
                    lam = _lower((arb(lam_hat) - eps) / (1 + arb(rel)))
                    if lam > 0:
                        rel = _upper(arb(rel) + eps / lam)
                    else:  # back to the absolute form: ‖E‖ <= r‖S‖ + ε
                        size = _frob(_ball_matrix(mid))
                        eta = _upper((arb(rel) * size + eps) / (1 - arb(rel)))
                        rel = None
                s_hat = mid
                steps += 1
                if not (math.isfinite(eta) and math.isfinite(peak_hi) and (rel or 0) < 0.5):
                    raise InputError(
                        "the moment equations' enclosure overflows (a diverging design)",
                        field="deadline",
                    )
                t = t1
        final = float(np.trace(s_hat))
        if rel is None:
            final_hi = _upper(arb(final) + arb(nd_) * arb(eta))
        else:
            final_hi = _upper(arb(final) / (1 - arb(rel)))
        return DeadlineBound(
            pb.t_end, final_hi, max(peak_hi, final_hi), peak_t, final, peak_mid, steps
        )
    finally:
        ctx.prec = old


def check_sampled_work(
    nd_: int, t_end: float, period: float, delay: int, limit: float | None = None
) -> None:
    """Refuse, before anything starts, a sampled recursion past :data:`MAX_SECONDS`
    (about 6 products of ((D+1)·Nd)² ball matrices a step), in one line naming
    ``--deadline``.

    Parameters
    ----------
    nd_ : int
        N·d.
    t_end, period : float
        T and h.
    delay : int
        D.
    limit : float, optional
        The longest work accepted (default :data:`MAX_SECONDS`).

    Raises
    ------
    InputError
        The estimate is past the limit.
    """
    k_steps = deadline_steps(t_end, period)[0] + 1
    w = (delay + 1) * nd_
    secs = k_steps * 6.0 * w**3 * ARB_FLOP_SECONDS
    check_work(
        secs,
        f"the proven moments take K = {k_steps} steps of a {w}×{w} ball "
        f"recursion (N·d = {nd_}, D = {delay}), roughly {secs:.3g} s",
        MAX_SECONDS if limit is None else limit,
        "raise the period, lower the delay or shorten T",
        field="deadline",
        option=True,
    )


def deadline_bound(pb: DeadlineProblem) -> DeadlineBound:
    """B_T and B_peak: the sampled recursion with a period, the continuous enclosure
    without.

    Parameters
    ----------
    pb : DeadlineProblem
        The problem.

    Returns
    -------
    DeadlineBound

    Raises
    ------
    InputError
        The enclosure overflows.
    """
    return sampled_bound(pb) if pb.period is not None else continuous_bound(pb)
