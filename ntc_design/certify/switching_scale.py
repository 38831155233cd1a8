"""Switching certificates that scale: ``L_B(k) + L_B(k)ᵀ ≻ 0`` in every scheduled mode
(the premise of Theorems 3-4), proven with sparse factorisations and re-checked by
``verify`` without any solver (issue 9).

**What is proven, per mode.** A lower bound ``λ_min(L_B(k) + L_B(k)ᵀ) > ℓ_k >= 0``: a
sparse Cholesky factorisation (CHOLMOD) of ``L_B + L_Bᵀ − ℓ_k I`` shifted by Rump's
rounding bound succeeds (:func:`~ntc_design.certify.scale.symmetric_part_bound`). L_B is
rebuilt by ``verify`` from the mode's topology and δ with an entrywise error bound
(:func:`~ntc_design.certify.scale.lap_b_blocks`), so nothing in the certificate but the
topology, δ and ℓ_k is used. ``ℓ_k`` is found by the issuer
from an eigenvalue estimate (ARPACK in shift-invert mode with the Cholesky factor as the
inverse), lowered to leave room for the rounding shift; when it cannot be proven the
bound falls back to ℓ = 0 (positive definiteness only).

**What follows.** With every scheduled mode proven, V(ε) = ‖ε‖² decreases along
ε̇ = −L_B(σ(t)) ε at rate at least min_k ℓ_k / 2 for *any* switching signal: P = I is a
common Lyapunov matrix. The dense path's search for other common P (block-diagonal,
dense LMIs) and its exact rational arithmetic are not run at this size (their memory
grows as (Nd)² to (Nd)⁴); the certificate says so.

**Cost.** One structural analysis (:func:`~ntc_design.linalg.cholesky_fill`, which
refuses a factor above the memory or work limits before it is computed), two numeric
factorisations and a few dozen triangular solves per mode for the issuer, one
factorisation per mode for ``verify``. Fill grows with the symmetrised graph: on random
networks (d = 3) a factorisation takes 0.05 s at N = 10⁴ and 20 s at N = 10⁵.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..design import SwitchingDesign
from ..errors import InputError
from ..linalg import DenseRefused, SPDFamily
from ..model import SwitchingTopology, Topology
from .certificate import (
    MAX_MODES,
    NUMBER_EXP,
    About,
    Check,
    ModeAbout,
    Verification,
    _need,
    _number,
    _same_topology,
    _vector,
    canonical,
    finish,
    finite_number,
    integrity_checks,
    out_of_range,
    same_theta,
    schedule_checks,
    scheduled_modes,
    switching_hash,
    topology_hash,
)
from .claims import Claim, ClaimKind, Property
from .scale import (
    FORMAT,
    VERSION,
    component_matrix,
    lap_b_blocks,
    rump_shift,
    shifted_symmetric_part,
    symmetric_part_bound,
    topology_from_subject,
)
from .scale import _subject as mode_subject

KIND = "switching-scale"
DESCRIPTION = "a switching topology at scale: every mode its schedule uses"
#: ℓ is the eigenvalue estimate minus twice the rounding shift, times (1 − LOWER_RTOL).
LOWER_RTOL = 1e-4
#: Largest Nd whose symmetric part's smallest eigenvalue is computed densely.
EIG_DENSE_MAX_ND = 1500


def _sym_matrices(top: Topology, delta: float):
    blocks = lap_b_blocks(top, delta)
    return component_matrix(blocks, np.arange(top.n))


def _min_eig_estimate(s, fam: SPDFamily | None) -> tuple[float, str]:
    """λ_min(S), S = L + Lᵀ, estimated: dense up to EIG_DENSE_MAX_ND, else ARPACK
    shift-invert at 0 with the Cholesky factor (``fam``, when S factorised), else ARPACK's
    smallest algebraic eigenvalue (bounded iterations; NaN when it does not converge)."""
    from scipy.sparse.linalg import ArpackError, LinearOperator, eigsh

    n = s.shape[0]
    if n <= EIG_DENSE_MAX_ND:
        return float(np.linalg.eigvalsh(s.toarray())[0]), "dense eigenvalues"
    try:
        if fam is not None:
            op = LinearOperator((n, n), matvec=fam.solve, dtype=float)
            w = eigsh(
                s,
                k=1,
                sigma=0.0,
                OPinv=op,
                which="LM",
                tol=1e-10,
                maxiter=200,
                return_eigenvectors=False,
            )
            return float(np.min(w)), "ARPACK shift-invert at 0 (CHOLMOD factor)"
        w = eigsh(s, k=1, which="SA", ncv=40, tol=1e-6, maxiter=2000, return_eigenvectors=False)
        return float(np.min(w)), "ARPACK smallest algebraic"
    except (ArpackError, ValueError, ArithmeticError):  # no convergence: no estimate
        return math.nan, "ARPACK did not converge"


@dataclass(frozen=True)
class ModeProof:
    """One mode's outcome: whether ``λ_min(L_B + L_Bᵀ) > lower`` is proven, the
    eigenvalue estimate (NaN when none) and how each was obtained."""

    holds: bool
    lower: float | None
    estimate: float
    estimate_method: str
    detail: str


def prove_mode(top: Topology, delta: float) -> ModeProof:
    """Prove ``λ_min(L_B + L_Bᵀ) > ℓ >= 0`` for one mode with the largest ℓ that the
    eigenvalue estimate allows (module docstring).

    Parameters
    ----------
    top : Topology
        The mode's topology.
    delta : float
        δ of its design.

    Returns
    -------
    ModeProof
        Whether it is proven, ℓ, the estimate and how.
    """
    lap, err = _sym_matrices(top, delta)
    s, e0 = shifted_symmetric_part(lap, err)
    fam = SPDFamily([s])
    try:  # L + Lᵀ itself: the eigensolver's inverse (and a failure says "indefinite")
        pd = fam.factor([1.0], 0.0)[0]
    except DenseRefused as exc:
        return ModeProof(False, None, math.nan, "not estimated", str(exc))
    est, how = _min_eig_estimate(s, fam if pd else None)
    fam = None  # free the factor before the proof's own: one factor in memory at a time
    if not pd:
        return ModeProof(
            False, None, est, how, "sparse Cholesky of L + Lᵀ fails (not positive definite)"
        )
    tries = [0.0]
    c0 = rump_shift(s, e0)
    if math.isfinite(est) and est > 4 * c0:
        tries.insert(0, float(np.nextafter((est - 2 * c0) * (1 - LOWER_RTOL), 0.0)))
    for lower in tries:
        if lower and not 2.0**-NUMBER_EXP <= lower <= 2.0**NUMBER_EXP:
            lower = min(lower, 2.0**NUMBER_EXP) if lower > 2.0**-NUMBER_EXP else 0.0
        p = symmetric_part_bound(lap, err, lower)
        if p.holds:
            return ModeProof(True, p.shift, est, how, p.detail)
    return ModeProof(False, None, est, how, p.detail)


def switching_scale_certificate(sd: SwitchingDesign) -> dict:
    """Certify a big switching set (kind ``switching-scale``): per mode a proven lower
    bound ``λ_min(L_B(k) + L_B(k)ᵀ) > ℓ_k`` (module docstring), the topology as compact
    arrays.

    Parameters
    ----------
    sd : SwitchingDesign
        One Lemma 1 design per mode.

    Returns
    -------
    dict
        The certificate, digest included; it certifies ``symmetric_part`` (a mode that is
        not proven makes it fail to verify). Re-check it with :func:`verify_switching_scale`
        or ``ntc verify``.
    """

    t0 = time.perf_counter()
    sched = sd.switching.schedule
    used = scheduled_modes(sched)
    proofs, est, lower, details = {}, {}, {}, {}
    for k in used:  # the schedule's modes only: a mode it never uses needs no proof
        des = sd.modes[k]
        r = prove_mode(des.topology, des.delta)
        est[k] = r.estimate if math.isfinite(r.estimate) else None
        details[k] = f"{r.detail}; λ_min estimate: {r.estimate_method}"
        if r.holds:
            proofs[k] = {"lower": r.lower}
            lower[k] = r.lower
    hashes = {k: topology_hash(d.topology) for k, d in sd.modes.items()}
    all_proven = all(k in proofs for k in used)
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": KIND,
        "certifies": [Property.SYMMETRIC_PART.value],
        "size": int(next(iter(sd.modes.values())).topology.nd),
        "subject": {
            "modes": {k: mode_subject(d) for k, d in sd.modes.items()},
            "schedule": [{"mode": m, "duration": t} for m, t in sched],
            "switching_hash": switching_hash(hashes, sched),
        },
        "proofs": proofs,
        "claims": [c.to_dict() for c in _claims(used)],
        "results": {
            "symmetric_part_min_eig": est,
            "symmetric_part_lower_bound": lower,
            "details": details,
            "common_lyapunov": {
                "structure": "identity" if all_proven else None,
                "note": "P = I: I·L_B(k) + L_B(k)ᵀ·I = L_B(k) + L_B(k)ᵀ ≻ 0 in every scheduled "
                "mode, so ‖ε‖² decreases under any switching"
                if all_proven
                else "not every scheduled mode is proven",
            },
            "skipped": [
                "common P other than I (block-diagonal and dense LMIs) and exact rational "
                "arithmetic: not run above the dense sizes (memory grows as (Nd)^2 to (Nd)^4)"
            ],
            "seconds": time.perf_counter() - t0,
        },
        "solver": {"name": None, "status": None},
    }
    return finish(doc, "verified-float (sparse Cholesky per mode)")


def _claims(modes) -> list[Claim]:
    return [Claim(ClaimKind.SYMMETRIC_PART, Property.SYMMETRIC_PART, mode=k) for k in modes]


def _proof_fields(x: Any, where: str) -> float:

    if not isinstance(x, dict) or set(x) != {"lower"}:
        raise InputError(f"{where}: expected {{lower}}")

    lo = _number(x["lower"], f"{where}.lower")
    if lo < 0 or (lo != 0 and not 2.0**-NUMBER_EXP <= lo <= 2.0**NUMBER_EXP):
        raise InputError(f"{where}.lower: must be 0 or in [2^-{NUMBER_EXP}, 2^{NUMBER_EXP}]")
    return float(lo)


def _same_number(x: Any, value: float) -> bool:

    return finite_number(x) == value


def _results_check(doc: dict, source: str, proofs: dict, scheduled: tuple[str, ...]):
    """The reported results against the proofs: the lower bounds are the proven ℓ, every
    estimate lies above its proven bound, P = I is claimed exactly when every scheduled
    mode is proven, and no proof is given for a mode the schedule does not use."""

    res = doc.get("results")
    if not isinstance(res, dict):
        raise InputError(f"{source}: results: expected an object")
    bad = [f"proofs.{k}: the schedule does not use mode {k}" for k in proofs if k not in scheduled]
    # the scheduled modes' proofs were validated (and re-proven) before this check
    want = {k: float(proofs[k]["lower"]) for k in scheduled if k in proofs}
    got_lb = res.get("symmetric_part_lower_bound")
    if (
        not isinstance(got_lb, dict)
        or set(got_lb) != set(want)
        or any(not _same_number(got_lb[k], v) for k, v in want.items())
    ):
        bad.append("symmetric_part_lower_bound differs from the proven bounds")
    est = res.get("symmetric_part_min_eig")
    if not isinstance(est, dict):
        bad.append("symmetric_part_min_eig: expected an object")
    else:
        for k, lo in want.items():
            e = est.get(k)
            ef = finite_number(e)
            if e is not None and not (ef is not None and ef > lo):
                bad.append(f"mode {k}: the estimate {e!r} is not above the proven bound {lo!r}")
    all_proven = all(k in proofs for k in scheduled)
    cl = res.get("common_lyapunov")
    if not isinstance(cl, dict) or cl.get("structure") != ("identity" if all_proven else None):
        bad.append("common_lyapunov: P = I is claimed exactly when every scheduled mode is proven")
    return Check(
        "reported results (bounds are the proven ones; estimates above them)",
        not bad,
        "; ".join(bad) or "consistent",
    )


def verify_switching_scale(
    doc: dict,
    source: str = "certificate",
    topology: Topology | SwitchingTopology | None = None,
    theta: Any = None,
):
    """Re-check a ``switching-scale`` certificate without any solver (module docstring):
    the digests, the subject (informed agents = U, one θ, the schedule, the switching
    hash), that the listed claims are those the scheduled modes require, and each
    scheduled mode's bound ``λ_min(L_B + L_Bᵀ) > ℓ`` by one sparse factorisation.

    Parameters
    ----------
    doc : dict
        The certificate.
    source : str, optional
        Its name, for messages.
    topology : Topology or SwitchingTopology, optional
        The user's own file: the certificate must be about it (canonical hashes).
    theta : sequence of float, optional
        The user's θ: the certificate must be about it.

    Returns
    -------
    Verification
        Valid when every check holds.

    Raises
    ------
    InputError
        The certificate or a topology in it is malformed, or a factorisation would not
        fit.
    """

    got = _need(doc, "digest", str, source)
    subject = _need(doc, "subject", dict, source)
    checks: list = integrity_checks(doc, subject, got)
    size = _need(doc, "size", int, source)
    modes_doc = _need(subject, "modes", dict, f"{source}: subject")
    if not modes_doc or len(modes_doc) > MAX_MODES:
        raise InputError(f"{source}: subject.modes: expected 1 to {MAX_MODES} modes")
    tops: dict[str, Topology] = {}
    deltas: dict[str, float] = {}
    thetas: dict[str, np.ndarray] = {}
    for name, sub in modes_doc.items():
        where = f"{source}: subject.modes.{name}"
        if not isinstance(sub, dict):
            raise InputError(f"{where}: expected an object")
        top = topology_from_subject(_need(sub, "topology", dict, where), f"{where}.topology")
        if top.nd != size:
            raise InputError(f"{where}: topology has Nd={top.nd}, certificate size is {size}")
        delta = _number(_need(sub, "delta", (int, float), where), f"{where}.delta")
        if not delta > 0 or out_of_range(delta):
            raise InputError(f"{where}.delta: must be a positive number in [2^-250, 2^250]")
        theta_m = _vector(_need(sub, "theta", list, where), top.dim, f"{where}.theta")
        informed = _need(sub, "informed", list, where)
        try:
            inf_idx = sorted(top.index(x) for x in informed)
        except InputError:
            raise InputError(f"{where}.informed: lists an unknown agent") from None
        ok_u = inf_idx == sorted(top.antagonised)
        checks.append(
            Check(f"{name}: informed agents are U", ok_u, "V_I = U" if ok_u else "V_I ≠ U")
        )
        tops[str(name)], deltas[str(name)], thetas[str(name)] = top, float(delta), theta_m
    first = next(iter(tops.values()))
    same_agents = all(
        [str(x) for x in t.labels] == [str(x) for x in first.labels] for t in tops.values()
    )
    checks.append(
        Check("every mode has the same agents", same_agents, "yes" if same_agents else "no")
    )
    distinct = {tuple(t.tolist()) for t in thetas.values()}
    ok_t = len(distinct) == 1 and bool(np.any(next(iter(thetas.values()))))
    checks.append(
        Check(
            "one θ ≠ 0 for every mode",
            ok_t,
            f"θ = {list(sorted(distinct)[0])}"
            if ok_t
            else f"{[list(t) for t in sorted(distinct)]}",
        )
    )
    hashes = {k: topology_hash(t) for k, t in tops.items()}
    schedule, scheduled, sw_hash = schedule_checks(subject, source, hashes, checks)
    if topology is not None:
        checks.append(_same_topology(topology, hashes, schedule, sw_hash))
    if theta is not None:
        checks.append(same_theta(theta, next(iter(thetas.values()))))
    props = _need(doc, "certifies", list, source)
    ok_p = props == [Property.SYMMETRIC_PART.value]
    checks.append(
        Check(
            f"certifies what kind {KIND!r} can",
            ok_p,
            "symmetric_part" if ok_p else f"kind {KIND!r} certifies exactly ['symmetric_part']",
        )
    )
    claims = _claims(m for m in scheduled if m in tops)
    listed = _need(doc, "claims", list, source)
    ok_c = sorted(canonical(c.to_dict()) for c in claims) == sorted(canonical(c) for c in listed)
    checks.append(
        Check(
            "listed claims are those the kind and subject require",
            ok_c,
            f"{len(claims)} claims" if ok_c else "the listed claims differ from the derived ones",
        )
    )
    proofs = _need(doc, "proofs", dict, source)
    for c in claims:
        k = c.mode or ""
        if k not in proofs:
            checks.append(Check(c.id, False, "no proof given for this mode", c))
            continue
        lo = _proof_fields(proofs[k], f"{source}: proofs.{k}")
        lap, err = _sym_matrices(tops[k], deltas[k])
        p = symmetric_part_bound(lap, err, lo)
        bound = f"λ_min > {lo:.6g}: " if lo else ""
        checks.append(Check(c.id, p.holds, f"verified-float: {bound}{p.detail}", c))
    checks.append(_results_check(doc, source, proofs, scheduled))
    about = About(
        KIND,
        DESCRIPTION,
        (Property.SYMMETRIC_PART,),
        tuple(
            ModeAbout(k, t.name, t.n, t.dim, hashes[k], deltas[k], tuple(thetas[k].tolist()))
            for k, t in tops.items()
        ),
        scheduled,
        schedule,
        None,
        sw_hash,
    )
    return Verification(
        all(c.ok for c in checks), "verified-float (sparse Cholesky per mode)", tuple(checks), about
    )


__all__ = [
    "KIND",
    "ModeProof",
    "prove_mode",
    "switching_scale_certificate",
    "verify_switching_scale",
]
