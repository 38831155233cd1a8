"""The ``hold`` section of kind ``digital_loss``: issuing, reading, proving and auditing
the mean-square certificate of :mod:`ntc_design.certify.loss_hold` (D = 0).

A certificate states S (``matrices.P.hold``, Nd×Nd) and R (``matrices.P.hold_R``, Ed×Ed),
and in ``results.digital`` α (the proven rate), α' (``alpha_step``), β, ρ, g, κ, t₀, k₀,
the largest p_e and, informational, c_true(hold). Its claims: S ≻ 0 (``pd``), the form
([[βS, SΠP_d], [·, R]] ≻ 0 and G₀ ≻ 0, exactly), the step G(κ) ≻ 0 (verified floats),
c(t) < κ from t₀, and the gain's change (c non-increasing and (1/c)' < g from t₀, with the
exact rational conditions on α, β, g, κ, ρ).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from ...errors import InputError
from ...expr.symbolic import parse_expression, symbol
from ...numerics.linalg import RANGE_TEXT, out_of_range
from ...rigorous.exact import exact_affordable
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..delayline import growth_bound, prove_growth
from ..digital import first_step, gain_t0, prove_psd
from ..fields import matrix, need, number
from ..loss import LossEdge
from ..loss_hold import HoldModel, HoldPlan, hold_matrices, hold_model, hold_rate
from ..loss_hold_plan import hold_ctrue, plan_hold

MS = Property.DIGITAL_MEAN_SQUARE
S_NAME = "hold"
R_NAME = "hold_R"
#: The numbers ``results.digital`` states for hold (besides k₀, p_max, c_true).
HOLD_KEYS = ("alpha", "alpha_step", "beta", "rho", "g", "kappa", "t0")


@dataclass(frozen=True)
class HoldStated:
    """``results.digital``'s numbers of a hold certificate."""

    alpha: float
    alpha1: float
    beta: float
    rho: float
    g: float
    kappa: float
    t0: float


def hold_claims(mode: str) -> tuple[Claim, ...]:
    """The claims of the hold section.

    Parameters
    ----------
    mode : str
        The topology's mode name.

    Returns
    -------
    tuple of Claim
    """
    return (
        Claim(ClaimKind.PD, MS, p=S_NAME),
        Claim(ClaimKind.LOSS_HOLD_FORM, MS, mode=mode, p=S_NAME),
        Claim(ClaimKind.LOSS_HOLD_STEP, MS, mode=mode, p=S_NAME),
        Claim(ClaimKind.DIGITAL_T0, MS),
        Claim(ClaimKind.LOSS_HOLD_GAIN, MS, mode=mode),
    )


def prove_nonincreasing(gain: Any, t0: float) -> tuple[bool, str]:
    """c is non-increasing on [t₀, ∞): a constant, or sympy's monotonicity of the
    expression on that interval.

    Parameters
    ----------
    gain : str or dict
        c(t) (a schedule is not accepted).
    t0 : float
        From where.

    Returns
    -------
    (bool, str)
    """
    if not isinstance(gain, str):
        return False, "hold needs c(t) as an expression"
    c = parse_expression(gain, "gain")
    if not c.has(symbol("t")):
        return True, "c is constant"
    try:
        dec = sp.is_decreasing(c, sp.Interval(sp.Rational(t0), sp.oo))
    except Exception:  # noqa: BLE001 - sympy may fail on anything
        dec = None
    if dec:
        return True, "c non-increasing from t₀ (sympy)"
    return False, "c non-increasing from t₀ not proven"


def rate_conditions(st: HoldStated, h: float) -> tuple[bool, str]:
    """The exact rational conditions: 0 < α <= α' − gβ/(1 − β), 0 < β < 1, ρ > 0,
    ghκβ <= 1 − β.

    Parameters
    ----------
    st : HoldStated
        The stated numbers.
    h : float
        The period.

    Returns
    -------
    (bool, str)
    """
    if any(out_of_range(x) for x in (st.alpha, st.alpha1, st.beta, st.rho, st.g, st.kappa)):
        return False, f"a number has {RANGE_TEXT}"
    b = Fraction(st.beta)
    if not (0 < b < 1 and st.g >= 0 and st.kappa > 0 and st.alpha > 0):
        return False, "not 0 < β < 1, g >= 0, κ > 0 and α > 0"
    if not st.rho > 0:
        return False, "ρ is not > 0"
    if Fraction(st.alpha) > hold_rate(st.alpha1, st.beta, st.g):
        return False, "α > α' − gβ/(1 − β)"
    if Fraction(st.g) * Fraction(h) * Fraction(st.kappa) * b > 1 - b:
        return False, "ghκβ > 1 − β"
    return True, "0 < α <= α' − gβ/(1 − β), ghκβ <= 1 − β (exact)"


def issue_hold(
    doc: dict,
    lap: np.ndarray,
    edges: list[LossEdge],
    noises: list,
    d: int,
    h: float,
    gain_doc: Any,
) -> tuple[dict | None, str | None]:
    """Find S, R and κ and the proven gain conditions; write the matrices into ``doc``.

    Parameters
    ----------
    doc : dict
        The certificate being issued (``matrices.P`` gets S and R).
    lap : numpy.ndarray
        L_B.
    edges : list of LossEdge
        The edges with their losses.
    noises : list of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    h : float
        The period.
    gain_doc : str or dict
        c(t).

    Returns
    -------
    (dict or None, str or None)
        ``results.digital`` without p_max, or None with why not.
    """
    if not isinstance(gain_doc, str):
        return None, "hold: needs c(t) as an expression (not a schedule)"
    g = growth_bound(gain_doc)
    if g is None:
        return None, "hold: (1/c)' has no finite bound"
    mo = hold_model(lap, edges, noises, d)
    decay = float(np.min(np.linalg.eigvals(lap).real))
    c_hi = hold_ctrue(mo, h)
    if c_hi is None:
        return None, "hold: no constant gain keeps the lossy second moments bounded"
    pl = plan_hold(mo, h, g, c_hi, decay)
    if pl is None:
        return None, "hold: no S, R found for the hold functional"
    t0, how = gain_t0(gain_doc, pl.kappa)
    if t0 is None:
        return None, f"hold: c(t) does not stay below κ = {pl.kappa:.6g}: {how}"
    ok, why = prove_growth(gain_doc, g, t0)
    if ok is not True:
        return None, f"hold: {why}"
    ok2, why2 = prove_nonincreasing(gain_doc, t0)
    if not ok2:
        return None, f"hold: {why2}"
    doc["matrices"]["P"][S_NAME] = pl.s.tolist()
    doc["matrices"]["P"][R_NAME] = pl.r.tolist()
    return {
        "P_from": "an SDP for S and R (Clarabel)",
        "policy": "hold",
        "alpha": pl.alpha,
        "alpha_step": pl.alpha1,
        "beta": pl.beta,
        "rho": pl.rho,
        "g": pl.g,
        "kappa": pl.kappa,
        "t0": t0,
        "t0_proof": how,
        "k0": first_step(t0, h, 0),
        "c_true": c_hi,
    }, None


def read_hold(res: dict, where: str) -> HoldStated:
    """Parse the stated numbers of a hold section.

    Parameters
    ----------
    res : dict
        ``results.digital``.
    where : str
        Its name, for messages.

    Returns
    -------
    HoldStated

    Raises
    ------
    InputError
        A missing or malformed number.
    """

    def num(key: str) -> float:
        return number(need(res, key, (int, float), where), f"{where}.{key}")

    return HoldStated(*(float(num(k)) for k in HOLD_KEYS))


def _model(mode: Any, edges: list[LossEdge], noises: list) -> HoldModel | None:
    if mode.exact is None:
        return None
    scale = 2**mode.exact.exp
    lap = np.vectorize(lambda v: Fraction(int(v), scale), otypes=[object])(mode.exact.num)
    return hold_model(lap, edges, noises, mode.top.dim)


#: The claim kinds of the hold section (besides ``pd`` and ``digital_t0``).
HOLD_CLAIMS = (ClaimKind.LOSS_HOLD_FORM, ClaimKind.LOSS_HOLD_STEP, ClaimKind.LOSS_HOLD_GAIN)


def prove_hold(
    claim: Claim,
    ctx: Any,
    st: Any,
    dg: Any,
    mode: Any,
    edges: list[LossEdge],
    noises: list,
) -> Check:
    """Prove one claim of the hold section.

    Parameters
    ----------
    claim : Claim
        ``loss_hold_form``, ``loss_hold_step`` or ``loss_hold_gain``.
    ctx : Any
        The reading's state (``p``, ``ps``, ``methods``, ``source``).
    st : HoldStated
        The stated numbers.
    dg : Any
        ``subject.digital`` as read (``period``, ``gain``).
    mode : Any
        The mode (its exact L_B is used).
    edges : list of LossEdge
        The edges with their losses.
    noises : list of EdgeNoise
        Their noise.

    Returns
    -------
    Check
    """
    if claim.kind is ClaimKind.LOSS_HOLD_GAIN:
        ok, how = rate_conditions(st, dg.period)
        if ok:
            ok1, how1 = prove_growth(dg.gain, st.g, st.t0)
            ok2, how2 = prove_nonincreasing(dg.gain, st.t0)
            ok, how = ok1 is True and ok2, f"{how}; {how1}; {how2}"
        return Check(claim.id, ok, how, claim)
    s = ctx.p(S_NAME)
    m = len(edges) * mode.top.dim
    raw = ctx.ps.get(R_NAME)
    if raw is None:
        raise InputError(f"missing {R_NAME!r}", field=f"{ctx.source}: matrices.P")
    r = matrix(raw, m, f"{ctx.source}: matrices.P.{R_NAME}")
    if s is None or out_of_range(r):
        return Check(claim.id, False, f"S or R has {RANGE_TEXT}", claim)
    ok, how = rate_conditions(st, dg.period)
    if not ok:
        return Check(claim.id, False, how, claim)
    mo = _model(mode, edges, noises)
    if mo is None:
        return Check(claim.id, False, "the exact L_B is not available", claim)
    pl = HoldPlan(s, r, st.alpha1, st.rho, st.beta, st.g, st.kappa, st.alpha)
    n = s.shape[0] + m
    exact = exact_affordable(n, 64)
    mats = dict(hold_matrices(mo, s, r, pl, dg.period, exact))
    names = ("[[βS, SΠP_d], [·, R]]", "G₀") if claim.kind is ClaimKind.LOSS_HOLD_FORM else ("G(κ)",)
    details, holds = [], True
    for name in names:
        proof = prove_psd(mats[name])
        ctx.methods.add(proof.method)
        holds = holds and proof.holds
        details.append(f"{name}: {proof.method}: {proof.detail}")
    return Check(claim.id, holds, "; ".join(details), claim)


def hold_detail(r: dict) -> str:
    """What a hold section proves, in words (for the rows and the verdicts).

    Parameters
    ----------
    r : dict
        ``results.digital``.

    Returns
    -------
    str
    """
    k, c = r.get("kappa"), r.get("c_true")
    share = f" ({k / c:.0%} of c_true(hold) = {c:.4g})" if isinstance(k, float) and c else ""
    return f"κ = {k:.4g}{share}" if isinstance(k, float) else ""


def audit_hold(audit: Any, state: Any) -> None:
    """Account for the hold section's numbers.

    Parameters
    ----------
    audit : ResultsAudit
        The audit.
    state : Any
        The kind's state (``stated``, ``subject``, ``loss``).
    """
    for key in HOLD_KEYS:
        audit.proven(("digital", key))
    audit.exact(("digital", "k0"), first_step(state.stated.t0, state.subject.period, 0))
    audit.exact(("digital", "p_max"), max(state.loss.losses.values(), default=0.0))
    audit.informational(("digital", "c_true"))


__all__ = [
    "HOLD_CLAIMS",
    "HOLD_KEYS",
    "HoldStated",
    "R_NAME",
    "S_NAME",
    "audit_hold",
    "hold_claims",
    "hold_detail",
    "issue_hold",
    "prove_hold",
    "prove_nonincreasing",
    "rate_conditions",
    "read_hold",
]
