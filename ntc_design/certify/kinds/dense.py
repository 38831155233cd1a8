"""What the two dense kinds (``hurwitz``, ``switching``) share: the subject read with every
L_B re-derived exactly (:func:`ntc_design.certify.dense.parse_mode`), stated L_B
compared with it, and each claim proven by its prover
(:data:`ntc_design.certify.dense.PROVERS`)."""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from ..checks import Check
from ..claims import Claim, ClaimKind, Property, derive_claims
from ..dense import PROVERS, DenseContext, parse_mode
from ..fields import matrix, need
from ..format import MAX_MODES, MAX_SIZE, RESULT_RTOL
from .base import CertificateKind, ModeReading, Reading, Subject


def read_dense(doc: dict, source: str) -> Reading:
    """Read a dense certificate's subject and matrices.

    Parameters
    ----------
    doc : dict
        The certificate.
    source : str
        Its name, for messages.

    Returns
    -------
    Reading
        The modes, their subject checks, and a :class:`DenseContext` for the provers.

    Raises
    ------
    InputError
        A malformed field, or sizes above the bounds.
    """
    n = need(doc, "size", int, source)
    if not 1 <= n <= MAX_SIZE:
        raise InputError(f"must be between 1 and {MAX_SIZE}, got {n}", field=f"{source}: size")
    subject = need(doc, "subject", dict, source)
    modes_doc = need(subject, "modes", dict, f"{source}: subject")
    if not modes_doc or len(modes_doc) > MAX_MODES:
        raise InputError(f"expected 1 to {MAX_MODES} modes", field=f"{source}: subject.modes")
    mats = need(doc, "matrices", dict, source)
    lbs = mats.get("L_B", {})
    if not isinstance(lbs, dict):
        raise InputError("expected an object mode -> matrix", field=f"{source}: matrices.L_B")
    ps = need(mats, "P", dict, f"{source}: matrices")
    checks: list[Check] = []
    modes = {str(k): parse_mode(str(k), v, n, source, checks) for k, v in modes_doc.items()}
    for name, m in modes.items():
        if name not in lbs:  # L_B is re-derived anyway; a stated one must match
            continue
        stated = matrix(lbs[name], n, f"{source}: matrices.L_B.{name}")
        diff = float(np.max(np.abs(m.lap - stated))) if m.in_range else math.inf
        bound = float(np.max(m.err + RESULT_RTOL * np.abs(m.lap))) if m.in_range else 0.0
        checks.append(
            Check(
                f"L_B({name}) matches its topology, B and δ",
                diff <= bound,
                f"max deviation {diff:.2e}",
            )
        )
    readings = {
        k: ModeReading(
            k,
            m.top.name,
            tuple(str(x) for x in m.top.labels),
            m.top.dim,
            m.hash,
            m.delta,
            m.theta,
        )
        for k, m in modes.items()
    }
    return Reading(readings, tuple(checks), DenseContext(source, n, modes, ps))


def prove_dense(claim: Claim, subject: Subject, reading: Reading) -> Check:
    """Prove one claim of a dense kind (exactly while affordable, else verified float).

    Parameters
    ----------
    claim : Claim
        The claim.
    subject : Subject
        The subject.
    reading : Reading
        From :func:`read_dense`.

    Returns
    -------
    Check
    """
    ctx: DenseContext = reading.state
    proof = PROVERS[claim.kind](claim, ctx)
    ctx.methods.add(proof.method)
    detail = f"{proof.method}: {proof.detail}"
    if claim.kind is ClaimKind.LYAPUNOV and claim.prop is Property.DECAY_RATE:
        detail += f" (α = {claim.alpha!r})"
    return Check(claim.id, proof.holds, detail, claim)


def dense_method(reading: Reading) -> str:
    """The proof methods used, joined (``exact-rational + verified-float``).

    Parameters
    ----------
    reading : Reading
        From :func:`read_dense`, after the proofs.

    Returns
    -------
    str
    """
    used = sorted(reading.state.methods - {"not attempted"}) or ["none"]
    return " + ".join(used)


class DenseKind(CertificateKind):
    """What the dense kinds share: their subject is read with L_B re-derived exactly, their
    claims are the property claims of :mod:`~ntc_design.certify.claims` for the scheduled
    modes, and each is proven by its dense prover."""

    def read(self, doc: dict, source: str) -> Reading:
        return read_dense(doc, source)

    def verification_method(self, reading: Reading) -> str:
        return dense_method(reading)

    def claims(
        self, properties: tuple[Property, ...], subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        return derive_claims(properties, subject.scheduled, alpha)

    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        return prove_dense(claim, subject, reading)


__all__ = ["DenseKind", "dense_method", "prove_dense", "read_dense"]
