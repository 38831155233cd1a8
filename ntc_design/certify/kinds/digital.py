"""Kinds ``digital`` and ``digital_switching``: a ``hurwitz`` or ``switching`` certificate
whose design runs as the sampled protocol (period h, delay D; :mod:`ntc_design.protocol.digital`),
with the proof that the sampled recursion contracts in mean square from step k₀ on
(:mod:`ntc_design.certify.digital` states the mathematics).

The subject adds ``digital: {period, delay, gain, noise}``; the matrices add ``P.digital``;
``results.digital`` states α, κ, γ, t₀ and k₀. For D > 0 ``results.digital.bound`` says
which functional proves the contraction: ``delay_line`` (:mod:`..delayline`: the matrices
add ``P.digital_R<j>`` and ``P.digital_T<j>``, the results the growth bound g of 1/c and
γ' as ``gamma``) or ``razumikhin`` (β, ℓ²; absent in older certificates). Every one of
them is proven by a derived claim (k₀ = ⌈t₀/h⌉ + D recomputed exactly); ``c_true``, the
mean-square limit shown beside κ, is an estimate checked only against the proven κ. When no level can be
certified (no P gives α > 0, or the gain never stays below κ) the certificate certifies the
continuous properties only and ``results.digital.stopped`` says where it stopped.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any, ClassVar, Generic, TypeVar

import numpy as np

from ...errors import InputError
from ...gain.schedule import ScheduleGain
from ...numerics.linalg import RANGE_TEXT, out_of_range
from ...protocol.digital import Digital, DigitalDesign
from ...rigorous.exact import Dyadic, exact_affordable
from ...rigorous.floatmat import FloatMat
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..delayline import (
    delay_line_gamma,
    form_matrices,
    growth_bound,
    ms_limit,
    plan_delay_line,
    plan_no_delay,
    prove_growth,
    step_matrix,
)
from ..dense import DenseContext
from ..digital import (
    additive_energy,
    edge_noises,
    first_step,
    gain_t0,
    level_holds,
    lipschitz_matrix,
    ms_matrix,
    noise_matrix,
    plan,
    prove_gain_below,
    prove_psd,
    scaled,
)
from ..fields import matrix, need, number
from ..format import finish, scheduled_modes
from ..theorems import TheoremVerdict, digital_verdicts
from .base import (
    CertificateKind,
    IssueOptions,
    Reading,
    ResultRow,
    ResultsAudit,
    Subject,
    number_text,
)
from .dense import prove_dense
from .hurwitz import HurwitzKind
from .switching import SwitchingKind

P_NAME = "digital"
MS = Property.DIGITAL_MEAN_SQUARE
#: The bounds a delayed certificate may use (``results.digital.bound``; absent: Razumikhin).
DELAY_LINE, RAZUMIKHIN = "delay_line", "razumikhin"
#: The largest (D+1)·Nd for which the delay line's SDP is tried at issue.
DELAY_LINE_MAX_ORDER = 200


@dataclass(frozen=True, eq=False)
class DigitalSubject:
    """``subject.digital`` as read: the period, the delay, the gain (text or a schedule
    document) and the noise (F as a d×d matrix, σ, per-edge σ by (from, to) labels)."""

    period: float
    delay: int
    gain: Any
    f: np.ndarray
    sigma: float
    sigma_edges: dict


@dataclass(frozen=True)
class Stated:
    """``results.digital``'s numbers that the claims use."""

    alpha: float
    kappa: float
    gamma: float
    t0: float
    beta: float | None
    ell2: float | None
    bound: str = RAZUMIKHIN
    g: float | None = None

    @property
    def growth(self) -> float:
        """g, which a delay-line certificate states (its claims are derived from it)."""
        assert self.g is not None, "a delay-line certificate states g"
        return self.g

    @property
    def razumikhin(self) -> tuple[float, float]:
        """β and ℓ², which a Razumikhin certificate with D > 0 states."""
        assert self.beta is not None and self.ell2 is not None, "Razumikhin states β, ℓ²"
        return self.beta, self.ell2


@dataclass(frozen=True, eq=False)
class DigitalState:
    """What a digital kind reads beside its base kind's dense modes: ``subject.digital``
    and ``results.digital``'s numbers (None when the certificate does not certify the
    sampled property)."""

    subject: DigitalSubject
    stated: Stated | None


StateT = TypeVar("StateT")


class DigitalContext(DenseContext, Generic[StateT]):
    """The reading state of a digital certificate: its base kind's :class:`DenseContext`
    (read as one by the base kind's provers, the exporter and the deadline figures) and
    the digital kind's frozen state, ``digital`` (a :class:`DigitalState`; for
    ``digital_loss`` its own)."""

    def __init__(self, dense: DenseContext, digital: StateT) -> None:
        super().__init__(dense.source, dense.n, dense.modes, dense.ps)
        self.digital = digital


def _gain_document(gain: Any) -> Any:
    if isinstance(gain, ScheduleGain):
        return gain.to_document()
    if isinstance(gain, str):
        return gain
    raise InputError(
        "the digital certificate needs c(t) as an expression or a schedule", field="gain"
    )


def _only(doc: Any, known: tuple[str, ...], where: str) -> None:
    """Refuse a field this reader does not read, naming it."""
    if isinstance(doc, dict):
        unknown = sorted(str(k) for k in doc if k not in known)
        if unknown:
            raise InputError(
                f"unknown field (known: {', '.join(known)})", field=f"{where}.{unknown[0]}"
            )


def read_digital(doc: dict, source: str, d: int, extra: tuple[str, ...] = ()) -> DigitalSubject:
    """Parse ``subject.digital``.

    Parameters
    ----------
    doc : dict
        The certificate.
    source : str
        Its name, for messages.
    d : int
        The state dimension.
    extra : tuple of str, optional
        Fields a derived kind reads itself (``loss``), allowed beside the digital ones.

    Returns
    -------
    DigitalSubject

    Raises
    ------
    InputError
        A missing or malformed field.
    """
    where = f"{source}: subject.digital"
    sub = need(need(doc, "subject", dict, source), "digital", dict, f"{source}: subject")
    _only(sub, ("period", "delay", "gain", "noise", *extra), where)
    try:
        dg = Digital(sub.get("period"), sub.get("delay"))
    except InputError as exc:
        raise InputError(f"subject.{exc}", field=source) from None
    gain = sub.get("gain")
    if isinstance(gain, dict):
        ScheduleGain(
            gain.get("t"),
            gain.get("c"),
            gain.get("interpolation", "linear"),
            gain["tail"] if isinstance(gain.get("tail"), str) else "",
            f"{where}.gain",
        )
    elif not isinstance(gain, str):
        raise InputError("expected an expression in t or a schedule", field=f"{where}.gain")
    noise = need(sub, "noise", dict, where)
    _only(noise, ("sigma", "f", "sigma_edges"), f"{where}.noise")
    if isinstance(gain, dict):
        _only(gain, ("t", "c", "interpolation", "tail"), f"{where}.gain")
    sigma = number(need(noise, "sigma", (int, float), f"{where}.noise"), f"{where}.noise.sigma")
    if sigma < 0:
        raise InputError("must be >= 0", field=f"{where}.noise.sigma")
    f_raw = need(noise, "f", (int, float, list), f"{where}.noise")
    f = (
        number(f_raw, f"{where}.noise.f") * np.eye(d)
        if not isinstance(f_raw, list)
        else matrix(f_raw, d, f"{where}.noise.f")
    )
    edges: dict = {}
    for k, e in enumerate(need(noise, "sigma_edges", list, f"{where}.noise")):
        w = f"{where}.noise.sigma_edges[{k}]"
        _only(e, ("from", "to", "sigma"), w)
        if (
            not isinstance(e, dict)
            or not isinstance(e.get("from"), str)
            or not isinstance(e.get("to"), str)
        ):
            raise InputError("expected {from, to, sigma}", field=w)
        s = number(need(e, "sigma", (int, float), w), f"{w}.sigma")
        if s < 0:
            raise InputError("must be >= 0", field=f"{w}.sigma")
        edges[(e["from"], e["to"])] = s
    if out_of_range(f) or out_of_range(sigma) or any(out_of_range(v) for v in edges.values()):
        raise InputError(f"{RANGE_TEXT}", field=f"{where}.noise")
    return DigitalSubject(dg.period, dg.delay, gain, f, sigma, edges)


def _stated(doc: dict, source: str, delay: int) -> Stated:
    res = need(need(doc, "results", dict, source), "digital", dict, f"{source}: results")
    where = f"{source}: results.digital"

    def num(key: str) -> float:
        return number(need(res, key, (int, float), where), f"{where}.{key}")

    bound = res.get("bound", RAZUMIKHIN) if delay else RAZUMIKHIN
    if bound not in (DELAY_LINE, RAZUMIKHIN):
        raise InputError(f"expected {DELAY_LINE!r} or {RAZUMIKHIN!r}", field=f"{where}.bound")
    raz = bool(delay) and bound == RAZUMIKHIN
    return Stated(
        num("alpha"),
        num("kappa"),
        num("gamma"),
        num("t0"),
        num("beta") if raz else None,
        num("ell2") if raz else None,
        bound,
        num("g") if bound == DELAY_LINE else None,
    )


def digital_claims(
    modes: tuple[str, ...], delay: int, bound: str = RAZUMIKHIN
) -> tuple[Claim, ...]:
    """The claims the sampled contraction needs for the scheduled modes.

    Parameters
    ----------
    modes : tuple of str
        The modes the schedule uses (the one mode of a fixed topology).
    delay : int
        D.
    bound : str, optional
        For D > 0: ``"razumikhin"`` or ``"delay_line"``
        (:mod:`ntc_design.certify.delayline`).

    Returns
    -------
    tuple of Claim
    """
    if delay and bound == DELAY_LINE:
        dl = [Claim(ClaimKind.DIGITAL_DL_FORM, MS, p=P_NAME)]
        dl += [Claim(ClaimKind.DIGITAL_DL_STEP, MS, mode=m, p=P_NAME) for m in modes]
        dl += [
            Claim(ClaimKind.DIGITAL_DL_ADDITIVE, MS, p=P_NAME),
            Claim(ClaimKind.DIGITAL_GROWTH, MS),
            Claim(ClaimKind.DIGITAL_T0, MS),
        ]
        return tuple(dl)
    out = [Claim(ClaimKind.PD, MS, p=P_NAME)]
    out += [Claim(ClaimKind.DIGITAL_MS, MS, mode=m, p=P_NAME) for m in modes]
    if delay:
        out += [Claim(ClaimKind.DIGITAL_NOISE, MS, mode=m, p=P_NAME) for m in modes]
        out += [Claim(ClaimKind.DIGITAL_LIPSCHITZ, MS, mode=m, p=P_NAME) for m in modes]
        out.append(Claim(ClaimKind.DIGITAL_LEVEL, MS))
    out += [Claim(ClaimKind.DIGITAL_ADDITIVE, MS, p=P_NAME), Claim(ClaimKind.DIGITAL_T0, MS)]
    return tuple(out)


class _DigitalMixin:
    """What the two digital kinds add to their dense base kind (``hurwitz`` or
    ``switching``): issuing the digital section, its claims, proofs, audit, rows and
    verdicts."""

    base_name: str  # the base kind's name
    name: ClassVar[str]

    @property
    def _base(self) -> Any:
        # the base kind's methods (next in the method resolution order)
        return super()

    # -------------------------------------------------------------- issuing
    def _modes_of(self, design: DigitalDesign) -> dict[str, Any]:
        base = design.base
        if hasattr(base, "switching"):
            used = scheduled_modes(base.switching.schedule)
            return {k: base.modes[k] for k in used}
        return {base.topology.name or "topology": base}

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """The base certificate with the digital section (see the module docstring).

        Parameters
        ----------
        design : DigitalDesign
            The design and its sampling.
        options : IssueOptions, optional
            As for the base kind.

        Returns
        -------
        dict
        """
        doc = self._base.issue(design.base, options)
        dg = design.digital
        modes = self._modes_of(design)
        d = next(iter(modes.values())).topology.dim
        f = design.f_matrix(d)
        noises = [
            edge_noises(m.topology, f, design.sigma, design.sigma_edges) for m in modes.values()
        ]
        laps = [m.grounded_laplacian() for m in modes.values()]
        fixed = (
            np.array(doc["matrices"]["P"]["lyapunov"])
            if "lyapunov" in doc["matrices"]["P"]
            else None
        )
        gain_doc = _gain_document(design.gain)
        doc["kind"] = self.name
        doc["subject"]["digital"] = {
            "period": dg.period,
            "delay": dg.delay,
            "gain": gain_doc,
            "noise": design.noise_document(),
        }
        pl = plan(laps, noises, d, dg.period, dg.delay, fixed)
        c_true, c_how = ms_limit(laps, noises, d, dg.period, dg.delay)
        if not dg.delay and c_true is not None and laps[0].shape[0] <= DELAY_LINE_MAX_ORDER:
            free = plan_no_delay(laps, noises, d, dg.period, c_true)  # a free P
            if free is not None and (pl is None or free.kappa > pl.kappa):
                pl = free
        t0, how = gain_t0(gain_doc, pl.kappa) if pl is not None else (None, "")
        dl = self._delay_line(laps, noises, d, dg.period, dg.delay, gain_doc, c_true)
        dl_t0: tuple[float | None, str] = (None, "")
        if dl is not None and (pl is None or t0 is None or dl.kappa > pl.kappa):
            dl_t0 = gain_t0(gain_doc, dl.kappa)
            if dl_t0[0] is not None and prove_growth(gain_doc, dl.g, dl_t0[0])[0] is not True:
                dl_t0 = (None, "")
        if t0 is None and dl_t0[0] is None:
            why = (
                "no Lyapunov matrix gives α > 0 for every mode"
                if pl is None
                else f"c(t) does not stay below κ = {pl.kappa:.6g}: {how}"
            )
            doc["results"]["digital"] = {"stopped": why}
            doc.pop("digest", None)
            return finish(doc)
        res: dict[str, Any]
        if dl is not None and dl_t0[0] is not None:
            t0, how = float(dl_t0[0]), dl_t0[1]
            doc["matrices"]["P"][P_NAME] = dl.s.tolist()
            for j, (r, t) in enumerate(zip(dl.rs, dl.ts, strict=True)):
                doc["matrices"]["P"][f"{P_NAME}_R{j}"] = r.tolist()
                doc["matrices"]["P"][f"{P_NAME}_T{j}"] = t.tolist()
            res = {"bound": DELAY_LINE, "P_from": "the delay line's SDP (Clarabel)"}
            res.update(alpha=dl.alpha, kappa=dl.kappa, gamma=dl.gamma, g=dl.g)
        else:
            assert pl is not None and t0 is not None
            doc["matrices"]["P"][P_NAME] = pl.p.tolist()
            res = {"bound": RAZUMIKHIN} if dg.delay else {}
            res.update(P_from=pl.source, alpha=pl.alpha, kappa=pl.kappa, gamma=pl.gamma)
            if dg.delay:
                res["beta"], res["ell2"] = pl.beta, pl.ell2
        assert t0 is not None
        res.update(t0=t0, t0_proof=how, k0=first_step(t0, dg.period, dg.delay))
        if c_true is not None:
            res["c_true"] = c_true
        res["c_true_how"] = c_how
        doc["results"]["digital"] = res
        doc["certifies"] = [*doc["certifies"], MS.value]
        claims = digital_claims(tuple(modes), dg.delay, res.get("bound", RAZUMIKHIN))
        doc["claims"] = [*doc["claims"], *(c.to_dict() for c in claims)]
        doc.pop("digest", None)
        return finish(doc)

    @staticmethod
    def _delay_line(
        laps: list, noises: list, d: int, h: float, delay: int, gain: Any, c_true: float | None
    ) -> Any:
        # the delay line's functional (D >= 1, an expression gain, a size the SDP affords)
        if not delay or c_true is None or laps[0].shape[0] * (delay + 1) > DELAY_LINE_MAX_ORDER:
            return None
        g = growth_bound(gain)
        return None if g is None else plan_delay_line(laps, noises, d, h, delay, g, c_true)

    # -------------------------------------------------------------- verifying
    def read(self, doc: dict, source: str) -> Reading:
        reading = self._base.read(doc, source)
        d = next(iter(reading.modes.values())).d
        sampled = read_digital(doc, source, d)
        stated = None
        if MS.value in doc.get("certifies", []):
            stated = _stated(doc, source, sampled.delay)
        state = DigitalState(sampled, stated)
        return replace(reading, state=DigitalContext(reading.state, state))

    def claims(
        self, properties: tuple[Property, ...], subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        base = tuple(p for p in properties if p is not MS)
        out = self._base.claims(base, subject, reading, alpha)
        if MS in properties:
            state: DigitalState = reading.state.digital
            bound = state.stated.bound if state.stated is not None else RAZUMIKHIN
            out = (*out, *digital_claims(subject.scheduled, state.subject.delay, bound))
        return out

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        if claim.prop is not MS:
            return self._base.prove(claim, subject, reading)
        if claim.kind is ClaimKind.PD:
            return prove_dense(claim, subject, reading)
        ctx: DigitalContext[DigitalState] = reading.state
        dg, st = ctx.digital.subject, ctx.digital.stated
        assert st is not None  # the sampled property's claims: its numbers were read
        if claim.kind is ClaimKind.DIGITAL_T0:
            ok, how = prove_gain_below(dg.gain, st.kappa, st.t0)
            return Check(
                claim.id, ok is True, f"interval: {how} (κ = {st.kappa!r}, t₀ = {st.t0!r})", claim
            )
        if claim.kind is ClaimKind.DIGITAL_GROWTH:
            ok, how = prove_growth(dg.gain, st.growth, st.t0)
            return Check(claim.id, ok is True, f"interval: {how}", claim)
        if claim.kind in (ClaimKind.DIGITAL_DL_FORM, ClaimKind.DIGITAL_DL_STEP):
            return self._prove_delay_line(claim, subject, ctx)
        if claim.kind is ClaimKind.DIGITAL_DL_ADDITIVE:
            mats = self._delay_line_matrices(ctx)
            if mats is None:
                return Check(claim.id, False, f"matrices.P has {RANGE_TEXT}", claim)
            worst = max(
                delay_line_gamma(
                    mats[0], mats[2], edge_noises(m.top, dg.f, dg.sigma, dg.sigma_edges), m.top.dim
                )
                for k, m in ctx.modes.items()
                if k in subject.scheduled
            )
            ok = Fraction(st.gamma) >= worst
            return Check(
                claim.id, ok, f"exact fractions: γ(S) + Σ γ(T_j) = {float(worst):.10g}", claim
            )
        if claim.kind is ClaimKind.DIGITAL_LEVEL:
            ok, how = level_holds(st.kappa, st.alpha, *st.razumikhin, dg.period, dg.delay)
            return Check(claim.id, ok, how, claim)
        p = ctx.p(P_NAME)
        if p is None:
            return Check(claim.id, False, f"matrices.P.{P_NAME} has {RANGE_TEXT}", claim)
        if claim.kind is ClaimKind.DIGITAL_ADDITIVE:
            worst = max(
                additive_energy(p, edge_noises(m.top, dg.f, dg.sigma, dg.sigma_edges), m.top.dim)
                for k, m in ctx.modes.items()
                if k in subject.scheduled
            )
            ok = Fraction(st.gamma) >= worst
            return Check(claim.id, ok, f"exact fractions: Σ g_eᵀPg_e = {float(worst):.10g}", claim)
        return self._prove_matrix(claim, ctx, p)

    @staticmethod
    def _delay_line_matrices(ctx: DigitalContext[DigitalState]) -> Any:
        # S, R_j, T_j of a delay-line certificate (None: an entry out of range)
        delay = ctx.digital.subject.delay
        try:  # a matrix missing (a forged delay) fails the claim
            s = ctx.p(P_NAME)
            rs = [ctx.p(f"{P_NAME}_R{j}") for j in range(delay)]
            ts = [ctx.p(f"{P_NAME}_T{j}") for j in range(delay)]
        except InputError:
            return None
        if s is None or any(x is None for x in rs + ts):
            return None
        return s, rs, ts

    def _prove_delay_line(
        self, claim: Claim, subject: Subject, ctx: DigitalContext[DigitalState]
    ) -> Check:
        dg, st = ctx.digital.subject, ctx.digital.stated
        assert st is not None  # the sampled property's claims: its numbers were read
        g = st.growth
        mats = self._delay_line_matrices(ctx)
        nums = [st.alpha, st.kappa, g, dg.period]
        if mats is None or any(out_of_range(x) for x in nums):
            return Check(claim.id, False, f"matrices.P or α, κ, g have {RANGE_TEXT}", claim)
        if not (st.alpha > 0 and st.kappa > 0 and g >= 0):
            return Check(claim.id, False, "α, κ must be > 0 and g >= 0", claim)
        s, rs, ts = mats
        if claim.kind is ClaimKind.DIGITAL_DL_FORM:

            def build(exact: bool) -> list:
                return form_matrices(s, rs, ts, st.alpha, st.kappa, g, dg.period, exact)

            exact = exact_affordable(s.shape[0], 4 * max(Dyadic.of(m).bits for m in [s, *rs, *ts]))
            details = []
            for name, m in build(exact):
                proof = prove_psd(m)
                ctx.methods.add(proof.method)
                if not proof.holds:
                    return Check(claim.id, False, f"{name}: {proof.method}: {proof.detail}", claim)
                details.append(name)
            return Check(
                claim.id,
                True,
                f"{'exact' if exact else 'verified floats'}: {', '.join(details)} ≻ 0",
                claim,
            )
        mode = ctx.modes.get(claim.mode or "")
        if mode is None or claim.mode not in subject.scheduled:
            return Check(
                claim.id, False, f"the certificate does not describe mode {claim.mode!r}", claim
            )
        if not mode.in_range:
            return Check(claim.id, False, f"mode {mode.name} has {RANGE_TEXT}", claim)
        edges = edge_noises(mode.top, dg.f, dg.sigma, dg.sigma_edges)

        def step(exact: bool) -> Any:
            lap = mode.exact if exact else FloatMat.of(mode.lap, mode.err)
            return step_matrix(
                s, rs, ts, lap, edges, mode.top.dim, st.alpha, st.kappa, g, dg.period, exact
            )

        m = step(True) if mode.exact is not None else None
        proof = (
            prove_psd(m)
            if m is not None and exact_affordable(m.num.shape[0], m.bits)
            else (prove_psd(step(False)))
        )
        ctx.methods.add(proof.method)
        return Check(claim.id, proof.holds, f"{proof.method}: {proof.detail}", claim)

    def _prove_matrix(
        self, claim: Claim, ctx: DigitalContext[DigitalState], p: np.ndarray
    ) -> Check:
        mode = ctx.modes.get(claim.mode or "")
        dg, st = ctx.digital.subject, ctx.digital.stated
        assert st is not None  # the sampled property's claims: its numbers were read
        if mode is None:
            return Check(
                claim.id, False, f"the certificate does not describe mode {claim.mode!r}", claim
            )
        nums = [st.alpha, st.kappa, dg.period] + (list(st.razumikhin) if dg.delay else [])
        if (
            not mode.in_range
            or any(out_of_range(x) for x in nums)
            or not (st.alpha > 0 and st.kappa > 0)
        ):
            return Check(
                claim.id, False, f"mode {mode.name}, α or κ has {RANGE_TEXT} (or is not > 0)", claim
            )
        edges = edge_noises(mode.top, dg.f, dg.sigma, dg.sigma_edges)
        d = mode.top.dim

        def build(exact: bool) -> Any:
            pm = Dyadic.of(p) if exact else FloatMat.of(p)
            lap = mode.exact if exact else FloatMat.of(mode.lap, mode.err)
            if claim.kind is ClaimKind.DIGITAL_MS:
                return ms_matrix(
                    pm, lap, noise_matrix(pm, edges, d, exact), st.alpha, st.kappa, dg.period
                )
            if claim.kind is ClaimKind.DIGITAL_NOISE:
                return scaled(pm, st.razumikhin[0]) - noise_matrix(pm, edges, d, exact)
            return lipschitz_matrix(pm, lap, st.razumikhin[1])

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
        # the base kind's results, then results.digital: every number stated by a claim
        # (proven there), k₀ recomputed exactly; a stopped section reports no number
        self._base.audit(audit, doc, subject, reading, alpha)
        state: DigitalState = reading.state.digital
        dg = state.subject
        if state.stated is None:
            sec = audit.get("digital")
            if isinstance(sec, dict) and any(isinstance(v, (int, float)) for v in sec.values()):
                for key, v in sec.items():
                    if isinstance(v, (int, float)) and not isinstance(v, bool):
                        audit.fail(f"digital.{key}: a number for a property not certified")
                        audit.informational(("digital", key))
            return
        st = state.stated
        extra: tuple[str, ...] = ()
        if dg.delay:
            extra = ("g",) if st.bound == DELAY_LINE else ("beta", "ell2")
        for key in ("alpha", "kappa", "gamma", "t0", *extra):
            audit.proven(("digital", key))
        # c_true (the second-moment map's stability limit) is shown beside κ, not claimed:
        # an estimate, bounded below by the proven κ (the inequality at a constant gain c <= κ
        # makes that map contract)
        if "c_true" in (doc.get("results", {}).get("digital") or {}):
            audit.estimate(("digital", "c_true"), st.kappa, None)
        audit.exact(("digital", "k0"), first_step(st.t0, dg.period, dg.delay))

    # -------------------------------------------------------------- presenting
    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        base = self._base.rows(results)
        r = results.get("digital") or {}
        if "stopped" in r:
            return (*base, ResultRow("sampled protocol", f"not certified: {r['stopped']}"))
        if r.get("bound") == DELAY_LINE:
            extra = f", g = {number_text(r.get('g'))} (the delay line's functional)"
        elif "beta" in r:
            extra = (
                f", β = {number_text(r.get('beta'))}, ℓ² = {number_text(r.get('ell2'))} "
                "(the Razumikhin bound)"
            )
        else:
            extra = ""
        rows = [
            ResultRow(
                "sampled protocol",
                f"contracts in mean square from step k₀ = {r.get('k0')} (t₀ = {number_text(r.get('t0'))}): "
                f"c(t) < κ = {number_text(r.get('kappa'))} from t₀ on; α = {number_text(r.get('alpha'))}, "
                f"γ = {number_text(r.get('gamma'))}{extra}; P from {r.get('P_from')}",
            )
        ]
        ct, kap = r.get("c_true"), r.get("kappa")
        if isinstance(ct, (int, float)) and isinstance(kap, (int, float)) and ct > 0:
            rows.append(
                ResultRow(
                    "mean-square limit",
                    f"κ = {kap:.4g} ({100 * kap / ct:.0f} % of the mean-square limit "
                    f"c_true = {ct:.4g}, the largest constant gain at which the sampled "
                    "second-moment map contracts; estimated, not a claim)",
                )
            )
        return (*base, *rows)

    def stated(
        self, properties: tuple[Property, ...], reading: Reading
    ) -> tuple[tuple[Property, str], ...]:
        base = self._base.stated(properties, reading)
        state: DigitalState = reading.state.digital
        st, dg = state.stated, state.subject
        if MS not in properties or st is None:
            return base
        k0 = first_step(st.t0, dg.period, dg.delay)
        return (
            *base,
            (MS, f"h = {dg.period:g}, D = {dg.delay}: from step k₀ = {k0} (κ = {st.kappa:.6g})"),
        )

    def verdicts(
        self, design: Any, certificate: dict, verification: Any, gain: Any
    ) -> tuple[TheoremVerdict, ...]:
        base = self._base.verdicts(design.base, certificate, verification, gain)
        r = certificate["results"].get("digital", {})
        dg = design.digital
        if "stopped" in r:
            detail = r["stopped"]
        else:
            detail = f"k₀ = {r['k0']} (t₀ = {r['t0']:.6g}, c(t) < κ = {r['kappa']:.6g} from t₀ on)"
        return (*base, *digital_verdicts(base, verification, gain, dg.period, dg.delay, detail))


class DigitalKind(_DigitalMixin, HurwitzKind):
    """One topology run as the sampled protocol: ``hurwitz`` plus the sampled contraction."""

    name = "digital"
    description = "one topology run as the sampled, delayed protocol (period h, delay D)"
    properties = (Property.HURWITZ, Property.DECAY_RATE, MS)
    required = frozenset({Property.HURWITZ})
    base_name = "hurwitz"
    subject_fields = frozenset({"modes", "digital"})

    def accepts(self, design: Any) -> bool:
        return isinstance(design, DigitalDesign) and HurwitzKind.accepts(self, design.base)


class DigitalSwitchingKind(_DigitalMixin, SwitchingKind):
    """A switching set run as the sampled protocol: ``switching`` plus the sampled
    contraction under the sampled schedule."""

    name = "digital_switching"
    description = "a switching topology run as the sampled, delayed protocol (period h, delay D)"
    properties = (Property.SYMMETRIC_PART, Property.COMMON_LYAPUNOV, MS)
    required = frozenset({Property.SYMMETRIC_PART})
    base_name = "switching"
    subject_fields = frozenset({"modes", "schedule", "switching_hash", "digital"})

    def accepts(self, design: Any) -> bool:
        return isinstance(design, DigitalDesign) and SwitchingKind.accepts(self, design.base)


# the mixin's overrides show the base class's documentation, as a kind's own do
for _name in ("issue", "read", "claims", "prove", "audit", "rows", "stated", "verdicts"):
    _member = getattr(_DigitalMixin, _name)
    _member.__doc__ = _member.__doc__ or getattr(CertificateKind, _name).__doc__

__all__ = [
    "DigitalContext",
    "DigitalKind",
    "DigitalState",
    "DigitalSubject",
    "DigitalSwitchingKind",
    "digital_claims",
    "read_digital",
]
