"""Which of Theorems 1-4 is guaranteed for a design, a certificate and a gain.

Theorems 1-2 (fixed topology): Assumptions 1-2 and the gain conditions; their proofs use
Assumption 2 only through Lemma 1's conclusion that −L_B is Hurwitz, so a certified
Hurwitz −L_B is accepted in its place (and said so). Theorems 3-4 (time-varying): also
Assumption 3 (bounded weights; automatic for a finite set of modes) and
L_B(t) + L_B(t)ᵀ ≻ 0 for every t, certified per mode. Theorems 2 and 4 also need
∫c² < ∞. Assumption 1 concerns the noise f_ji, which a topology does not fix: it is
reported as assumed (it holds for f(x) = s·x with σ̄ = |s|).
"""

from __future__ import annotations

from ..gain import CONDITION_LABELS, GainAnalysis
from .certificate import Verification


def _premise(name: str, value: bool | None, detail: str) -> dict:
    return {"premise": name, "holds": value, "detail": detail}


def _gain_premises(gain: GainAnalysis | None, almost_sure: bool) -> list[dict]:
    if gain is None:
        return [
            _premise(
                "gain c(t)", None, "no gain given (--gain): the gain conditions are not checked"
            )
        ]
    keys = [k for k in CONDITION_LABELS if almost_sure or k != "square_integrable"]
    return [
        _premise(CONDITION_LABELS[k], gain.condition(k).value, gain.condition(k).reason)
        for k in keys
    ]


def _verdict(number: int, sense: str, premises: list[dict]) -> dict:
    vals = [p["holds"] for p in premises]
    guaranteed = (
        False if any(v is False for v in vals) else (None if any(v is None for v in vals) else True)
    )
    return {
        "theorem": number,
        "sense": sense,
        "guaranteed": guaranteed,
        "premises": premises,
        "failing": [p for p in premises if p["holds"] is False],
        "undetermined": [p for p in premises if p["holds"] is None],
    }


def _claim(ver: Verification, prefix: str) -> list:
    return [c for c in ver.checks if c.name.startswith(prefix)]


def fixed_verdicts(design_doc: dict, ver: Verification, gain: GainAnalysis | None) -> list[dict]:
    """Theorems 1 (mean square) and 2 (almost sure) for one fixed topology."""
    a2 = design_doc["assumption_holds"]
    viol = "; ".join(f"agent {v['agent']}: {v['reason']}" for v in design_doc["violations"])
    lyap = [
        c for c in ver.checks if "P_lyapunov·L_B" in c.name or c.name.startswith("−L_B(")
    ]
    hurwitz = bool(lyap) and all(c.ok for c in lyap) and ver.valid
    th = design_doc.get("thresholds") or {}
    hdetail = (
        f"certified ({lyap[0].detail})"
        if hurwitz
        else "not certified: " + "; ".join(c.name for c in ver.failed)
    )
    if th.get("hurwitz") is not None:
        hdetail += f"; δ = {design_doc['delta']:.6g} vs exact threshold δ_H = {th['hurwitz']:.6g}"
    structural = _premise(
        "−L_B Hurwitz (Lemma 1's conclusion, used by the proof)",
        hurwitz,
        hdetail
        + (
            ""
            if a2
            else f"; Assumption 2 itself fails ({viol}) and is replaced by this certificate"
        ),
    )
    a1 = _premise(
        "Assumption 1 (‖f_ji(x)‖ <= σ̄‖x‖)",
        True,
        "assumed: a property of the noise model, not of the topology",
    )
    return [
        _verdict(1, "mean square", [a1, structural, *_gain_premises(gain, False)]),
        _verdict(2, "almost sure", [a1, structural, *_gain_premises(gain, True)]),
    ]


def switching_verdicts(
    design_doc: dict,
    ver: Verification,
    gain: GainAnalysis | None,
    bound: float,
    sym_min: dict[str, float],
) -> list[dict]:
    """Theorems 3 (mean square) and 4 (almost sure) for a switching topology;
    ``sym_min[k]`` is λ_min(L_B(k) + L_B(k)ᵀ) and ``bound`` the largest |weight entry|."""
    sym_prem = []
    for k, mode in design_doc["modes"].items():
        checks = _claim(ver, f"L_B({k}) + L_B({k})ᵀ")
        ok = bool(checks) and all(c.ok for c in checks) and ver.valid
        th = mode.get("thresholds") or {}
        ver_min = sym_min.get(k)
        lam = f"λ_min = {ver_min:.6g}" if ver_min is not None else ""
        if ok:
            detail = f"certified ({lam}, {checks[0].detail})"
        else:
            short = -ver_min if ver_min is not None else None
            detail = f"fails{f' by {short:.6g} ({lam})' if short is not None else ''}"
            if th.get("symmetric") is not None:
                detail += f"; it holds for δ > δ_S = {th['symmetric']:.6g} (designed δ = {mode['delta']:.6g})"
        sym_prem.append(_premise(f"L_B({k}) + L_B({k})ᵀ ≻ 0", ok, detail))
    a1 = _premise(
        "Assumption 1 (‖f_ji(x)‖ <= σ̄‖x‖)", True, "assumed: a property of the noise model"
    )
    a3 = _premise(
        "Assumption 3 (bounded weight entries)",
        True,
        f"finite set of modes: |a_kl| <= D = {bound:.6g}",
    )
    a2_fail = [k for k, m in design_doc["modes"].items() if not m["assumption_holds"]]
    a2 = _premise(
        "Assumption 2 in every mode (used through L_B + L_Bᵀ ≻ 0)",
        True if all(p["holds"] for p in sym_prem) else (not a2_fail),
        "holds in every mode"
        if not a2_fail
        else f"fails in mode(s) {', '.join(a2_fail)}; the proofs of Theorems 3-4 use only L_B + L_Bᵀ ≻ 0, certified directly",
    )
    return [
        _verdict(3, "mean square", [a1, a2, a3, *sym_prem, *_gain_premises(gain, False)]),
        _verdict(4, "almost sure", [a1, a2, a3, *sym_prem, *_gain_premises(gain, True)]),
    ]
