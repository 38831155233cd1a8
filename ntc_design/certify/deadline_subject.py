"""The deadline figures in a certificate: ``subject.deadline`` (T, the period and delay or
none, the gain, the noise and the initial state) and ``results.deadline`` (T, B_T,
B_peak, the peak's time), issued by :func:`add_deadline` and re-derived by
:func:`prove_deadline` for every dense kind (``hurwitz``, ``switching`` and their digital
forms) from the certificate's content: L_B is the one the kind re-derived from the
subject, never a stated matrix (:mod:`ntc_design.certify.deadline` has the mathematics).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, Option, check_work
from ..rigorous.exact import Dyadic
from .checks import Check
from .deadline import (
    MAX_SECONDS,
    DeadlineBound,
    DeadlineProblem,
    check_sampled_work,
    continuous_work,
    deadline_bound,
    deadline_mode,
)
from .deadline_gain import GainBalls
from .deadline_loss import loss_bound, loss_problem, read_loss_section
from .dense import DenseContext
from .digital import edge_noises
from .fields import matrix, need, number, parse_schedule
from .format import finish
from .kinds.base import Reading, ResultsAudit, number_text
from .kinds.registry import KINDS

#: A stated bound may exceed the one re-derived by this share (a later version that
#: encloses more tightly keeps older certificates valid), not more: the figures belong to
#: the subject's initial state, gain and T.
FIGURE_SLACK = 0.05


def initial_moment(initial: Any, theta: np.ndarray, n: int, source: str = "initial") -> np.ndarray:
    """E[e(0) e(0)ᵀ] from ``{x0: [...]}`` (a given state) or ``{mean: [...], variance:
    [...]}`` (a distribution with independent components: its exact second moment).

    Parameters
    ----------
    initial : dict
        The subject's ``deadline.initial``.
    theta : numpy.ndarray
        θ.
    n : int
        N.
    source : str, optional
        Where it is written, for messages.

    Returns
    -------
    numpy.ndarray
        Nd × Nd.

    Raises
    ------
    InputError
        A missing field or a wrong size, naming it.
    """
    nd_ = n * theta.size
    if not isinstance(initial, dict):
        raise InputError("expected {x0: [...]} or {mean: [...], variance: [...]}", field=source)
    key = "x0" if "x0" in initial else "mean"
    mean = np.asarray(
        [number(v, f"{source}.{key}") for v in need(initial, key, list, source)], dtype=float
    )
    var = (
        np.asarray(
            [number(v, f"{source}.variance") for v in need(initial, "variance", list, source)],
            dtype=float,
        )
        if key == "mean"
        else np.zeros(nd_)
    )
    if mean.size != nd_ or var.size != nd_:
        raise InputError(f"expected N·d = {nd_} numbers", field=f"{source}.{key}")
    if np.any(var < 0):
        raise InputError("must be >= 0", field=f"{source}.variance")
    e = mean - np.tile(theta, n)
    return np.outer(e, e) + np.diag(var)


def noise_parts(noise: Any, d: int, source: str) -> tuple[np.ndarray, float, dict]:
    """F (d×d), σ and the per-edge σ from a ``{sigma, f, sigma_edges}`` document.

    Parameters
    ----------
    noise : dict
        The document.
    d : int
        The state dimension.
    source : str
        Where it is written.

    Returns
    -------
    (numpy.ndarray, float, dict)

    Raises
    ------
    InputError
        A missing or malformed field.
    """
    if not isinstance(noise, dict):
        raise InputError("expected {sigma, f, sigma_edges}", field=source)
    sigma = number(need(noise, "sigma", (int, float), source), f"{source}.sigma")
    f_raw = need(noise, "f", (int, float, list), source)
    f = (
        matrix(f_raw, d, f"{source}.f")
        if isinstance(f_raw, list)
        else number(f_raw, f"{source}.f") * np.eye(d)
    )
    edges = {}
    for k, e in enumerate(noise.get("sigma_edges", [])):
        if not isinstance(e, dict) or not all(isinstance(e.get(x), str) for x in ("from", "to")):
            raise InputError("expected {from, to, sigma}", field=f"{source}.sigma_edges[{k}]")
        edges[(e["from"], e["to"])] = number(e.get("sigma"), f"{source}.sigma_edges[{k}].sigma")
    if sigma < 0 or any(v < 0 for v in edges.values()):
        raise InputError("must be >= 0", field=f"{source}.sigma")
    return f, sigma, edges


def build_problem(
    modes: dict[str, tuple[Any, np.ndarray, np.ndarray, Dyadic | None]],
    schedule: Sequence[tuple[str, float]] | None,
    section: dict,
    theta: np.ndarray,
    source: str = "deadline",
    limit: float | None = None,
) -> DeadlineProblem:
    """The problem from the modes (topology, L_B, its error bound) and a ``deadline``
    section (``T``, ``period``, ``delay``, ``gain``, ``noise``, ``initial``).

    Parameters
    ----------
    modes : dict of str to (Topology, numpy.ndarray, numpy.ndarray, Dyadic or None)
        Each mode's topology, L_B, an entrywise bound on L_B's error and L_B exactly
        (None when not affordable).
    schedule : sequence of (str, float) or None
        The periodic schedule (None: one mode).
    section : dict
        The deadline section (as a certificate's subject states it).
    theta : numpy.ndarray
        θ.
    source : str, optional
        Where the section is written, for messages.
    limit : float, optional
        Refuse work estimated past this many seconds (default :data:`MAX_SECONDS`).

    Returns
    -------
    DeadlineProblem

    Raises
    ------
    InputError
        A missing or malformed field, or work past the limit (naming ``--deadline``).
    """
    if not isinstance(section, dict):
        raise InputError("expected an object", field=source)
    t_end = number(need(section, "T", (int, float), source), f"{source}.T")
    if not t_end > 0:
        raise InputError("must be > 0", field=f"{source}.T")
    period = section.get("period")
    if period is not None:
        period = number(period, f"{source}.period")
        if not 0 < period <= t_end:
            raise InputError("must be in (0, T]", field=f"{source}.period")
    delay = section.get("delay", 0)
    if not isinstance(delay, int) or isinstance(delay, bool) or not 0 <= delay <= 10_000:
        raise InputError("expected an integer D >= 0", field=f"{source}.delay")
    first = next(iter(modes.values()))[0]  # the agents and d of every mode
    n, d = first.n, first.dim
    f, sigma, edges = noise_parts(section.get("noise"), d, f"{source}.noise")
    names = tuple(modes)
    moment0 = initial_moment(section.get("initial"), theta, n, f"{source}.initial")
    gain = GainBalls(section.get("gain"))
    nd_ = n * d
    if period is not None:
        check_sampled_work(nd_, t_end, period, delay, limit)
    built = tuple(
        deadline_mode(lap, err, edge_noises(top, f, sigma, edges), d, exact)
        for top, lap, err, exact in modes.values()
    )
    pb = DeadlineProblem(
        built,
        names,
        tuple(schedule) if schedule is not None else None,
        gain,
        t_end,
        period,
        delay,
        moment0,
    )
    if period is None:
        secs = continuous_work(pb)
        check_work(
            secs,
            f"the enclosure of the moment equations (N·d = {nd_}, "
            f"T = {t_end:g}) takes roughly {secs:.3g} s",
            MAX_SECONDS if limit is None else limit,
            f"shorten T or use {Option('period')}",
            field="deadline",
            option=True,
        )
    return pb


@dataclass(frozen=True)
class DeadlineProof:
    """What verify proved about ``subject.deadline``: its checks and the bound."""

    checks: tuple[Check, ...]
    bound: DeadlineBound | None


def _bound(doc: dict, reading: Reading, source: str, limit: float | None = None) -> DeadlineBound:
    ctx = reading.state
    if not isinstance(ctx, DenseContext):
        raise InputError(
            f"kind {doc.get('kind')!r} states no deadline figures "
            "(a dense kind: hurwitz, switching, digital, digital_switching)",
            field=f"{source}: subject.deadline",
        )
    subject = doc["subject"]
    schedule = parse_schedule(subject, f"{source}: subject") if "schedule" in subject else None
    modes = {k: (m.top, m.lap, m.err, m.exact) for k, m in ctx.modes.items()}
    theta = next(iter(reading.modes.values())).theta
    where = f"{source}: subject.deadline"
    return section_bound(modes, schedule, subject["deadline"], theta, where, limit)


def section_bound(
    modes: dict[str, tuple[Any, np.ndarray, np.ndarray, Dyadic | None]],
    schedule: Sequence[tuple[str, float]] | None,
    section: dict,
    theta: np.ndarray,
    source: str = "deadline",
    limit: float | None = None,
) -> DeadlineBound:
    """B_T and B_peak for a ``deadline`` section: :func:`build_problem` and the sampled or
    continuous bound, or, when the section loses messages (``loss``), the lossy one
    (:mod:`ntc_design.certify.deadline_loss`).

    Parameters
    ----------
    modes, schedule, section, theta, source, limit
        As for :func:`build_problem`.

    Returns
    -------
    DeadlineBound

    Raises
    ------
    InputError
        As :func:`build_problem`; a malformed ``loss``, or a diverging recursion.
    """
    pb = build_problem(modes, schedule, section, theta, source, limit)
    if "loss" in section:  # lossy links
        top = next(iter(modes.values()))[0]
        f, sigma, edges = noise_parts(section["noise"], top.dim, f"{source}.noise")
        noises = edge_noises(top, f, sigma, edges)
        return loss_bound(loss_problem(pb, top, noises, section, theta, source, limit))
    return deadline_bound(pb)


def add_deadline(doc: dict, section: dict, limit: float | None = None) -> DeadlineBound:
    """Add the deadline figures to a certificate (in place) and seal it again.

    Parameters
    ----------
    doc : dict
        A certificate of a dense kind.
    section : dict
        ``subject.deadline``: ``T``, ``period`` (None: continuous), ``delay``, ``gain``,
        ``noise`` ``{sigma, f, sigma_edges}`` and ``initial`` (``{x0}`` or ``{mean,
        variance}``).
    limit : float, optional
        Refuse work estimated past this many seconds (default :data:`MAX_SECONDS`).

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
    bound = _bound(doc, reading, "certificate", limit)
    doc["results"]["deadline"] = bound.to_dict()
    doc.pop("digest", None)
    finish(doc, doc.get("verification_method"))
    return bound


def continuous_figures(doc: dict) -> DeadlineBound:
    """The continuous design's figures for a certificate's ``subject.deadline`` (the same
    T, gain, noise and initial state, no period): what the sampled ones are compared with.

    Parameters
    ----------
    doc : dict
        A certificate with ``subject.deadline``.

    Returns
    -------
    DeadlineBound

    Raises
    ------
    InputError
        As :func:`add_deadline`.
    """
    probe = copy.deepcopy(doc)
    probe["subject"]["deadline"] = {**doc["subject"]["deadline"], "period": None, "delay": 0}
    probe["subject"]["deadline"].pop("loss", None)  # the continuous design loses nothing
    reading = KINDS[doc["kind"]].read(probe, "certificate")
    return _bound(probe, reading, "certificate")


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
    if bound.loss is not None:
        how += f" on lossy links ({bound.loss['policy']}, p_e <= {bound.loss['p_max']:g})"
    check = Check(
        f"deadline T = {bound.t_end:g}: E Σ‖x_i(T) − θ‖² <= B_T, max over [0, T] <= B_peak",
        ok,
        f"{how}: proven <= {bound.ms_error_bound!r} and peak <= {bound.peak_bound!r}; stated "
        f"{stated.get('ms_error_bound')!r}, {stated.get('peak_bound')!r}",
    )
    return DeadlineProof((check, *_loss_checks(doc, reading, source)), bound)


def _loss_checks(doc: dict, reading: Reading, source: str) -> tuple[Check, ...]:
    """The deadline's lossy links are the subject's (``subject.digital.loss``, when the
    kind states one): the figures belong to the protocol the certificate is about."""
    subject = doc["subject"]
    digital = subject.get("digital")
    stated = digital.get("loss") if isinstance(digital, dict) else None
    if stated is None:
        return ()
    ctx = reading.state
    if not isinstance(ctx, DenseContext):
        return ()
    top = next(iter(ctx.modes.values())).top
    where = f"{source}: subject"
    mine = subject["deadline"].get("loss")
    theirs = read_loss_section(stated, top, f"{where}.digital.loss")
    same = mine is not None and read_loss_section(mine, top, f"{where}.deadline.loss") == theirs
    lossless = not any(p > 0 for p in theirs.losses.values())
    return (
        Check(
            "deadline: the lossy links of subject.digital (policy and every p_e)",
            same or (mine is None and lossless),
            f"subject.digital.loss: {theirs.policy}, p_e <= {theirs.p_max:g}; "
            f"subject.deadline.loss: {'none' if mine is None else 'different' if not same else 'the same'}",
        ),
    )


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
    if b.loss is not None:
        audit.exact(("deadline", "loss", "policy"), b.loss["policy"])
        audit.exact(("deadline", "loss", "p_max"), b.loss["p_max"])
    elif audit.has("deadline", "loss"):
        audit.fail("deadline.loss: stated, but the subject's deadline loses no message")


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
    loss = r.get("loss")
    lossy = (
        f" on lossy links (p_e <= {number_text(loss.get('p_max'))}, {loss.get('policy')})"
        if isinstance(loss, dict)
        else ""
    )
    return (
        f"E Σ‖x_i(T) − θ‖² <= {number_text(r.get('ms_error_bound'), 7)} at T = "
        f"{number_text(r.get('T'))}; peak <= {number_text(r.get('peak_bound'), 7)} "
        f"(t = {number_text(r.get('peak_time'), 4)}){lossy}"
    )


__all__ = [
    "FIGURE_SLACK",
    "DeadlineProof",
    "add_deadline",
    "audit_deadline",
    "deadline_text",
    "prove_deadline",
    "section_bound",
]
