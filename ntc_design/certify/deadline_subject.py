"""The deadline figures in a certificate: ``subject.deadline`` (T, the period and delay or
none, the gain, the noise and the initial state) and ``results.deadline`` (T, B_T,
B_peak, the peak's time), issued by :func:`add_deadline` and re-derived by
:func:`prove_deadline` for every dense kind (``hurwitz``, ``switching`` and their digital
forms) from the certificate's content: L_B is the one the kind re-derived from the
subject, never a stated matrix (:mod:`ntc_design.certify.deadline` has the mathematics).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .checks import Check
from .deadline import DeadlineBound, build_problem, deadline_bound
from .dense import DenseContext
from .fields import parse_schedule
from .format import finish
from .kinds.base import Reading, ResultsAudit, number_text
from .kinds.registry import KINDS


#: A stated bound may exceed the one re-derived by this share (a later version that
#: encloses more tightly keeps older certificates valid), not more: the figures belong to
#: the subject's initial state, gain and T.
FIGURE_SLACK = 0.05


@dataclass(frozen=True)
class DeadlineProof:
    """What verify proved about ``subject.deadline``: its checks and the bound."""

    checks: tuple[Check, ...]
    bound: DeadlineBound | None


def _bound(doc: dict, reading: Reading, source: str) -> DeadlineBound:
    ctx = reading.state
    if not isinstance(ctx, DenseContext):
        raise InputError(
            f"{source}: subject.deadline: kind {doc.get('kind')!r} states no deadline figures "
            "(a dense kind: hurwitz, switching, digital, digital_switching)"
        )
    subject = doc["subject"]
    schedule = parse_schedule(subject, f"{source}: subject") if "schedule" in subject else None
    modes = {k: (m.top, m.lap, m.err, m.exact) for k, m in ctx.modes.items()}
    theta = next(iter(reading.modes.values())).theta
    pb = build_problem(modes, schedule, subject["deadline"], theta, f"{source}: subject.deadline")
    return deadline_bound(pb)


def add_deadline(doc: dict, section: dict) -> DeadlineBound:
    """Add the deadline figures to a certificate (in place) and seal it again.

    Parameters
    ----------
    doc : dict
        A certificate of a dense kind.
    section : dict
        ``subject.deadline``: ``T``, ``period`` (None: continuous), ``delay``, ``gain``,
        ``noise`` ``{sigma, f, sigma_edges}`` and ``initial`` (``{x0}`` or ``{mean,
        variance}``).

    Returns
    -------
    DeadlineBound

    Raises
    ------
    InputError
        Another kind, a malformed section, or work past the limit (naming ``--deadline``).
    """
    doc["subject"]["deadline"] = section
    reading = KINDS[doc["kind"]].read(doc, "certificate")
    bound = _bound(doc, reading, "certificate")
    doc["results"]["deadline"] = bound.to_dict()
    doc.pop("digest", None)
    finish(doc, doc.get("verification_method"))
    return bound


def prove_deadline(doc: dict, reading: Reading, source: str) -> DeadlineProof:
    """Re-derive the deadline figures from the certificate's content (nothing when its
    subject states no deadline).

    Parameters
    ----------
    doc : dict
        The certificate.
    reading : Reading
        The kind's reading (its re-derived L_B).
    source : str
        Its name, for messages.

    Returns
    -------
    DeadlineProof

    Raises
    ------
    InputError
        A malformed ``subject.deadline``.
    """
    if "deadline" not in doc.get("subject", {}):
        return DeadlineProof((), None)
    bound = _bound(doc, reading, source)
    res = doc.get("results", {}).get("deadline")
    stated = res if isinstance(res, dict) else {}
    ok = (
        all(
            isinstance(stated.get(k), (int, float)) and stated[k] >= v * (1 - 1e-12)
            for k, v in (("ms_error_bound", bound.ms_error_bound), ("peak_bound", bound.peak_bound))
        )
        and stated.get("T") == bound.t_end
    )
    how = "ball recursion" if doc["subject"]["deadline"].get("period") else "Taylor enclosure"
    check = Check(
        f"deadline T = {bound.t_end:g}: E Σ‖x_i(T) − θ‖² <= B_T, max over [0, T] <= B_peak",
        ok,
        f"{how}: proven <= {bound.ms_error_bound!r} and peak <= {bound.peak_bound!r}; stated "
        f"{stated.get('ms_error_bound')!r}, {stated.get('peak_bound')!r}",
    )
    return DeadlineProof((check,), bound)


def audit_deadline(audit: ResultsAudit, proof: DeadlineProof) -> None:
    """Account for ``results.deadline``: T exact, the bounds at or above the re-derived
    ones, the peak's time within [0, T]. Without a proof its numbers stay unread (and
    fail the audit).

    Parameters
    ----------
    audit : ResultsAudit
        The audit.
    proof : DeadlineProof
        From :func:`prove_deadline`.
    """
    b = proof.bound
    if b is None:
        return
    audit.exact(("deadline", "T"), b.t_end)
    for key, value in (("ms_error_bound", b.ms_error_bound), ("peak_bound", b.peak_bound)):
        audit.bound(("deadline", key), value, "upper")
        got = audit.get("deadline", key)
        if isinstance(got, (int, float)) and got > (1 + FIGURE_SLACK) * value:
            audit.fail(
                f"deadline.{key}: {got!r} is more than {FIGURE_SLACK:.0%} above the bound "
                f"proven for this subject ({value:.10g}): not this subject's figure"
            )
    audit.estimate(("deadline", "peak_time"), 0.0, b.t_end)


def deadline_text(results: dict) -> str | None:
    """``results.deadline`` as one line (None when absent).

    Parameters
    ----------
    results : dict
        A certificate's results.

    Returns
    -------
    str or None
    """
    r = results.get("deadline")
    if not isinstance(r, dict):
        return None
    return (
        f"E Σ‖x_i(T) − θ‖² <= {number_text(r.get('ms_error_bound'), 7)} at T = "
        f"{number_text(r.get('T'))}; peak <= {number_text(r.get('peak_bound'), 7)} "
        f"(t = {number_text(r.get('peak_time'), 4)})"
    )


__all__ = [
    "FIGURE_SLACK",
    "DeadlineProof",
    "add_deadline",
    "audit_deadline",
    "deadline_text",
    "prove_deadline",
]
