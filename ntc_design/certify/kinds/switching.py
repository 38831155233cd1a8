"""Kind ``switching``: L_B(k) + L_B(k)ᵀ ≻ 0 in every scheduled mode (Theorems 3-4), and a
common Lyapunov P for every scheduled mode when one was found."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ...protocol import SwitchingDesign
from ..claims import Property, derive_claims
from ..dense import DENSE_CERT_MAX_ND, min_eig, mode_subject
from ..format import FORMAT, VERSION, finish, scheduled_modes, switching_hash, topology_hash
from ..lyapunov import common_lyapunov, verified_margin
from ..theorems import TheoremVerdict, switching_verdicts
from .base import IssueOptions, Reading, ResultRow, ResultsAudit, Subject, number_text
from .dense import DenseKind


def switching_nd(design: SwitchingDesign) -> int:
    """N·d of a switching design's modes.

    Parameters
    ----------
    design : SwitchingDesign
        The design.

    Returns
    -------
    int
    """
    return design.switching.n * design.switching.dim


def weight_bound(design: SwitchingDesign) -> float:
    """max |entry| over every weight of every mode (Assumption 3's bound).

    Parameters
    ----------
    design : SwitchingDesign
        The design.

    Returns
    -------
    float
    """
    # one reduction over each mode's (E, d, d) weight array: a loop over the weights dict
    # cost 2-6 s per certify of two 10⁵-agent modes
    return max(
        (
            float(np.max(np.abs(w), initial=0.0))
            for top in design.switching.modes.values()
            for w in (top.edge_arrays.w,)
        ),
        default=0.0,
    )


def switching_certificate(
    sd: SwitchingDesign, structures=("identity", "block-diagonal", "dense")
) -> dict:
    """Certify a switching set: L_B(k) + L_B(k)ᵀ ≻ 0 for every scheduled mode k
    (Theorems 3-4), and a common Lyapunov matrix P for all of them when one is found.

    Parameters
    ----------
    sd : SwitchingDesign
        One Lemma 1 design per mode.
    structures : sequence of str
        Structures tried for the common P, cheapest first.

    Returns
    -------
    dict
        The certificate (kind ``switching``); it certifies ``symmetric_part`` always (a
        mode where it fails makes the certificate fail to verify) and
        ``common_lyapunov`` when a P was found.
    """
    used = scheduled_modes(sd.switching.schedule)
    laps = {k: d.grounded_laplacian() for k, d in sd.modes.items()}
    n = next(iter(laps.values())).shape[0]
    sym = {k: min_eig(lap + lap.T) for k, lap in laps.items()}
    common = common_lyapunov({k: laps[k] for k in used}, sd.switching.dim, structures)
    matrices: dict[str, Any] = {"L_B": {k: v.tolist() for k, v in laps.items()}, "P": {}}
    props = [Property.SYMMETRIC_PART]
    if common.p is not None:
        matrices["P"]["common"] = common.p.tolist()
        props.append(Property.COMMON_LYAPUNOV)
    mode_hashes = {k: topology_hash(d.topology) for k, d in sd.modes.items()}
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "switching",
        "certifies": [p.value for p in props],
        "size": int(n),
        "subject": {
            "modes": {k: mode_subject(d) for k, d in sd.modes.items()},
            "schedule": [{"mode": m, "duration": t} for m, t in sd.switching.schedule],
            "switching_hash": switching_hash(mode_hashes, sd.switching.schedule),
        },
        "matrices": matrices,
        "claims": [c.to_dict() for c in derive_claims(props, used, 0.0)],
        "results": {
            "symmetric_part_min_eig": sym,
            "common_lyapunov": {
                "structure": common.structure,
                "attempts": [
                    {"structure": s, "status": st, "seconds": sec} for s, st, sec in common.attempts
                ],
                "margin": common.margin,
            },
        },
        "solver": {"name": "Clarabel (via cvxpy)", "status": [a[1] for a in common.attempts]},
    }
    return finish(doc)


class SwitchingKind(DenseKind):
    """A switching set up to Nd = ``DENSE_CERT_MAX_ND``: dense matrices, exact re-check."""

    name = "switching"
    description = "a switching topology: every mode its schedule uses"
    properties: ClassVar[tuple[Property, ...]] = (Property.SYMMETRIC_PART, Property.COMMON_LYAPUNOV)
    required = frozenset({Property.SYMMETRIC_PART})
    switching = True
    method = "exact-rational"
    subject_fields = frozenset({"modes", "schedule", "switching_hash"})

    def accepts(self, design: Any) -> bool:
        return isinstance(design, SwitchingDesign) and switching_nd(design) <= DENSE_CERT_MAX_ND

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        return switching_certificate(design)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        est = certificate["results"]["symmetric_part_min_eig"]
        return switching_verdicts(design, verification, gain, weight_bound(design), est)

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        cl = results["common_lyapunov"]
        return (
            ResultRow(
                "λ_min(L_B + L_Bᵀ)",
                ", ".join(
                    f"{k} {number_text(v)}" for k, v in results["symmetric_part_min_eig"].items()
                ),
            ),
            ResultRow(
                "common Lyapunov matrix",
                f"{cl['structure'] or 'none found'} ("
                + "; ".join(f"{a['structure']}: {a['status']}" for a in cl["attempts"])
                + ")",
            ),
        )

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # λ_min(L_B(k) + L_B(k)ᵀ) of every mode and the common P's verified margin
        # recomputed; the solver's run times are informational.
        ctx = reading.state
        for k, m in ctx.modes.items():
            s = m.lap + m.lap.T
            audit.recomputed(("symmetric_part_min_eig", k), min_eig(s), float(np.max(np.abs(s))))
        got = audit.get("symmetric_part_min_eig")
        if not isinstance(got, dict):
            audit.fail("symmetric_part_min_eig: expected an object mode -> number")
        cl = audit.get("common_lyapunov")
        if isinstance(cl, dict):
            for i in range(
                len(cl.get("attempts", []) if isinstance(cl.get("attempts"), list) else [])
            ):
                audit.informational(("common_lyapunov", "attempts", i, "seconds"))
            if cl.get("margin") is not None:
                p = ctx.p("common") if "common" in ctx.ps else None
                if p is None:
                    audit.fail("common_lyapunov.margin: reported, but there is no common P")
                else:
                    used = [ctx.modes[k].lap for k in subject.scheduled if k in ctx.modes]
                    audit.recomputed(
                        ("common_lyapunov", "margin"), verified_margin(used, p, 0.0), 1.0
                    )
