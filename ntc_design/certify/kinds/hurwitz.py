"""Kind ``hurwitz``: one topology, −L_B Hurwitz by a Lyapunov P (P ≻ 0, P L_B + L_Bᵀ P ≻ 0),
with a decay rate α when the LMI found one (P ≻ 0, P L_B + L_Bᵀ P − 2αP ≻ 0, α > 0)."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from ...choices import RateMethod, choices
from ...errors import InputError
from ...protocol import ProtocolDesign
from ..claims import Property, derive_claims
from ..dense import DENSE_CERT_MAX_ND, eig_bound, min_eig, mode_subject, require_lmi
from ..fields import need, number
from ..format import FORMAT, VERSION, finish
from ..lyapunov import decay_rate_lmi, decay_rate_lyapunov, hurwitz_by_lyapunov
from ..theorems import TheoremVerdict, fixed_verdicts
from .base import IssueOptions, Reading, ResultRow, ResultsAudit, Subject
from .dense import DenseKind

RATE_METHODS = choices(RateMethod)


def hurwitz_certificate(
    d: ProtocolDesign,
    name: str | None = None,
    rate: bool = True,
    rate_method: RateMethod = "lyapunov",
) -> dict:
    """Certify −L_B Hurwitz for one design in two independent ways: (a) the Lyapunov
    equation P L_B + L_Bᵀ P = I with P ≻ 0; (b) a decay rate α with
    P L_B + L_Bᵀ P − 2αP ≻ 0: by the shifted Lyapunov equation (default, no SDP solver,
    :func:`~ntc_design.certify.lyapunov.decay_rate_lyapunov`) or by the LMI bisection
    (``rate_method="lmi"``, Clarabel through cvxpy).

    Parameters
    ----------
    d : ProtocolDesign
        The Lemma 1 design whose L_B is certified.
    name : str, optional
        The mode's name (default: the topology's name, or ``"topology"``).
    rate : bool
        Also certify a decay rate α.
    rate_method : {"lyapunov", "lmi"}
        How α is found (the certificate's content and its verification are the same).

    Returns
    -------
    dict
        The certificate (kind ``hurwitz``); it certifies ``hurwitz`` always and
        ``decay_rate`` when a P for α > 0 was found. Check it with :func:`verify`: a
        non-Hurwitz −L_B gives a certificate that does not verify.

    Raises
    ------
    InputError
        An unknown ``rate_method``, or an LMI too large for the machine.
    """
    name = name or d.topology.name or "topology"
    if rate_method not in RATE_METHODS:
        raise InputError(f"expected lyapunov or lmi, got {rate_method!r}", field="rate_method")
    if rate and rate_method == "lmi":  # estimated before any dense step: never an OOM kill
        require_lmi(d.topology.nd, "decay-rate LMI")
    lap_b = d.grounded_laplacian()
    lya = hurwitz_by_lyapunov(lap_b)
    eig = eig_bound(lap_b)
    matrices: dict[str, Any] = {"L_B": {name: lap_b.tolist()}, "P": {"lyapunov": lya.p.tolist()}}
    results: dict[str, Any] = {
        "eig_bound": eig,
        "lyapunov": {
            "residual": lya.residual,
            "P_min_eig": lya.p_min_eig,
            "method": "Schur, blocked Bartels–Stewart",
        },
    }
    props = [Property.HURWITZ]
    alpha = 0.0
    solver: dict[str, Any] = {"name": None, "status": None}
    if rate:
        find = decay_rate_lmi if rate_method == "lmi" else decay_rate_lyapunov
        r = find(lap_b, eig_bound=eig)
        if r.p is not None:
            props.append(Property.DECAY_RATE)
            alpha = r.alpha
            matrices["P"]["rate"] = r.p.tolist()
        results["lmi"] = {
            "alpha": alpha,
            "eig_bound": eig,
            "gap": eig - alpha,
            "status": r.status,
            "bisection_steps": r.iterations,
        }
        solver = {
            "name": "Clarabel (via cvxpy)" if rate_method == "lmi" else "Bartels–Stewart (SciPy)",
            "status": r.status,
        }
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "hurwitz",
        "certifies": [p.value for p in props],
        "size": int(lap_b.shape[0]),
        "subject": {"modes": {name: mode_subject(d)}},
        "matrices": matrices,
        "claims": [c.to_dict() for c in derive_claims(props, [name], alpha)],
        "results": results,
        "solver": solver,
    }
    return finish(doc)


class HurwitzKind(DenseKind):
    """One topology up to Nd = ``DENSE_CERT_MAX_ND``: dense P, exact re-check."""

    name = "hurwitz"
    description = "one topology: −L_B Hurwitz, with a decay rate when one is proven"
    properties: ClassVar[tuple[Property, ...]] = (Property.HURWITZ, Property.DECAY_RATE)
    required = frozenset({Property.HURWITZ})
    switching = False
    method = "exact-rational"

    def accepts(self, design: Any) -> bool:
        return isinstance(design, ProtocolDesign) and design.topology.nd <= DENSE_CERT_MAX_ND

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """The certificate of one design (:func:`hurwitz_certificate`).

        Parameters
        ----------
        design : ProtocolDesign
            The design.
        options : IssueOptions, optional
            Its ``rate_method`` (``"lyapunov"`` or ``"lmi"``) is used.

        Returns
        -------
        dict

        Raises
        ------
        InputError
            An unknown ``rate_method``, or an LMI too large for the machine.
        """
        return hurwitz_certificate(design, rate_method=(options or IssueOptions()).rate_method)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        return fixed_verdicts(design, verification, gain)

    def rate(self, doc: dict, source: str) -> float:
        res = need(doc, "results", dict, source)
        lmi = need(res, "lmi", dict, f"{source}: results")
        return number(need(lmi, "alpha", (int, float), f"{source}: results.lmi"), "α")

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        lya, lmi = results.get("lyapunov") or {}, results.get("lmi")
        resid = f"Lyapunov residual {lya.get('residual', math.nan):.2e}"
        if not lmi:
            return (ResultRow("decay rate", f"not certified; {resid}"),)
        return (
            ResultRow(
                "decay rate",
                f"α = {lmi['alpha']:.6g}, eigenvalue bound = {lmi['eig_bound']:.6g} "
                f"(gap {lmi['gap']:.2e}); {resid}",
            ),
        )

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # eig_bound = min Re λ(L_B), the Lyapunov residual and λ_min(P) recomputed; the
        # LMI's α is the proven one, below the eigenvalue bound, and its gap recomputed.
        ctx = reading.state
        (mode,) = ctx.modes.values()
        scale = float(np.max(np.abs(mode.lap))) if mode.in_range else 1.0
        eig = eig_bound(mode.lap)
        audit.recomputed(("eig_bound",), eig, scale)
        if audit.has("lyapunov"):
            p = ctx.p("lyapunov") if "lyapunov" in ctx.ps else None
            if p is None:
                audit.fail("lyapunov: reported, but matrices.P.lyapunov is missing or out of range")
            else:
                r = p @ mode.lap + mode.lap.T @ p - np.eye(ctx.n)
                resid = float(np.linalg.norm(r) / np.sqrt(ctx.n))
                audit.recomputed(("lyapunov", "residual"), resid, 1.0)
                audit.recomputed(("lyapunov", "P_min_eig"), min_eig(p), float(np.max(np.abs(p))))
        rated = alpha != 0.0 or Property.DECAY_RATE.value in doc.get("certifies", [])
        if audit.has("lmi"):
            audit.recomputed(("lmi", "eig_bound"), eig, scale)
            audit.recomputed(("lmi", "gap"), eig - alpha, scale)
            if rated:
                audit.estimate(("lmi", "alpha"), None, eig, " (α cannot exceed min Re λ(L_B))")
            else:  # no rate certified: the issuer reports α = 0
                audit.exact(("lmi", "alpha"), 0.0)
            audit.informational(("lmi", "bisection_steps"), integer=True)
