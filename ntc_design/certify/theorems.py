"""Which of Theorems 1-4 (Niu & Wu, Sec. 4) is guaranteed for a design, a certificate and
a gain.

Theorems 1-2 (fixed topology): Assumptions 1-2 and the gain conditions; their proofs use
Assumption 2 only through Lemma 1's conclusion that −L_B is Hurwitz, so a certified
Hurwitz −L_B is accepted in its place (and said so). Theorems 3-4 (time-varying): also
Assumption 3 (bounded weights; automatic for a finite set of modes) and
L_B(t) + L_B(t)ᵀ ≻ 0 for every t, certified per mode. Theorems 2 and 4 also need
∫c² < ∞. Assumption 1 concerns the noise f_ji, which a topology does not fix: it is
reported as assumed (it holds for f(x) = s·x with σ̄ = |s|).

What a certificate proves is read from its typed checks (:class:`Property` of each claim),
never from the claims' names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..errors import Option, one_line
from ..gain.conditions import CONDITION_LABELS, GainAnalysis
from ..present.rows import Table, lines, verdict
from ..protocol import ProtocolDesign, SwitchingDesign, fix_notes
from ..protocol.digital import DigitalDesign
from .checks import Verification
from .claims import Property
from .mu2 import T0_SCAN_END


@dataclass(frozen=True)
class Premise:
    """One premise of a theorem: holds (True), fails (False) or undetermined (None)."""

    name: str
    holds: bool | None
    detail: str
    #: what stands in for a premise that fails as stated but whose use in the proof is
    #: certified directly (Assumption 2, replaced by the certified −L_B Hurwitz or
    #: L_B + L_Bᵀ ≻ 0); None when the premise holds as stated
    replaced_by: str | None = None

    def to_dict(self) -> dict:
        """The premise as a JSON-ready mapping.

        Returns
        -------
        dict
            ``premise`` (its name), ``holds``, ``detail`` and ``replaced_by``.
        """
        return {
            "premise": self.name,
            "holds": self.holds,
            "detail": self.detail,
            "replaced_by": self.replaced_by,
        }


@dataclass(frozen=True)
class TheoremVerdict:
    """Whether a theorem is guaranteed, with every premise."""

    theorem: int
    sense: str  # "mean square" or "almost sure"
    premises: tuple[Premise, ...]
    #: the sampled protocol's analogue (period h, delay D; :mod:`.digital`), not the SAN's
    sampled: bool = False

    @property
    def guaranteed(self) -> bool | None:
        """False when a premise fails, None when one is undetermined, else True."""
        vals = [p.holds for p in self.premises]
        if any(v is False for v in vals):
            return False
        return None if any(v is None for v in vals) else True

    @property
    def failing(self) -> tuple[Premise, ...]:
        """The premises that fail."""
        return tuple(p for p in self.premises if p.holds is False)

    @property
    def undetermined(self) -> tuple[Premise, ...]:
        """The premises that could not be decided."""
        return tuple(p for p in self.premises if p.holds is None)

    @property
    def replaced(self) -> tuple[Premise, ...]:
        """The premises that fail as stated and are replaced by what is certified."""
        return tuple(p for p in self.premises if p.replaced_by is not None)

    def to_dict(self) -> dict:
        """The verdict as a JSON-ready mapping.

        Returns
        -------
        dict
            ``theorem``, ``sense``, ``guaranteed`` and the premises (all, failing,
            undetermined, replaced).
        """
        return {
            "theorem": self.theorem,
            "sense": self.sense,
            "sampled": self.sampled,
            "guaranteed": self.guaranteed,
            "premises": [p.to_dict() for p in self.premises],
            "failing": [p.to_dict() for p in self.failing],
            "undetermined": [p.to_dict() for p in self.undetermined],
            "replaced": [p.to_dict() for p in self.replaced],
        }


#: How a theorem verdict reads.
GUARANTEE_WORD = {True: "guaranteed", False: "not guaranteed", None: "undetermined"}


def theorem_table(
    verdicts: tuple[TheoremVerdict, ...] | list[TheoremVerdict], notes: Sequence[str] = ()
) -> Table:
    """The theorem verdicts as the table every face shows: each theorem, its sense, the
    verdict, and every premise that fails, is undetermined or is replaced (with what
    replaces it).

    Parameters
    ----------
    verdicts : sequence of TheoremVerdict
        The verdicts.
    notes : sequence of str, optional
        Said once below the verdicts (Assumption 2's violations and their fixes:
        :func:`assumption_notes`), however many theorems share the premise.

    Returns
    -------
    ntc_design.present.rows.Table
    """
    rows = []
    for th in verdicts:
        why = [f"fails: {p.name}: {p.detail}" for p in th.failing]
        why += [f"undetermined: {p.name}: {p.detail}" for p in th.undetermined]
        why += [
            f"replaced: {p.name} {p.detail}; in its place: {p.replaced_by}" for p in th.replaced
        ]
        rows.append(
            (
                f"Theorem {th.theorem} ({th.sense})",
                verdict(th.guaranteed, word=GUARANTEE_WORD[th.guaranteed]),
                lines(why or ["every premise holds"]),
            )
        )
    return Table.build(
        "theorems", ("theorem", "verdict", "premises"), rows, list(notes), layout="list"
    )


#: Violations of Assumption 2 named in the theorems' notes (``--json`` has them all).
MAX_VIOLATION_NOTES = 10


def assumption_notes(design: Any) -> list[str]:
    """Assumption 2's violations of a design (every mode's), each once, and each fix once
    with the agents it is for: the notes under the theorem verdicts, which name the
    premise without repeating them.

    Parameters
    ----------
    design : ProtocolDesign, SwitchingDesign, DigitalDesign or another design
        The design (the sampled protocol's: its continuous design's; a design without a
        decomposition, as a time-varying one, gives no notes).

    Returns
    -------
    list of str
    """
    if isinstance(design, DigitalDesign):  # the sampled protocol of a continuous design
        design = design.base
    if isinstance(design, SwitchingDesign):
        modes = {f"mode {k}: ": d for k, d in design.modes.items()}
    elif isinstance(design, ProtocolDesign):
        modes = {"": design}
    else:
        return []
    notes: list[str] = []
    for at, d in modes.items():
        viol = d.decomposition.violations
        if not viol:
            continue
        lab = d.topology.labels
        notes += [
            f"{at}Assumption 2 fails for agent {one_line(str(lab[v.agent]))}: {v.reason}"
            for v in viol[:MAX_VIOLATION_NOTES]
        ]
        if len(viol) > MAX_VIOLATION_NOTES:
            json = Option("json", alias="to_dict()")
            notes.append(f"{at}… and {len(viol) - MAX_VIOLATION_NOTES} more ({json} lists them)")
        notes += [f"{at}{n}" for n in fix_notes(viol, lab)]
    return notes


def _violating(design: ProtocolDesign, most: int = 5) -> str:
    """The agents violating Assumption 2, the first ``most`` named (the reasons are said
    once, in :func:`assumption_notes`)."""
    lab = design.topology.labels
    viol = design.decomposition.violations
    names = ", ".join(one_line(str(lab[v.agent])) for v in viol[:most])
    more = f", … ({len(viol)} in all)" if len(viol) > most else ""
    return f"agent{'s' if len(viol) > 1 else ''} {names}{more}"


def violations_text(design, most: int = 5) -> str:
    """Assumption 2's violations in words, the first ``most`` agents named (a network of
    10⁵ unreached agents gives one short line, not a megabyte).

    Parameters
    ----------
    design : ProtocolDesign
        A design whose decomposition failed.
    most : int, optional
        How many agents to name.

    Returns
    -------
    str
    """
    lab = design.topology.labels
    viol = design.decomposition.violations
    text = "; ".join(f"agent {lab[v.agent]}: {v.reason}" for v in viol[:most])
    return text + (f"; … {len(viol) - most} more agents" if len(viol) > most else "")


def gain_premises(gain: GainAnalysis | None, almost_sure: bool) -> list[Premise]:
    """The gain's premises: ∫c = ∞ and c → 0, and ∫c² < ∞ for almost-sure consensus.

    Parameters
    ----------
    gain : GainAnalysis or None
        None when no gain was given (the premise is then unknown).
    almost_sure : bool
        Add ∫c² < ∞ (Theorems 2 and 4).

    Returns
    -------
    list of Premise
    """
    if gain is None:
        return [
            Premise(
                "gain c(t)",
                None,
                f"no gain given ({Option('gain')}): the gain conditions are not checked",
            )
        ]
    keys = [k for k in CONDITION_LABELS if almost_sure or k != "square_integrable"]
    return [
        Premise(CONDITION_LABELS[k], gain.condition(k).value, gain.condition(k).reason)
        for k in keys
    ]


A1 = Premise(
    "Assumption 1 (‖f_ji(x)‖ <= σ̄‖x‖)",
    True,
    "assumed: a property of the noise model, not of the topology",
)


def fixed_verdicts(
    design: ProtocolDesign, ver: Verification, gain: GainAnalysis | None
) -> tuple[TheoremVerdict, ...]:
    """Theorems 1 (mean square) and 2 (almost sure) for one fixed topology.

    Parameters
    ----------
    design : ProtocolDesign
        The Lemma 1 design (Assumption 2 is read from it).
    ver : Verification
        The verification of the design's ``hurwitz`` certificate.
    gain : GainAnalysis or None
        The gain's conditions; None when no gain was given.

    Returns
    -------
    tuple of TheoremVerdict
    """
    hurwitz = ver.property_holds(Property.HURWITZ)
    th = design.thresholds
    proofs = [c for c in ver.checks if c.claim is not None and c.claim.prop is Property.HURWITZ]
    if hurwitz:
        hdetail = f"certified ({proofs[-1].detail})"
    else:
        hdetail = "not certified: " + ("; ".join(c.name for c in ver.failed) or "no proof")
    if th is not None and th.hurwitz is not None:
        hdetail += f"; δ = {design.delta:.6g} vs exact threshold δ_H = {th.hurwitz:.6g}"
    structural = Premise("−L_B Hurwitz (Lemma 1's conclusion, used by the proof)", hurwitz, hdetail)
    name = "Assumption 2 (V1/V2 decomposition; used through −L_B Hurwitz)"
    if design.assumption_holds:
        a2 = Premise(name, True, "holds")
    else:
        why = f"fails for {_violating(design)} (each violation and its fix: below)"
        a2 = Premise(
            name,
            hurwitz,
            why,
            "−L_B Hurwitz, certified directly (Lemma 1's conclusion is what the proof uses)"
            if hurwitz
            else None,
        )
    return (
        TheoremVerdict(1, "mean square", (A1, structural, a2, *gain_premises(gain, False))),
        TheoremVerdict(2, "almost sure", (A1, structural, a2, *gain_premises(gain, True))),
    )


def switching_verdicts(
    design: SwitchingDesign,
    ver: Verification,
    gain: GainAnalysis | None,
    bound: float,
    sym_min: dict[str, float],
) -> tuple[TheoremVerdict, ...]:
    """Theorems 3 (mean square) and 4 (almost sure) for a switching topology.

    Parameters
    ----------
    design : SwitchingDesign
        The per-mode Lemma 1 design.
    ver : Verification
        The verification of the design's ``switching`` certificate.
    gain : GainAnalysis or None
        The gain's conditions; None when no gain was given.
    bound : float
        The largest |weight entry| over the modes (Assumption 3's D).
    sym_min : dict
        λ_min(L_B(k) + L_B(k)ᵀ) per mode, for the messages.

    Returns
    -------
    tuple of TheoremVerdict
    """
    used = dict.fromkeys(m for m, _ in design.switching.schedule)
    sym_prem = []
    for k in used:
        mode = design.modes[k]
        ok = ver.property_holds(Property.SYMMETRIC_PART, mode=k)
        proof = [
            c
            for c in ver.checks
            if c.claim is not None and c.claim.prop is Property.SYMMETRIC_PART and c.claim.mode == k
        ]
        lam_v = sym_min.get(k)
        lam = f"λ_min = {lam_v:.6g}" if lam_v is not None else ""
        if ok:
            detail = f"certified ({lam}, {proof[0].detail})"
        else:
            short = -lam_v if lam_v is not None and lam_v <= 0 else None
            if short is not None:
                detail = f"fails by {short:.6g} ({lam})"
            else:  # no proof, but no evidence that it fails either: say which
                why = "; ".join(f"{c.name}: {c.detail}" for c in ver.failed) or "no proof"
                detail = f"not certified{f' ({lam})' if lam else ''}: {why}"
            th = mode.thresholds
            if th is not None and th.symmetric is not None:
                detail += (
                    f"; it holds for δ > δ_S = {th.symmetric:.6g} (designed δ = {mode.delta:.6g})"
                )
        sym_prem.append(Premise(f"L_B({k}) + L_B({k})ᵀ ≻ 0", ok, detail))
    a3 = Premise(
        "Assumption 3 (bounded weight entries)",
        True,
        f"finite set of modes: |a_kl| <= D = {bound:.6g}",
    )
    a2_fail = [k for k in used if not design.modes[k].assumption_holds]
    all_sym = all(p.holds for p in sym_prem)
    a2 = Premise(
        "Assumption 2 in every mode (used through L_B + L_Bᵀ ≻ 0)",
        True if all_sym else (not a2_fail),
        "holds in every mode"
        if not a2_fail
        else f"fails in mode(s) {', '.join(a2_fail)} (each violation and its fix: below)",
        "L_B(k) + L_B(k)ᵀ ≻ 0 in every scheduled mode, certified directly (the proofs of "
        "Theorems 3-4 use only that)"
        if a2_fail and all_sym
        else None,
    )
    a1 = Premise("Assumption 1 (‖f_ji(x)‖ <= σ̄‖x‖)", True, "assumed: a property of the noise model")
    return (
        TheoremVerdict(3, "mean square", (a1, a2, a3, *sym_prem, *gain_premises(gain, False))),
        TheoremVerdict(4, "almost sure", (a1, a2, a3, *sym_prem, *gain_premises(gain, True))),
    )


def time_varying_verdicts(result: dict, ver, gain) -> tuple:
    """Theorems 3 and 4 for a continuously time-varying topology.

    Parameters
    ----------
    result : dict
        The certificate's ``results.time_varying``.
    ver : Verification
        Its verification.
    gain : GainAnalysis or None
        The gain's conditions; None when no gain was given.

    Returns
    -------
    tuple of TheoremVerdict
        The verdicts of Theorems 3 and 4.
    """
    r = result
    a1 = Premise(
        "Assumption 1 (‖f_ji(x)‖ <= σ̄‖x‖)", True, f"f(x) = F x with σ̄ = {r['sigma_bar']:.4g}"
    )
    a3 = Premise(
        "Assumption 3 (bounded weight entries)",
        ver.valid,
        f"|a_kl(t)| <= D = {r['D']:.6g} for every t (ball arithmetic over {r['domain_text']})",
    )
    lam = Premise(
        "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ > 0 for every t (uniform, used by the proof)",
        ver.valid and r["lambda2"] > 0,
        f"Λ₂ = {r['lambda2']:.6g} certified on {r['intervals']} t-intervals "
        f"(sampled infimum {r['sampled_inf']:.6g})",
    )
    return (
        TheoremVerdict(3, "mean square", (a1, a3, lam, *gain_premises(gain, False))),
        TheoremVerdict(4, "almost sure", (a1, a3, lam, *gain_premises(gain, True))),
    )


def _eventually_decreasing(expr: sp.Expr) -> bool | None:
    """Whether c is non-increasing on [10⁹, ∞) (sympy), so that its sampled series and its
    integral converge or diverge together (the integral test)."""
    t = sp.Symbol("t", real=True)
    free = [s for s in expr.free_symbols if s.name == "t"]
    if not free:
        return True
    try:
        return bool(sp.is_decreasing(expr.subs(free[0], t), sp.Interval(T0_SCAN_END, sp.oo)))
    except Exception:  # noqa: BLE001 - sympy may fail on anything
        return None


def sampled_gain_premises(gain: GainAnalysis | None, h: float, almost_sure: bool) -> list[Premise]:
    """The sampled gain's premises: Σ_k c(kh) = ∞ and c(kh) → 0, and Σ_k c(kh)² < ∞ for
    almost-sure convergence, from the continuous conditions: c(t) → 0 gives c(kh) → 0; for
    the sums, c non-increasing beyond some time makes each sum and its integral (over h)
    converge or diverge together (the integral test).

    Parameters
    ----------
    gain : GainAnalysis or None
        The gain's continuous conditions.
    h : float
        The period.
    almost_sure : bool
        Add Σ c(kh)² < ∞.

    Returns
    -------
    list of Premise
    """
    if gain is None:
        return [Premise("gain c(kh)", None, f"no gain given ({Option('gain')})")]
    mono = _eventually_decreasing(gain.expr)
    transfer = "c non-increasing on [1e9, ∞) (sympy): integral test"

    def series(key: str, name: str) -> Premise:
        cont = gain.condition(key)
        if mono:
            return Premise(
                name, cont.value, f"{transfer}, with {CONDITION_LABELS[key]}: {cont.reason}"
            )
        return Premise(
            name,
            None,
            "c is not proven eventually non-increasing: the sum is not compared with the integral",
        )

    out = [
        Premise(
            f"c continuous and >= 0 (sampled every h = {h:g})",
            gain.continuous_nonnegative.value,
            gain.continuous_nonnegative.reason,
        ),
        series("integral_diverges", "Σ_k c(kh) = ∞"),
        Premise(
            "c(kh) → 0", gain.tends_to_zero.value, f"from c(t) → 0: {gain.tends_to_zero.reason}"
        ),
    ]
    if almost_sure:
        out.append(series("square_integrable", "Σ_k c(kh)² < ∞"))
    return out


def digital_verdicts(
    base: tuple[TheoremVerdict, ...],
    ver: Verification,
    gain: GainAnalysis | None,
    h: float,
    delay: int,
    detail: str,
) -> tuple[TheoremVerdict, ...]:
    """The sampled protocol's analogues of the base verdicts (Theorems 1-2 or 3-4): the
    same structural premises, the certified contraction of the sampled recursion from step
    k₀ on, and the sampled gain conditions.

    Parameters
    ----------
    base : tuple of TheoremVerdict
        The continuous verdicts of the design (mean square, then almost sure).
    ver : Verification
        The digital certificate's verification.
    gain : GainAnalysis or None
        The gain's conditions.
    h : float
        The period.
    delay : int
        D.
    detail : str
        What the certificate states (k₀, κ, …) or why it stops.

    Returns
    -------
    tuple of TheoremVerdict
        The sampled mean-square and almost-sure verdicts.
    """
    ok = ver.property_holds(Property.DIGITAL_MEAN_SQUARE)
    contraction = Premise(
        f"the sampled recursion (h = {h:g}, D = {delay}) contracts in mean square from step k₀",
        ok,
        f"certified: {detail}" if ok else f"not certified: {detail}",
    )
    gain_names = set(CONDITION_LABELS.values()) | {"gain c(t)"}
    out = []
    for th, sure in zip(base, (False, True), strict=True):
        structural = tuple(p for p in th.premises if p.name not in gain_names)
        sense = f"{th.sense}, sampled: h = {h:g}, D = {delay}"
        prem = (*structural, contraction, *sampled_gain_premises(gain, h, sure))
        out.append(TheoremVerdict(th.theorem, sense, prem, sampled=True))
    return tuple(out)


__all__ = [
    "assumption_notes",
    "digital_verdicts",
    "sampled_gain_premises",
    "violations_text",
    "gain_premises",
    "time_varying_verdicts",
    "Premise",
    "TheoremVerdict",
    "fixed_verdicts",
    "switching_verdicts",
]
