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

**Cost.** Per mode, the issuer factorises ``L + Lᵀ − c₀I`` (the proof of ℓ = 0, whose
factor is also ARPACK's shift-invert operator for the estimate) and, when that
factorisation is at most ``RATE_PROOF_MAX_FLOPS``, ``L + Lᵀ − (ℓ + c)I`` (the proof of
ℓ; when it fails, ℓ = 0 stands with no third factorisation). Above it ℓ = 0 stands, with
the estimate reported beside it: one factorisation per mode. Modes of Nd >=
``PARALLEL_MIN_ND`` are proven in forked processes, one per CPU (CHOLMOD's BLAS here is
single-threaded), and ``verify`` does the same. ``verify`` factorises once per mode; ``ntc certify`` re-verifies its own
certificate without factorising a bit-identical matrix again (``SPDFamily.factor``,
``reuse``). Each factorisation is preceded by a structural analysis
(:func:`~ntc_design.numerics.linalg.cholesky_fill`) that refuses a factor above the memory or
work limits before it is computed. Fill grows with the symmetrised graph: on random
networks (d = 3) a factorisation takes 0.05 s at N = 10⁴ and 16-20 s at N = 10⁵.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..model import Topology
from ..numerics.linalg import DenseRefused, SPDFamily, fork_map, proof_workers
from ..protocol import SwitchingDesign
from .arrays import mode_subject
from .claims import Claim, ClaimKind, Property
from .fields import number
from .format import (
    FORMAT,
    NUMBER_EXP,
    VERSION,
    finish,
    scheduled_modes,
    switching_hash,
    topology_hash,
)
from .scale import (
    component_matrix,
    lap_b_blocks,
    symmetric_part_bound,
    symmetric_part_factor,
)

DESCRIPTION = "a switching topology at scale: every mode its schedule uses"
#: ℓ is the eigenvalue estimate minus twice the rounding shift, times (1 − LOWER_RTOL).
LOWER_RTOL = 1e-4
#: Largest Nd whose symmetric part's smallest eigenvalue is computed densely.
EIG_DENSE_MAX_ND = 1500
#: Largest factorisation (flops, from the symbolic analysis) repeated to prove ℓ > 0. The
#: theorems need ℓ = 0 only; ℓ > 0 (a proven decay rate) costs a second factorisation of
#: the same size. A 10⁵-agent random mode takes 6.2e11 flops (16 s here): above this, ℓ = 0
#: stands, proven by the factor that also serves the estimate (one factorisation per mode).
RATE_PROOF_MAX_FLOPS = 1e11
#: Modes of at least this Nd are proven in parallel processes (:func:`fork_map`), one per
#: CPU: a fork costs ~0.1 s, a 10⁵-agent mode's factorisation 16 s on one core.
PARALLEL_MIN_ND = 30_000


def sym_matrices(top: Topology, delta: float):
    """L_B (sparse) and an entrywise bound on its rounding error, rebuilt from the
    topology and δ.

    Parameters
    ----------
    top : Topology
        The mode's topology.
    delta : float
        δ of its design.

    Returns
    -------
    tuple of scipy.sparse matrices
    """
    blocks = lap_b_blocks(top, delta)
    return component_matrix(blocks, np.arange(top.n))


#: ARPACK's tolerance for the shift-invert estimate: each solve with a 10⁵-agent factor
#: takes about 0.15 s; 1e-6 needed 71 of them on a 10⁵-agent mode (1e-10: 101) and was
#: accurate to 1e-12 there, far inside the room ℓ leaves (LOWER_RTOL).
ARPACK_TOL = 1e-6
#: ... and when the estimate is only reported (no proof of ℓ > 0 follows): a Ritz value's
#: error is about the squared residual over the gap, so 1e-3 still gives several digits.
ARPACK_REPORT_TOL = 1e-3


def _min_eig_estimate(
    s, fam: SPDFamily | None, sigma: float = 0.0, tol: float = ARPACK_TOL
) -> tuple[float, str]:
    """λ_min(S), S = L + Lᵀ, estimated: dense up to EIG_DENSE_MAX_ND, else ARPACK
    shift-invert at ``sigma`` with the Cholesky factor of S − sigma·I (``fam``, when it
    factorised), else ARPACK's smallest algebraic eigenvalue (bounded iterations; NaN when
    it does not converge)."""
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
                sigma=sigma,
                OPinv=op,
                which="LM",
                tol=tol,
                maxiter=200,
                return_eigenvectors=False,
            )
            return float(np.min(w)), "ARPACK shift-invert (CHOLMOD factor of the ℓ = 0 proof)"
        w = eigsh(s, k=1, which="SA", ncv=40, tol=1e-6, maxiter=2000, return_eigenvectors=False)
        return float(np.min(w)), "ARPACK smallest algebraic"
    except (ArpackError, ValueError, ArithmeticError):  # no convergence: no estimate
        return math.nan, "ARPACK did not converge"


def mode_processes(tops: list[Topology]) -> int:
    """Processes to prove these modes in (:func:`~ntc_design.numerics.linalg.fork_map`): one per
    CPU, within memory, when one of them has Nd >= ``PARALLEL_MIN_ND``; else this one.

    Parameters
    ----------
    tops : list of Topology
        The modes to prove.

    Returns
    -------
    int
    """
    big = any(t.nd >= PARALLEL_MIN_ND for t in tops)
    return proof_workers(len(tops)) if big else 1


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
    lap, err = sym_matrices(top, delta)
    try:  # the proof of ℓ = 0, whose factor is also the eigensolver's inverse
        p0, fam = symmetric_part_factor(lap, err, 0.0)
    except DenseRefused as exc:
        return ModeProof(False, None, math.nan, "not estimated", str(exc))
    s = (lap + lap.T).tocsr()
    flops = fam.fill.flops if fam is not None else 0.0
    tol = ARPACK_TOL if flops <= RATE_PROOF_MAX_FLOPS else ARPACK_REPORT_TOL
    est, how = _min_eig_estimate(s, fam if p0.holds else None, p0.c, tol)
    del fam  # free the factor before the proof's own: one factor in memory at a time
    if not p0.holds:
        return ModeProof(False, None, est, how, p0.detail)
    if math.isfinite(est) and est > 4 * p0.c and flops > RATE_PROOF_MAX_FLOPS:
        skip = (
            f"; ℓ > 0 not attempted: it needs a second factorisation of {flops:.2g} flops "
            f"(above {RATE_PROOF_MAX_FLOPS:.0e}); ℓ = 0 and the estimate are reported"
        )
        return ModeProof(True, 0.0, est, how, p0.detail + skip)
    if math.isfinite(est) and est > 4 * p0.c:
        lower = float(np.nextafter((est - 2 * p0.c) * (1 - LOWER_RTOL), 0.0))
        if not 2.0**-NUMBER_EXP <= lower <= 2.0**NUMBER_EXP:
            lower = min(lower, 2.0**NUMBER_EXP) if lower > 2.0**-NUMBER_EXP else 0.0
        if lower:
            p = symmetric_part_bound(lap, err, lower)
            if p.holds:
                return ModeProof(True, p.shift, est, how, p.detail)
    return ModeProof(True, 0.0, est, how, p0.detail)  # ℓ = 0: proven by the first factor


def switching_scale_document(sd: SwitchingDesign, kind: str) -> dict:
    """Certify a big switching set (kind ``switching-scale``): per mode a proven lower
    bound ``λ_min(L_B(k) + L_B(k)ᵀ) > ℓ_k`` (module docstring), the topology as compact
    arrays.

    Parameters
    ----------
    sd : SwitchingDesign
        One Lemma 1 design per mode.
    kind : str
        The kind's name, written into the document by the kind that issues it
        (:class:`ntc_design.certify.kinds.switching_scale.SwitchingScaleKind`).

    Returns
    -------
    dict
        The certificate, digest included; it certifies ``symmetric_part`` (a mode that is
        not proven makes it fail to verify). Re-check it with
        :func:`ntc_design.certify.verify` or ``ntc verify``.

    Raises
    ------
    InputError
        A process proving a mode in parallel died (e.g. killed for memory).
    """

    t0 = time.perf_counter()
    sched = sd.switching.schedule
    used = scheduled_modes(sched)
    proofs, est, lower, details = {}, {}, {}, {}
    # the schedule's modes only (a mode it never uses needs no proof)
    tops = [sd.modes[k].topology for k in used]
    calls = [(prove_mode, (sd.modes[k].topology, sd.modes[k].delta)) for k in used]
    for k, r in zip(used, fork_map(calls, mode_processes(tops)), strict=True):
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
        "kind": kind,
        "certifies": [Property.SYMMETRIC_PART.value],
        "size": int(next(iter(sd.modes.values())).topology.nd),
        "subject": {
            "modes": {k: mode_subject(d) for k, d in sd.modes.items()},
            "schedule": [{"mode": m, "duration": t} for m, t in sched],
            "switching_hash": switching_hash(hashes, sched),
        },
        "proofs": proofs,
        "claims": [
            Claim(ClaimKind.SYMMETRIC_PART, Property.SYMMETRIC_PART, mode=k).to_dict() for k in used
        ],
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


def proof_fields(x: Any, where: str) -> float:
    """The proven lower bound ℓ of a mode's ``{lower}`` record (0 or a bounded number).

    Parameters
    ----------
    x : Any
        The record.
    where : str
        Its field, for messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not ``{lower}``, or ℓ negative or out of range.
    """
    if not isinstance(x, dict) or set(x) != {"lower"}:
        raise InputError("expected {lower}", field=where)

    lo = number(x["lower"], f"{where}.lower")
    if lo < 0 or (lo != 0 and not 2.0**-NUMBER_EXP <= lo <= 2.0**NUMBER_EXP):
        raise InputError(
            f"must be 0 or in [2^-{NUMBER_EXP}, 2^{NUMBER_EXP}]", field=f"{where}.lower"
        )
    return float(lo)


__all__ = [
    "ModeProof",
    "mode_processes",
    "prove_mode",
    "switching_scale_document",
    "proof_fields",
    "sym_matrices",
]
