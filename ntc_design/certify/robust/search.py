"""Robust certification: Lemma 1's protocol when every weight is known only within a
relative Loewner interval.

**The set.** For a radius ρ ∈ [0, 1], a realisation A' keeps each weight's sign and lies in

    (1 − ρ)|A_ij| ⪯ |A'_ij| ⪯ (1 + ρ)|A_ij|,

equivalently ``|A'_ij| = F(I + E)F`` with ``F = |A_ij|^{1/2}``, E symmetric, ‖E‖₂ <= ρ (so
each weight keeps its sign and its kernel). The protocol (informed agents, B_i, δ, x0) stays
at its nominal design; only L changes, ``L_B(A') = L_B + Σ_e E_i Δ_e D_eᵀ`` with
``Δ_e = |A'_e| − |A_e|``, ``E_i = e_i ⊗ I_d`` and ``D_e = E_i − s_e E_j`` for the edge
e = (j → i) of sign s_e.

**Three brackets**, each a certified end and a realisation attaining the other:

* *decay* α: every realisation has ``min Re λ(L_B(A')) >= α_lower`` (quadratic stability
  with one S-procedure multiplier per edge, below); a hill-climbed realisation attains
  ``α_upper``;
* *consensus offset* ``‖x*(A') − 1⊗θ‖₂``: at most ``offset_upper`` for every realisation
  (an S-procedure bound on the equilibrium equation, below); a hill-climbed realisation
  attains ``offset_lower``. Only antagonistic weights move x*: ``D_eᵀ(1⊗θ) = (1 − s_e)θ``;
* *margin*: −L_B(A') Hurwitz for every realisation of radius ρ_lower (the decay LMI at
  α = 0); a realisation of radius ρ_upper is not Hurwitz (hill-climbed, or every weight
  vanishing at ρ = 1).

**Channels without square roots** (so that ``ntc verify`` re-checks them exactly). For an
edge with ``W = |A_e|``, ``w = Δ_e v`` lies in range(W) and ``w = W y`` with
``yᵀ W y = wᵀ W⁺ w <= ρ² vᵀ W v`` (as ``E² ⪯ ρ² I``). ``y`` is written ``V η`` with V the
pivot columns of W (an exact basis of its range). Then

* decay: ``Ψ = [[M − Σ τ_e ρ² D_e W_e D_eᵀ, P E_i W_e V_e], [·ᵀ, τ_e V_eᵀ W_e V_e]] ≻ 0``
  with ``M = P(L_B − αI) + (L_B − αI)ᵀP`` and P ≻ 0 proves ``min Re λ(L_B(A')) > α``
  for every realisation (S-procedure; Boyd, El Ghaoui, Feron & Balakrishnan, *Linear
  Matrix Inequalities in System and Control Theory*, SIAM 1994, §2.6.3 and §5.1);
* offset: with ``ξ = (z, η, 1)`` and z = x* − 1⊗θ, every realisation gives
  ``L_B z + Σ_e E_i W_e V_e η_e = 0`` and ``η_eᵀ V_eᵀ W_e V_e η_e <= ρ² ‖D_eᵀ(z + 1⊗θ)‖²_{W_e}``;
  ``Γ = γ·e eᵀ − zzᵀ-form − Σ λ_e g_e + sym(Aᵀ Y) ≻ 0`` (Finsler's lemma for the equation,
  λ_e >= 0) proves ``‖z‖² <= γ``, given that every L_B(A') is invertible (the decay
  bracket's certified end at the same ρ).

**Edges of radius 0** are not perturbed and get no channel: at ρ = 0, Ψ is the nominal
Lyapunov inequality P(L_B − αI) + (L_B − αI)ᵀP ≻ 0 and Γ bounds the nominal equilibrium,
so the brackets are the nominal figures (:func:`robust`). **A weight singular only by
rounding** (v vᵀ written in floating point: exactly it is full rank, even indefinite, by
1e−18) has no positive definite VᵀWV, so no Ψ could be ≻ 0; its channels bound the change
by W̄ = W + ηI ⪰ W instead (:func:`channel_bound`), a set that holds the one above.

Past ROBUST_MAX_ND the sparse bounds of :mod:`.robust_scale` are tightened up to
RICCATI_MAX_ND: decay and margin by the Riccati search (:mod:`.robust_are`), the offset by
the same S-procedure with the equation eliminated (:mod:`.robust_offset`).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from ...errors import InputError, check_work, format_seconds, require_radius
from ...protocol import ProtocolDesign
from ..dense import lap_b_float
from .are import RICCATI_MAX_ND, RiccatiSearch
from .lmi import DecayLMI, channels, descend, offset_sdp
from .offset import offset_search
from .problem import (
    Bracket,
    Problem,
    Realisation,
    dense_problem,
    uncertain_edges,
)
from .realise import abscissa, climb, offset_of
from .report import RobustReport
from .scale import robust_scale

check_radius = require_radius  # the one radius check (errors.require_radius)

#: Robust LMIs are solved up to this Nd (dense P; the S-procedure adds Σ rank(W_e) rows).
ROBUST_MAX_ND = 40  # dense LMIs up to here (one solve took 2.4 s at Nd = 36, 92 s at 75)
DEFAULT_RADIUS = 0.05
#: The work model of :func:`robust_seconds`, measured on a loaded 2-core machine: a
#: decay LMI with m unknowns (P and the τ_e) about DECAY_SECONDS·m² (8.1 s at Nd = 39,
#: m = 794), the offset SDP (Y and the λ_e) OFFSET_SECONDS·m² (49 s at m = 3198), the
#: Riccati brackets RICCATI_SECONDS·(Nd)³ (19 s at Nd = 120, 68 s at 198), the sparse
#: ones SPARSE_SECONDS per weight entry (N + E)·d² (62 s at N = 10⁵, d = 3), each plus
#: BASE_SECONDS (the realisation searches, the certificate's check).
DECAY_SECONDS = 1.3e-5
OFFSET_SECONDS = 5.5e-6
RICCATI_SECONDS = 1.2e-5
SPARSE_SECONDS = 3.5e-5
BASE_SECONDS = 5.0
#: A robust run estimated longer than MAX_SECONDS is refused (one longer than a minute
#: says how long before it starts: errors.check_work).
MAX_SECONDS = 3600.0


# -- the brackets ----------------------------------------------------------------------------


def _worst(p: Problem, rad: np.ndarray, objective: str, starts: int, seed: int) -> Realisation:
    """The realisation :func:`.robust_search.climb` finds, with what it attains (min Re λ, or the offset)."""
    es = climb(p, rad, objective, starts, seed)
    lap = p.lap(es)
    value = abscissa(lap) if objective == "decay" else offset_of(p, lap)
    return Realisation(float(np.max(rad, initial=0.0)), p.weights(es), value)


def robust_seconds(
    design: ProtocolDesign, bisection_steps: int = 3, margin: bool = True
) -> tuple[float, str]:
    """The estimated time of :func:`robust` before it starts (the model of
    :data:`DECAY_SECONDS` and its peers; within a factor of a few): what is solved, by
    size.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    bisection_steps : int, optional
        As for :func:`robust`.
    margin : bool, optional
        Whether the margin bracket is computed too.

    Returns
    -------
    (float, str)
        Seconds, and what they are spent on.
    """
    top = design.topology
    nd_ = top.nd
    if nd_ > ROBUST_MAX_ND:
        entries = (top.n + int(top.edge_arrays.rows.size)) * top.dim**2
        sparse = SPARSE_SECONDS * entries
        if nd_ > RICCATI_MAX_ND:
            return BASE_SECONDS + sparse, f"sparse bounds over {entries:.3g} weight entries"
        return (
            BASE_SECONDS + sparse + RICCATI_SECONDS * nd_**3,
            f"Riccati searches on N·d = {nd_}",
        )
    ed = uncertain_edges(top)
    rank = sum(len(p) for p in ed.pivots)
    m_decay = nd_ * (nd_ + 1) // 2 + ed.m
    m_offset = nd_ * (nd_ + rank + 1) + ed.m + 1
    solves = (1 + bisection_steps) * (2 if margin else 1)  # the first fraction, bisection
    seconds = BASE_SECONDS + solves * DECAY_SECONDS * m_decay**2 + OFFSET_SECONDS * m_offset**2
    return seconds, (
        f"about {solves} decay LMIs of {m_decay} unknowns and an offset SDP of {m_offset}, "
        f"dense, on N·d = {nd_}"
    )


def check_robust_work(
    design: ProtocolDesign, bisection_steps: int = 3, margin: bool = True
) -> None:
    """Refuse a robust run estimated above :data:`MAX_SECONDS` (one line naming the size);
    warn with the estimate above :data:`ntc_design.errors.LONG_WORK_SECONDS`.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    bisection_steps : int, optional
        As for :func:`robust`.
    margin : bool, optional
        Whether the margin bracket is computed too.

    Raises
    ------
    InputError
        The estimate exceeds :data:`MAX_SECONDS`.
    """
    seconds, what = robust_seconds(design, bisection_steps, margin)
    line = f"roughly {format_seconds(seconds)} ({what})"
    too_large = "the network is too large for the robust brackets"
    check_work(seconds, line, MAX_SECONDS, too_large, field="robust")


def robust(
    design: ProtocolDesign,
    radius: float = DEFAULT_RADIUS,
    starts: int = 6,
    seed: int = 0,
    bisection_steps: int = 3,
    margin: bool = True,
) -> RobustReport:
    """The decay, offset and margin brackets of a Lemma 1 design under relative weight
    uncertainty of radius ρ (see the module docstring for the set and the methods).

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design (its protocol is kept for every realisation).
    radius : float, optional
        ρ in [0, 1) for every edge whose file gives no ``uncertainty:`` of its own
        (:attr:`ntc_design.model.Topology.uncertainty`).
    starts : int, optional
        Random starts of the realisation searches (besides the nominal point and ±ρI).
    seed : int, optional
        Their seed (SeedSequence).
    bisection_steps : int, optional
        Bisection steps on α and on ρ after the first fraction of the attained end that
        verifies (:data:`FRACTIONS`).
    margin : bool, optional
        Also the margin bracket (the most expensive; a sweep over ρ needs it once).

    Returns
    -------
    RobustReport
        At ρ = 0 (every edge unperturbed) the brackets are the nominal figures: the decay's
        proven end within ``(1 − FRACTIONS[0])/2**bisection_steps`` of the nominal rate,
        relative (6.25e−4 with the defaults), its other end the nominal rate; the offset's
        proven end within 1e−4·‖1⊗θ‖ of the nominal offset (the SDP's strict margin).
        Above :data:`ROBUST_MAX_ND`, the sparse brackets of
        :func:`ntc_design.certify.robust.scale.robust_scale`, up to
        :data:`ntc_design.certify.robust.are.RICCATI_MAX_ND` tightened by the Riccati
        search and the dense realisation searches; the Riccati proofs are kept for
        the certificate (:func:`ntc_design.certify.kinds.robust.robust_certificate`).

    Raises
    ------
    InputError
        A bad radius, a nominal −L_B that is not Hurwitz, or work estimated above
        :data:`MAX_SECONDS` (:func:`check_robust_work`).

    Examples
    --------
    >>> import ntc_design as nd
    >>> d = nd.design(nd.load(nd.example_path("g1.yaml")), [1, 2, -1], thresholds=False)
    >>> rep = robust(d, 0.05, starts=0, bisection_steps=2)
    >>> rep.decay.lower <= rep.decay.upper <= rep.nominal_decay + 1e-9
    True
    """
    t0 = time.perf_counter()
    rho = check_radius(radius)
    check_robust_work(design, bisection_steps, margin)
    if design.topology.nd > ROBUST_MAX_ND:  # sparse bounds, tightened by Riccati if dense
        rep = robust_scale(design, rho)
        if design.topology.nd <= RICCATI_MAX_ND:
            rep = _riccati_brackets(rep, rho, starts, seed, bisection_steps, margin, t0)
        return rep
    p = dense_problem(design)
    rad = p.edges.radii(design.topology, rho)
    rmax = float(np.max(rad, initial=0.0))
    alpha0 = abscissa(p.lap_b)
    if not alpha0 > 0:
        raise InputError(
            f"the nominal −L_B is not Hurwitz (min Re λ(L_B) = {alpha0:.6g}); "
            "certify the nominal design first",
            field="robust",
        )
    ch = channels(p)
    lmi = DecayLMI(p, ch)
    # decay: the realisation first, so that the bisection runs below what it attains
    wd = _worst(p, rad, "decay", starts, seed)
    a_lo, dec = descend(lambda a: lmi(a, rad), max(wd.value, 0.0), bisection_steps)
    decay = Bracket(
        a_lo if dec is not None else None,
        wd.value,
        wd,
        "lower",
        "quadratic stability, one S-procedure multiplier per edge (Clarabel); realisation "
        "by projected gradient on the eigenvalue",
    )
    # offset
    off = offset_sdp(p, ch, rad) if dec is not None else None  # x* exists: decay proven
    wo = _worst(p, rad, "offset", starts, seed + 1)
    offset = Bracket(
        wo.value,
        None if off is None else math.sqrt(off[0]),
        wo,
        "upper",
        "S-procedure on the equilibrium equation with Finsler's multiplier (Clarabel); "
        "realisation by projected gradient",
    )
    # margin
    destab = _destabilising(p, rmax, starts, seed + 2) if margin else None
    r_top = 1.0 if destab is None else destab.radius
    r_lo, mar = descend(lambda r: lmi(0.0, r), r_top, bisection_steps) if margin else (0.0, None)
    margin_b = Bracket(
        r_lo if mar is not None else None,
        None if destab is None else destab.radius,
        destab,
        "lower",
        "the decay LMI at α = 0, bisection on ρ; destabilising realisation by bisection on "
        "ρ with the eigenvalue search, else every weight vanishing at ρ = 1",
    )
    proofs = {"decay": dec, "alpha": a_lo, "offset": off, "margin": mar, "margin_radius": r_lo}
    return RobustReport(
        design,
        rmax,
        tuple(rad.tolist()),
        alpha0,
        decay,
        offset,
        margin_b,
        proofs,
        time.perf_counter() - t0,
    )


def robust_sweep(design: ProtocolDesign, radii, **options: Any) -> list[RobustReport]:
    """The decay and offset brackets at each radius (one :func:`robust` each, without the
    margin), for a figure of the brackets against ρ.

    Parameters
    ----------
    design : ProtocolDesign
        The nominal design.
    radii : sequence of float
        The radii ρ, each in [0, 1).
    **options
        ``starts``, ``seed``, ``bisection_steps`` of :func:`robust`.

    Returns
    -------
    list of RobustReport

    Raises
    ------
    InputError
        A bad radius, or a nominal −L_B that is not Hurwitz.
    """
    return [robust(design, float(r), margin=False, **options) for r in radii]


def _riccati_brackets(
    rep: RobustReport, rho: float, starts: int, seed: int, steps: int, margin: bool, t0: float
) -> RobustReport:
    """The sparse report ``rep`` of a design of at most RICCATI_MAX_ND, tightened: decay
    and margin lower ends by the Riccati search (:mod:`.robust_are`, proven in the
    process), the attained ends by the dense searches; each end keeps the better of the
    two methods, and says which."""

    des = rep.design
    p = dense_problem(des)
    rad = p.edges.radii(des.topology, rho)
    rmax = float(np.max(rad, initial=0.0))
    lap = lap_b_float(des.topology, des.B, des.delta)
    search = RiccatiSearch(*lap, p.edges, p.d)
    proofs: dict[str, Any] = dict.fromkeys(("decay", "alpha", "offset", "margin"))
    proofs["margin_radius"] = 0.0
    riccati = "quadratic stability with one multiplier per edge, P by a Riccati equation "
    riccati += "alternating with the multipliers (proven by verified Cholesky)"
    wd = _worst(p, rad, "decay", starts, seed)
    dec = rep.decay
    if dec.upper is None or wd.value < dec.upper:
        dec = Bracket(dec.lower, wd.value, wd, "lower", dec.method)
    a_lo, got = descend(lambda a: search(a, rad), max(float(dec.upper or 0.0), 0.0), steps)
    if got is not None:  # kept for the certificate even when dominance proves more
        proofs.update(decay=got, alpha=a_lo)
    if got is not None and (dec.lower is None or a_lo > dec.lower):
        dec = Bracket(a_lo, dec.upper, dec.realisation, "lower", riccati + "; upper: a "
                      "realisation by projected gradient on the eigenvalue")  # fmt: skip
    off = rep.offset
    wo = _worst(p, rad, "offset", starts, seed + 1)
    if off.lower is None or wo.value > off.lower:
        off = Bracket(wo.value, off.upper, wo, "upper", off.method.split("; lower")[0]
                      + "; lower: a realisation by projected gradient")  # fmt: skip
    # the S-procedure offset, when every L_B(A') is proven invertible (decay, any method)
    got_o = offset_search(des, lap)(rad) if dec.lower is not None else None
    if got_o is not None and proofs["decay"] is not None:  # the certificate needs both
        proofs["offset"] = (got_o[0], got_o[1], None)
    if got_o is not None and (off.upper is None or math.sqrt(got_o[0]) < off.upper):
        off = Bracket(off.lower, math.sqrt(got_o[0]), off.realisation, "upper",
                      "S-procedure on the equilibrium equation with the equation eliminated "
                      "(one multiplier per edge, CVXOPT; proven by verified Cholesky); "
                      "lower: a realisation by projected gradient")  # fmt: skip
    mar = rep.margin
    if margin:
        destab = _destabilising(p, rmax, starts, seed + 2)
        if destab is not None and (mar.upper is None or destab.radius < mar.upper):
            mar = Bracket(mar.lower, destab.radius, destab, "lower", mar.method)
        r_lo, got_m = descend(lambda r: search(0.0, r), float(mar.upper or 1.0), steps)
        if got_m is not None:
            proofs.update(margin=got_m, margin_radius=r_lo)
        if got_m is not None and (mar.lower is None or r_lo > mar.lower):
            mar = Bracket(r_lo, mar.upper, mar.realisation, "lower", "the Riccati search at "
                          "α = 0, bisection on ρ; upper: " + mar.method.split("upper: ")[-1])  # fmt: skip
    proofs["method"] = "riccati"  # the certificate's claims are checked in the Schur form
    return RobustReport(
        des, rep.radius, rep.radii, rep.nominal_decay, dec, off, mar, proofs,
        time.perf_counter() - t0,
    )  # fmt: skip


def _destabilising(p: Problem, r_lo: float, starts: int, seed: int) -> Realisation | None:
    """The smallest radius (bisection in [r_lo, 1)) at which the eigenvalue search finds a
    realisation with min Re λ <= 0; else the all-vanishing realisation at ρ = 1 when it is
    not Hurwitz; None when neither."""
    m, d = p.edges.m, p.d

    def found(r: float) -> np.ndarray | None:
        es = climb(p, r, "decay", starts, seed)
        return es if abscissa(p.lap(es)) <= 0 else None

    top = found(1.0 - 1e-6)
    if top is None:
        es1 = -np.broadcast_to(np.eye(d), (m, d, d)).copy()
        lap1 = p.lap(es1)
        if abscissa(lap1) <= 1e-12 * max(1.0, float(np.max(np.abs(p.lap_b)))):
            return Realisation(1.0, p.weights(es1) * 0.0, abscissa(lap1))
        return None
    lo, hi, best = r_lo, 1.0 - 1e-6, top
    for _ in range(10):
        mid = 0.5 * (lo + hi)
        got = found(mid)
        if got is None:
            lo = mid
        else:
            hi, best = mid, got
    return Realisation(hi, p.weights(best), abscissa(p.lap(best)))


__all__ = [
    "BASE_SECONDS",
    "DEFAULT_RADIUS",
    "MAX_SECONDS",
    "ROBUST_MAX_ND",
    "check_radius",
    "check_robust_work",
    "robust",
    "robust_seconds",
    "robust_sweep",
]
