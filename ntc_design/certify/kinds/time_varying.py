"""Kind ``time_varying``: weights that are expressions of t; the uniform bound
λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ > 0 for every t, Assumption 3's D, the proof's Λ₁ and p̄,
and t₀ after which μ₂(t) > 0 (:mod:`ntc_design.certify.time_varying` has the branch and
bound). Verify re-parses the topology (re-proving its sign classes), re-encloses every
recorded t-interval, and checks every reported number: a bound on its sound side of the
re-enclosed one, the rest recomputed."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from ...errors import InputError
from ...model.timevarying import ExpressionTopology, from_document
from ...protocol.timevarying import TimeVaryingDesign, lemma1_structure
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..fields import matrix, need, number, vector
from ..format import document_hash
from ..mu2 import mu2_t0, mu2_threshold, noise_sigma_bar
from ..theorems import TheoremVerdict, time_varying_verdicts
from ..time_varying import RESULTS_KEY, Enclosures, LeafBound, domain_of, time_varying_document
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

MAX_INTERVALS = 100_000
#: Relative agreement of re-enclosed numbers with the reported ones (the same Arb and
#: LAPACK operations give the same bits on one machine; other BLAS builds may differ in
#: the last digits).
ENCLOSURE_RTOL = 1e-9

CLAIMS = (ClaimKind.LAMBDA2, ClaimKind.WEIGHT_BOUND, ClaimKind.LAMBDA1, ClaimKind.T0)
RESULT_NUMBERS = ("lambda2", "D", "Lambda1", "p_bar")


@dataclass(eq=False)
class TimeVaryingState:
    """The certificate as read, and the re-enclosed leaves (computed once, on demand)."""

    tv: ExpressionTopology
    margin: float
    sigma: float
    f: Any
    gain: str | None
    intervals: list
    results: dict
    source: str
    _leaves: list[LeafBound] | None = field(default=None)
    _enc: Enclosures | None = field(default=None)
    _t0: tuple | None = field(default=None)

    @property
    def enclosures(self) -> Enclosures:
        # The interval enclosures of the weights (built once).
        if self._enc is None:
            self._enc = Enclosures(self.tv, lemma1_structure(self.tv), self.margin, self.sigma)
        return self._enc

    @property
    def leaves(self) -> list[LeafBound]:
        # Every recorded interval re-enclosed (one BLAS thread: many small matrices).
        if self._leaves is None:
            with threadpool_limits(limits=1):
                self._leaves = [
                    self.enclosures.leaf(float(a), float(b)) for a, b, _ in self.intervals
                ]
        return self._leaves

    def number(self, key: str) -> float:
        # A reported result that the claims use (read as a finite number).
        return number(self.results.get(key), f"{self.source}: results.time_varying.{key}")

    @property
    def t0(self) -> tuple[float | None, str]:
        # t₀ recomputed from the reported (proven) Λ₂, Λ₁ and the noise's σ̄.
        if self._t0 is None:
            kappa = mu2_threshold(
                self.number("lambda2"), self.number("Lambda1"), noise_sigma_bar(self.f), self.tv.n
            )
            self._t0 = (
                mu2_t0(self.gain, kappa) if self.gain is not None else (None, "no gain given")
            )
        return self._t0


class TimeVaryingKind(CertificateKind):
    """Weights that are expressions of t, periodic or constant after a time."""

    name = "time_varying"
    description = (
        "a continuously time-varying topology: the uniform bound Λ₂ of Theorems 3-4 for every t"
    )
    properties = (Property.UNIFORM_SYMMETRIC_PART,)
    required = frozenset({Property.UNIFORM_SYMMETRIC_PART})
    switching = False
    method = "interval"
    fields = frozenset({"intervals"})
    subject_fields = frozenset({"topology", "theta", "margin", "noise", "gain"})
    mode_fields = frozenset()

    def accepts(self, design: Any) -> bool:
        return isinstance(design, TimeVaryingDesign)

    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """The certificate of a time-varying design (:func:`time_varying_document`).

        Parameters
        ----------
        design : TimeVaryingDesign
            The design.
        options : IssueOptions, optional
            Its ``gain`` (for t₀ of μ₂), ``noise_sigma`` and ``noise_f`` are used.

        Returns
        -------
        dict

        Raises
        ------
        InputError
            The uniform bound cannot be certified, or the gain is a schedule.
        """
        o = options or IssueOptions()
        return time_varying_document(
            design.topology, design.theta, self.name, design.margin, o.gain, o.noise_sigma,
            o.noise_f,
        )  # fmt: skip

    def verdicts(self, design, certificate, verification, gain) -> tuple[TheoremVerdict, ...]:
        return time_varying_verdicts(time_varying_results(certificate), verification, gain)

    def read(self, doc: dict, source: str) -> Reading:
        # The topology (its sign classes re-proven), θ (length d), ΔC > 0, the noise
        # (σ >= 0, f a number or a d×d matrix), the gain, the intervals.
        subj = need(doc, "subject", dict, source)
        w = f"{source}: subject"
        tv = from_document(need(subj, "topology", dict, w), f"{w}.topology")
        if tv.domain is None:
            raise InputError("declares neither period nor constant_after", field=f"{w}.topology")
        size = need(doc, "size", int, source)
        if tv.nd != size:
            raise InputError(f"has Nd={tv.nd}, certificate size is {size}", field=f"{w}.topology")
        theta = vector(need(subj, "theta", list, w), tv.dim, f"{w}.theta")
        margin = number(need(subj, "margin", (int, float), w), f"{w}.margin")
        if not margin > 0:
            raise InputError("ΔC must be positive", field=f"{w}.margin")
        noise = need(subj, "noise", dict, w)
        sigma = number(need(noise, "sigma", (int, float), f"{w}.noise"), f"{w}.noise.sigma")
        if sigma < 0:
            raise InputError("must be >= 0", field=f"{w}.noise.sigma")
        f = need(noise, "f", (int, float, list), f"{w}.noise")
        f = (
            number(f, f"{w}.noise.f")
            if not isinstance(f, list)
            else matrix(f, tv.dim, f"{w}.noise.f")
        )
        gain = subj.get("gain")
        if gain is not None and not isinstance(gain, str):
            raise InputError("expected an expression of t or null", field=f"{w}.gain")
        res = need(need(doc, "results", dict, source), RESULTS_KEY, dict, f"{source}: results")
        ivs = need(doc, "intervals", list, source)
        if (
            not ivs
            or len(ivs) > MAX_INTERVALS
            or any(
                not isinstance(q, list)
                or len(q) != 3
                or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in q)
                for q in ivs
            )
        ):
            raise InputError(
                f"expected 1 to {MAX_INTERVALS} intervals [a, b, bound]",
                field=f"{source}: intervals",
            )
        for k, q in enumerate(ivs):
            for x in q:
                number(x, f"{source}: intervals[{k}]")
        state = TimeVaryingState(tv, margin, sigma, f, gain, ivs, res, source)
        mode = ModeReading(
            tv.name or "topology",
            tv.name,
            tuple(str(i + 1) for i in range(tv.n)),
            tv.dim,
            document_hash(tv.to_dict()),
            None,
            theta,
        )
        return Reading({mode.name: mode}, (), state)

    def claims(
        self, properties, subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        return tuple(Claim(k, Property.UNIFORM_SYMMETRIC_PART) for k in CLAIMS)

    def record(self, claim: Claim) -> dict:
        return {"id": claim.id, "kind": claim.kind.value}

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        # Each claim from the re-enclosed intervals (never from the reported numbers
        # alone: those are the bounds the claims state, checked against the enclosures).
        st: TimeVaryingState = reading.state
        if claim.kind is ClaimKind.LAMBDA2:
            return self._lambda2(claim, st)
        leaves = st.leaves
        if claim.kind is ClaimKind.WEIGHT_BOUND:
            d_max, d = max(q.D for q in leaves), st.number("D")
            return Check(
                claim.id, d_max <= d, f"re-enclosed sup {d_max:.6g} vs claimed D = {d:.6g}", claim
            )
        if claim.kind is ClaimKind.LAMBDA1:
            lam1, p_bar = max(q.lambda1 for q in leaves), max(q.p_bar for q in leaves)
            c1, cp = st.number("Lambda1"), st.number("p_bar")
            return Check(
                claim.id,
                lam1 <= c1 and p_bar <= cp,
                f"re-enclosed Λ₁ {lam1:.6g} (claimed {c1:.6g}), p̄ {p_bar:.6g} (claimed {cp:.6g})",
                claim,
            )
        t0_new, how = st.t0
        t0 = st.results.get("t0")
        if st.gain is None:
            return Check(
                claim.id,
                t0 is None,
                "no gain given: no t₀ is claimed" if t0 is None else "t₀ reported without a gain",
                claim,
            )
        if t0 is None:
            return Check(claim.id, t0_new is None, f"no t₀ claimed ({how})", claim)
        t0f = number(t0, f"{st.source}: results.time_varying.t0")
        ok = t0_new is not None and t0_new <= t0f * (1 + 1e-9) + 1e-12
        return Check(claim.id, ok, f"t₀ = {t0_new} ({how}) vs claimed {t0f}", claim)

    @staticmethod
    def _lambda2(claim: Claim, st: TimeVaryingState) -> list[Check]:
        ivs = st.intervals
        a0, b0, text = domain_of(st.tv)
        cover = (
            ivs[0][0] <= a0
            and ivs[-1][1] >= b0
            and all(ivs[k][1] == ivs[k + 1][0] for k in range(len(ivs) - 1))
            and all(q[0] < q[1] for q in ivs)
        )
        checks = [
            Check(
                "the intervals cover the domain",
                bool(cover),
                f"{len(ivs)} intervals over {text}" if cover else "gap, overlap or short cover",
            )
        ]
        if not cover:  # nothing is enclosed over a malformed cover
            checks.append(Check(claim.id, False, "the intervals do not cover the domain", claim))
            return checks
        lows = np.array([q.lower for q in st.leaves])
        recorded = np.array([float(q[2]) for q in ivs])
        lam2, worst = st.number("lambda2"), float(lows.min())
        # a recorded bound is a lower bound (at or below its re-enclosure, so a tighter
        # later enclosure keeps it true) and at least the claimed Λ₂, the least of them: a
        # bound negated, or below Λ₂, states what the certificate does not
        over = recorded > lows + ENCLOSURE_RTOL * np.abs(lows)
        under = recorded < lam2
        bad = over | under
        k = int(np.argmax(bad))
        checks.append(
            Check(
                "each interval's recorded bound lies between the claimed Λ₂ and its "
                "re-enclosed one",
                not bad.any(),
                "recomputed"
                if not bad.any()
                else f"interval {k}: recorded {recorded[k]:.6g}, re-enclosed {lows[k]:.6g}, "
                f"claimed Λ₂ = {lam2:.6g}",
            )
        )
        checks.append(
            Check(
                claim.id,
                lam2 > 0 and worst >= lam2,
                f"re-enclosed: least bound {worst:.6g} vs claimed Λ₂ = {lam2:.6g}",
                claim,
            )
        )
        return checks

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        r = results[RESULTS_KEY]
        return (
            ResultRow(
                "uniform bound",
                f"over {r['domain_text']}: Λ₂ = {r['lambda2']:.6g} certified on "
                f"{r['intervals']} t-intervals (sampled infimum {r['sampled_inf']:.6g} at "
                f"t = {r['t_at_sampled_inf']:.4g}, gap {100 * r['relative_gap']:.2f} %, "
                f"{r['seconds']:.1f} s)",
            ),
            ResultRow(
                "Assumption 3",
                f"D = {r['D']:.6g}; Λ₁ = {r['Lambda1']:.6g}, p̄ = {r['p_bar']:.6g}; "
                f"μ₂(t) > 0 for t >= t₀ = {number_text(r['t0'])} (σ̄ = {r['sigma_bar']:.4g}; "
                f"{r['t0_proof']})",
            ),
        )

    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        # Λ₂ (a lower bound), D, Λ₁, p̄ (upper bounds) on the sound side of their
        # re-enclosed values; the sampled infimum is λ_min at its time and lies above Λ₂;
        # the gap, σ̄, κ and the domain are recomputed, t₀ (from the reported Λ₂, Λ₁) is
        # at or after the recomputed one; the run time is informational.
        st: TimeVaryingState = reading.state
        tv = (RESULTS_KEY,)
        if set(audit.results) != {RESULTS_KEY}:
            audit.fail("results: expected only 'time_varying'")
        leaves = st.leaves
        enclosed = {
            "lambda2": min(q.lower for q in leaves),
            "D": max(q.D for q in leaves),
            "Lambda1": max(q.lambda1 for q in leaves),
            "p_bar": max(q.p_bar for q in leaves),
        }
        for key in RESULT_NUMBERS:  # one-sided: a looser bound than today's is still true
            side = "lower" if key == "lambda2" else "upper"
            audit.bound((*tv, key), enclosed[key], side, rtol=ENCLOSURE_RTOL)
        a0, b0, text = domain_of(st.tv)
        lam2 = st.number("lambda2")
        t_inf = audit.get(*tv, "t_at_sampled_inf")
        audit.estimate((*tv, "t_at_sampled_inf"), a0, b0, " (outside the domain)")
        t = (
            number(t_inf, f"{st.source}: results.time_varying.t_at_sampled_inf")
            if isinstance(t_inf, (int, float)) and not isinstance(t_inf, bool)
            else a0
        )
        with threadpool_limits(limits=1):
            sample = float(st.enclosures.samples(np.array([min(max(t, a0), b0)]))[0])
        audit.recomputed((*tv, "sampled_inf"), sample, rtol=1e-8)
        s_inf = audit.get(*tv, "sampled_inf")
        if isinstance(s_inf, (int, float)) and not isinstance(s_inf, bool) and s_inf < lam2:
            audit.fail(f"sampled_inf {s_inf!r} lies below the certified Λ₂ {lam2!r}")
        if isinstance(s_inf, (int, float)) and not isinstance(s_inf, bool) and s_inf > 0:
            audit.recomputed((*tv, "relative_gap"), (s_inf - lam2) / s_inf)
        else:
            audit.exact((*tv, "relative_gap"), None)
        sigma_bar = noise_sigma_bar(st.f)
        audit.recomputed((*tv, "sigma_bar"), sigma_bar, 1e-300)
        kappa = mu2_threshold(lam2, st.number("Lambda1"), sigma_bar, st.tv.n)
        if math.isfinite(kappa):
            audit.recomputed((*tv, "kappa"), kappa)
        else:
            audit.exact((*tv, "kappa"), None)
        t0_new, how = st.t0
        if t0_new is None:
            audit.exact((*tv, "t0"), None)
        else:
            audit.bound((*tv, "t0"), t0_new, "upper", 1e-12)  # μ₂ > 0 from t₀ on
        audit.exact((*tv, "t0_proof"), how)
        audit.exact((*tv, "domain", 0), float(a0))
        audit.exact((*tv, "domain", 1), float(b0))
        audit.exact((*tv, "domain_text"), text)
        audit.exact((*tv, "intervals"), len(st.intervals))
        audit.informational((*tv, "seconds"))


__all__ = ["TimeVaryingKind"]


def time_varying_results(certificate: dict) -> dict:
    """A time-varying certificate's results (Λ₂, D, Λ₁, p̄, t₀, the domain), as issued.

    Parameters
    ----------
    certificate : dict
        A certificate of this kind.

    Returns
    -------
    dict
    """
    return certificate["results"][RESULTS_KEY]
