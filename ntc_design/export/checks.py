"""What ``ntc export`` checks of the gain it emits: the code computes the gain that was
analysed, and its values stay in a range the state can take.

The certificate analyses c(t) exactly (sympy, ball arithmetic); the exported code computes
it in doubles, constants folded as written (:class:`~ntc_design.gain.code.GainCode`, the
same operations in C and Python). The two can part: ``1/(1+t) + exp(40) − exp(40)`` is
analysed as 1/(1+t) and computed as 0 (the 1/(1+t) is lost to rounding against
exp(40) ≈ 2.4e17). :func:`check_emitted_gain` evaluates the emitted code at the sample
times t_k = k·h and the analysed expression in ball arithmetic at 200 bits
(:func:`~ntc_design.rigorous.interval.enclose`) and refuses, naming the gain, when

- they differ by more than :data:`GAIN_RTOL` relative (16 ulps; :data:`GAIN_ATOL` absolute
  below 1e-300, where c·h·L_B moves no state), or
- a value is not finite, or one step's drift factor h·|c_k|·‖L_B‖∞ exceeds
  :data:`MAX_STEP_GAIN` (a state multiplied by 1e10 a step leaves the double range,
  1e308, in about 30 steps; c(0) = 1e300 is refused).

A schedule's table is emitted as its doubles, by the analysed interpolation rule: only its
tail is compared, every value is range-checked. The samples are every step up to
:data:`MAX_SAMPLES`; past that the first half of them and the other half spread
geometrically to the horizon (a rounding that sets in late, e.g. exp(t − 1100) − exp(t −
1100) absorbing 1/(1+t) from t ≈ 1,140 on, is met at every later sample).
"""

from __future__ import annotations

import math

import numpy as np
from flint import arb, ctx

from ..errors import InputError, one_line
from ..expr.symbolic import parse_expression
from ..protocol.agents import AgentLaw
from ..rigorous.interval import NotEnclosable, enclose

#: The emitted gain may differ from the analysed one by this much, relative (16 ulps).
GAIN_RTOL = 16 * 2.0**-52
#: ... or by this much absolute (c·h·L_B then moves no state a double can hold).
GAIN_ATOL = 1e-300
#: The largest drift factor h·|c_k|·‖L_B‖∞ of one step.
MAX_STEP_GAIN = 1e10
#: The most sample times checked.
MAX_SAMPLES = 20_000
#: Ball arithmetic precision (bits) of the reference values.
PRECISION = 200


def sample_steps(steps: int) -> np.ndarray:
    """The steps k whose gain is checked: all of 0 … K−1 up to :data:`MAX_SAMPLES`, else
    the first half of them and the rest spread geometrically to K−1.

    Parameters
    ----------
    steps : int
        K.

    Returns
    -------
    numpy.ndarray
        Sorted, distinct step indices.
    """
    if steps <= MAX_SAMPLES:
        return np.arange(steps, dtype=np.int64)
    half = MAX_SAMPLES // 2
    spread = np.geomspace(half, steps - 1, MAX_SAMPLES - half).round().astype(np.int64)
    return np.unique(np.concatenate([np.arange(half, dtype=np.int64), spread]))


def lb_norm_bound(law: AgentLaw) -> float:
    """An upper bound of ‖L_B‖∞ over the modes: per agent 2·Σ‖|A_ij|‖∞ over its in-edges
    plus ‖δ|B_i|‖∞.

    Parameters
    ----------
    law : AgentLaw
        The agents' law.

    Returns
    -------
    float
    """
    worst = 0.0
    for ml in law.modes:
        rows = np.abs(ml.weight).sum(axis=2).max(axis=1) if ml.n_edges else np.zeros(0)
        per = np.abs(ml.bd).sum(axis=2).max(axis=1)
        np.add.at(per, ml.dst, 2.0 * rows)
        worst = max(worst, float(per.max(initial=0.0)))
    return worst


def _reference(expr, t: float) -> float | None:
    """The analysed c(t) to 200 bits, rounded to a double; None when no ball rule applies."""
    try:
        ball = enclose(expr, arb(t))
    except NotEnclosable:
        return None
    if not ball.is_finite():
        return math.nan
    return float(ball.mid())


def check_emitted_gain(law: AgentLaw, steps: int, where: str = "gain") -> None:
    """Refuse a gain whose emitted code is not the analysed gain at the samples, or whose
    values the state cannot take (see the module docstring).

    Parameters
    ----------
    law : AgentLaw
        The agents' law (its gain, h and L_B).
    steps : int
        K, the horizon's steps.
    where : str, optional
        The gain's name in messages.

    Raises
    ------
    InputError
        One line naming the gain, the time and the two values.
    """
    g = law.gain
    h = law.digital.period
    norm = lb_norm_bound(law)
    expr = parse_expression(g.program.text, f"{where}.tail" if g.is_schedule else where)
    shown = one_line(g.label)[:80]
    old = ctx.prec
    ctx.prec = PRECISION
    try:
        for k in sample_steps(steps).tolist():
            t = float(k) * h  # t_k as the emitted code computes it
            c = g.value(t)
            if not math.isfinite(c) or not abs(c) * h * norm <= MAX_STEP_GAIN:
                raise InputError(
                    f"c(t) = {shown} is {c:.3g} at t = {t:.6g} (step {k}): one step "
                    f"h·|c|·‖L_B‖ = {abs(c) * h * norm:.3g} exceeds {MAX_STEP_GAIN:.0e}, the "
                    "state would leave the double range; nothing exported",
                    field=where,
                )
            if not t >= g.end:
                continue  # the table: its doubles, by the analysed rule
            ref = _reference(expr, t)
            if ref is None:
                continue
            if not abs(c - ref) <= GAIN_RTOL * abs(ref) + GAIN_ATOL:
                raise InputError(
                    f"c(t) = {shown} computes to {c!r} at t = {t:.6g} (step {k}) but "
                    f"is {ref!r} (the analysed gain): its constants cancel in floating point; "
                    "simplify it; nothing exported",
                    field=where,
                )
    finally:
        ctx.prec = old


__all__ = [
    "GAIN_ATOL",
    "GAIN_RTOL",
    "MAX_SAMPLES",
    "MAX_STEP_GAIN",
    "PRECISION",
    "check_emitted_gain",
    "lb_norm_bound",
    "sample_steps",
]
