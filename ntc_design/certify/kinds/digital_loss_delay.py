"""The ``digital_loss`` kind's delayed part (D >= 1, ``skip`` or ``rescale``): issuing the
section from :mod:`ntc_design.certify.loss_delay`'s plan, its claims and their proofs.

``results.digital`` then says ``bound: delay_line`` and states α, κ, g (the growth bound
of 1/c), t₀, k₀ = ⌈t₀/h⌉ + D, p_max, under skip the offset, and c_true on lossy links
(an estimate shown beside κ); the matrices add ``P.loss`` (S), ``P.loss_R<j>`` and
``P.loss_T<j>``. The claims: the delay line's form (S, T_j ≻ 0 and the R_j decrease,
:func:`.delayline.form_matrices`), its step G(κ) ⪰ 0 with L̄ and N'
(:func:`.loss_delay.loss_step_matrix`), (1/c)' < g and c < κ from t₀ on, and the offset.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InputError
from ...numerics.linalg import RANGE_TEXT, out_of_range
from ...rigorous.exact import Dyadic, exact_affordable
from ...rigorous.floatmat import FloatMat
from ..checks import Check
from ..claims import Claim, ClaimKind, Property
from ..delayline import form_matrices, prove_growth
from ..digital import first_step, gain_t0, prove_psd
from ..loss_delay import loss_step_matrix, plan_loss_delay

MS = Property.DIGITAL_MEAN_SQUARE
#: ``results.digital.bound`` of a delayed lossy certificate.
DELAY_LINE = "delay_line"


def delayed_claims(mode: str, policy: str, p_name: str) -> tuple[Claim, ...]:
    """The claims of the delayed lossy contraction.

    Parameters
    ----------
    mode : str
        The topology's mode name.
    policy : str
        ``skip`` (with the offset) or ``rescale``.
    p_name : str
        The matrices' name (``loss``).

    Returns
    -------
    tuple of Claim
    """
    out = [
        Claim(ClaimKind.DIGITAL_DL_FORM, MS, p=p_name),
        Claim(ClaimKind.LOSS_DL_STEP, MS, mode=mode, p=p_name),
        Claim(ClaimKind.DIGITAL_GROWTH, MS),
        Claim(ClaimKind.DIGITAL_T0, MS),
    ]
    if policy == "skip":
        out.append(Claim(ClaimKind.LOSS_OFFSET, MS, mode=mode))
    return tuple(out)


def issue_delayed(
    doc: dict,
    lap: np.ndarray,
    edges: list,
    noises: list,
    d: int,
    digital: Any,
    gain: Any,
    p_name: str,
) -> tuple[dict | None, str]:
    """Plan the delayed section and write its matrices into ``doc`` (nothing written when
    it stops).

    Parameters
    ----------
    doc : dict
        The certificate being issued.
    lap : numpy.ndarray
        L_B.
    edges : list of LossEdge
        The edges with their losses.
    noises : list of EdgeNoise
        Their noise.
    d : int
        The state dimension.
    digital : Digital
        The period, the delay and the policy.
    gain : str or dict
        c(t) as written in the subject.
    p_name : str
        The matrices' name.

    Returns
    -------
    (dict or None, str)
        ``results.digital`` without the offset (None: stopped) and why it stopped.
    """
    h, delay, policy = digital.period, digital.delay, digital.policy
    pl, c_true, how = plan_loss_delay(lap, edges, noises, d, h, delay, policy, gain)
    if pl is None:
        return None, f"the lossy delay line is not certified: {how}"
    t0, t0_how = gain_t0(gain, pl.kappa)
    if t0 is None:
        return None, f"c(t) does not stay below κ = {pl.kappa:.6g}: {t0_how}"
    if prove_growth(gain, pl.g, float(t0))[0] is not True:
        return None, f"(1/c)' < g = {pl.g:.6g} from t₀ on is not proven"
    mats = doc["matrices"]["P"]
    mats[p_name] = pl.s.tolist()
    for j, (r, t) in enumerate(zip(pl.rs, pl.ts, strict=True)):
        mats[f"{p_name}_R{j}"] = r.tolist()
        mats[f"{p_name}_T{j}"] = t.tolist()
    res: dict[str, Any] = {
        "bound": DELAY_LINE,
        "P_from": "the lossy delay line's SDP (Clarabel)",
        "policy": policy,
        "alpha": pl.alpha,
        "kappa": pl.kappa,
        "g": pl.g,
        "t0": float(t0),
        "t0_proof": t0_how,
        "k0": first_step(float(t0), h, delay),
    }
    if c_true is not None:
        res["c_true"] = c_true
    res["c_true_how"] = how
    return res, ""


def delayed_matrices(ctx: Any, p_name: str) -> Any:
    """S, R_j, T_j as read (None: one missing or out of range).

    Parameters
    ----------
    ctx : Any
        The reading's state.
    p_name : str
        The matrices' name.

    Returns
    -------
    (numpy.ndarray, list, list) or None
    """
    delay = ctx.digital.subject.delay
    try:
        s = ctx.p(p_name)
        rs = [ctx.p(f"{p_name}_R{j}") for j in range(delay)]
        ts = [ctx.p(f"{p_name}_T{j}") for j in range(delay)]
    except InputError:
        return None
    if s is None or any(x is None for x in rs + ts):
        return None
    return s, rs, ts


def prove_delayed(
    claim: Claim, ctx: Any, mode: Any, edges: list, noises: list, p_name: str
) -> Check:
    """Prove the delay line's form, its lossy step or the growth bound.

    Parameters
    ----------
    claim : Claim
        A ``digital_delay_line_form``, ``loss_delay_line_step`` or ``digital_growth``
        claim.
    ctx : Any
        The reading's state (``digital``, ``stated``, ``loss``, ``p``, ``methods``).
    mode : Any
        The mode read (``exact``, ``lap``, ``err``, ``in_range``, ``top``).
    edges : list of LossEdge
        The edges with their stated losses.
    noises : list of EdgeNoise
        Their noise.
    p_name : str
        The matrices' name.

    Returns
    -------
    Check
    """
    dg, st = ctx.digital.subject, ctx.digital.stated
    if claim.kind is ClaimKind.DIGITAL_GROWTH:
        ok, how = prove_growth(dg.gain, st.g, st.t0)
        return Check(claim.id, ok is True, f"interval: {how}", claim)
    mats = delayed_matrices(ctx, p_name)
    nums = [st.alpha, st.kappa, st.g, dg.period]
    if mats is None or any(x is None or out_of_range(x) for x in nums):
        return Check(claim.id, False, f"matrices.P or α, κ, g have {RANGE_TEXT}", claim)
    if not (st.alpha > 0 and st.kappa > 0 and st.g >= 0):
        return Check(claim.id, False, "α, κ must be > 0 and g >= 0", claim)
    s, rs, ts = mats
    if claim.kind is ClaimKind.DIGITAL_DL_FORM:
        exact = exact_affordable(s.shape[0], 4 * max(Dyadic.of(m).bits for m in [s, *rs, *ts]))
        names = []
        for name, m in form_matrices(s, rs, ts, st.alpha, st.kappa, st.g, dg.period, exact):
            proof = prove_psd(m)
            ctx.methods.add(proof.method)
            if not proof.holds:
                return Check(claim.id, False, f"{name}: {proof.method}: {proof.detail}", claim)
            names.append(name)
        how = "exact" if exact else "verified floats"
        return Check(claim.id, True, f"{how}: {', '.join(names)} ≻ 0", claim)
    if not mode.in_range:
        return Check(claim.id, False, f"mode {mode.name} has {RANGE_TEXT}", claim)
    d, pol = mode.top.dim, ctx.digital.loss.policy

    def step(exact: bool) -> Any:
        lap = mode.exact if exact else FloatMat.of(mode.lap, mode.err)
        return loss_step_matrix(
            s, rs, ts, lap, edges, noises, d, st.alpha, st.kappa, st.g, dg.period, pol, exact
        )

    m = step(True) if mode.exact is not None else None
    if m is not None and exact_affordable(m.num.shape[0], m.bits):
        proof = prove_psd(m)
    else:
        proof = prove_psd(step(False))
    ctx.methods.add(proof.method)
    return Check(claim.id, proof.holds, f"{proof.method}: {proof.detail}", claim)


__all__ = [
    "DELAY_LINE",
    "delayed_claims",
    "delayed_matrices",
    "issue_delayed",
    "prove_delayed",
]
