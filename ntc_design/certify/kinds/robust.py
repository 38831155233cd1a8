"""Kind ``robust``: one topology whose weights are known within a relative Loewner radius ρ
(:mod:`ntc_design.certify.robust.search`). It certifies the margin (−L_B(A') Hurwitz for every
realisation within ρ_lower), and where proven the decay bound α_lower and the consensus
offset bound √γ at ρ. ``ntc verify`` rebuilds every S-procedure matrix exactly (dyadic
rationals: P, the multipliers, ρ and α are doubles, the channel bases are the weights' own
pivot columns) and tests it by Sylvester's criterion, or by Rump's verified Cholesky when
the exact test is too large; the realisations reported as the other ends are re-checked
(inside the set, and attaining their figures) in floating point."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ...model import Topology
from ...protocol.lemma1 import coupling_matrix
from ...rigorous.exact import Dyadic
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..dense import PROVERS, DenseContext, DenseMode, mode_subject
from ..fields import need, number
from ..format import FORMAT, VERSION, finish
from ..robust import (
    ROBUST_MAX_ND,
    RobustDesign,
    RobustReport,
    abscissa,
    check_radius,
    radius_phrase,
    radius_text,
    uncertain_edges,
)
from ..robust.are import RICCATI_MAX_ND, RiccatiSearch
from ..robust.exact import (
    exact_channels,
    gamma_exact,
    prove_pd,
    psi_exact,
)
from ..robust.offset import OffsetSearch, input_float
from ..theorems import TheoremVerdict
from .base import (
    CertificateKind,
    IssueOptions,
    Reading,
    ResultRow,
    ResultsAudit,
    Subject,
    number_text,
)
from .dense import read_dense

REALISATION_RTOL = 1e-9  # a realisation may sit this far (relative) outside the set


def _radii(x: Any, m: int, where: str) -> np.ndarray:
    """The subject's radius: one number for every uncertain edge, or a list of m."""
    if isinstance(x, list):
        if len(x) != m:
            raise InputError(f"expected {m} radii, one per uncertain edge", field=where)
        return np.array([check_radius(v, where) for v in x], dtype=float)
    return np.full(m, check_radius(x, where))


def robust_certificate(rep: RobustReport, name: str | None = None) -> dict:
    """The ``robust`` certificate of a report of :func:`ntc_design.certify.robust.search.robust`.

    Parameters
    ----------
    rep : RobustReport
        The brackets and their proofs.
    name : str, optional
        The mode's name (default: the topology's name, or ``"topology"``).

    Returns
    -------
    dict
        The certificate: it certifies ``robust_margin`` when a margin radius was proven
        (ρ_lower, possibly 0), ``robust_decay`` with α_lower at ρ, ``robust_offset`` with
        γ at ρ when those were proven.

    Raises
    ------
    InputError
        A report of the sparse path alone (above
        :data:`ntc_design.certify.robust.are.RICCATI_MAX_ND`).
    """
    d = rep.design
    name = name or d.topology.name or "topology"
    pr = rep.proofs
    if not pr:  # the sparse path proves in the process; there is nothing to re-check
        raise InputError(
            f"a certificate is issued up to Nd = {RICCATI_MAX_ND} (this network: "
            f"Nd = {d.topology.nd}); above, the sparse bounds are proven but not stored",
            field="robust",
        )
    props: list[Property] = []
    mats: dict[str, Any] = {"L_B": {name: d.grounded_laplacian().tolist()}, "P": {}}
    mult: dict[str, Any] = {}
    uniform = len(set(rep.radii)) <= 1
    stated_radius: Any = rep.radius if uniform else list(rep.radii)
    results: dict[str, Any] = {
        "radius": stated_radius,
        "nominal_decay": rep.nominal_decay,
        "seconds": rep.seconds,
    }
    reals: dict[str, Any] = {}
    top = d.topology
    ed = uncertain_edges(top)
    if pr["margin"] is not None:
        props.append(Property.ROBUST_MARGIN)
        mats["P"]["robust_margin"] = pr["margin"][0].tolist()
        mult["robust_margin"] = pr["margin"][1].tolist()
        results["margin"] = {"lower": pr["margin_radius"]}
        if rep.margin.realisation is not None:
            results["margin"]["upper"] = rep.margin.upper
            reals["margin"] = {
                "radius": rep.margin.realisation.radius,
                "edges": rep.margin.realisation.edges(top, ed),
            }
    if pr["decay"] is not None:
        props.append(Property.ROBUST_DECAY)
        mats["P"]["robust_decay"] = pr["decay"][0].tolist()
        mult["robust_decay"] = pr["decay"][1].tolist()
        results["decay"] = {"lower": pr["alpha"]}
        if rep.decay.realisation is not None:
            results["decay"]["upper"] = rep.decay.upper
            reals["decay"] = {"edges": rep.decay.realisation.edges(top, ed)}
    if pr["offset"] is not None and Property.ROBUST_DECAY in props:
        gam, lam, y = pr["offset"]
        props.append(Property.ROBUST_OFFSET)
        mult["robust_offset"] = lam.tolist()
        if y is not None:  # past the LMI's size Y is a witness ntc verify rebuilds
            mats["Y"] = y.tolist()
        results["offset"] = {"gamma": gam, "upper": math.sqrt(gam)}
        if rep.offset.realisation is not None:
            results["offset"]["lower"] = rep.offset.lower
            reals["offset"] = {"edges": rep.offset.realisation.edges(top, ed)}
    mats["multipliers"] = mult
    subject_mode = mode_subject(d)
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "robust",
        "certifies": [p.value for p in props],
        "size": int(top.nd),
        "subject": {"modes": {name: subject_mode}, "radius": stated_radius},
        "matrices": mats,
        "claims": [c.to_dict() for c in _claims(tuple(props), name, _stated(results, rep.radius))],
        "results": results,
        "realizations": reals,
        "solver": {
            "name": "Riccati search (SciPy)"
            if pr.get("method") == "riccati"
            else "CVXOPT or Clarabel (via cvxpy)",
            "status": "optimal",
        },
    }
    return finish(doc)


@dataclass(frozen=True)
class _Stated:
    radius: float
    margin: float | None
    alpha: float | None


def _stated(results: dict, radius: float) -> _Stated:
    m = results.get("margin") or {}
    dc = results.get("decay") or {}
    return _Stated(radius, m.get("lower"), dc.get("lower"))


def _claims(props: tuple[Property, ...], mode: str, st: _Stated) -> tuple[Claim, ...]:
    out: list[Claim] = []
    if Property.ROBUST_MARGIN in props:
        out += [
            Claim(ClaimKind.PD, Property.ROBUST_MARGIN, p="robust_margin"),
            Claim(
                ClaimKind.ROBUST_LMI, Property.ROBUST_MARGIN, mode, "robust_margin", 0.0, st.margin
            ),
        ]
    if Property.ROBUST_DECAY in props or Property.ROBUST_OFFSET in props:
        # the offset's premise (every L_B(A') invertible) is the decay LMI at the same radii
        out += [
            Claim(ClaimKind.PD, Property.ROBUST_DECAY, p="robust_decay"),
            Claim(
                ClaimKind.ROBUST_LMI,
                Property.ROBUST_DECAY,
                mode,
                "robust_decay",
                float(st.alpha or 0.0),
                st.radius,
            ),
        ]
    if Property.ROBUST_OFFSET in props:
        out.append(
            Claim(ClaimKind.ROBUST_OFFSET, Property.ROBUST_OFFSET, mode, None, 0.0, st.radius)
        )
    return tuple(out)


@dataclass(frozen=True, eq=False)
class _State:
    dense: DenseContext
    mode: DenseMode
    radius: float  # the largest ρ_e
    radii: np.ndarray  # ρ_e per uncertain edge (UncertainEdges order)
    margin: float | None
    alpha: float | None
    multipliers: dict
    y: Any
    gamma: float | None
    doc: dict


def _rect(x: Any, rows: int, cols: int, where: str) -> np.ndarray:
    """A rows×cols matrix of finite numbers (shape checked before anything is built)."""
    if (
        not isinstance(x, list)
        or len(x) != rows
        or any(not isinstance(r, list) or len(r) != cols for r in x)
    ):
        raise InputError(f"expected a {rows}×{cols} matrix", field=where)
    out = np.array([[number(v, where) for v in r] for r in x], dtype=float)
    if not np.all(np.isfinite(out)):
        raise InputError("expected finite numbers", field=where)
    return out


def _floats(x: Any, n: int, where: str) -> np.ndarray:
    if not isinstance(x, list) or len(x) != n:
        raise InputError(f"expected a list of {n} numbers", field=where)
    out = np.array([number(v, where) for v in x], dtype=float)
    if np.any(out < 0):
        raise InputError("multipliers must be >= 0", field=where)
    return out


class RobustKind(CertificateKind):
    """Weights within a relative Loewner radius: margin, decay and offset bounds."""

    name = "robust"
    description = "weights known within a relative radius ρ: robust margin, decay and offset"
    properties = (Property.ROBUST_MARGIN, Property.ROBUST_DECAY, Property.ROBUST_OFFSET)
    required = frozenset({Property.ROBUST_MARGIN})
    switching = False
    method = "exact-rational, or verified-float past the LMI size"
    fields = frozenset({"matrices", "realizations"})
    subject_fields = frozenset({"modes", "radius"})

    def accepts(self, design: Any) -> bool:
        # brackets whose margin search proved a radius, within the dense proofs' reach
        return (
            isinstance(design, RobustDesign)
            and design.design.topology.nd <= RICCATI_MAX_ND
            and design.report.proofs.get("margin") is not None
        )

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """The certificate of a robust design's brackets (the proofs its report holds).

        Parameters
        ----------
        design : RobustDesign
            The nominal design with its brackets (:func:`ntc_design.certify.robust.robust`).
        options : IssueOptions, optional
            Unused: the radius and the searches are the report's.

        Returns
        -------
        dict

        Raises
        ------
        InputError
            Not a robust design, or one whose margin search proved no radius.
        """
        if not isinstance(design, RobustDesign):
            raise InputError("expected a RobustDesign (the brackets of robust())", field="robust")
        return robust_certificate(design.report)

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        return ()

    def read(self, doc: dict, source: str) -> Reading:
        base = read_dense(doc, source)
        ctx: DenseContext = base.state
        (mode,) = ctx.modes.values()
        sub = need(doc, "subject", dict, source)
        m_edges = uncertain_edges(mode.top).m if mode.in_range else 0
        radii = _radii(sub.get("radius"), m_edges, f"{source}: subject.radius")
        radius = float(np.max(radii, initial=0.0))
        res = need(doc, "results", dict, source)
        mats = need(doc, "matrices", dict, source)
        mult = need(mats, "multipliers", dict, f"{source}: matrices")
        for key in ("margin", "decay", "offset"):
            if key in res and not isinstance(res[key], dict):
                raise InputError("expected an object", field=f"{source}: results.{key}")
        m_lo = res.get("margin", {}).get("lower")
        a_lo = res.get("decay", {}).get("lower")
        margin = (
            None if m_lo is None else check_radius(m_lo, f"{source}: results.margin.lower", False)
        )
        if margin is not None and margin > 1:
            raise InputError("above 1", field=f"{source}: results.margin.lower")
        alpha = None if a_lo is None else number(a_lo, f"{source}: results.decay.lower")
        gam = res.get("offset", {}).get("gamma")
        gamma = None if gam is None else number(gam, f"{source}: results.offset.gamma")
        state = _State(ctx, mode, radius, radii, margin, alpha, mult, mats.get("Y"), gamma, doc)
        return Reading(base.modes, base.checks, state)

    def claims(
        self, properties: tuple[Property, ...], subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        st: _State = reading.state
        (mode,) = subject.scheduled
        return _claims(properties, mode, _Stated(st.radius, st.margin, st.alpha))

    def verification_method(self, reading: Reading) -> str:
        # the proofs that ran (each prover records its method), not all the kind may use
        return " + ".join(sorted(reading.state.dense.methods - {"not attempted"}) or ["none"])

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        st: _State = reading.state
        src = st.dense.source
        if claim.kind is ClaimKind.PD:
            proof = PROVERS[ClaimKind.PD](claim, st.dense)
            st.dense.methods.add(proof.method)
            return Check(claim.id, proof.holds, f"{proof.method}: {proof.detail}", claim)
        if claim.kind is ClaimKind.ROBUST_LMI:
            return _prove_lmi(claim, st)
        mode = st.mode
        if mode.in_range and mode.top.nd > ROBUST_MAX_ND:
            return _prove_offset_float(claim, st)
        if not mode.in_range or mode.exact is None:
            return Check(claim.id, False, "L_B is out of range or too large for the exact test")
        ch = exact_channels(mode.top)
        # the offset's premise (every L_B(A') invertible) is the decay claim, derived with it
        if st.gamma is None or st.y is None:
            return Check(claim.id, False, "results.offset.gamma or matrices.Y is missing", claim)
        lam = _floats(
            st.multipliers.get("robust_offset"),
            len(ch),
            f"{src}: matrices.multipliers.robust_offset",
        )
        n = mode.top.nd
        y = _rect(st.y, n, n + sum(c.vwv.num.shape[0] for c in ch) + 1, f"{src}: matrices.Y")
        target = np.tile(mode.theta, mode.top.n)
        u = _input_exact(mode)
        r0 = u - mode.exact @ Dyadic.of(target.reshape(n, 1))
        proof = prove_pd(gamma_exact(mode.exact, ch, target, r0, st.gamma, lam, y, st.radii))
        st.dense.methods.add(proof.method)
        at = _set_text(st)
        return Check(claim.id, proof.holds, f"{proof.method}: {proof.detail} ({at})", claim)

    def stated(
        self, properties: tuple[Property, ...], reading: Reading
    ) -> tuple[tuple[Property, str], ...]:
        """ρ_lower, α_lower at ρ and the offset bound √γ at ρ, as the file states them
        (each proven by its claim's check).

        Parameters
        ----------
        properties : tuple of Property
            What the certificate certifies.
        reading : Reading
            From :meth:`read`.

        Returns
        -------
        tuple of (Property, str)
        """
        st: _State = reading.state
        out: list[tuple[Property, str]] = []
        # the decay and offset are proven for the subject's set, per-edge radii included
        # (not for every weight at the largest of them); the margin is one ρ on every edge
        at = radius_phrase(st.radii.tolist(), st.radius, _edge_names(st))
        per_edge = len(set(st.radii.tolist())) > 1
        if Property.ROBUST_MARGIN in properties and st.margin is not None:
            one = ", one ρ on every edge" if per_edge else ""
            out.append((Property.ROBUST_MARGIN, f"margin radius {st.margin:.6g}{one}"))
        if Property.ROBUST_DECAY in properties and st.alpha is not None:
            out.append((Property.ROBUST_DECAY, f"α = {st.alpha:.6g} {at}"))
        if Property.ROBUST_OFFSET in properties and st.gamma is not None and st.gamma >= 0:
            bound = math.sqrt(st.gamma)
            out.append((Property.ROBUST_OFFSET, f"<= {bound:.6g} {at}"))
        return tuple(out)

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        rows = []
        for key, label in (("decay", "robust decay rate"), ("offset", "consensus offset")):
            b = results.get(key)
            if b:
                rows.append(
                    ResultRow(
                        label, f"[{number_text(b.get('lower'))}, {number_text(b.get('upper'))}]"
                    )
                )
        m = results.get("margin")
        if m:
            rows.append(
                ResultRow(
                    "margin radius",
                    f"[{number_text(m.get('lower'))}, {number_text(m.get('upper'))}]",
                )
            )
        return tuple(rows)

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        st: _State = reading.state
        mode = st.mode
        stated = doc.get("subject", {}).get("radius")
        if isinstance(stated, list):
            for k, v in enumerate(st.radii.tolist()):
                audit.exact(("radius", k), v)
            if not isinstance(audit.get("radius"), list) or len(audit.get("radius")) != len(
                st.radii
            ):
                audit.fail("radius: not the subject's per-edge radii")
        else:
            audit.exact(("radius",), st.radius)
        scale = float(np.max(np.abs(mode.lap))) if mode.in_range else 1.0
        audit.recomputed(("nominal_decay",), abscissa(mode.lap), scale)
        audit.informational(("seconds",))
        if audit.has("margin", "lower"):
            audit.exact(("margin", "lower"), float(st.margin or 0.0))
        if audit.has("decay", "lower"):
            audit.exact(("decay", "lower"), float(st.alpha or 0.0))
        if audit.has("offset", "gamma"):
            audit.exact(("offset", "gamma"), float(st.gamma or 0.0))
            audit.bound(("offset", "upper"), math.sqrt(max(st.gamma or 0.0, 0.0)), "upper")
        reals = doc.get("realizations") or {}
        if not isinstance(reals, dict):
            audit.fail("realizations: expected an object")
            return
        # the other ends, attained by a realisation: the robust rate is at most its rate,
        # the worst offset at least its offset (so the reported ends on their sound side)
        for key, path in (("decay", ("decay", "upper")), ("offset", ("offset", "lower"))):
            if audit.has(*path):
                got = _attained(reals.get(key), mode, st.radii, key)
                if isinstance(got, str):
                    audit.fail(f"realizations.{key}: {got}")
                    audit.informational(path)
                else:
                    # a realisation's figure is computed in floating point: an eigenvalue
                    # to the matrix's size; an offset (a solve) to 1e−12‖1⊗θ‖ at least, so
                    # a zero offset's rounding (1e−16‖1⊗θ‖) is not read as a forgery
                    target = np.tile(mode.theta, mode.top.n)
                    floor = scale if key == "decay" else 1e-4 * float(np.linalg.norm(target))
                    audit.bound(path, got, path[1], floor)
        if audit.has("margin", "upper"):
            r = reals.get("margin")
            rad = r.get("radius") if isinstance(r, dict) else None
            try:
                rho = check_radius(rad, "realizations.margin.radius", below_one=False)
            except InputError as exc:
                audit.fail(str(exc))
                audit.informational(("margin", "upper"))
                return
            got = _attained(r, mode, np.full(len(st.radii), rho), "decay")
            if isinstance(got, str):
                audit.fail(f"realizations.margin: {got}")
            elif got > 1e-12 * scale:
                audit.fail(
                    f"realizations.margin: min Re λ = {got:.3g} > 0, it is not destabilising"
                )
            audit.bound(("margin", "upper"), rho, "upper")  # a destabilising radius


def _edge_names(st: _State) -> list[str] | None:
    """The uncertain edges' names (``from→to``), in the order of ``st.radii``."""
    return uncertain_edges(st.mode.top).labels(st.mode.top) if st.mode.in_range else None


def _set_text(st: _State) -> str:
    """The subject's uncertainty set in a check's detail: ``ρ = 0.05``, or the per-edge
    radii named by edge (:func:`ntc_design.certify.robust.search.radius_text`)."""
    return radius_text(st.radii.tolist(), st.radius, edges=_edge_names(st))


def _prove_lmi(claim: Claim, st: _State) -> Check:
    """A decay or margin claim: Ψ(P, τ) ≻ 0 exactly up to the LMI's size; past it, P ≻ 0,
    τ > 0 and the Schur form M(P, τ) ≻ 0 of :mod:`ntc_design.certify.robust.are` by
    verified Cholesky with every rounding bounded, L_B's own included."""
    mode, src = st.mode, st.dense.source
    small = mode.top.nd <= ROBUST_MAX_ND
    if not mode.in_range or (small and mode.exact is None):
        return Check(claim.id, False, "L_B is out of range or too large for the exact test")
    stated = st.margin if claim.prop is Property.ROBUST_MARGIN else st.alpha
    if stated is None:  # a property needs its number: ρ_lower, or α_lower
        what = "margin.lower" if claim.prop is Property.ROBUST_MARGIN else "decay.lower"
        return Check(claim.id, False, f"results.{what} is missing", claim)
    p = st.dense.p(claim.p or "")
    if p is None:
        return Check(claim.id, False, f"matrices.P.{claim.p} is out of range", claim)
    ed = uncertain_edges(mode.top)
    tau = _floats(st.multipliers.get(claim.p), ed.m, f"{src}: matrices.multipliers.{claim.p}")
    radius = float(claim.radius or 0.0)
    rad = st.radii if claim.prop is Property.ROBUST_DECAY else np.full(ed.m, radius)
    if small:
        assert mode.exact is not None  # checked above
        proof = prove_pd(psi_exact(mode.exact, exact_channels(mode.top), p, tau, claim.alpha, rad))
        ok, how = proof.holds, f"{proof.method}: {proof.detail}"
        st.dense.methods.add(proof.method)
    elif mode.top.nd > RICCATI_MAX_ND:  # certificates are issued up to this size
        ok, how = False, f"Nd = {mode.top.nd} is past {RICCATI_MAX_ND}"
    else:
        search = RiccatiSearch(mode.lap, mode.err, ed, mode.top.dim)
        ok = search.proven(p, tau, claim.alpha, np.asarray(rad, dtype=float))  # P symmetric too
        st.dense.methods.add("verified-float")
        how = "verified-float: P ≻ 0, τ > 0 and P S + SᵀP − Q(τ) − P R(τ) P ≻ 0 " + (
            "hold" if ok else "not proven"
        )
    at = _set_text(st) if claim.prop is Property.ROBUST_DECAY else f"ρ = {radius!r}"
    return Check(claim.id, ok, f"{how} (α = {claim.alpha!r}, {at})", claim)


def _prove_offset_float(claim: Claim, st: _State) -> Check:
    """An offset claim past the LMI's size: G_e G_eᵀ ≻ W_e and Γ(γ, λ) ≻ 0 with the
    witnesses G and Y rebuilt from the subject (:mod:`ntc_design.certify.robust.offset`),
    every rounding bounded; the premise (every L_B(A') invertible) is the decay claim."""
    mode, src = st.mode, st.dense.source
    if mode.top.nd > RICCATI_MAX_ND:  # certificates are issued up to this size
        return Check(claim.id, False, f"Nd = {mode.top.nd} is past {RICCATI_MAX_ND}", claim)
    if st.gamma is None:
        return Check(claim.id, False, "results.offset.gamma is missing", claim)
    ed = uncertain_edges(mode.top)
    lam = _floats(
        st.multipliers.get("robust_offset"), ed.m, f"{src}: matrices.multipliers.robust_offset"
    )
    search = OffsetSearch(
        mode.lap, mode.err, *input_float(mode.top, mode.b, mode.delta, mode.theta), ed,
        mode.top.dim,
    )  # fmt: skip
    ok = search.proven(st.gamma, lam, np.asarray(st.radii, dtype=float))
    st.dense.methods.add("verified-float")
    how = "verified-float: G_e G_eᵀ ≻ W_e and Γ(γ, λ) ≻ 0 with Y rebuilt " + (
        "hold" if ok else "not proven"
    )
    return Check(claim.id, ok, f"{how} ({_set_text(st)})", claim)


def _input_exact(mode: DenseMode) -> Dyadic:
    """u = δ·blockdiag(B_i)·(1⊗x0) exactly, x0 = k1·θ as the design rounds it."""
    top, d = mode.top, mode.top.dim
    k1 = 1.0 + 2.0 / mode.delta
    x0 = k1 * mode.theta
    col = np.zeros((top.nd, 1), dtype=object)
    dl = Dyadic.of(mode.delta)
    parts = []
    for i, b in mode.b.items():
        v = Dyadic.of(np.asarray(b, dtype=float)).scale(dl) @ Dyadic.of(x0.reshape(d, 1))
        parts.append((i, v))
    e = max([v.exp for _, v in parts] + [0])
    for i, v in parts:
        col[i * d : (i + 1) * d] += v.num * (1 << (e - v.exp))
    return Dyadic(col, e)


def _attained(real: Any, mode: DenseMode, radii: np.ndarray, what: str) -> float | str:
    """What a stored realisation attains (min Re λ, or the offset), after checking that it
    lists every uncertain edge once, in the set of this radius; or why it is refused."""
    if not isinstance(real, dict) or not isinstance(real.get("edges"), list):
        return "missing, or not an object with edges"
    top = mode.top
    ed = uncertain_edges(top)
    if len(real["edges"]) != ed.m:
        return f"expected {ed.m} edges"
    w = dict(top.weights)
    d = top.dim
    for k, e in enumerate(real["edges"]):
        if not isinstance(e, dict):
            return f"edge {k}: expected an object"
        to, fr = e.get("to"), e.get("from")
        if not isinstance(to, (int, str)) or not isinstance(fr, (int, str)):
            return f"edge {k}: from and to must be agent labels"
        try:
            i, j = top.index(to), top.index(fr)
        except InputError:
            return f"edge {k}: unknown agent"
        if (i, j) != (int(ed.dst[k]), int(ed.src[k])):
            return f"edge {k}: expected the edge {top.labels[int(ed.src[k])]}->{top.labels[int(ed.dst[k])]}"
        a = np.asarray(e.get("weight"), dtype=object)
        if a.shape != (d, d):
            return f"edge {k}: weight is not {d}×{d}"
        try:
            a = a.astype(float)
        except (TypeError, ValueError):
            return f"edge {k}: weight is not numeric"
        if not np.all(np.isfinite(a)) or not np.array_equal(a, a.T):
            return f"edge {k}: weight is not finite and symmetric"
        wa = ed.s[k] * a
        radius = float(radii[k])
        tol = REALISATION_RTOL * max(float(np.max(np.abs(ed.w[k]))), 1e-300)
        if (
            np.linalg.eigvalsh(wa - (1 - radius) * ed.w[k])[0] < -tol
            or np.linalg.eigvalsh((1 + radius) * ed.w[k] - wa)[0] < -tol
        ):
            return f"edge {k}: weight outside its interval (radius {radius!r})"
        w[(i, j)] = a
    dmat = coupling_matrix(top, mode.b)
    lap_r = _laplacian(top, w) + mode.delta * dmat
    if what == "decay":
        return abscissa(lap_r)
    x0 = (1.0 + 2.0 / mode.delta) * mode.theta
    u = mode.delta * dmat @ np.tile(x0, top.n)
    try:
        xs = np.linalg.solve(lap_r, u)
    except np.linalg.LinAlgError:
        return "L_B of the realisation is singular"
    return float(np.linalg.norm(xs - np.tile(mode.theta, top.n)))


def _laplacian(top: Topology, w: dict) -> np.ndarray:
    """The signed Laplacian of the weights ``w`` on the topology's agents (dense)."""
    d, n = top.dim, top.nd
    lap = np.zeros((n, n))
    for (i, j), a in w.items():
        lam = np.linalg.eigvalsh(a)
        s = 1.0 if lam[-1] > 0 else (-1.0 if lam[0] < 0 else 0.0)
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += s * a
    return lap


__all__ = ["RobustKind", "gamma_exact", "psi_exact", "robust_certificate"]
