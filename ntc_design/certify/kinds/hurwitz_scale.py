"""Kind ``hurwitz-scale``: one big topology, −L_B Hurwitz component by component
(:mod:`ntc_design.certify.scale` has the mathematics: block triangular order, block
diagonal dominance after Feingold & Varga, sparse symmetric-part and dense Lyapunov
fallbacks). Verify rebuilds everything from the stated topology and δ, with no solver."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ...present.rows import counted
from ...protocol import ProtocolDesign
from ..arrays import read_array_mode, unpack
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..dense import DENSE_CERT_MAX_ND, prove_pd_expr
from ..fields import need
from ..format import topology_hash
from ..scale import (
    LYAPUNOV_COMPONENT_MAX_ND,
    RATE_DENSE_MAX_ND,
    BlockData,
    component_matrix,
    dominance_holds,
    dominance_rate_bound,
    edge_norm_bounds,
    lap_b_blocks,
    prove_mu,
    prove_symmetric_part,
    rate_estimate,
    scale_document,
)
from ..theorems import TheoremVerdict, fixed_verdicts
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

METHODS = ("dominance", "symmetric", "lyapunov", "none")
#: verify redoes the rate estimate when its dense eigenvalue work, Σ (n_C·d)³ over the
#: components, is at most this (about a second); above, it bounds it on both sides.
RECOMPUTE_FLOPS = 2e9


@dataclass(frozen=True, eq=False)
class ScaleState:
    """A hurwitz-scale certificate as read: the topology, δ, and the component data."""

    mode: str
    top: Any
    delta: float
    comp: np.ndarray
    methods: np.ndarray
    v: np.ndarray
    mu: np.ndarray
    lyapunov: dict
    blocks: BlockData
    source: str


def rate_upper_bound(blocks: BlockData, comp: np.ndarray, ncomp: int) -> float | None:
    """A rigorous upper bound on what an honest decay-rate estimate can be: each one-agent
    or dense-estimated component's min Re λ is at most the mean of its eigenvalues,
    trace/(n_C·d); above the dense size only a Gershgorin bound on λ_max of the symmetric
    part holds (Bendixson: Re λ <= λ_max(sym)).

    Parameters
    ----------
    blocks : BlockData
        L_B's blocks.
    comp : numpy.ndarray
        The component of each agent.
    ncomp : int
        The number of components.

    Returns
    -------
    float or None
        None when there is no component.
    """
    if not comp.size:
        return None
    d = blocks.top.dim
    sizes = np.bincount(comp, minlength=ncomp)
    tr = np.bincount(comp, weights=np.trace(blocks.diag, axis1=1, axis2=2), minlength=ncomp)
    dense = (sizes > 0) & (sizes * d <= RATE_DENSE_MAX_ND)
    if dense.any():
        return float(np.min(tr[dense] / (sizes[dense] * d)))
    best = -np.inf  # every component is large: the estimate is below the largest bound
    for c in np.flatnonzero(sizes > 0).tolist():
        lap_c, _ = component_matrix(blocks, np.flatnonzero(comp == c))
        s = 0.5 * (lap_c + lap_c.T)
        off = abs(s).sum(axis=1).A1 - np.abs(s.diagonal())
        best = max(best, float(np.max(s.diagonal() + off)))
    return best


class HurwitzScaleKind(CertificateKind):
    """One topology above Nd = ``DENSE_CERT_MAX_ND``: no dense step."""

    name = "hurwitz-scale"
    description = "one topology at scale: −L_B Hurwitz, component by component"
    properties = (Property.HURWITZ,)
    required = frozenset({Property.HURWITZ})
    switching = False
    method = "verified-float (component-wise)"
    fields = frozenset({"components"})
    mode_fields = frozenset({"topology", "theta", "margin", "delta", "informed"})

    def accepts(self, design: Any) -> bool:
        return isinstance(design, ProtocolDesign) and design.topology.nd > DENSE_CERT_MAX_ND

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        return scale_document(design, self.name)

    def agent_margins(self, certificate: dict, n: int) -> np.ndarray | None:
        return unpack(certificate["components"]["mu"], "components.mu", "f8", (n,))

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        return fixed_verdicts(design, verification, gain)

    def read(self, doc: dict, source: str) -> Reading:
        # The topology (arrays), δ, θ, informed agents = U, and the component data.
        subject = need(doc, "subject", dict, source)
        modes = need(subject, "modes", dict, f"{source}: subject")
        if len(modes) != 1:
            raise InputError(
                "a hurwitz-scale certificate has one mode", field=f"{source}: subject.modes"
            )
        ((mname, sub),) = modes.items()
        where = f"{source}: subject.modes.{mname}"
        top, delta, theta, informed = read_array_mode(sub, where, need(doc, "size", int, source))
        checks = list(informed)
        n = top.n
        cw = f"{source}: components"
        comps = need(doc, "components", dict, source)
        comp = unpack(need(comps, "label", dict, cw), f"{cw}.label", "i8", (n,))
        meth = need(comps, "method", list, cw)
        if any(not isinstance(m, str) for m in meth):
            raise InputError("expected strings", field=f"{cw}.method")
        unknown = set(meth) - set(METHODS)
        if unknown:
            raise InputError(f"unknown method {sorted(unknown)[0]!r}", field=f"{cw}.method")
        if n and (comp.min() < 0 or comp.max() >= len(meth)):
            raise InputError(
                f"a component number is out of range 0..{len(meth) - 1}", field=f"{cw}.label"
            )
        v = unpack(need(comps, "v", dict, cw), f"{cw}.v", "f8", (n,))
        mu = unpack(need(comps, "mu", dict, cw), f"{cw}.mu", "f8", (n,))
        lyap = need(comps, "lyapunov", dict, cw)
        state = ScaleState(
            str(mname),
            top,
            float(delta),
            comp,
            np.array(meth, dtype=object),
            v,
            mu,
            lyap,
            lap_b_blocks(top, float(delta)),
            source,
        )
        mode = ModeReading(
            str(mname),
            top.name,
            tuple(str(x) for x in top.labels),
            top.dim,
            topology_hash(top),
            float(delta),
            theta,
        )
        return Reading({str(mname): mode}, tuple(checks), state)

    def claims(
        self, properties, subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        (m,) = subject.modes
        return (Claim(ClaimKind.COMPONENTS, Property.HURWITZ, mode=m),)

    def record(self, claim: Claim) -> dict:
        return {"id": claim.id, "kind": claim.kind.value, "mode": claim.mode}

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> list[Check]:
        # Every edge goes forward in the component order; every component is proven by
        # its method (dominance, symmetric part, or a Lyapunov P); none is left out.
        st: ScaleState = reading.state
        top, comp, methods, n = st.top, st.comp, st.methods, st.top.n
        checks: list[Check] = []
        ea = top.edge_arrays
        nz = np.any(ea.w != 0, axis=(1, 2))
        back = nz & (comp[ea.cols] > comp[ea.rows])
        k = int(np.argmax(back)) if back.any() else 0
        checks.append(
            Check(
                "components in a topological order (L_B block triangular)",
                not back.any(),
                "every edge goes forward"
                if not back.any()
                else f"edge {top.labels[ea.cols[k]]}->{top.labels[ea.rows[k]]} goes backward",
            )
        )
        dom_agents = methods[comp] == "dominance" if n else np.zeros(0, dtype=bool)
        if dom_agents.any():
            checks.append(self._dominance(st, dom_agents))
        checks += self._fallbacks(st)
        none = np.flatnonzero(methods == "none")
        ok = none.size == 0 and all(c.ok for c in checks)
        detail = (
            f"{methods.size} component(s) covered"
            if none.size == 0
            else f"{none.size} component(s) not certified (e.g. component {none[0]}, agents "
            + ", ".join(str(top.labels[i]) for i in np.flatnonzero(comp == none[0])[:5])
            + ")"
        )
        checks.append(Check(claim.id, ok, detail, claim))
        return checks

    @staticmethod
    def _dominance_data(st: ScaleState, dom_agents: np.ndarray):
        ea = st.top.edge_arrays
        same = st.comp[ea.rows] == st.comp[ea.cols]
        inner = same & dom_agents[ea.rows]
        nu = np.zeros(ea.w.shape[0])
        nu_ok = np.ones(ea.w.shape[0], dtype=bool)
        if inner.any():
            nu[inner], nu_ok[inner] = edge_norm_bounds(ea.w[inner])
        rhs = np.zeros(st.top.n)
        np.add.at(rhs, ea.rows[inner], nu[inner] * st.v[ea.cols[inner]])
        return nu, nu_ok, rhs

    def _dominance(self, st: ScaleState, dom_agents: np.ndarray) -> Check:
        idx = np.flatnonzero(dom_agents)
        pos = st.mu[idx] > 0
        ok_mu = np.zeros(idx.size, dtype=bool)
        ok_mu[pos] = prove_mu(st.blocks, idx[pos], st.mu[idx][pos])
        nu, nu_ok, _ = self._dominance_data(st, dom_agents)
        dom = dominance_holds(st.top, st.comp, st.mu, st.v, nu, dom_agents)
        ok = bool(ok_mu.all() and nu_ok.all() and dom[idx].all())
        count = int(np.sum(st.methods == "dominance"))
        detail = (
            f"{counted(count, 'component')}, {counted(idx.size, 'agent')}: μ_i, ν_ij proven (batched shifted "
            "Cholesky), M v > 0 with rounding bounded"
            if ok
            else f"fails at agent {st.top.labels[idx[np.argmin(ok_mu & dom[idx])]]}"
        )
        return Check("block diagonal dominance (Feingold–Varga)", ok, detail)

    def _fallbacks(self, st: ScaleState) -> list[Check]:
        checks = []
        # the agents of each component, grouped once (not a pass over all agents each)
        order = np.argsort(st.comp, kind="stable")
        starts = np.concatenate([[0], np.cumsum(np.bincount(st.comp, minlength=st.methods.size))])

        def agents_of(c: int) -> np.ndarray:
            return order[starts[c] : starts[c + 1]]

        sym_ok, sym_n, sym_fail = True, 0, ""
        for c in np.flatnonzero(st.methods == "symmetric").tolist():
            lap_c, err_c = component_matrix(st.blocks, agents_of(c))
            ok, how = prove_symmetric_part(lap_c, err_c)
            sym_n += 1
            if not ok:
                sym_ok, sym_fail = False, f"component {c}: {how}"
        if sym_n:
            checks.append(
                Check(
                    "symmetric part ≻ 0 on components (sparse Cholesky, Rump shift)",
                    sym_ok,
                    f"{sym_n} component(s)" if sym_ok else sym_fail,
                )
            )
        cw = f"{st.source}: components"
        for c in np.flatnonzero(st.methods == "lyapunov").tolist():
            agents = agents_of(c)
            m = agents.size * st.top.dim
            if m > LYAPUNOV_COMPONENT_MAX_ND:
                raise InputError(
                    f"component above Nd = {LYAPUNOV_COMPONENT_MAX_ND}", field=f"{cw}.lyapunov.{c}"
                )
            entry = need(st.lyapunov, str(c), dict, f"{cw}.lyapunov")
            p = unpack(
                need(entry, "P", dict, f"{cw}.lyapunov.{c}"), f"{cw}.lyapunov.{c}.P", "f8", (m, m)
            )
            lap_c, err_c = component_matrix(st.blocks, agents)
            p1 = prove_pd_expr(p, None, None, 0.0, None, False)
            p2 = prove_pd_expr(p, None, lap_c.toarray(), 0.0, err_c.toarray(), False)
            checks.append(
                Check(
                    f"Lyapunov P on component {c} (Nd = {m})",
                    p1.holds and p2.holds,
                    f"{p1.detail}; {p2.detail}",
                )
            )
        return checks

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        r, est = results, results["rate_estimate"]
        return (
            ResultRow(
                "components",
                f"{r['components']} (largest {r['largest_component_agents']} agents), by "
                + ", ".join(f"{m} {k}" for m, k in r["methods"].items()),
            ),
            ResultRow("decay rate", f"{number_text(est['value'])} ({est['method']})", True),
            *(ResultRow("skipped", sk) for sk in r["skipped"]),
        )

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # Counts recomputed; the rate's lower bound at or below the recomputed one (every
        # component a dominance one) and the rate estimate between that bound (or 0) and
        # :func:`rate_upper_bound`; the run time informational.
        st: ScaleState = reading.state
        meth = st.methods.tolist()
        ncomp = len(meth)
        sizes = np.bincount(st.comp, minlength=ncomp) if st.comp.size else np.zeros(0, int)
        audit.exact(("components",), ncomp)
        audit.exact(("largest_component_agents",), int(sizes.max(initial=0)))
        for m in METHODS:
            audit.exact(("methods", m), meth.count(m))
        got = audit.get("methods")
        if isinstance(got, dict) and set(got) != set(METHODS):
            audit.fail(f"methods: expected the counts of {', '.join(METHODS)}")
        lower = None
        all_dom = bool(st.top.n) and bool(np.all(st.methods[st.comp] == "dominance"))
        if all_dom:
            _, _, rhs = self._dominance_data(st, np.ones(st.top.n, dtype=bool))
            lower = float(np.min(dominance_rate_bound(st.mu, st.v, rhs))) * (1 - 1e-12)
            audit.bound(("rate_lower_bound", "value"), lower, "lower")
        elif audit.get("rate_lower_bound", "value") is not None:
            audit.informational(("rate_lower_bound", "value"))  # accounted for: it fails here
            audit.fail("rate_lower_bound given, but not every component is a dominance one")
        hurwitz = meth.count("none") == 0
        d = st.top.dim
        if (
            sizes.size
            and int(np.sum((sizes * d) ** 3)) <= RECOMPUTE_FLOPS
            and bool(np.all(sizes * d <= RATE_DENSE_MAX_ND))
        ):  # every block dense and small: the issuer's estimate, redone
            rate, _ = rate_estimate(st.blocks, st.comp, ncomp)
            audit.recomputed(("rate_estimate", "value"), rate, rtol=1e-9)
        else:
            upper = rate_upper_bound(st.blocks, st.comp, ncomp)
            floor = lower if lower is not None else (0.0 if hurwitz else None)
            why = " (a rigorous upper bound on min Re λ(L_B): trace/(n·d) of a component)"
            audit.estimate(("rate_estimate", "value"), floor, upper, why)
        est = audit.get("rate_estimate", "value")
        audit.informational(("eig_bound",))  # the same estimate under its older name
        if audit.get("eig_bound") != est:
            audit.fail("eig_bound differs from rate_estimate.value")
        if hurwitz and isinstance(est, (int, float)) and not est > 0:
            audit.fail(
                f"the decay-rate estimate {est!r} is not positive, yet −L_B is claimed Hurwitz"
            )
        audit.informational(("seconds",))


__all__ = ["HurwitzScaleKind", "rate_upper_bound"]


def scale_certificate(des: ProtocolDesign, name: str | None = None) -> dict:
    """Certify −L_B Hurwitz for a big network component by component
    (:mod:`ntc_design.certify.scale`) as a ``hurwitz-scale`` certificate.

    Parameters
    ----------
    des : ProtocolDesign
        The design whose L_B is certified.
    name : str, optional
        Mode name used in claim ids (default: the topology's name).

    Returns
    -------
    dict
        The certificate, digest included; re-check it with
        :func:`ntc_design.certify.verify` / ``ntc verify``.
    """
    return scale_document(des, HurwitzScaleKind.name, name)
