"""Kind ``switching-scale``: a big switching set, a proven lower bound
λ_min(L_B(k) + L_B(k)ᵀ) > ℓ_k >= 0 per scheduled mode by one sparse factorisation
(:mod:`ntc_design.certify.switching_scale` has the mathematics)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import InputError
from ...numerics.linalg import fork_map
from ...protocol import SwitchingDesign
from ..arrays import read_array_mode
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..dense import DENSE_CERT_MAX_ND
from ..fields import need
from ..format import MAX_MODES, topology_hash
from ..scale import symmetric_part_bound
from ..switching_scale import (
    EIG_DENSE_MAX_ND,
    mode_processes,
    proof_fields,
    switching_scale_document,
    sym_matrices,
)
from ..theorems import TheoremVerdict, switching_verdicts
from .base import (
    CertificateKind,
    IssueOptions,
    ModeReading,
    Reading,
    ResultRow,
    ResultsAudit,
    Subject,
    number_text,
)
from .switching import switching_nd, weight_bound


@dataclass(frozen=True, eq=False)
class SwitchingScaleState:
    """The modes' topologies and δ, and the stated proofs (mode -> {lower})."""

    tops: dict
    deltas: dict[str, float]
    proofs: dict
    source: str
    checked: dict = field(default_factory=dict)  # mode -> SymmetricPartProof, once proven


def _check_mode(top, delta: float, lower: float):
    """One sparse factorisation of L_B + L_Bᵀ − ℓI with Rump's shift (the proof of ℓ)."""
    lap, err = sym_matrices(top, delta)
    return symmetric_part_bound(lap, err, lower)


class SwitchingScaleKind(CertificateKind):
    """A switching set above Nd = ``DENSE_CERT_MAX_ND``: a sparse proof per mode."""

    name = "switching-scale"
    description = "a switching topology at scale: every mode its schedule uses"
    properties = (Property.SYMMETRIC_PART,)
    required = frozenset({Property.SYMMETRIC_PART})
    switching = True
    method = "verified-float (sparse Cholesky per mode)"
    fields = frozenset({"proofs"})
    subject_fields = frozenset({"modes", "schedule", "switching_hash"})
    mode_fields = frozenset({"topology", "theta", "margin", "delta", "informed"})

    def accepts(self, design: Any) -> bool:
        return isinstance(design, SwitchingDesign) and switching_nd(design) > DENSE_CERT_MAX_ND

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        return switching_scale_document(design, self.name)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        est = certificate["results"]["symmetric_part_min_eig"]
        return switching_verdicts(design, verification, gain, weight_bound(design), est)

    def read(self, doc: dict, source: str) -> Reading:
        # Each mode's topology (arrays), δ, θ and informed agents = U.
        subject = need(doc, "subject", dict, source)
        size = need(doc, "size", int, source)
        modes_doc = need(subject, "modes", dict, f"{source}: subject")
        if not modes_doc or len(modes_doc) > MAX_MODES:
            raise InputError(f"expected 1 to {MAX_MODES} modes", field=f"{source}: subject.modes")
        checks: list = []
        modes, tops, deltas = {}, {}, {}
        for name, sub in modes_doc.items():
            where = f"{source}: subject.modes.{name}"
            top, delta, theta, informed = read_array_mode(sub, where, size)
            checks.extend(informed)
            k = str(name)
            tops[k], deltas[k] = top, float(delta)
            modes[k] = ModeReading(
                k,
                top.name,
                tuple(str(x) for x in top.labels),
                top.dim,
                topology_hash(top),
                float(delta),
                theta,
            )
        proofs = need(doc, "proofs", dict, source)
        return Reading(modes, tuple(checks), SwitchingScaleState(tops, deltas, proofs, source))

    def claims(
        self, properties, subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        return tuple(
            Claim(ClaimKind.SYMMETRIC_PART, Property.SYMMETRIC_PART, mode=k)
            for k in subject.scheduled
            if k in subject.modes
        )

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check:
        # One sparse factorisation of L_B + L_Bᵀ − ℓI with Rump's shift.
        st: SwitchingScaleState = reading.state
        k = claim.mode or ""
        if k not in st.proofs:
            return Check(claim.id, False, "no proof given for this mode", claim)
        lo = proof_fields(st.proofs[k], f"{st.source}: proofs.{k}")
        if k not in st.checked:  # every stated mode at once: in parallel when they are big
            todo = [m for m in subject.scheduled if m in st.proofs and m in st.tops]
            los = {m: proof_fields(st.proofs[m], f"{st.source}: proofs.{m}") for m in todo}
            calls = [(_check_mode, (st.tops[m], st.deltas[m], los[m])) for m in todo]
            workers = mode_processes([st.tops[m] for m in todo])
            st.checked.update(zip(todo, fork_map(calls, workers), strict=True))
        p = st.checked[k]
        bound = f"λ_min > {lo:.6g}: " if lo else ""
        return Check(claim.id, p.holds, f"verified-float: {bound}{p.detail}", claim)

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        lb = results["symmetric_part_lower_bound"]
        est = results["symmetric_part_min_eig"]
        return (
            ResultRow(
                "λ_min(L_B + L_Bᵀ)",
                ", ".join(f"{k} {number_text(v)}" for k, v in est.items()),
                True,
            ),
            ResultRow(
                "proven lower bound ℓ: λ_min > ℓ (sparse Cholesky)",
                ", ".join(f"{k}: {number_text(lb.get(k))}" for k in est) or "none proven",
            ),
            ResultRow("common Lyapunov matrix", results["common_lyapunov"]["note"]),
            *(ResultRow("skipped", sk) for sk in results["skipped"]),
        )

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # The lower bounds are the proven ℓ; each estimate lies above its proven bound
        # and below min_i (L_B + L_Bᵀ)_ii (a Rayleigh quotient); P = I is claimed exactly
        # when every scheduled mode is proven; no proof for a mode the schedule skips.
        st: SwitchingScaleState = reading.state
        for k in st.proofs:
            if k not in subject.scheduled:
                audit.fail(f"proofs.{k}: the schedule does not use mode {k}")
        proven = {
            k: proof_fields(st.proofs[k], f"{st.source}: proofs.{k}")
            for k in subject.scheduled
            if k in st.proofs
        }
        lbs = audit.get("symmetric_part_lower_bound")
        if not isinstance(lbs, dict) or set(lbs) != set(proven):
            audit.fail("symmetric_part_lower_bound: one entry per proven scheduled mode")
        for k, lo in proven.items():
            audit.exact(("symmetric_part_lower_bound", k), lo)
        est = audit.get("symmetric_part_min_eig")
        if not isinstance(est, dict) or not set(est) <= set(subject.scheduled):
            audit.fail("symmetric_part_min_eig: an object scheduled mode -> estimate")
        else:
            for k in est:
                if k not in st.tops:
                    continue
                lap, _ = sym_matrices(st.tops[k], st.deltas[k])
                sym = lap + lap.T
                if sym.shape[0] <= EIG_DENSE_MAX_ND:  # the issuer's dense estimate, redone
                    lam = float(np.linalg.eigvalsh(sym.toarray())[0])
                    audit.recomputed(("symmetric_part_min_eig", k), lam, rtol=1e-9)
                    continue
                audit.estimate(
                    ("symmetric_part_min_eig", k),
                    proven.get(k),
                    float(np.min(sym.diagonal())),
                    " (λ_min(S) <= min_i S_ii)",
                    optional=True,
                    rtol=1e-6,
                )
        all_proven = all(k in proven for k in subject.scheduled)
        audit.exact(("common_lyapunov", "structure"), "identity" if all_proven else None)
        audit.informational(("seconds",))


__all__ = ["SwitchingScaleKind"]


def switching_scale_certificate(sd: SwitchingDesign) -> dict:
    """A ``switching-scale`` certificate for a switching set above the dense sizes
    (:func:`ntc_design.certify.switching_scale.switching_scale_document`).

    Parameters
    ----------
    sd : SwitchingDesign
        One Lemma 1 design per mode.

    Returns
    -------
    dict
        The certificate, digest included.
    """
    return switching_scale_document(sd, SwitchingScaleKind.name)
