"""Kind ``digital_loss``: a ``hurwitz`` certificate whose design runs as the sampled
protocol on lossy links (:mod:`ntc_design.protocol.loss`), with the proof that the
recursion contracts in mean square, the expectation taken over the arrivals, around the
mean's limit x* (:mod:`ntc_design.certify.loss` states the mathematics).

The subject adds ``digital: {period, delay, gain, noise, loss: {policy, edges}}`` (every
edge's p_e by its labels); the matrices add ``P.loss``; ``results.digital`` states α, κ,
t₀, k₀, the largest p_e and, under skip, the offset ‖x* − 1⊗θ‖. Each is proven by a
derived claim or recomputed: the inequality exactly (dyadic rationals) or in verified
floats, c(t) < κ beyond t₀ in ball arithmetic, the offset by an exact rational solve.
The certificate covers ``skip`` and ``rescale``, D = 0 here and D >= 1 by the delay line's
functional over the arrivals (:mod:`.digital_loss_delay`); ``hold`` (D = 0) by the
functional of :mod:`ntc_design.certify.loss_hold` (:mod:`.digital_loss_hold`). Where no
proof closes it certifies the continuous properties only and ``results.digital.stopped``
says why.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any

import numpy as np

from ...errors import InputError
from ...numerics.linalg import RANGE_TEXT, out_of_range
from ...protocol.digital import DigitalDesign
from ...protocol.loss import require_loss, require_policy
from ...rigorous.exact import Dyadic, exact_affordable
from ...rigorous.floatmat import FloatMat
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..digital import edge_noises, first_step, gain_t0, prove_gain_below, prove_psd
from ..fields import need, number
from ..format import finish
from ..loss import exact_offset, loss_edges, loss_ms_matrix, offset_value, plan_loss
from ..theorems import TheoremVerdict, digital_verdicts
from .base import IssueOptions, Reading, ResultRow, ResultsAudit, Subject, number_text
from .dense import prove_dense
from .digital import DigitalContext, DigitalKind, DigitalSubject, read_digital
from .digital_loss_delay import DELAY_LINE, delayed_claims, issue_delayed, prove_delayed
from .digital_loss_hold import (
    HOLD_CLAIMS,
    HoldStated,
    audit_hold,
    hold_claims,
    hold_detail,
    issue_hold,
    prove_hold,
    read_hold,
)
from .hurwitz import HurwitzKind

P_NAME = "loss"
MS = Property.DIGITAL_MEAN_SQUARE
#: The stated offset equals the exact one to this relative tolerance.
OFFSET_RTOL = 1e-9


@dataclass(frozen=True)
class LossSubject:
    """``subject.digital.loss`` as read: the policy and p_e by (i, j)."""

    policy: str
    losses: dict


@dataclass(frozen=True)
class LossStated:
    """``results.digital``'s numbers that the claims use."""

    alpha: float
    kappa: float
    t0: float
    offset: float | None
    g: float | None = None  # the delay line's growth bound of 1/c (D >= 1)


@dataclass(frozen=True, eq=False)
class LossState:
    """What ``digital_loss`` reads beside the ``hurwitz`` modes: ``subject.digital``, its
    ``loss`` and ``results.digital``'s numbers (None: the sampled property not certified)."""

    subject: DigitalSubject
    loss: LossSubject
    stated: LossStated | HoldStated | None  # hold's own numbers (.digital_loss_hold)


def _gain_document(gain: Any) -> Any:
    to_doc = getattr(gain, "to_document", None)
    if to_doc is not None:
        return to_doc()
    if isinstance(gain, str):
        return gain
    raise InputError(
        "the digital certificate needs c(t) as an expression or a schedule", field="gain"
    )


def design_losses(design: DigitalDesign) -> dict[tuple[int, int], float]:
    """p_e of every edge of the design's topology: its own ``loss:`` over the uniform one.

    Parameters
    ----------
    design : DigitalDesign
        The design.

    Returns
    -------
    dict of (int, int) to float
    """
    top = design.base.topology
    own = dict(getattr(top, "loss", {}) or {})
    return {k: float(own.get(k, design.digital.loss)) for k in top.edges}


def read_loss(doc: dict, source: str, top: Any) -> LossSubject:
    """Parse ``subject.digital.loss`` against the mode's topology.

    Parameters
    ----------
    doc : dict
        The certificate.
    source : str
        Its name.
    top : Topology
        The mode's topology.

    Returns
    -------
    LossSubject

    Raises
    ------
    InputError
        A missing or malformed field, an edge not in the topology, a bad p.
    """
    where = f"{source}: subject.digital.loss"
    sub = need(
        need(need(doc, "subject", dict, source), "digital", dict, source),
        "loss",
        dict,
        f"{source}: subject.digital",
    )
    policy = require_policy(f"{where}.policy", sub.get("policy"))
    index = {str(a): k for k, a in enumerate(top.labels)}
    edges = set(top.edges)
    losses: dict = {}
    for k, e in enumerate(need(sub, "edges", list, where)):
        w = f"{where}.edges[{k}]"
        if (
            not isinstance(e, dict)
            or not isinstance(e.get("from"), str)
            or not isinstance(e.get("to"), str)
        ):
            raise InputError("expected {from, to, p}", field=w)
        key = (index.get(e["to"], -1), index.get(e["from"], -1))
        if key not in edges or key in losses:
            raise InputError(f"no edge {e['from']}->{e['to']} (or listed twice)", field=w)
        losses[key] = require_loss(f"{w}.p", e.get("p"))
    return LossSubject(policy, losses)


def loss_claims(mode: str, policy: str) -> tuple[Claim, ...]:
    """The claims the contraction on lossy links needs.

    Parameters
    ----------
    mode : str
        The topology's mode name.
    policy : str
        ``skip`` (with the offset) or ``rescale``.

    Returns
    -------
    tuple of Claim
    """
    out = [
        Claim(ClaimKind.PD, MS, p=P_NAME),
        Claim(ClaimKind.LOSS_MS, MS, mode=mode, p=P_NAME),
        Claim(ClaimKind.DIGITAL_T0, MS),
    ]
    if policy == "skip":
        out.append(Claim(ClaimKind.LOSS_OFFSET, MS, mode=mode))
    return tuple(out)


def _limit_row(r: dict) -> tuple[ResultRow, ...]:
    """κ against c_true on lossy links, where the certificate shows it."""
    ct, kap = r.get("c_true"), r.get("kappa")
    if not (isinstance(ct, (int, float)) and isinstance(kap, (int, float)) and ct > 0):
        return ()
    return (
        ResultRow(
            "mean-square limit, lossy links",
            f"κ = {kap:.4g} ({100 * kap / ct:.0f} % of c_true = {ct:.4g}, the largest constant "
            "gain at which the lossy second-moment map contracts; estimated, not a claim)",
        ),
    )


class DigitalLossKind(DigitalKind):
    """One topology run as the sampled protocol on lossy links: ``hurwitz`` plus the
    contraction over the arrivals (and the offset under skip)."""

    name = "digital_loss"
    description = "one topology run as the sampled protocol on lossy links"

    def accepts(self, design: Any) -> bool:
        """A digital design of one topology whose messages may be lost.

        Parameters
        ----------
        design : Any
            The design.

        Returns
        -------
        bool
        """
        if not isinstance(design, DigitalDesign) or not HurwitzKind.accepts(self, design.base):
            return False
        return any(p > 0 for p in design_losses(design).values())

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """The ``hurwitz`` certificate with the lossy section (module docstring).

        Parameters
        ----------
        design : DigitalDesign
            The design.
        options : IssueOptions, optional
            As for ``hurwitz``.

        Returns
        -------
        dict
        """
        doc = HurwitzKind.issue(self, design.base, options)
        dg, top = design.digital, design.base.topology
        mode = next(iter(doc["subject"]["modes"]))
        d = top.dim
        losses = design_losses(design)
        lab = [str(x) for x in top.labels]
        gain_doc = _gain_document(design.gain)
        doc["kind"] = self.name
        doc["subject"]["digital"] = {
            "period": dg.period,
            "delay": dg.delay,
            "gain": gain_doc,
            "noise": design.noise_document(),
            "loss": {
                "policy": dg.policy,
                "edges": [{"from": lab[j], "to": lab[i], "p": p} for (i, j), p in losses.items()],
            },
        }
        why = None
        if dg.policy == "hold" and dg.delay:
            why = "hold is certified for D = 0 (a delay is not)"
        pl = None
        if why is None and dg.policy == "hold":
            edges = loss_edges(top, losses)
            noises = edge_noises(top, design.f_matrix(d), design.sigma, design.sigma_edges)
            lap = design.base.grounded_laplacian()
            res_h, why = issue_hold(doc, lap, edges, noises, d, dg.period, gain_doc)
            if res_h is not None:
                res_h["p_max"] = max(losses.values())
                doc["results"]["digital"] = res_h
                doc["certifies"] = [*doc["certifies"], MS.value]
                doc["claims"] = [*doc["claims"], *(c.to_dict() for c in hold_claims(mode))]
                doc.pop("digest", None)
                return finish(doc)
        elif why is None:
            edges = loss_edges(top, losses)
            noises = edge_noises(top, design.f_matrix(d), design.sigma, design.sigma_edges)
            lap = design.base.grounded_laplacian()
            pm = doc["matrices"]["P"]
            fixed = np.array(pm["lyapunov"]) if "lyapunov" in pm else None
            if dg.delay:  # the delay line's functional over the arrivals
                return self._issue_delayed(doc, design, lap, edges, noises, gain_doc, mode)
            pl = plan_loss(lap, edges, noises, d, dg.period, dg.policy, fixed)
            if pl is None:
                why = "no Lyapunov matrix gives α > 0 for the mean matrix"
        t0, how = gain_t0(gain_doc, pl.kappa) if pl is not None else (None, "")
        if why is None and t0 is None and pl is not None:
            why = f"c(t) does not stay below κ = {pl.kappa:.6g}: {how}"
        if why is not None or pl is None or t0 is None:
            doc["results"]["digital"] = {"stopped": why}
            doc.pop("digest", None)
            return finish(doc)
        doc["matrices"]["P"][P_NAME] = pl.p.tolist()
        res: dict[str, Any] = {
            "P_from": pl.source,
            "policy": dg.policy,
            "p_max": max(losses.values()),
            "alpha": pl.alpha,
            "kappa": pl.kappa,
            "t0": t0,
            "t0_proof": how,
            "k0": first_step(t0, dg.period, 0),
        }
        if dg.policy == "skip":
            norm2 = exact_offset(lap, edges, np.asarray(design.base.theta, dtype=float), d)
            if norm2 is None:
                doc["results"]["digital"] = {"stopped": "the offset's exact solve is too large"}
                doc["matrices"]["P"].pop(P_NAME)
                doc.pop("digest", None)
                return finish(doc)
            res["offset"] = offset_value(norm2)
        doc["results"]["digital"] = res
        doc["certifies"] = [*doc["certifies"], MS.value]
        doc["claims"] = [*doc["claims"], *(c.to_dict() for c in loss_claims(mode, dg.policy))]
        doc.pop("digest", None)
        return finish(doc)

    def _issue_delayed(
        self, doc: dict, design: Any, lap: Any, edges: Any, noises: Any, gain: Any, mode: str
    ) -> dict:
        """The delayed section (:mod:`.digital_loss_delay`) and, under skip, the offset."""
        dg, top = design.digital, design.base.topology
        res, why = issue_delayed(doc, lap, edges, noises, top.dim, dg, gain, P_NAME)
        norm2 = None
        if res is not None and dg.policy == "skip":
            norm2 = exact_offset(lap, edges, np.asarray(design.base.theta, dtype=float), top.dim)
            if norm2 is None:
                res, why = None, "the offset's exact solve is too large"
        if res is None:
            for k in [k for k in doc["matrices"]["P"] if k == P_NAME or k.startswith(P_NAME + "_")]:
                doc["matrices"]["P"].pop(k)
            doc["results"]["digital"] = {"stopped": why}
        else:
            res["p_max"] = max(e.p for e in edges)
            if norm2 is not None:
                res["offset"] = offset_value(norm2)
            doc["results"]["digital"] = res
            doc["certifies"] = [*doc["certifies"], MS.value]
            claims = delayed_claims(mode, dg.policy, P_NAME)
            doc["claims"] = [*doc["claims"], *(c.to_dict() for c in claims)]
        doc.pop("digest", None)
        return finish(doc)

    def read(self, doc: dict, source: str) -> Reading:
        """The ``hurwitz`` reading with the sampled and lossy subject and the stated numbers.

        Parameters
        ----------
        doc : dict
            The certificate.
        source : str
            Its name.

        Returns
        -------
        Reading
        """
        reading = HurwitzKind.read(self, doc, source)
        mode = next(iter(reading.state.modes.values()))
        sampled = read_digital(doc, source, mode.top.dim, ("loss",))
        loss = read_loss(doc, source, mode.top)
        stated: LossStated | HoldStated | None = None
        if MS.value in doc.get("certifies", []):
            res = need(need(doc, "results", dict, source), "digital", dict, f"{source}: results")
            where = f"{source}: results.digital"

            def num(key: str) -> float:
                return number(need(res, key, (int, float), where), f"{where}.{key}")

            if loss.policy == "hold":
                stated = read_hold(res, where)
            else:
                off = num("offset") if loss.policy == "skip" else None
                g = num("g") if sampled.delay else None
                stated = LossStated(num("alpha"), num("kappa"), num("t0"), off, g)
        state = LossState(sampled, loss, stated)
        return replace(reading, state=DigitalContext(reading.state, state))

    def claims(
        self, properties: tuple[Property, ...], subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        """The ``hurwitz`` claims and, for the sampled property, :func:`loss_claims`.

        Parameters
        ----------
        properties : tuple of Property
            What the certificate certifies.
        subject : Subject
            Its subject.
        reading : Reading
            From :meth:`read`.
        alpha : float
            The decay rate.

        Returns
        -------
        tuple of Claim
        """
        base = tuple(p for p in properties if p is not MS)
        out = HurwitzKind.claims(self, base, subject, reading, alpha)
        if MS in properties:
            ctx: DigitalContext[LossState] = reading.state
            hold = ctx.digital.loss.policy == "hold"
            if hold and ctx.digital.subject.delay:
                raise InputError(
                    "digital_mean_square on lossy links with hold needs D = 0",
                    field=f"{ctx.source}: certifies",
                )
            mode = next(iter(ctx.modes))
            if hold:
                out = (*out, *hold_claims(mode))
            elif ctx.digital.subject.delay:
                out = (*out, *delayed_claims(mode, ctx.digital.loss.policy, P_NAME))
            else:
                out = (*out, *loss_claims(mode, ctx.digital.loss.policy))
        return out

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        """Prove one claim from the certificate's content.

        Parameters
        ----------
        claim : Claim
            The claim.
        subject : Subject
            The subject.
        reading : Reading
            From :meth:`read`.

        Returns
        -------
        Check
        """
        if claim.prop is not MS:
            return HurwitzKind.prove(self, claim, subject, reading)
        if claim.kind is ClaimKind.PD:
            return prove_dense(claim, subject, reading)
        ctx: DigitalContext[LossState] = reading.state
        dg, st, ls = ctx.digital.subject, ctx.digital.stated, ctx.digital.loss
        assert st is not None  # the sampled property's claims: its numbers were read
        if claim.kind is ClaimKind.DIGITAL_T0:
            ok, how = prove_gain_below(dg.gain, st.kappa, st.t0)
            return Check(
                claim.id, ok is True, f"interval: {how} (κ = {st.kappa!r}, t₀ = {st.t0!r})", claim
            )
        if claim.kind in (ClaimKind.DIGITAL_DL_FORM, ClaimKind.DIGITAL_GROWTH):  # mode-free
            return prove_delayed(claim, ctx, None, [], [], P_NAME)
        mode = ctx.modes.get(claim.mode or "")
        if mode is None:
            return Check(claim.id, False, f"no mode {claim.mode!r} in the certificate", claim)
        edges = loss_edges(mode.top, ls.losses)
        d = mode.top.dim
        if (claim.kind in HOLD_CLAIMS) != (ls.policy == "hold"):
            return Check(claim.id, False, "a claim of another policy's section", claim)
        if claim.kind in HOLD_CLAIMS:
            noises = edge_noises(mode.top, dg.f, dg.sigma, dg.sigma_edges)
            return prove_hold(claim, ctx, st, dg, mode, edges, noises)
        if claim.kind is ClaimKind.LOSS_DL_STEP:
            noises = edge_noises(mode.top, dg.f, dg.sigma, dg.sigma_edges)
            return prove_delayed(claim, ctx, mode, edges, noises, P_NAME)
        assert isinstance(st, LossStated)  # hold's claims returned above
        if claim.kind is ClaimKind.LOSS_OFFSET:
            if mode.exact is None or st.offset is None:
                return Check(claim.id, False, "the exact L_B is not available", claim)
            scale = 2**mode.exact.exp
            lap = np.vectorize(lambda v: Fraction(int(v), scale), otypes=[object])(mode.exact.num)
            norm2 = exact_offset(lap, edges, mode.theta, d)
            if norm2 is None:
                return Check(claim.id, False, "L̄ is singular or too large to solve", claim)
            want = offset_value(norm2)
            ok = abs(st.offset - want) <= OFFSET_RTOL * max(want, 1e-300)
            return Check(claim.id, ok, f"exact rational solve: ‖x* − 1⊗θ‖ = {want:.12g}", claim)
        p = ctx.p(P_NAME)
        if p is None:
            return Check(claim.id, False, f"matrices.P.{P_NAME} has {RANGE_TEXT}", claim)
        if (
            not mode.in_range
            or any(out_of_range(x) for x in (st.alpha, st.kappa))
            or not (st.alpha > 0 and st.kappa > 0)
        ):
            return Check(claim.id, False, f"α or κ has {RANGE_TEXT} (or is not > 0)", claim)
        noises = edge_noises(mode.top, dg.f, dg.sigma, dg.sigma_edges)

        def build(exact: bool) -> Any:
            pm = Dyadic.of(p) if exact else FloatMat.of(p)
            lap = mode.exact if exact else FloatMat.of(mode.lap, mode.err)
            return loss_ms_matrix(
                pm, lap, edges, noises, d, st.alpha, st.kappa, dg.period, ls.policy
            )

        m = build(True) if mode.exact is not None else None
        if m is not None and exact_affordable(m.num.shape[0], m.bits):
            proof = prove_psd(m)
        else:
            proof = prove_psd(build(False))
        ctx.methods.add(proof.method)
        return Check(claim.id, proof.holds, f"{proof.method}: {proof.detail}", claim)

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        """Account for every number in ``results``.

        Parameters
        ----------
        audit : ResultsAudit
            The audit.
        doc : dict
            The certificate.
        subject : Subject
            Its subject.
        reading : Reading
            From :meth:`read`.
        alpha : float
            The decay rate.
        """
        HurwitzKind.audit(self, audit, doc, subject, reading, alpha)
        state: LossState = reading.state.digital
        if state.stated is None:
            sec = audit.get("digital")
            if isinstance(sec, dict):
                for key, v in sec.items():
                    if isinstance(v, (int, float)) and not isinstance(v, bool):
                        audit.fail(f"digital.{key}: a number for a property not certified")
                        audit.informational(("digital", key))
            return
        # the words the rows print are the subject's, never the file's: the policy, and at
        # D >= 1 the delay line's functional (the one proof of a delay on lossy links)
        audit.exact(("digital", "policy"), state.loss.policy)
        if state.subject.delay:
            audit.exact(("digital", "bound"), DELAY_LINE)
        elif "bound" in (audit.get("digital") or {}):
            audit.fail("digital.bound: states a delay line's functional without a delay")
        if state.loss.policy == "hold":
            audit_hold(audit, state)
            return
        for key in ("alpha", "kappa", "t0") + (("offset",) if state.loss.policy == "skip" else ()):
            audit.proven(("digital", key))
        dg = state.subject
        if dg.delay:
            audit.proven(("digital", "g"))
            # c_true on lossy links is shown beside κ, not claimed: the step inequality at a
            # constant c <= κ makes the lossy second-moment map contract, so it is >= κ
            if "c_true" in (doc.get("results", {}).get("digital") or {}):
                audit.estimate(("digital", "c_true"), state.stated.kappa, None)
        audit.exact(("digital", "k0"), first_step(state.stated.t0, dg.period, dg.delay))
        audit.exact(("digital", "p_max"), max(state.loss.losses.values(), default=0.0))

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        """What the certificate reports, as rows.

        Parameters
        ----------
        results : dict
            Its ``results``.

        Returns
        -------
        tuple of ResultRow
        """
        base = HurwitzKind.rows(self, results)
        r = results.get("digital") or {}
        if "stopped" in r:
            return (
                *base,
                ResultRow("sampled protocol, lossy links", f"not certified: {r['stopped']}"),
            )
        where = (
            f"to x* at ‖x* − 1⊗θ‖ = {number_text(r.get('offset'))} (skip)"
            if "offset" in r
            else f"to 1⊗θ (hold; {hold_detail(r)})"
            if r.get("policy") == "hold"
            else "to 1⊗θ (rescale)"
        )
        return (
            *base,
            ResultRow(
                "sampled protocol, lossy links",
                f"p_e <= {number_text(r.get('p_max'))}: E‖x − x*‖² contracts from step "
                f"k₀ = {r.get('k0')} (c(t) < κ = {number_text(r.get('kappa'))} from "
                f"t₀ = {number_text(r.get('t0'))}; α = {number_text(r.get('alpha'))}); the mean "
                f"goes {where}; P from {r.get('P_from')}"
                + (
                    f"; g = {number_text(r.get('g'))} (the delay line's functional)"
                    if r.get("bound") == DELAY_LINE
                    else ""
                ),
            ),
            *_limit_row(r),
        )

    def stated(
        self, properties: tuple[Property, ...], reading: Reading
    ) -> tuple[tuple[Property, str], ...]:
        """The numbers each property states.

        Parameters
        ----------
        properties : tuple of Property
            The certified properties.
        reading : Reading
            From :meth:`read`.

        Returns
        -------
        tuple of (Property, str)
        """
        base = HurwitzKind.stated(self, properties, reading)
        state: LossState = reading.state.digital
        st, dg = state.stated, state.subject
        if MS not in properties or st is None:
            return base
        k0 = first_step(st.t0, dg.period, dg.delay)
        offset = getattr(st, "offset", None)
        off = f", x* at {offset:.6g} from 1⊗θ" if offset is not None else ""
        return (*base, (MS, f"h = {dg.period:g}, lossy links: from step k₀ = {k0}{off}"))

    def verdicts(
        self, design: Any, certificate: dict, verification: Any, gain: Any
    ) -> tuple[TheoremVerdict, ...]:
        """The continuous verdicts and their sampled analogues on lossy links.

        Parameters
        ----------
        design : DigitalDesign
            The design.
        certificate : dict
            The certificate.
        verification : Verification
            Its verification.
        gain : GainAnalysis or None
            The gain's conditions.

        Returns
        -------
        tuple of TheoremVerdict
        """
        base = HurwitzKind.verdicts(self, design.base, certificate, verification, gain)
        r = certificate["results"].get("digital", {})
        dg = design.digital
        if "stopped" in r:
            detail = r["stopped"]
        elif "offset" in r:
            detail = (
                f"k₀ = {r['k0']}, lossy links (skip): converges to x*, "
                f"‖x* − 1⊗θ‖ = {r['offset']:.4g}, not to θ"
            )
        else:
            detail = f"k₀ = {r['k0']}, lossy links ({r.get('policy', 'rescale')}): converges to θ"
        return (*base, *digital_verdicts(base, verification, gain, dg.period, dg.delay, detail))


__all__ = [
    "DigitalLossKind",
    "LossState",
    "LossStated",
    "LossSubject",
    "design_losses",
    "loss_claims",
    "read_loss",
]
