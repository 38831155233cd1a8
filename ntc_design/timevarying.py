"""Continuously time-varying topologies: weights A_ij(t) written as expressions of t, and the
Lemma 1 protocol evaluated at every instant (Niu & Wu, Lemma 1 and Sec. 4.2).

:class:`ExpressionTopology` holds the weights as parsed expressions
(:mod:`ntc_design.tvfiles`), compiled once to vectorised NumPy functions. Construction
*proves* that every weight keeps one sign class (PD, PSD, ND, NSD; for a semidefinite weight
with a fixed kernel) for every t of its domain — one period, [0, constant_after], or t >= 0
— by interval arithmetic on t-intervals (:mod:`ntc_design.rigorous.interval`), and refuses the file
naming the edge and the t where the proof fails. Because the classes are fixed, so are the
edges, U, Ω_i and the positive-negative paths; what moves with t is the weights, C(t),
δ(t) = C(t) + ΔC, B_i(t), x0(t) and L_B(t).

:func:`lemma1_batch` evaluates Lemma 1 at a batch of times at once (batched Cholesky and
symmetric eigenvalues), exactly as :func:`ntc_design.design.design_topology` does at one
time: V_I = U, B_i(t) = Σ_{Ω_i}|A_ij(t)|, C(t) = max over the C-minimising V1(t) of
C_i(t), δ(t) = C(t) + ΔC (δ = ΔC when C is undefined or C + ΔC <= 0), x0 = (1 + 2/δ)θ.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import sympy as sp

from .errors import InputError, require_theta
from .expr import compile_expression, symbol
from .files import read_document
from .linalg import DEF_RTOL, Definiteness, classify, is_symmetric, pd
from .model import Label, Topology, antagonistic_in_weight, positive_negative_reachable
from .rigorous.exact import gamma, verified_float_pd
from .rigorous.interval import NotEnclosable, bounds, enclose, t_ball
from .tvfiles import ExprWeight, TimeVaryingData, parse_time_varying

SIGN_PIECES = 64  # first split of the domain for the sign-class proofs
SIGN_MIN_WIDTH = 1e-7  # relative to the domain: below this the proof gives up at that t


@dataclass(frozen=True, eq=False)
class ExprEdge:
    """One edge j -> i of an :class:`ExpressionTopology`: its weight A_ij(t) and the sign
    class proven for every t of the domain."""

    i: int  # to
    j: int  # from
    weight: ExprWeight
    cls: Definiteness
    field: str

    @property
    def sign(self) -> int:
        """sgn(A_ij(t)), the same for every t."""
        return self.cls.sign


def _fmt(x: float) -> str:
    return f"{x:.6g}"


class _SignProof:
    """Proofs that a scalar or a matrix keeps one strict sign on a domain, by bisection."""

    def __init__(self, where: Callable[[str], str], domain: tuple[float, float] | None):
        self.where = where
        self.domain = domain

    def scalar(self, e: sp.Expr, what: str) -> int:
        """+1 or −1: the sign of e on the whole domain (proved), else InputError."""
        if not e.has(symbol("t")):
            v = float(e)
            if v == 0:
                return 0
            return 1 if v > 0 else -1
        if self.domain is None:
            if e.is_positive:
                return 1
            if e.is_negative:
                return -1
            raise InputError(
                self.where(
                    f"cannot prove that {what} = {e} keeps one sign for every t >= 0; "
                    "declare period or constant_after"
                )
            )
        fn = compile_expression(e)
        a0, b0 = self.domain
        probe = fn(np.linspace(a0, b0, 257))
        sgn = 1 if probe[0] > 0 else -1
        if not np.all(np.isfinite(probe)):
            k = int(np.argmax(~np.isfinite(probe)))
            t = a0 + (b0 - a0) * k / 256
            raise InputError(self.where(f"{what} = {e} is unbounded near t = {_fmt(t)}"))
        bad = np.nonzero(sgn * probe <= 0)[0]
        if bad.size:
            t = a0 + (b0 - a0) * bad[0] / 256
            raise InputError(
                self.where(
                    f"{what} = {e} changes sign ({probe[bad[0]]:.4g} at t = {_fmt(t)}); "
                    "a weight must keep one sign class for every t"
                )
            )
        stack = [
            (a0 + (b0 - a0) * k / SIGN_PIECES, a0 + (b0 - a0) * (k + 1) / SIGN_PIECES)
            for k in range(SIGN_PIECES)
        ]
        min_w = SIGN_MIN_WIDTH * max(b0 - a0, 1.0)
        cache_free = 0
        while stack:
            a, b = stack.pop()
            try:
                lo, hi = bounds(enclose(e, t_ball(a, b)))
            except NotEnclosable as exc:
                raise InputError(self.where(f"{what} = {e}: {exc}")) from None
            if (sgn > 0 and lo > 0) or (sgn < 0 and hi < 0):
                continue
            if b - a < min_w:
                if not math.isfinite(lo) or not math.isfinite(hi):
                    raise InputError(
                        self.where(f"{what} = {e} is unbounded near t = {_fmt(0.5 * (a + b))}")
                    )
                raise InputError(
                    self.where(
                        f"cannot prove that {what} = {e} stays "
                        f"{'positive' if sgn > 0 else 'negative'} near t = {_fmt(0.5 * (a + b))} "
                        "(it may reach 0); a weight must keep one sign class for every t"
                    )
                )
            m = 0.5 * (a + b)
            stack += [(a, m), (m, b)]
            cache_free += 1
        return sgn

    def matrix(self, entries, what: str) -> int:
        """+1 (PD) or −1 (ND) on the whole domain for a symmetric matrix of expressions."""
        d = len(entries)
        if self.domain is None:
            raise InputError(
                self.where(
                    f"{what}: a weight written by rows with expressions needs a declared "
                    "period or constant_after (its definiteness is proven on that domain)"
                )
            )
        a0, b0 = self.domain
        fns = [[compile_expression(entries[k][m]) for m in range(d)] for k in range(d)]
        ts = np.linspace(a0, b0, 257)
        vals = np.stack([np.stack([fns[k][m](ts) for m in range(d)], -1) for k in range(d)], -2)
        if not np.all(np.isfinite(vals)):
            k = int(np.argmax(~np.all(np.isfinite(vals), axis=(1, 2))))
            raise InputError(self.where(f"{what} is unbounded near t = {_fmt(ts[k])}"))
        lam = np.linalg.eigvalsh(vals)
        sgn = 1 if lam[0, 0] > 0 else -1
        ext = lam[:, 0] if sgn > 0 else -lam[:, -1]
        if np.any(ext <= 0):
            k = int(np.argmax(ext <= 0))
            raise InputError(
                self.where(
                    f"{what} is not {'positive' if sgn > 0 else 'negative'} definite at "
                    f"t = {_fmt(ts[k])} (eigenvalues {lam[k, 0]:.4g} .. {lam[k, -1]:.4g}); a "
                    "weight written by rows must stay definite (one sign class) for every t"
                )
            )
        stack = [
            (a0 + (b0 - a0) * k / SIGN_PIECES, a0 + (b0 - a0) * (k + 1) / SIGN_PIECES)
            for k in range(SIGN_PIECES)
        ]
        min_w = SIGN_MIN_WIDTH * max(b0 - a0, 1.0)
        while stack:
            a, b = stack.pop()
            mid, rad = enclose_matrix(entries, a, b)
            if not np.all(np.isfinite(rad)):
                if b - a < min_w:
                    raise InputError(self.where(f"{what} is unbounded near t = {_fmt(a)}"))
            else:
                lam_lo = sym_min_eig_lower(sgn * mid, rad)
                if lam_lo > 0:
                    continue
                if b - a < min_w:
                    raise InputError(
                        self.where(
                            f"cannot prove {what} stays definite near t = {_fmt(0.5 * (a + b))}"
                        )
                    )
            m = 0.5 * (a + b)
            stack += [(a, m), (m, b)]
        return sgn


def enclose_matrix(entries, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """A rigorous entrywise enclosure of a matrix of expressions over a t-interval.

    Parameters
    ----------
    entries : sequence of sequences of sympy.Expr
        The d×d entries of A(t).
    a, b : float
        The interval [a, b] of t.

    Returns
    -------
    tuple of numpy.ndarray
        (mid, rad) with |A(t) − mid| <= rad entrywise for every t in [a, b] (rad infinite
        where an entry is unbounded).

    Raises
    ------
    NotEnclosable
        An entry uses a function without an interval rule.
    """
    tb = t_ball(a, b)
    cache: dict = {}
    d = len(entries)
    lo = np.empty((d, d))
    hi = np.empty((d, d))
    for k in range(d):
        for m in range(d):
            lo[k, m], hi[k, m] = bounds(enclose(entries[k][m], tb, cache))
    return interval_mid_rad(lo, hi)


def interval_mid_rad(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint and a radius (rounded up) of entrywise intervals [lo, hi]."""
    with np.errstate(invalid="ignore", over="ignore"):
        mid = 0.5 * lo + 0.5 * hi
        rad = np.maximum(hi - mid, mid - lo)
        rad = np.nextafter(rad, np.inf)
    bad = ~np.isfinite(lo) | ~np.isfinite(hi)
    mid = np.where(bad, 0.0, mid)
    rad = np.where(bad, np.inf, rad)
    return mid, rad


U_ROUND = 2.0**-53


def sym_min_eig_lower(mid: np.ndarray, rad: np.ndarray) -> float:
    """A rigorous lower bound on λ_min(M) for every symmetric M with |M − mid| <= rad.

    Weyl: λ_min(M) >= λ_min(mid) − ‖M − mid‖₂ >= λ_min(mid) − ρ(rad) and ρ(rad) <= the
    largest row sum of rad (Perron). λ_min(mid) is computed in floating point and then
    proven: mid − s·I ≻ 0 for s = λ̃ − η by a Cholesky factorisation whose shift covers
    every rounding error (:func:`ntc_design.rigorous.exact.verified_float_pd`, Rump 2006).

    Parameters
    ----------
    mid : numpy.ndarray
        The midpoint matrix (symmetrised here).
    rad : numpy.ndarray
        The entrywise radius, >= 0.

    Returns
    -------
    float
        The bound (−inf when nothing could be proven or rad is not finite).
    """

    n = mid.shape[0]
    ms = 0.5 * (mid + mid.T)
    if not np.all(np.isfinite(rad)):
        return -math.inf
    asym = 0.5 * np.abs(mid - mid.T)
    rho = float(np.max(np.sum(rad + asym, axis=1))) * (1 + 2 * n * U_ROUND)
    if n == 1:
        return float(np.nextafter(ms[0, 0], -np.inf)) - rho
    lam = float(np.linalg.eigvalsh(ms)[0])
    scale = float(np.max(np.abs(np.diag(ms)))) + float(np.max(np.sum(np.abs(ms), axis=1)))
    eta = 8 * gamma(n + 2) * scale + 1e-300
    for _ in range(8):
        s = lam - eta
        shifted = ms - s * np.eye(n)
        err = gamma(2) * np.abs(shifted)
        if verified_float_pd(shifted, err).holds:
            return float(np.nextafter(s - rho, -np.inf))
        eta *= 8
    return -math.inf


@dataclass(frozen=True, eq=False)
class ExpressionTopology:
    """A topology whose weights are expressions of t, each of one sign class for every t.

    ``domain`` is where the weights are given and the proofs hold: one period
    ``[0, period]`` (the weights repeat), ``[0, constant_after]`` (A(t) = A(T) afterwards)
    or ``None`` for every t >= 0."""

    labels: tuple[Label, ...]
    dim: int
    edges: tuple[ExprEdge, ...]
    period: sp.Expr | None = None
    constant_after: sp.Expr | None = None
    name: str | None = None
    source: str | None = None
    document: dict = field(default_factory=dict, repr=False)

    # -- construction --------------------------------------------------------------
    @classmethod
    def from_data(cls, data: TimeVaryingData) -> ExpressionTopology:
        """Build from a parsed file, proving each weight's sign class on the domain.

        Parameters
        ----------
        data : ntc_design.tvfiles.TimeVaryingData
            As :func:`ntc_design.tvfiles.parse_time_varying` returns it.

        Returns
        -------
        ExpressionTopology
            The topology with every edge's proven class.

        Raises
        ------
        InputError
            A weight whose class cannot be proven fixed (naming the edge and the t), or a
            weight that is not periodic with the declared period.
        """
        index = {str(a): k for k, a in enumerate(data.labels)}
        dom = None
        if data.period is not None:
            dom = (0.0, _upper(data.period))
        elif data.constant_after is not None:
            dom = (0.0, _upper(data.constant_after))
        edges = []
        for e in data.edges:
            i, j = index[str(e.target)], index[str(e.source)]

            def where(msg: str, f: str = e.field) -> str:
                return f"{data.source}: {f}: {msg}" if data.source else f"{f}: {msg}"

            cls_ = _prove_class(e.weight, data.dim, _SignProof(where, dom), where)
            if data.period is not None and not e.weight.constant:
                _check_periodic(e.weight, data.period, where)
            edges.append(ExprEdge(i, j, e.weight, cls_, e.field))
        return cls(
            data.labels,
            data.dim,
            tuple(edges),
            data.period,
            data.constant_after,
            data.name,
            data.source,
            data.document,
        )

    # -- basic accessors ---------------------------------------------------------------
    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)

    @property
    def nd(self) -> int:
        """N·d, the size of the stacked state."""
        return self.n * self.dim

    @property
    def constant(self) -> bool:
        """Every weight is a constant expression."""
        return all(e.weight.constant for e in self.edges)

    @property
    def domain(self) -> tuple[float, float] | None:
        """[0, period], [0, constant_after], or None for every t >= 0."""
        if self.period is not None:
            return (0.0, float(self.period))
        if self.constant_after is not None:
            return (0.0, float(self.constant_after))
        return None

    @cached_property
    def _compiled(self) -> list[Callable[[np.ndarray], np.ndarray]]:
        t = symbol("t")
        out = []
        for e in self.edges:
            w = e.weight
            if w.form == "scale":
                s = compile_expression(w.scale)
                base = np.asarray(w.base, dtype=float)
                out.append(lambda ts, s=s, base=base: s(ts)[:, None, None] * base)
            elif w.constant:
                m = np.array([[float(v) for v in r] for r in w.entries])
                out.append(lambda ts, m=m: np.broadcast_to(m, (ts.size, *m.shape)).copy())
            else:
                d = self.dim
                fns = {
                    (k, m): compile_expression(w.entries[k][m])
                    for k in range(d)
                    for m in range(d)
                    if w.entries[k][m].has(t)
                }
                const = np.array([[0.0 if v.has(t) else float(v) for v in r] for r in w.entries])

                def f(ts, fns=fns, const=const):
                    out_ = np.broadcast_to(const, (ts.size, *const.shape)).copy()
                    for (k, m), fn in fns.items():
                        out_[:, k, m] = fn(ts)
                    return out_

                out.append(f)
        return out

    def local_time(self, ts: np.ndarray) -> np.ndarray:
        """The time at which the expressions are evaluated.

        Parameters
        ----------
        ts : numpy.ndarray
            Times.

        Returns
        -------
        numpy.ndarray
            t, or min(t, constant_after), flattened.
        """
        ts = np.asarray(ts, dtype=float).reshape(-1)
        if self.constant_after is not None:
            return np.minimum(ts, float(self.constant_after))
        return ts

    def weights_at(self, ts: Sequence[float] | np.ndarray) -> np.ndarray:
        """A_ij(t) for every edge at every time.

        Parameters
        ----------
        ts : sequence of float or numpy.ndarray
            K times.

        Returns
        -------
        numpy.ndarray
            Shape (K, E, d, d), edges in :attr:`edges` order.

        Raises
        ------
        InputError
            A weight is not finite at one of the times.
        """
        tl = self.local_time(ts)
        if not self.edges:
            return np.zeros((tl.size, 0, self.dim, self.dim))
        w = np.stack([f(tl) for f in self._compiled], axis=1)
        if not np.all(np.isfinite(w)):
            k = int(np.argmax(~np.all(np.isfinite(w), axis=(1, 2, 3))))
            raise InputError(
                f"{self.source or 'topology'}: a weight is not finite at t = {tl[k]:.6g}"
            )
        return w

    def at(self, t: float) -> Topology:
        """The topology frozen at time t.

        Parameters
        ----------
        t : float
            The time.

        Returns
        -------
        Topology
            The weights A_ij(t) as a :class:`~ntc_design.model.Topology`.
        """
        w = self.weights_at([t])[0]
        weights = {(e.i, e.j): w[k] for k, e in enumerate(self.edges)}
        fields = {(e.i, e.j): e.field for e in self.edges}
        return Topology(self.labels, self.dim, weights, self.name, self.source, fields)

    def fixed(self) -> Topology:
        """The fixed topology of constant weights.

        Returns
        -------
        Topology
            The same network as a :class:`~ntc_design.model.Topology`.

        Raises
        ------
        ValueError
            A weight depends on t (see :attr:`constant`).
        """
        if not self.constant:
            raise ValueError("the weights depend on t")
        weights = {
            (e.i, e.j): np.array([[float(v) for v in r] for r in e.weight.entries])
            for e in self.edges
        }
        fields = {(e.i, e.j): e.field for e in self.edges}
        return Topology(self.labels, self.dim, weights, self.name, self.source, fields)

    @cached_property
    def structure(self) -> Topology:
        """The frozen topology at a reference time: its edges, signs, Ω_i, U and
        positive-negative paths hold at every t (the classes are proven fixed)."""
        ref = self.domain[1] / 2 if self.domain else 0.5
        top = self.at(ref)
        for _k, e in enumerate(self.edges):
            got = top.classes[(e.i, e.j)]
            if got is not e.cls:
                raise InputError(
                    f"{e.field}: classified {got.value} at t = {ref:.6g}, proven {e.cls.value}"
                )
        return top

    def to_dict(self) -> dict:
        """The topology in its file form.

        Returns
        -------
        dict
            A copy of the mapping as read.
        """
        return dict(self.document)


def _upper(e: sp.Expr) -> float:
    from flint import arb  # noqa: F401 - enclose needs flint

    return bounds(enclose(e, t_ball(0.0, 0.0)))[1]


def _check_periodic(w: ExprWeight, period: sp.Expr, where: Callable[[str], str]) -> None:
    """A(t + P) = A(t) symbolically (sympy), else the file is refused."""
    t = symbol("t")
    exprs = [w.scale] if w.form == "scale" else [e for r in w.entries for e in r]
    for e in exprs:
        if not e.has(t):
            continue
        diff = e.subs(t, t + period) - e
        ok = diff == 0 or sp.simplify(sp.expand_trig(diff)) == 0
        if not ok:
            fn = compile_expression(diff)
            ts = np.linspace(0, float(period), 33)
            v = fn(ts)
            k = int(np.argmax(np.abs(v)))
            raise InputError(
                where(
                    f"{e} is not periodic with period {period} (A(t+P) − A(t) = {v[k]:.4g} at "
                    f"t = {ts[k]:.4g})"
                    if np.max(np.abs(v)) > 1e-12
                    else f"cannot prove that {e} has period {period}"
                )
            )


def _prove_class(
    w: ExprWeight, d: int, proof: _SignProof, where: Callable[[str], str]
) -> Definiteness:
    """The sign class of a weight, proven for every t of the domain."""
    t = symbol("t")
    if w.constant:
        m = np.array([[float(v) for v in r] for r in w.entries])
        if not is_symmetric(m):
            raise InputError(where("weight is not symmetric (A_ij must equal A_ijᵀ)"))
        c = classify(m)
        if c is Definiteness.INDEFINITE:
            raise InputError(
                where("weight is indefinite; it must be positive or negative (semi)definite")
            )
        return c
    if w.form == "scale":
        base = np.asarray(w.base, dtype=float)
        if not is_symmetric(base):
            raise InputError(where("matrix is not symmetric"))
        c = classify(base)
        if c is Definiteness.INDEFINITE:
            raise InputError(where("matrix is indefinite"))
        if c is Definiteness.ZERO:
            return c
        s = proof.scalar(w.scale, "scale")
        if s == 0:
            return Definiteness.ZERO
        flip = {
            Definiteness.PD: Definiteness.ND,
            Definiteness.PSD: Definiteness.NSD,
            Definiteness.ND: Definiteness.PD,
            Definiteness.NSD: Definiteness.PSD,
        }
        return c if s > 0 else flip[c]
    if w.form == "diag":
        signs = [proof.scalar(w.entries[k][k], f"diag[{k}]") for k in range(d)]
        nz = {s for s in signs if s != 0}
        if len(nz) > 1:
            raise InputError(where("diag has entries of both signs: the weight is indefinite"))
        if not nz:
            return Definiteness.ZERO
        s = nz.pop()
        full = all(x != 0 for x in signs)
        if s > 0:
            return Definiteness.PD if full else Definiteness.PSD
        return Definiteness.ND if full else Definiteness.NSD
    # rows with expressions: symmetric identically, definite for every t
    for k in range(d):
        for m in range(k + 1, d):
            a, b = w.entries[k][m], w.entries[m][k]
            if a != b and sp.simplify(a - b) != 0:
                raise InputError(
                    where(f"weight is not symmetric: entry [{k}][{m}] = {a} but [{m}][{k}] = {b}")
                )
    del t
    s = proof.matrix(w.entries, "weight")
    return Definiteness.PD if s > 0 else Definiteness.ND


# ----------------------------------------------------------------- Lemma 1 at every t


@dataclass(frozen=True)
class Lemma1Structure:
    """What Lemma 1 needs that does not move with t (the sign classes are fixed)."""

    n: int
    d: int
    ii: np.ndarray  # (E,) target of each edge
    jj: np.ndarray  # (E,) source
    sign: np.ndarray  # (E,) sgn A_ij
    informed: tuple[int, ...]  # V_I = U
    candidates: tuple[int, ...]  # agents whose Σ_Ω|A_ij| ≻ 0 (may be in V1)
    reach: np.ndarray  # (n_cand, N) bool: reached from the candidate by +- paths
    neg_in: np.ndarray  # (N, E) 1 where edge e is antagonistic into i
    in_inc: np.ndarray  # (N, E) 1 where edge e enters i
    out_inc: np.ndarray  # (N, E) 1 where edge e leaves i


def lemma1_structure(tv: ExpressionTopology) -> Lemma1Structure:
    """What Lemma 1 needs that does not move with t: incidence arrays, U, the V1
    candidates and the positive-negative reachability from each.

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.

    Returns
    -------
    Lemma1Structure
        The fixed structure.
    """
    top = tv.structure
    n, d = tv.n, tv.dim
    e_n = len(tv.edges)
    ii = np.array([e.i for e in tv.edges], dtype=np.int64)
    jj = np.array([e.j for e in tv.edges], dtype=np.int64)
    sign = np.array([e.sign for e in tv.edges], dtype=float)
    in_inc = np.zeros((n, e_n))
    out_inc = np.zeros((n, e_n))
    neg_in = np.zeros((n, e_n))
    for k in range(e_n):
        if sign[k] != 0:
            in_inc[ii[k], k] = 1
            out_inc[jj[k], k] = 1
            if sign[k] < 0:
                neg_in[ii[k], k] = 1

    cands = tuple(i for i in range(n) if pd(antagonistic_in_weight(top, i)))
    reach = np.zeros((len(cands), n), dtype=bool)
    for k, c in enumerate(cands):
        for a in positive_negative_reachable(top, [c]):
            reach[k, a] = True
    return Lemma1Structure(
        n, d, ii, jj, sign, tuple(top.antagonised), cands, reach, neg_in, in_inc, out_inc
    )


@dataclass(frozen=True)
class Lemma1Batch:
    """Lemma 1 at K times. Arrays are indexed by time first."""

    t: np.ndarray  # (K,)
    C: np.ndarray  # (K,) NaN where undefined (no candidate)
    C_i: np.ndarray  # (K, n_cand)
    delta: np.ndarray  # (K,)
    k1: np.ndarray  # (K,)
    x0: np.ndarray  # (K, d)
    B: np.ndarray  # (K, N, d, d) B_i (zero for naive agents)
    abs_w: np.ndarray  # (K, E, d, d) |A_ij(t)|
    weights: np.ndarray  # (K, E, d, d) A_ij(t)
    assumption_holds: np.ndarray  # (K,) bool
    v1_size: np.ndarray  # (K,)

    def lap_b(self, st: Lemma1Structure) -> np.ndarray:
        """L_B(t) = L(t) + δ(t)·blockdiag(B_i(t)) (Niu & Wu, eq. (8)) at each time.

        Parameters
        ----------
        st : Lemma1Structure
            The structure this batch was computed with.

        Returns
        -------
        numpy.ndarray
            Shape (K, Nd, Nd).
        """
        return grounded_laplacian_batch(st, self.weights, self.abs_w, self.delta, self.B)

    def input_vector(self) -> np.ndarray:
        """The drift from the external signal, u(t) = (Δ(t)⊗I) B(t) x0(t), at each time.

        Returns
        -------
        numpy.ndarray
            Shape (K, Nd).
        """
        u = np.einsum("knab,kb->kna", self.B, self.x0) * self.delta[:, None, None]
        return u.reshape(u.shape[0], -1)


def grounded_laplacian_batch(
    st: Lemma1Structure,
    weights: np.ndarray,
    abs_w: np.ndarray,
    delta: np.ndarray | float,
    b: np.ndarray,
) -> np.ndarray:
    """``L_B = L + δ·blockdiag(B_i)`` (Niu & Wu, eq. (8)) for a batch of times.

    Parameters
    ----------
    st : Lemma1Structure
        Edge incidence and signs.
    weights : numpy.ndarray
        A_ij(t), shape (K, E, d, d).
    abs_w : numpy.ndarray
        |A_ij(t)|, shape (K, E, d, d).
    delta : numpy.ndarray or float
        δ(t), shape (K,), or one δ.
    b : numpy.ndarray
        B_i(t), shape (K, N, d, d) (zero for naive agents).

    Returns
    -------
    numpy.ndarray
        Shape (K, Nd, Nd): blocks L_ij = −A_ij, L_ii = Σ|A_ik| + δ B_i.
    """
    k_n = weights.shape[0]
    n, d = st.n, st.d
    lap = np.zeros((k_n, n, n, d, d))
    live = st.sign != 0
    np.add.at(lap, (slice(None), st.ii[live], st.jj[live]), -weights[:, live])
    diag = np.einsum("ie,keab->kiab", st.in_inc, abs_w)
    diag = diag + np.asarray(delta, dtype=float).reshape(-1, 1, 1, 1) * b
    ar = np.arange(n)
    lap[:, ar, ar] += diag
    return lap.transpose(0, 1, 3, 2, 4).reshape(k_n, n * d, n * d)


def lemma1_batch(
    tv: ExpressionTopology,
    st: Lemma1Structure,
    ts: Sequence[float] | np.ndarray,
    theta: np.ndarray,
    margin: float,
) -> Lemma1Batch:
    """Lemma 1 at every time of ``ts`` (vectorised over the batch).

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.
    st : Lemma1Structure
        ``lemma1_structure(tv)``.
    ts : sequence of float or numpy.ndarray
        K times.
    theta : numpy.ndarray
        The target θ (d numbers).
    margin : float
        ΔC > 0: δ(t) = C(t) + ΔC.

    Returns
    -------
    Lemma1Batch
        C(t), δ(t), k1(t), x0(t), B_i(t) and whether Assumption 2 holds at each time.

    Raises
    ------
    InputError
        A weight is not finite at one of the times.
    """
    ts = np.asarray(ts, dtype=float).reshape(-1)
    k_n, n, d = ts.size, st.n, st.d
    w = tv.weights_at(ts)
    abs_w = st.sign[None, :, None, None] * w
    b = np.einsum("ie,keab->kiab", st.neg_in, abs_w)  # B_i = Σ_Ω|A_ij|
    inn = np.einsum("ie,keab->kiab", st.in_inc, abs_w)
    out = np.einsum("ie,keab->kiab", st.out_inc, abs_w)
    nc = len(st.candidates)
    holds = np.ones(k_n, dtype=bool)
    v1_size = np.zeros(k_n, dtype=np.int64)
    if nc:
        cand = np.array(st.candidates)
        s = 0.5 * (b[:, cand] + np.swapaxes(b[:, cand], -1, -2))
        m = out[:, cand] - inn[:, cand]
        m = 0.5 * (m + np.swapaxes(m, -1, -2))
        lc = np.linalg.cholesky(s)
        y = np.linalg.solve(lc, m)
        z = np.linalg.solve(lc, np.swapaxes(y, -1, -2))
        c_i = 0.5 * np.linalg.eigvalsh(0.5 * (z + np.swapaxes(z, -1, -2)))[..., -1]
        # in-degree-domination of every agent at every t (Definition 4, model tolerance)
        diff = inn - out
        lam = np.linalg.eigvalsh(0.5 * (diff + np.swapaxes(diff, -1, -2)))[..., 0]
        scale = np.maximum(
            np.linalg.norm(inn, 2, axis=(-2, -1)), np.linalg.norm(out, 2, axis=(-2, -1))
        )
        idd = (scale == 0) | (lam >= -DEF_RTOL * scale)
        c = np.empty(k_n)
        order = np.argsort(c_i, axis=1, kind="stable")
        for k in range(k_n):
            covered = np.zeros(n, dtype=bool)
            in_v1 = np.zeros(n, dtype=bool)
            found = None
            for r, q in enumerate(order[k]):
                covered |= st.reach[q]
                in_v1[cand[q]] = True
                nxt = order[k][r + 1] if r + 1 < nc else None
                if nxt is not None and c_i[k, nxt] == c_i[k, q]:
                    continue  # a level includes every tie (as design.assumption2)
                if covered.all() and np.all(idd[k] | in_v1):
                    found = c_i[k, q]
                    v1_size[k] = int(in_v1.sum())
                    break
            if found is None:
                holds[k] = False
                found = float(np.max(c_i[k]))
            c[k] = found
        dl = np.where(c + margin > 0, c + margin, margin)
    else:
        c_i = np.zeros((k_n, 0))
        c = np.full(k_n, np.nan)
        holds[:] = False
        dl = np.full(k_n, float(margin))
    k1 = 1.0 + 2.0 / dl
    x0 = k1[:, None] * np.asarray(theta, dtype=float)[None, :]
    bfull = np.zeros((k_n, n, d, d))
    inf = list(st.informed)
    bfull[:, inf] = b[:, inf]
    return Lemma1Batch(ts, c, c_i, dl, k1, x0, bfull, abs_w, w, holds, v1_size)


DESIGN_SAMPLES = 721


@dataclass(frozen=True, eq=False)
class TimeVaryingDesign:
    """Lemma 1 at every instant for an :class:`ExpressionTopology` (evaluated on demand by
    :func:`lemma1_batch`); ``to_dict`` summarises it over a sample of its domain."""

    topology: ExpressionTopology
    theta: np.ndarray
    margin: float

    def __post_init__(self) -> None:
        # θ checked up front (its length against d), before any certificate or run
        object.__setattr__(self, "theta", require_theta(self.theta, self.topology.dim))

    @cached_property
    def structure(self) -> Lemma1Structure:
        """The topology's :class:`Lemma1Structure` (computed once)."""
        return lemma1_structure(self.topology)

    def at(self, ts: Sequence[float] | np.ndarray) -> Lemma1Batch:
        """Lemma 1 at the times ``ts``; see :func:`lemma1_batch`.

        Parameters
        ----------
        ts : sequence of float or numpy.ndarray
            K times.

        Returns
        -------
        Lemma1Batch
            The design at each time.
        """
        return lemma1_batch(self.topology, self.structure, ts, self.theta, self.margin)

    def sample_times(self, k: int = DESIGN_SAMPLES) -> np.ndarray:
        """Evenly spaced times over the domain ([0, 10] when it is every t >= 0).

        Parameters
        ----------
        k : int, optional
            How many.

        Returns
        -------
        numpy.ndarray
            The times, ends included.
        """
        a, b = self.topology.domain or (0.0, 10.0)
        return np.linspace(a, b, k)

    def to_dict(self) -> dict:
        """The design summarised over a sample of the domain, as a JSON-ready mapping.

        Returns
        -------
        dict
            Ranges of C, δ, k1, x0 and λ_min(L_B + L_Bᵀ), whether Assumption 2 holds at
            every sample (and the first times it fails), the identity residual of
            eq. (11) and the edges with their classes.
        """
        tv, st = self.topology, self.structure
        # fewer samples and bounded batches for large networks (L_B is K×Nd×Nd)
        ts = self.sample_times(DESIGN_SAMPLES if tv.nd <= 100 else 181)
        per = max(1, int(64 * 2**20 // (8 * 2 * tv.n * tv.n * tv.dim * tv.dim)))
        parts = []
        one = np.tile(self.theta, tv.n)
        for chunk in np.array_split(ts, -(-ts.size // per)):
            bb = self.at(chunk)
            lap = bb.lap_b(st)
            u = bb.input_vector()
            res_ = -np.einsum("kij,j->ki", lap, one) + u
            scale = np.max(np.abs(lap).sum(axis=2), axis=1) * np.max(np.abs(self.theta))
            sym_ = np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0]
            parts.append((bb, np.max(np.abs(res_), axis=1) / np.maximum(scale, 1e-300), sym_))
        b = Lemma1Batch(
            ts,
            *(
                np.concatenate([getattr(p[0], f) for p in parts])
                for f in ("C", "C_i", "delta", "k1", "x0")
            ),
            parts[0][0].B[:1],
            parts[0][0].abs_w[:1],
            parts[0][0].weights[:1],
            np.concatenate([p[0].assumption_holds for p in parts]),
            np.concatenate([p[0].v1_size for p in parts]),
        )
        res = np.concatenate([p[1] for p in parts])
        sym = np.concatenate([p[2] for p in parts])
        lab = tv.labels

        def rng(x: np.ndarray) -> dict:
            return {"min": float(np.nanmin(x)), "max": float(np.nanmax(x))}

        return {
            "topology": tv.name,
            "time_varying": True,
            "domain": list(tv.domain) if tv.domain else None,
            "period": str(tv.period) if tv.period is not None else None,
            "constant_after": str(tv.constant_after) if tv.constant_after is not None else None,
            "samples": int(ts.size),
            "theta": self.theta.tolist(),
            "margin": self.margin,
            "informed": [lab[i] for i in st.informed],
            "candidates_V1": [lab[i] for i in st.candidates],
            "C": rng(b.C) if st.candidates else None,
            "delta": rng(b.delta),
            "k1": rng(b.k1),
            "x0": {"min": b.x0.min(axis=0).tolist(), "max": b.x0.max(axis=0).tolist()},
            "assumption_holds": bool(np.all(b.assumption_holds)),
            "assumption_fails_at": [float(t) for t in ts[~b.assumption_holds][:5]],
            "identity_residual": float(np.max(res)),
            "sym_min_eig": rng(sym),
            "edges": [
                {
                    "from": lab[e.j],
                    "to": lab[e.i],
                    "class": e.cls.value,
                    "constant": e.weight.constant,
                }
                for e in tv.edges
            ],
        }


def load_time_varying(path: str | Path) -> ExpressionTopology:
    """Read a time-varying topology file.

    Parameters
    ----------
    path : str or pathlib.Path
        A YAML or JSON file with weights as expressions of t.

    Returns
    -------
    ExpressionTopology
        The topology with every edge's proven sign class.

    Raises
    ------
    InputError
        The file cannot be read, is malformed, or a weight's class cannot be proven.
    """

    return ExpressionTopology.from_data(parse_time_varying(read_document(path), str(path)))


def from_document(doc: dict, source: str | None = None) -> ExpressionTopology:
    return ExpressionTopology.from_data(parse_time_varying(doc, source))


__all__ = [
    "ExprEdge",
    "ExpressionTopology",
    "TimeVaryingDesign",
    "Lemma1Batch",
    "Lemma1Structure",
    "enclose_matrix",
    "grounded_laplacian_batch",
    "lemma1_batch",
    "lemma1_structure",
    "load_time_varying",
    "sym_min_eig_lower",
]
