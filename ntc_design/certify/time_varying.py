"""Theorems 3-4 certified for every t: the uniform bound Λ₂ of a continuously time-varying
topology, by branch and bound on t-intervals (Niu & Wu, proof of Theorem 3, after eq. (19)).

The proof of Theorem 3 needs a *uniform* bound λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ > 0 for all
t >= 0 (positive definiteness at every t is not enough: a weight fading like e^{−t} is
positive definite at every t and has no such Λ₂). With the weights periodic (or constant
after T) the infimum over t >= 0 is the infimum over one period (or over [0, T]).

On a t-interval I the certified lower bound is computed as follows (every step rigorous):

1. every weight entry is enclosed over I in Arb ball arithmetic (:mod:`ntc_design.rigorous.interval`);
2. δ(t) = C(t) + ΔC (Lemma 1, evaluated at each t) is bounded below on I: each C_i(t) =
   ½ λ_max(S_i⁻¹M_i) is at least ½ xᵀM_i x / xᵀS_i x for any fixed x (x = the top generalised
   eigenvector at the midpoint, the quotient enclosed in ball arithmetic); V1(t) is the
   C-minimising admissible set, so C(t) >= the least max over every set *possibly*
   admissible on I (in-degree-domination possibly true: an upper bound on λ_min by a
   Rayleigh quotient); the least such max is attained by a prefix in the order of the lower
   bounds (admissibility is closed under adding agents);
3. L_B + L_Bᵀ = (L + Lᵀ) + 2δ·blockdiag(B_i) with blockdiag(B_i) ⪰ 0, so λ_min is
   non-decreasing in δ and δ may be replaced by its lower bound; the entries of the
   resulting symmetric interval matrix give a midpoint M and a radius R (rounding included);
4. λ_min >= λ_min(M) − ‖R‖₂ (Weyl), with λ_min(M) proven by a shifted verified Cholesky and
   ‖R‖₂ <= the largest row sum of R (Perron).

Intervals whose bound is below (1 − ``rtol``)× the best sampled value are bisected. The
certificate records the intervals with their bounds; ``ntc verify`` recomputes every bound
from the topology's expressions. From the same enclosures come Assumption 3's
D = sup|a_kl(t)|, the proof's Λ₁ >= λ_max²(|A_ij(t)|) and p̄ >= Σ σ² Σ_l (Σ_k |a|_lk)², and
the time t₀ after which μ₂(t) = c(t)[Λ₂ − 2σ̄Λ₁N c(t)] > 0 for the given gain.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from ..errors import InputError
from ..expr.symbolic import symbol
from ..gain.conditions import GainAnalysis
from ..model import Topology
from ..model.enclosure import interval_mid_rad, sym_min_eig_lower
from ..model.paper import F_SCALE, SIGMA
from ..model.timevarying import ExpressionTopology
from ..numerics.linalg import DEF_RTOL
from ..protocol import design_topology
from ..protocol.timevarying import (
    Lemma1Structure,
    grounded_laplacian_batch,
    lemma1_batch,
    lemma1_structure,
)
from ..rigorous.exact import gamma
from ..rigorous.interval import bounds, enclose, t_ball, upper
from .format import FORMAT, VERSION, finish
from .mu2 import mu2_t0, mu2_threshold, noise_sigma_bar

_T = symbol("t")
RTOL = 0.008  # bisect until the certified Λ₂ is within 0.8 % of the sampled infimum
MAX_INTERVALS = 4000
RESULTS_KEY = "time_varying"  # where the document keeps its results
FIRST_PIECES = 32


class CertificationRefused(InputError):
    """The uniform bound of Theorems 3-4 cannot be certified; the message says why."""


@dataclass(frozen=True)
class LeafBound:
    """What one t-interval [a, b] certifies: the lower bound on λ_min(L_B + L_Bᵀ), the
    midpoint sample, the lower bound on δ and the interval's D, Λ₁ and p̄."""

    a: float
    b: float
    lower: float  # certified lower bound on λ_min(L_B + L_Bᵀ) on [a, b]
    sample: float  # λ_min at the midpoint (floating point, the design as computed)
    delta_lo: float
    D: float
    lambda1: float
    p_bar: float


class Enclosures:
    """Per t-interval enclosures of the weights and what is built from them."""

    def __init__(self, tv: ExpressionTopology, st: Lemma1Structure, margin: float, sigma: float):
        self.tv, self.st, self.margin, self.sigma = tv, st, float(margin), float(sigma)
        d = tv.dim
        self.live = [k for k, e in enumerate(tv.edges) if e.sign != 0]
        self.varying = [k for k in self.live if not tv.edges[k].weight.constant]
        self.const_w = {
            k: np.array([[float(v) for v in r] for r in tv.edges[k].weight.entries])
            for k in self.live
            if k not in self.varying
        }
        self.d = d
        t = symbol("t")
        # first and second derivatives of the varying entries (sympy, on parsed input)
        self.deriv: dict[int, tuple[list, list] | None] = {}
        self.scale_d: dict[int, tuple[sp.Expr, sp.Expr]] = {}
        for k in self.varying:
            ents = tv.edges[k].weight.entries
            try:
                d1 = [[sp.diff(x, t) for x in row] for row in ents]
                d2 = [[sp.diff(x, t, 2) for x in row] for row in d1]
                enclose(sum((x for row in d2 for x in row), sp.Integer(0)), t_ball(0.0, 1.0))
                self.deriv[k] = (d1, d2)
                w = tv.edges[k].weight
                if w.form == "scale":
                    s1 = sp.diff(w.scale, t)
                    self.scale_d[k] = (s1, sp.diff(s1, t))
            except Exception:  # noqa: BLE001 - no usable derivative: zero-order bound
                self.deriv[k] = None
        # agents whose incident edges are all constant: their C_i and in-degree-domination
        # never change (computed once, exactly as the design computes them)
        touched = set()
        for k in self.varying:
            touched |= {int(st.ii[k]), int(st.jj[k])}
        self.touched = touched
        self._static_c: dict[int, float] = {}
        self._static_idd: dict[int, bool] = {}

    def _taylor(self, a: float, b: float) -> tuple[np.ndarray, ...]:
        """Taylor data of the weights on [a, b] about m = (a + b)/2: A(m) and A'(m) as
        (mid, rad), A''(ξ) enclosed over [a, b] as (mid, rad), and R0, the full radius of
        edges without a usable derivative (their variation is bounded in zero order)."""
        tv, d = self.tv, self.d
        e_n = len(tv.edges)
        m = 0.5 * (a + b)
        tl = tv.local_time(np.array([a, m, b]))
        tm, tb = t_ball(float(tl[1]), float(tl[1])), t_ball(float(tl[0]), float(tl[2]))
        shape = (e_n, d, d)
        v_lo, v_hi = np.zeros(shape), np.zeros(shape)
        d1_lo, d1_hi = np.zeros(shape), np.zeros(shape)
        d2_lo, d2_hi = np.zeros(shape), np.zeros(shape)
        r0_lo, r0_hi = np.zeros(shape), np.zeros(shape)
        for k, wc in self.const_w.items():
            v_lo[k] = v_hi[k] = wc
        c_m: dict = {}
        c_b: dict = {}
        for k in self.varying:
            w = tv.edges[k].weight
            der = self.deriv[k]
            if w.form == "scale" and der is not None:
                # A = s(t)·W: enclose s, s', s'' once, then scale W (outward rounding)
                base = np.asarray(w.base, dtype=float)
                for (lo_a, hi_a), e, tb_ in (
                    ((v_lo, v_hi), w.scale, tm),
                    ((d1_lo, d1_hi), self.scale_d[k][0], tm),
                    ((d2_lo, d2_hi), self.scale_d[k][1], tb),
                ):
                    lo, hi = bounds(enclose(e, tb_, c_m if tb_ is tm else c_b))
                    p1, p2 = base * lo, base * hi
                    lo_a[k] = np.nextafter(np.minimum(p1, p2), -np.inf)
                    hi_a[k] = np.nextafter(np.maximum(p1, p2), np.inf)
                continue
            ents = w.entries
            for r in range(d):
                for c in range(d):
                    x = ents[r][c]
                    if not x.has(_T):
                        v_lo[k, r, c] = v_hi[k, r, c] = float(x)
                        continue
                    if der is None:
                        lo, hi = bounds(enclose(x, tb, c_b))
                        mid = 0.5 * lo + 0.5 * hi
                        v_lo[k, r, c] = v_hi[k, r, c] = mid
                        r0_lo[k, r, c], r0_hi[k, r, c] = lo - mid, hi - mid
                        continue
                    v_lo[k, r, c], v_hi[k, r, c] = bounds(enclose(x, tm, c_m))
                    d1_lo[k, r, c], d1_hi[k, r, c] = bounds(enclose(der[0][r][c], tm, c_m))
                    d2_lo[k, r, c], d2_hi[k, r, c] = bounds(enclose(der[1][r][c], tb, c_b))
        out = []
        for a_lo, a_hi in ((v_lo, v_hi), (d1_lo, d1_hi), (d2_lo, d2_hi), (r0_lo, r0_hi)):
            out += list(interval_mid_rad(a_lo, a_hi))
        return tuple(out)

    def samples(self, ts: np.ndarray) -> np.ndarray:
        """λ_min(L_B(t) + L_B(t)ᵀ) of the design as computed (floating point): an estimate.

        Parameters
        ----------
        ts : numpy.ndarray
            The times.

        Returns
        -------
        numpy.ndarray
            One value per time.
        """
        tv = self.tv
        per = max(1, int(32 * 2**20 // (8 * 2 * tv.nd * tv.nd)))
        out = []
        for chunk in np.array_split(ts, -(-len(ts) // per)):
            lb = lemma1_batch(tv, self.st, chunk, np.ones(self.d), self.margin)
            lap = lb.lap_b(self.st)
            out.append(np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0])
        return np.concatenate(out)

    def leaf(self, a: float, b: float, sample: float = math.nan) -> LeafBound:
        """The certified bounds on the t-interval [a, b] (module docstring, steps 1-4).

        Parameters
        ----------
        a, b : float
            The interval.
        sample : float, optional
            The sampled λ_min in it, recorded with the bounds.

        Returns
        -------
        LeafBound

        Raises
        ------
        CertificationRefused
            A weight is unbounded on the interval.
        """
        st, tv, d = self.st, self.tv, self.d
        tay = self._taylor(a, b)
        vm, vr, d1m, d1r, d2m, d2r, r0m, r0r = tay
        h = 0.5 * (b - a)
        mid = vm
        rad = vr + h * (np.abs(d1m) + d1r) + 0.5 * h * h * (np.abs(d2m) + d2r) + np.abs(r0m) + r0r
        rad = rad * (1 + 1e-12)
        if not (np.all(np.isfinite(rad)) and np.all(np.isfinite(mid))):
            k = int(np.argmax(~np.all(np.isfinite(rad) & np.isfinite(mid), axis=(1, 2))))
            raise CertificationRefused(
                f"weight unbounded on t ∈ [{a:.6g}, {b:.6g}] (Assumption 3 needs bounded entries)",
                field=tv.edges[k].field,
            )
        g = gamma(4 * d + 8)
        live = np.array(self.live, dtype=np.int64)
        hi = (np.abs(mid) + rad)[live] * (1 + g)  # |a_kl| <= hi
        d_sup = float(np.max(hi)) if hi.size else 0.0
        inf_norm = np.max(np.sum(hi, axis=2), axis=1) * (1 + g)
        fro = np.sqrt(np.sum(hi * hi, axis=(1, 2))) * (1 + g)
        lam1 = float(np.max(np.minimum(inf_norm, fro) ** 2)) * (1 + g) if hi.size else 0.0
        sgn = st.sign[live][:, None]
        rs_m = sgn * np.sum(mid[live], axis=2)
        rs_r = np.sum(rad[live], axis=2) + g * np.sum(np.abs(mid[live]), axis=2)
        rs_hi = np.abs(rs_m) + rs_r
        p_up = float(self.sigma**2 * np.sum(rs_hi * rs_hi)) * (1 + g)
        dl = self._delta_lower(mid, rad)
        lower = self._lambda_lower(a, b, dl, tay)
        return LeafBound(a, b, lower, sample, dl, d_sup, lam1, p_up)

    def _delta_lower(self, mid: np.ndarray, rad: np.ndarray) -> float:
        """A lower bound on δ(t) = C(t) + ΔC over an interval where every weight lies in
        mid ± rad (see the module docstring); midpoint-radius arithmetic with rounding."""
        st, d, n = self.st, self.d, self.st.n
        if not st.candidates:
            return self.margin
        g = gamma(4 * d + 2 * len(st.sign) + 8)
        absmid = st.sign[:, None, None] * mid
        inn_m = np.einsum("ie,eab->iab", st.in_inc, absmid)
        out_m = np.einsum("ie,eab->iab", st.out_inc, absmid)
        s_m = np.einsum("ie,eab->iab", st.neg_in, absmid)
        inn_r = np.einsum("ie,eab->iab", st.in_inc, rad) + g * np.einsum(
            "ie,eab->iab", st.in_inc, np.abs(mid)
        )
        out_r = np.einsum("ie,eab->iab", st.out_inc, rad) + g * np.einsum(
            "ie,eab->iab", st.out_inc, np.abs(mid)
        )
        s_r = np.einsum("ie,eab->iab", st.neg_in, rad) + g * np.einsum(
            "ie,eab->iab", st.neg_in, np.abs(mid)
        )

        def quad(x: np.ndarray, mm: np.ndarray, mr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            ax = np.abs(x)
            v = np.einsum("ka,kab,kb->k", x, mm, x)
            r = np.einsum("ka,kab,kb->k", ax, mr + g * np.abs(mm), ax) * (1 + g)
            return v - r, v + r

        cand = np.array(st.candidates)
        mm = out_m[cand] - inn_m[cand]
        mm = 0.5 * (mm + np.swapaxes(mm, 1, 2))
        ss = 0.5 * (s_m[cand] + np.swapaxes(s_m[cand], 1, 2))
        lc = np.linalg.cholesky(ss)
        z = np.linalg.solve(lc, np.swapaxes(np.linalg.solve(lc, mm), 1, 2))
        _, vec = np.linalg.eigh(0.5 * (z + np.swapaxes(z, 1, 2)))
        x = np.linalg.solve(np.swapaxes(lc, 1, 2), vec[:, :, -1:])[:, :, 0]
        n_lo, _ = quad(x, mm, out_r[cand] + inn_r[cand])
        d_lo, d_hi = quad(x, ss, s_r[cand])
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.where(n_lo >= 0, n_lo / d_hi, n_lo / d_lo)
        q = np.where(d_lo > 0, q * (1 - 4 * g) - 1e-300, -np.inf)
        c_lo = 0.5 * q
        # in-degree-domination possibly true: an upper bound on λ_min(Σ_in − Σ_out)
        xm = inn_m - out_m
        xm = 0.5 * (xm + np.swapaxes(xm, 1, 2))
        _, vec = np.linalg.eigh(xm)
        v = vec[:, :, 0]
        _, up = quad(v, xm, inn_r + out_r)
        up = up / (np.sum(v * v, axis=1) * (1 - 4 * g))
        sc = np.maximum(
            np.sqrt(np.sum((np.abs(inn_m) + inn_r) ** 2, axis=(1, 2))),
            np.sqrt(np.sum((np.abs(out_m) + out_r) ** 2, axis=(1, 2))),
        ) * (1 + g)
        possibly = up >= -DEF_RTOL * sc
        order = np.argsort(c_lo, kind="stable")
        covered = np.zeros(n, dtype=bool)
        in_v1 = np.zeros(n, dtype=bool)
        c_low = float(np.max(c_lo))
        for q_ in order:
            covered |= st.reach[q_]
            in_v1[st.candidates[q_]] = True
            if covered.all() and np.all(possibly | in_v1):
                c_low = float(c_lo[q_])
                break
        v_ = c_low + self.margin
        # the design computes δ in floating point: allow a relative 1e-12 below
        return max(v_ - 1e-12 * abs(v_) - 1e-300, 0.0) if math.isfinite(v_) else 0.0

    def _assemble(self, w: np.ndarray, dl: float, magnitude: bool = False) -> np.ndarray:
        """S = L + Lᵀ + 2δ·blockdiag(B_i) for weights ``w`` (E, d, d) (linear in w), or the
        same with every coefficient's absolute value (``magnitude``, w >= 0)."""
        st = self.st
        sg = np.ones_like(st.sign) if magnitude else st.sign
        absw = sg[:, None, None] * w
        b = np.einsum("ie,eab->iab", st.neg_in, absw)
        off = -w if magnitude else w
        lap = grounded_laplacian_batch(st, off[None], absw[None], dl, b[None])[0]
        return lap + lap.T

    def _lambda_lower(self, a: float, b: float, dl: float, tay=None) -> float:
        """Certified lower bound on λ_min(L + Lᵀ + 2δ_lo·blockdiag(B_i)) on [a, b].

        S(t) = S(m) + τ S'(m) + τ²/2 S''(ξ) with |τ| <= h = (b − a)/2. λ_min of the affine
        family S(m) + τ S'(m) is concave in τ, so its least value on [−h, h] is at τ = ±h;
        the remainder costs h²/2·‖S''‖₂ (Weyl). Every matrix carries its rounding and
        enclosure radii into the Weyl term."""
        st = self.st
        vm, vr, d1m, d1r, d2m, d2r, r0m, r0r = tay if tay is not None else self._taylor(a, b)
        h = 0.5 * (b - a)
        s0 = self._assemble(vm, dl)
        s1 = self._assemble(d1m, dl)
        mag = lambda x: self._assemble(np.abs(x), dl, magnitude=True)  # noqa: E731
        g = gamma(st.n + 8)
        err0 = mag(vr) + g * mag(np.abs(vm)) + h * (mag(d1r) + g * mag(np.abs(d1m)))
        rem = 0.5 * h * h * mag(np.abs(d2m) + d2r) + mag(np.abs(r0m) + r0r)
        rho_rem = float(np.max(np.sum(rem, axis=1))) * (1 + 1e-12) if rem.size else 0.0
        lows = [
            sym_min_eig_lower(s0 + sgn * h * s1, err0 + g * (np.abs(s0) + h * np.abs(s1)))
            for sgn in (-1.0, 1.0)
        ]
        return float(np.nextafter(min(lows) - rho_rem, -np.inf))


def domain_of(tv: ExpressionTopology) -> tuple[float, float, str]:
    """The t-domain whose infimum is the infimum over t >= 0: one period, or [0, T] with
    the constant tail, as an upper-rounded interval and in words.

    Parameters
    ----------
    tv : ExpressionTopology
        With ``period`` or ``constant_after``.

    Returns
    -------
    tuple of (float, float, str)

    Raises
    ------
    InputError
        Neither is declared.
    """

    if tv.period is not None:
        return 0.0, upper(enclose(tv.period, t_ball(0.0, 0.0))), f"one period [0, {tv.period}]"
    if tv.constant_after is not None:
        return (
            0.0,
            upper(enclose(tv.constant_after, t_ball(0.0, 0.0))),
            f"[0, {tv.constant_after}] and the constant tail",
        )
    raise InputError("the topology declares neither period nor constant_after")


def refuse_unbounded_horizon(tv: ExpressionTopology, margin: float) -> None:
    """Neither period nor constant_after: say why no uniform bound can be certified.

    Parameters
    ----------
    tv : ExpressionTopology
        A topology with weights given for every t >= 0.
    margin : float
        ΔC of Lemma 1, for the limit topology's L_B.

    Raises
    ------
    CertificationRefused
        Always, with the reason: an entry without a limit or unbounded as t → ∞, a weight
        fading to 0, a limit topology with λ_min(L_B + L_Bᵀ) = 0, or none of these found.
    """
    t = symbol("t")
    limits = []
    for e in tv.edges:
        lim = np.zeros((tv.dim, tv.dim))
        for r, row in enumerate(e.weight.entries):
            for c, x in enumerate(row):
                if not x.has(t):
                    lim[r, c] = float(x)
                    continue
                try:
                    v = sp.limit(x, t, sp.oo)
                except Exception:  # noqa: BLE001 - sympy may fail on anything
                    v = None
                if v is None or not v.is_number or v.has(sp.AccumBounds):
                    if v is not None and v.has(sp.AccumBounds):
                        continue
                    raise CertificationRefused(
                        f"entry [{r}][{c}] = {x} has no limit as t → ∞ that sympy "
                        "can find; declare period or constant_after to certify Theorems 3-4",
                        field=e.field,
                    )
                if v in (sp.oo, -sp.oo, sp.zoo):
                    raise CertificationRefused(
                        f"entry [{r}][{c}] = {x} is unbounded (→ {v} as t → ∞): "
                        "Assumption 3 (|a_kl(t)| <= D) fails",
                        field=e.field,
                    )
                lim[r, c] = float(v)
        limits.append(lim)
    fading = [
        e.field for e, lim in zip(tv.edges, limits, strict=True) if e.sign != 0 and not np.any(lim)
    ]

    w = {(e.i, e.j): lim for e, lim in zip(tv.edges, limits, strict=True) if np.any(lim)}
    lam_inf = None
    try:
        top = Topology(tv.labels, tv.dim, w)
        des = design_topology(top, np.ones(tv.dim), margin, thresholds=False)
        lb = des.grounded_laplacian()
        lb = np.asarray(lb.todense()) if hasattr(lb, "todense") else np.asarray(lb)
        lam_inf = float(np.linalg.eigvalsh(lb + lb.T)[0])
    except InputError:
        pass
    if fading or (lam_inf is not None and lam_inf <= 1e-12):
        why = (
            f"{', '.join(fading)} fade{'s' if len(fading) == 1 else ''} to 0"
            if fading
            else (f"the limit topology has λ_min(L_B + L_Bᵀ) = {lam_inf:.3g}")
        )
        raise CertificationRefused(
            f"Λ₂ = 0: {why} as t → ∞, so inf_t λ_min(L_B(t) + L_B(t)ᵀ) = 0 although it may be "
            "positive at every t; the proof of Theorems 3-4 needs a uniform Λ₂ > 0"
        )
    raise CertificationRefused(
        "the weights are neither periodic nor constant after a time: declare period or "
        "constant_after to certify the uniform bound Λ₂ of Theorems 3-4"
    )


@dataclass(frozen=True)
class TimeVaryingBound:
    """The certified uniform bound Λ₂ with the sampled infimum it is compared with,
    Assumption 3's D, the proof's Λ₁ and p̄, the intervals and the domain."""

    lambda2: float
    sampled_inf: float
    t_at_inf: float
    D: float
    lambda1: float
    p_bar: float
    leaves: tuple[LeafBound, ...]
    domain: tuple[float, float]
    domain_text: str
    seconds: float


def certify_lambda2(
    tv: ExpressionTopology,
    margin: float = 0.1,
    sigma: float = SIGMA,
    rtol: float = RTOL,
    max_intervals: int = MAX_INTERVALS,
) -> TimeVaryingBound:
    """Branch and bound for Λ₂ <= inf_t λ_min(L_B(t) + L_B(t)ᵀ) (see the module docstring).

    Parameters
    ----------
    tv : ExpressionTopology
        The topology (its sign classes already proven).
    margin : float
        ΔC of Lemma 1 (δ(t) = C(t) + ΔC).
    sigma : float
        The additive noise intensity σ_ji (for p̄).
    rtol : float
        Bisect until the certified bound is within this fraction of the sampled infimum.
    max_intervals : int
        A bound on the number of leaves.

    Returns
    -------
    TimeVaryingBound
        Λ₂ with its intervals.

    Raises
    ------
    CertificationRefused
        No period or constant_after (with the reason: Λ₂ = 0, unbounded, ...), a weight
        unbounded on the domain, or L_B + L_Bᵀ not positive definite at some t.
    """
    from threadpoolctl import threadpool_limits

    # one BLAS thread: the matrices are small (Nd <= a few hundred) and many; threads
    # only contend (1.3 s against 0.06 s of CPU per interval at Nd = 300 on a busy machine)
    with threadpool_limits(limits=1):
        return _certify_lambda2(tv, margin, sigma, rtol, max_intervals)


def _certify_lambda2(
    tv: ExpressionTopology, margin: float, sigma: float, rtol: float, max_intervals: int
) -> TimeVaryingBound:
    t_start = time.perf_counter()
    if tv.domain is None:
        refuse_unbounded_horizon(tv, margin)
    a0, b0, text = domain_of(tv)
    st = lemma1_structure(tv)
    enc = Enclosures(tv, st, margin, sigma)
    pieces = np.linspace(a0, b0, FIRST_PIECES + 1)
    pieces[-1] = b0
    heap: list[tuple[float, int, LeafBound]] = []
    best, best_t = math.inf, 0.0
    count = 0
    todo = [(float(x), float(y)) for x, y in zip(pieces[:-1], pieces[1:], strict=True)]
    while todo:
        mids = np.array([0.5 * (x + y) for x, y in todo])
        smp = enc.samples(mids)
        k = int(np.argmin(smp))
        if smp[k] < best:
            best, best_t = float(smp[k]), float(mids[k])
        if best <= 0:
            raise CertificationRefused(
                f"L_B(t) + L_B(t)ᵀ is not positive definite at t = {best_t:.6g} "
                f"(λ_min = {best:.4g}): Theorems 3-4 do not apply"
            )
        for (x, y), sm in zip(todo, smp, strict=True):
            leaf = enc.leaf(x, y, float(sm))
            heapq.heappush(heap, (leaf.lower, count, leaf))
            count += 1
        todo = []
        target = (1 - rtol) * best
        while heap and heap[0][0] < target and len(heap) + len(todo) < max_intervals:
            _, _, leaf = heapq.heappop(heap)
            m = 0.5 * (leaf.a + leaf.b)
            if not leaf.a < m < leaf.b or len(todo) >= 128:
                heapq.heappush(heap, (leaf.lower, count, leaf))
                count += 1
                break
            todo += [(leaf.a, m), (m, leaf.b)]
        if len(heap) + len(todo) >= max_intervals:
            for x, y in todo:  # evaluate what was split, then stop
                leaf = enc.leaf(x, y)
                heapq.heappush(heap, (leaf.lower, count, leaf))
                count += 1
            break
    leaves = tuple(sorted((x[2] for x in heap), key=lambda q: q.a))
    lam2 = min(q.lower for q in leaves)
    if not lam2 > 0:
        raise CertificationRefused(
            f"could not certify λ_min(L_B(t) + L_B(t)ᵀ) > 0 on {text} with {len(leaves)} "
            f"intervals (certified {lam2:.4g}, sampled infimum {best:.4g} at t = {best_t:.6g})"
        )
    return TimeVaryingBound(
        lam2,
        best,
        best_t,
        max(q.D for q in leaves),
        max(q.lambda1 for q in leaves),
        max(q.p_bar for q in leaves),
        leaves,
        (a0, b0),
        text,
        time.perf_counter() - t_start,
    )


def time_varying_document(
    tv: ExpressionTopology,
    theta,
    kind: str,
    margin: float = 0.1,
    gain: GainAnalysis | str | None = None,
    sigma: float = SIGMA,
    f: Any = F_SCALE,
) -> dict:
    """Certify the uniform bound of Theorems 3-4 and write it as a certificate mapping.

    Parameters
    ----------
    tv : ExpressionTopology
        The topology, with ``period`` or ``constant_after``.
    theta : sequence of float
        The target θ (recorded in the subject).
    kind : str
        The issuing kind's name (written into the document).
    margin : float, optional
        ΔC of Lemma 1.
    gain : GainAnalysis or str, optional
        c(t), as certify() analysed it (its expression is not parsed again), or its text.
    sigma : float, optional
        The additive noise intensity σ_ji.
    f : float or array_like, optional
        The multiplicative noise f(x) = f·x (or F x).

    Returns
    -------
    dict
        The certificate with its digest; its results under :data:`RESULTS_KEY`.

    Raises
    ------
    CertificationRefused
        The uniform bound cannot be certified (see :func:`certify_lambda2`).
    InputError
        A gain that is not an allowed expression of t, or a schedule.
    """
    bound = certify_lambda2(tv, margin, sigma)
    sigma_bar = noise_sigma_bar(f)
    kappa = mu2_threshold(bound.lambda2, bound.lambda1, sigma_bar, tv.n)
    if isinstance(gain, GainAnalysis) and gain.label is not None:
        raise InputError(
            "a schedule's t₀ of μ₂ is not derived: give c(t) as one expression", field="gain"
        )
    c = gain.expr if isinstance(gain, GainAnalysis) else gain  # a text is parsed by mu2_t0
    t0, t0_how = mu2_t0(c, kappa) if c is not None else (None, "no gain given")
    results = {
        "lambda2": bound.lambda2,
        "sampled_inf": bound.sampled_inf,
        "t_at_sampled_inf": bound.t_at_inf,
        "relative_gap": (bound.sampled_inf - bound.lambda2) / bound.sampled_inf,
        "D": bound.D,
        "Lambda1": bound.lambda1,
        "p_bar": bound.p_bar,
        "sigma_bar": sigma_bar,
        "kappa": kappa,
        "t0": t0,
        "t0_proof": t0_how,
        "domain": list(bound.domain),
        "domain_text": bound.domain_text,
        "intervals": len(bound.leaves),
        "seconds": bound.seconds,
    }
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": kind,
        "certifies": ["uniform_symmetric_part"],
        "size": int(tv.nd),
        "subject": {
            "topology": tv.to_dict(),
            "theta": [float(x) for x in np.asarray(theta, dtype=float)],
            "margin": float(margin),
            "noise": {"sigma": float(sigma), "f": np.asarray(f, dtype=float).tolist()},
            "gain": gain.expression if isinstance(gain, GainAnalysis) else gain,
        },
        "intervals": [[q.a, q.b, q.lower] for q in bound.leaves],
        "claims": [
            {"id": "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval", "kind": "lambda2"},
            {"id": "|a_kl(t)| <= D (Assumption 3)", "kind": "D"},
            {"id": "λ_max²(|A_ij(t)|) <= Λ₁ and Σσ²Σ_l(Σ_k|a_lk|)² <= p̄", "kind": "lambda1"},
            {"id": "μ₂(t) > 0 for t >= t₀", "kind": "t0"},
        ],
        "results": {RESULTS_KEY: results},
        "solver": {"name": "branch and bound, Arb ball arithmetic", "status": "ok"},
    }
    return finish(doc, "interval")


__all__ = [
    "CertificationRefused",
    "LeafBound",
    "TimeVaryingBound",
    "certify_lambda2",
    "mu2_t0",
    "mu2_threshold",
    "refuse_unbounded_horizon",
    "time_varying_document",
    "Enclosures",
    "domain_of",
    "noise_sigma_bar",
]
