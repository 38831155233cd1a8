"""``verify``: re-check a certificate of any kind through one path.

What every kind shares is done here, once: the format and version, the digests, the
subject's θ (finite, of length d, non-zero, one for every mode), for a switching subject
its schedule (every scheduled mode described, the same agents, the switching hash), the
certified properties (those the kind may certify, its required ones included), the claims
(derived by the kind from its subject and compared with the listed ones, never read from
the file), the audit of every reported number, and whether the certificate is about the
user's own file and θ. The kind (:mod:`ntc_design.certify.kinds`) reads its subject,
derives its claims, proves each one and audits its results.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..gain.schedule import schedule_checks
from ..io.documents import check_text
from ..model import SwitchingTopology, Topology
from ..model.timevarying import ExpressionTopology
from ..present.rows import counted
from .checks import (
    About,
    Check,
    ModeAbout,
    Verification,
    integrity_checks,
    same_theta,
    same_topology,
    scheduled_described,
)
from .claims import Property
from .deadline_subject import audit_deadline, prove_deadline
from .fields import need, parse_schedule
from .format import (
    FORMAT,
    MAX_CERT_BYTES,
    SUPPORTED_VERSIONS,
    canonical,
    document_hash,
    scheduled_modes,
    switching_hash,
)
from .kinds.base import COMMON_FIELDS, CertificateKind, Reading, ResultsAudit, Subject
from .kinds.registry import KINDS


def _invalid(method: str, name: str, detail: str) -> Verification:
    return Verification(False, method, (Check(name, False, detail),))


def _theta_check(reading: Reading) -> Check:
    """One θ ≠ 0 for every mode (each mode's θ was read as d finite numbers)."""
    thetas = {tuple(m.theta.tolist()) for m in reading.modes.values()}
    first = next(iter(reading.modes.values())).theta
    ok = len(thetas) == 1 and bool(np.any(first != 0))
    detail = (
        f"θ = {first.tolist()}"
        if ok
        else "θ = 0 (Lemma 1 needs θ ≠ 0)"
        if len(thetas) == 1
        else f"modes differ: {sorted(thetas)}"
    )
    return Check("θ ≠ 0, one for every mode", ok, detail)


#: The fields of a subject's topology (dense and sparse forms, a time-varying one), of one
#: of its edges, and of a schedule entry.
TOPOLOGY_FIELDS = frozenset(
    {"name", "dim", "agents", "edges", "from", "to", "weights", "matrices", "period"}
)
EDGE_FIELDS = frozenset({"from", "to", "weight"})
SCHEDULE_FIELDS = frozenset({"mode", "duration"})


def _only(doc: Any, known: frozenset[str], where: str) -> None:
    """Refuse a field no reader checks (one line naming it): what verify does not prove is
    not in a certificate."""
    if not isinstance(doc, dict):
        return  # the reader names the wrong type
    unknown = sorted(str(k) for k in doc if k not in known)
    if unknown:
        field = f"{where}{unknown[0]}"
        known_text = f"unknown field (known: {', '.join(sorted(known))})"
        raise InputError(known_text[: max(0, 298 - len(field))], field=field)


def known_fields(kind: CertificateKind, doc: dict, source: str) -> None:
    """Refuse a certificate with a field its kind does not read: at the top level, in the
    subject, in each mode, its topology, its edges and the schedule's entries.

    Parameters
    ----------
    kind : CertificateKind
        The certificate's kind.
    doc : dict
        The certificate.
    source : str
        Its name, for messages.

    Raises
    ------
    InputError
        An unknown field, named.
    """
    _only(doc, COMMON_FIELDS | kind.fields, f"{source}: ")
    subject = doc.get("subject")
    # the deadline section is read by the shared path (prove_deadline), for every kind: a
    # kind it cannot bound is refused there
    _only(subject, kind.subject_fields | {"deadline"}, f"{source}: subject.")
    if not isinstance(subject, dict):
        return
    sampled = subject.get("digital")
    if "gain" in doc and isinstance(sampled, dict) and doc["gain"] != sampled.get("gain"):
        # the sampled proofs read subject.digital.gain only: another schedule at the top
        # level would verify its own conditions and read as certified
        raise InputError(
            "differs from subject.digital.gain, the gain the sampled "
            "protocol is proven for (a digital certificate states one gain)",
            field=f"{source}: gain",
        )
    tops = []
    if "topology" in kind.subject_fields:
        tops.append((subject.get("topology"), f"{source}: subject.topology"))
    modes = subject.get("modes")
    if isinstance(modes, dict):
        for name, mode in modes.items():
            where = f"{source}: subject.modes.{name}"
            _only(mode, kind.mode_fields, f"{where}.")
            if isinstance(mode, dict):
                tops.append((mode.get("topology"), f"{where}.topology"))
    for top, where in tops:
        _only(top, TOPOLOGY_FIELDS, f"{where}.")
        edges = top.get("edges") if isinstance(top, dict) else None
        for k, e in enumerate(edges if isinstance(edges, list) else []):
            _only(e, EDGE_FIELDS, f"{where}.edges[{k}].")
    schedule = subject.get("schedule")
    for k, e in enumerate(schedule if isinstance(schedule, list) else []):
        _only(e, SCHEDULE_FIELDS, f"{source}: subject.schedule[{k}].")


def _subject(
    kind: CertificateKind, doc_subject: dict, reading: Reading, source: str, checks: list[Check]
) -> Subject:
    """The schedule and the checks on it (switching kinds), or the one mode."""
    modes = reading.modes
    if not kind.switching:
        if len(modes) != 1:
            raise InputError(
                f"a {kind.name!r} certificate has one mode", field=f"{source}: subject.modes"
            )
        return Subject(modes, None, tuple(modes), None)
    schedule = parse_schedule(doc_subject, f"{source}: subject")
    scheduled = scheduled_modes(schedule)
    hashes = {k: m.hash for k, m in modes.items()}
    checks.append(scheduled_described(scheduled, hashes))
    first = next(iter(modes.values())).labels
    same = all(m.labels == first for m in modes.values())
    checks.append(Check("every mode has the same agents", same, "yes" if same else "no"))
    sw_hash = switching_hash(hashes, schedule)
    ok_h = doc_subject.get("switching_hash") == sw_hash
    checks.append(
        Check(
            "switching hash",
            ok_h,
            sw_hash if ok_h else f"stated {doc_subject.get('switching_hash')!r}, is {sw_hash}",
        )
    )
    return Subject(modes, schedule, scheduled, sw_hash)


def _properties(kind: CertificateKind, listed: list, checks: list[Check]) -> tuple[Property, ...]:
    """The properties certified, in the kind's order, with the check that they are ones
    the kind can certify and include the ones it must."""
    if any(not isinstance(p, str) for p in listed):
        raise InputError("expected a list of property names", field="certifies")
    names = {q.value for q in kind.properties}
    unknown = [p for p in listed if p not in names]
    props = tuple(q for q in kind.properties if q.value in listed)
    lacking = sorted(q.value for q in kind.required - set(props))
    twice = len(set(listed)) != len(listed)
    ok = not unknown and not lacking and bool(props) and not twice
    why = (
        [f"unknown property {u!r}" for u in unknown]
        + [f"kind {kind.name!r} must certify {q!r}" for q in lacking]
        + (["certifies nothing"] if not props else [])
        + (["a property is listed twice"] if twice else [])
    )
    checks.append(
        Check(
            f"certifies what kind {kind.name!r} can",
            ok,
            ", ".join(q.value for q in props) if ok else "; ".join(why),
        )
    )
    return props


def _claims_check(kind: CertificateKind, claims: tuple, listed: list) -> Check:
    """The listed claims are exactly the derived ones (compared canonically)."""
    want = sorted(canonical(kind.record(c)) for c in claims)
    got = sorted(canonical(c) for c in listed)
    ok = want == got
    ids = {c.id for c in claims}
    listed_ids = {c["id"] for c in listed if isinstance(c, dict) and isinstance(c.get("id"), str)}
    why = [f"missing {i!r}" for i in sorted(ids - listed_ids)] + [
        f"not required {i!r}" for i in sorted(listed_ids - ids)
    ]
    return Check(
        "listed claims are those the kind and subject require",
        ok,
        f"{len(claims)} claims"
        if ok
        else "; ".join(why) or "a listed claim differs from the derived one",
    )


def _user_topology(
    topology: Topology | SwitchingTopology | ExpressionTopology, subject: Subject
) -> Check:
    hashes = {k: m.hash for k, m in subject.modes.items()}
    if isinstance(topology, ExpressionTopology):
        mine = document_hash(topology.to_dict())
        ok = subject.schedule is None and list(hashes.values()) == [mine]
        return Check(
            "about the given topology",
            ok,
            f"topology hash {mine}" if ok else "the certificate is about another topology",
        )
    return same_topology(topology, hashes, subject.schedule, subject.switching_hash)


def verify(
    doc: Any,
    source: str = "certificate",
    topology: Topology | SwitchingTopology | ExpressionTopology | None = None,
    theta: Any = None,
) -> Verification:
    """Re-check a certificate mapping of any kind, deriving what must be proven from its
    kind and subject.

    Parameters
    ----------
    doc : Any
        The parsed JSON of a certificate.
    source : str
        Its name in messages (the file).
    topology : Topology, SwitchingTopology or ExpressionTopology, optional
        The user's own topology: the certificate must be about it (canonical hashes).
    theta : sequence of float, optional
        The user's θ: the certificate must be about it.

    Returns
    -------
    Verification
        ``valid`` when every check holds; an unknown format version or kind gives an
        invalid verification (nothing can be proven about it).

    Raises
    ------
    InputError
        When the certificate is malformed (wrong types or shapes, missing fields, sizes
        above the bounds).

    Examples
    --------
    >>> import json
    >>> from ntc_design.certify import verify
    >>> doc = json.load(open("certificates/g1.json"))
    >>> ver = verify(doc)
    >>> ver.valid, ver.about.kind
    (True, 'hurwitz')
    >>> doc["results"]["eig_bound"] = 100.0  # a forged number, even when re-digested,
    >>> verify(doc).valid                   # makes the certificate invalid
    False
    """
    kind_or_refusal = _kind_of(doc, source)
    if isinstance(kind_or_refusal, Verification):
        return kind_or_refusal
    kind = kind_or_refusal
    doc_subject = need(doc, "subject", dict, source)
    stated = need(doc, "digest", str, source)
    listed = need(doc, "claims", list, source)
    listed_props = need(doc, "certifies", list, source)
    checks: list[Check] = integrity_checks(doc, doc_subject, stated)
    modes_doc = doc_subject.get("modes")
    if not kind.switching and isinstance(modes_doc, dict) and len(modes_doc) != 1:
        # before the kind reads a subject it takes to be one topology (a kind edited)
        raise InputError(
            f"kind {kind.name!r} is about one topology, but subject.modes lists "
            f"{counted(len(modes_doc), 'mode')}",
            field=source,
        )

    known_fields(kind, doc, source)  # a field no reader checks is refused, never trusted
    reading = kind.read(doc, source)
    checks += reading.checks
    checks.append(_theta_check(reading))
    subject = _subject(kind, doc_subject, reading, source, checks)
    if topology is not None:
        checks.append(_user_topology(topology, subject))
    if theta is not None:
        checks.append(same_theta(theta, next(iter(subject.modes.values())).theta))

    try:
        props = _properties(kind, listed_props, checks)
    except InputError as exc:
        raise InputError(f"{exc}", field=source) from None
    alpha = kind.rate(doc, source) if Property.DECAY_RATE in props else 0.0
    claims = kind.claims(props, subject, reading, alpha)
    checks.append(_claims_check(kind, claims, listed))
    for c in claims:
        proof = kind.prove(c, subject, reading)
        checks += proof if isinstance(proof, list) else [proof]

    deadline = prove_deadline(doc, reading, source)  # the figures at T, when stated
    checks += deadline.checks
    if "gain" in doc:  # a tabulated schedule: its conditions derived here, never read
        checks += [
            Check(name, ok, detail) for name, ok, detail in schedule_checks(doc["gain"], source)
        ]
    audit = ResultsAudit(doc.get("results"), source)
    kind.audit(audit, doc, subject, reading, alpha)
    audit_deadline(audit, deadline)
    checks.append(audit.check())
    about = _about(kind, props, subject, alpha if Property.DECAY_RATE in props else None)
    about = replace(about, stated=kind.stated(props, reading))
    return Verification(
        all(c.ok for c in checks), kind.verification_method(reading), tuple(checks), about
    )


def _kind_of(doc: Any, source: str) -> CertificateKind | Verification:
    """The certificate's kind, or an invalid verification for a version or kind this
    ntc does not know (nothing can be proven about it)."""
    if not isinstance(doc, dict):
        raise InputError("expected a JSON object", field=source)
    if doc.get("format") != FORMAT:
        raise InputError(f"field 'format' must be {FORMAT!r}", field=source)
    version = need(doc, "version", int, source)
    if version not in SUPPORTED_VERSIONS:
        return _invalid(
            "none",
            "format version",
            f"version {version} is not one this ntc reads "
            f"({', '.join(map(str, SUPPORTED_VERSIONS))}); nothing is proven",
        )
    name = need(doc, "kind", str, source)
    kind = KINDS.get(name)
    if kind is None:
        return _invalid(
            "none",
            "certificate kind",
            f"unknown kind {name!r} (known: {', '.join(KINDS)}); nothing is proven",
        )
    return kind


def _about(kind: CertificateKind, props, subject, alpha: float | None) -> About:
    """What the certificate is about, from its (re-derived) subject."""
    return About(
        kind.name,
        kind.description,
        props,
        tuple(
            ModeAbout(k, m.topology, m.n, m.d, m.hash, m.delta, tuple(m.theta.tolist()))
            for k, m in subject.modes.items()
        ),
        subject.scheduled,
        subject.schedule,
        alpha,
        subject.switching_hash,
    )


def verify_file(
    path: str | Path,
    topology: Topology | SwitchingTopology | ExpressionTopology | None = None,
    theta: Any = None,
) -> Verification:
    """Read a certificate file (size-capped) and :func:`verify` it.

    Parameters
    ----------
    path : str or Path
        The certificate (JSON).
    topology, theta
        As in :func:`verify`.

    Returns
    -------
    Verification

    Raises
    ------
    InputError
        When the file is missing, too large, not JSON, or malformed.
    """
    p = Path(path)
    if not p.is_file():
        what = (
            "is a folder"
            if p.is_dir()
            else "no such file"
            if not p.exists()
            else "not a regular file"
        )
        raise InputError(
            f"{what}; expected a certificate (the JSON file ntc certify --out writes)", field=str(p)
        )
    if p.stat().st_size > MAX_CERT_BYTES:
        raise InputError(f"larger than {MAX_CERT_BYTES // 2**20} MB", field=str(p))
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        kind = (
            "a YAML file"
            if p.suffix.lower() in (".yaml", ".yml")
            else f"a {p.suffix} file"
            if p.suffix.lower() in (".csv", ".mat", ".npz")
            else f"not valid JSON ({exc.__class__.__name__})"
        )
        raise InputError(
            f"{kind}; expected a certificate (the JSON file ntc certify --out writes; "
            "a topology file goes to ntc verify CERT --topology FILE)",
            field=str(p),
        ) from None
    except RecursionError:
        raise InputError("nested too deeply", field=str(p)) from None
    except (ValueError, OSError) as exc:  # e.g. an integer literal with 10^5 digits
        raise InputError(f"cannot read ({exc.__class__.__name__})", field=str(p)) from None
    check_text(doc, str(p))  # a lone surrogate (a label, a name) cannot be shown or written
    return verify(doc, str(p), topology, theta)


__all__ = ["known_fields", "verify", "verify_file"]
