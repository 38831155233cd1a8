"""What verification reports: checks, what a certificate is about, the verification, and
the checks every kind shares (digests, θ, the schedule's modes, the user's own file)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import one_line
from ..model import SwitchingTopology, Topology
from ..present.rows import Table, verdict
from .claims import PROPERTY_TEXT, Claim, Property
from .format import DIGEST_NOTE, digest, document_hash, switching_hash, topology_hash


@dataclass(frozen=True)
class Check:
    """One thing verify established or failed to: ``claim`` is the inequality when the
    check proves one, None for a check of the certificate's integrity."""

    name: str
    ok: bool
    detail: str
    claim: Claim | None = None

    def to_dict(self) -> dict:
        """The check as a JSON-ready mapping.

        Returns
        -------
        dict
            ``name``, ``ok``, ``detail`` and, for a check of a claim, ``claim``.
        """
        doc = {"name": self.name, "ok": self.ok, "detail": self.detail}
        if self.claim is not None:
            doc["claim"] = self.claim.to_dict()
        return doc


@dataclass(frozen=True)
class ModeAbout:
    """A mode of the certified subject: its topology and protocol parameters."""

    name: str
    topology: str | None
    n: int
    d: int
    topology_hash: str
    delta: float | None  # None: δ(t) = C(t) + ΔC (time-varying)
    theta: tuple[float, ...]

    def to_dict(self) -> dict:
        """The mode as a JSON-ready mapping.

        Returns
        -------
        dict
            ``name``, ``topology``, ``N``, ``d``, ``topology_hash``, ``delta``, ``theta``.
        """
        return {
            "name": self.name,
            "topology": self.topology,
            "N": self.n,
            "d": self.d,
            "topology_hash": self.topology_hash,
            "delta": self.delta,
            "theta": list(self.theta),
        }


@dataclass(frozen=True)
class About:
    """What a certificate certifies about which topology (as verify derived it)."""

    kind: str
    description: str
    properties: tuple[Property, ...]
    modes: tuple[ModeAbout, ...]
    scheduled: tuple[str, ...]
    schedule: tuple[tuple[str, float], ...] | None
    alpha: float | None
    switching_hash: str | None
    stated: tuple[tuple[Property, str], ...] = ()  # the numbers each property states

    def to_dict(self) -> dict:
        """What is certified, as a JSON-ready mapping.

        Returns
        -------
        dict
            The kind, its description, each property with its meaning (and the numbers it
            states, where the kind has them), the modes, the schedule, α and the switching
            hash.
        """
        said = dict(self.stated)
        return {
            "kind": self.kind,
            "description": self.description,
            "properties": [
                {"property": p.value, "meaning": PROPERTY_TEXT[p]}
                | ({"stated": said[p]} if p in said else {})
                for p in self.properties
            ],
            "modes": [m.to_dict() for m in self.modes],
            "scheduled_modes": list(self.scheduled),
            "schedule": (
                [{"mode": m, "duration": t} for m, t in self.schedule]
                if self.schedule is not None
                else None
            ),
            "alpha": self.alpha,
            "switching_hash": self.switching_hash,
        }


@dataclass(frozen=True)
class Verification:
    """The outcome of :func:`verify`: valid when every check holds."""

    valid: bool
    method: str
    checks: tuple[Check, ...] = field(default=())
    about: About | None = None

    @property
    def failed(self) -> list[Check]:
        """The checks that do not hold (empty when the certificate is valid)."""
        return [c for c in self.checks if not c.ok]

    def property_holds(self, prop: Property, mode: str | None = None) -> bool:
        """Whether ``prop`` (for ``mode``, if given) is proven: the certificate's
        integrity checks hold and so does every claim of that property (there is one).

        Parameters
        ----------
        prop : Property
            The property asked about.
        mode : str, optional
            Only the claims about this mode (and those about no mode, such as P ≻ 0).

        Returns
        -------
        bool
            True only when it is proven.
        """
        integrity = all(c.ok for c in self.checks if c.claim is None)
        mine = [c for c in self.checks if c.claim is not None and c.claim.prop is prop]
        if mode is not None:  # the claims about this mode, and those about no mode (P ≻ 0)
            if not any(c.claim is not None and c.claim.mode == mode for c in mine):
                return False
            mine = [c for c in mine if c.claim is not None and c.claim.mode in (None, mode)]
        return integrity and bool(mine) and all(c.ok for c in mine)

    def table(self) -> Table:
        """Every check with its result and detail, as every face shows it.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        rows = [
            (c.name, verdict(c.ok, word="ok" if c.ok else "FAILS"), c.detail) for c in self.checks
        ]
        return Table.build(
            f"certificate checks ({self.method})", ("check", "result", "detail"), rows
        )

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        failed = [c.name for c in self.failed]
        what = f"{len(self.checks)} checks" + (
            f", failing: {'; '.join(failed[:3])}" if failed else ""
        )
        return f"Verification({'valid' if self.valid else 'INVALID'}, {self.method}, {what})"

    def to_dict(self) -> dict:
        """The verification as a JSON-ready mapping (what ``ntc verify`` prints as JSON).

        Returns
        -------
        dict
            ``valid``, ``method``, the digest note, what is certified, every check and
            the names of the failed ones.
        """
        return {
            "valid": self.valid,
            "method": self.method,
            "digest_note": DIGEST_NOTE,
            "certifies": self.about.to_dict() if self.about is not None else None,
            "checks": [c.to_dict() for c in self.checks],
            "failed": [c.name for c in self.failed],
        }


def integrity_checks(doc: dict, subject: Any, stated: str) -> list[Check]:
    """The digest and subject-digest checks every kind starts with.

    Parameters
    ----------
    doc : dict
        The certificate.
    subject : Any
        Its subject.
    stated : str
        The digest it states.

    Returns
    -------
    list of Check
    """
    ok_d = digest(doc) == stated
    ok_s = document_hash(subject) == doc.get("subject_digest")
    return [
        Check(
            "digest",
            ok_d,
            ("matches (" if ok_d else "does not match: the file changed after it was issued (")
            + "a checksum, not a signature)",
        ),
        Check("subject digest", ok_s, "matches" if ok_s else "does not match"),
    ]


def same_theta(theta: Any, got: np.ndarray) -> Check:
    """The check that a certificate is about the user's θ.

    Parameters
    ----------
    theta : sequence of float
        The user's θ.
    got : numpy.ndarray
        The certificate's θ.

    Returns
    -------
    Check
    """
    want = np.asarray(theta, dtype=float).reshape(-1)
    ok = want.shape == got.shape and bool(np.array_equal(want, got))
    return Check(
        "θ is the one given",
        ok,
        f"θ = {got.tolist()}"
        if ok
        else f"the certificate is about θ = {got.tolist()}, not {want.tolist()}",
    )


def scheduled_described(scheduled: tuple[str, ...], modes: Mapping[str, Any]) -> Check:
    """The check that every mode a schedule uses is described by the certificate.

    Parameters
    ----------
    scheduled : tuple of str
        The modes the schedule uses.
    modes : mapping
        The modes the certificate describes, by name.

    Returns
    -------
    Check
    """
    missing = [m for m in scheduled if m not in modes]
    return Check(
        "every scheduled mode is described",
        not missing,
        f"schedule uses {', '.join(scheduled)}"
        if not missing
        else f"the schedule uses {', '.join(map(repr, missing))}, which the certificate "
        "does not describe",
    )


def same_topology(
    topology: Topology | SwitchingTopology,
    hashes: Mapping[str, str],
    schedule: tuple[tuple[str, float], ...] | None,
    sw_hash: str | None,
) -> Check:
    """Whether the user's own file is what the certificate is about (canonical hashes of
    every mode and of the schedule).

    Parameters
    ----------
    topology : Topology or SwitchingTopology
        The user's file.
    hashes : mapping
        Mode name -> topology hash, as verify derived them.
    schedule : tuple or None
        The certificate's schedule (None for one topology).
    sw_hash : str or None
        Its switching hash.

    Returns
    -------
    Check
    """
    name = "about the given topology"
    if isinstance(topology, SwitchingTopology):
        if schedule is None:
            return Check(
                name, False, "a switching file was given; the certificate is about one topology"
            )
        mine_modes = {k: topology_hash(t) for k, t in topology.modes.items()}
        mine = switching_hash(mine_modes, topology.schedule)
        ok = mine == sw_hash
        if ok:
            return Check(name, True, f"switching hash {mine}")
        diff = [
            f"mode {k} differs" if k in hashes else f"mode {k} is not in the certificate"
            for k, h in mine_modes.items()
            if hashes.get(k) != h
        ] + [f"mode {k} is not in the file" for k in hashes if k not in mine_modes]
        if tuple(topology.schedule) != tuple(schedule):
            diff.append("the schedule differs")
        return Check(
            name,
            False,
            f"the file hashes to {mine}, the certificate is about {sw_hash}"
            + (f" ({'; '.join(diff)})" if diff else ""),
        )
    if schedule is not None:
        return Check(
            name, False, "one topology was given; the certificate is about a switching set"
        )
    mine = topology_hash(topology)
    (theirs,) = hashes.values()
    ok = mine == theirs
    return Check(
        name,
        ok,
        f"topology hash {mine}"
        if ok
        else f"the file hashes to {mine}, the certificate is about {theirs}",
    )


def verification_tables(doc: dict) -> list[Table]:
    """``ntc verify``'s account as the tables every face renders: what the certificate is
    about (kind, modes, schedule, the properties it certifies) and every check, then the
    digest note. Text from the certificate is put on one line here (control characters
    escaped): a forged name cannot print a line of its own.

    Parameters
    ----------
    doc : dict
        :meth:`Verification.to_dict`'s mapping.

    Returns
    -------
    list of ntc_design.present.rows.Table
    """
    tables = []
    ab = doc["certifies"]
    if ab is not None:
        rows: list[tuple[Any, Any]] = [("kind", one_line(f"{ab['kind']} ({ab['description']})"))]
        for m in ab["modes"]:
            used = "" if m["name"] in ab["scheduled_modes"] else " (not scheduled)"
            delta = f"δ = {m['delta']:.6g}" if m["delta"] is not None else "δ(t) = C(t) + ΔC"
            rows.append(
                (
                    one_line(f"mode {m['name']}"),
                    one_line(
                        f"topology {m['topology'] or '(unnamed)'}, N = {m['N']}, d = {m['d']}, "
                        f"{m['topology_hash']}, {delta}, θ = {m['theta']}{used}"
                    ),
                )
            )
        if ab["schedule"] is not None:
            sched = ", ".join(f"{s['mode']} {s['duration']:g}" for s in ab["schedule"])
            rows.append(("schedule", one_line(f"{sched} ({ab['switching_hash']})")))
        for p in ab["properties"]:
            alpha = f" (α = {ab['alpha']:.10g})" if p["property"] == "decay_rate" else ""
            alpha += f" ({p['stated']})" if p.get("stated") else ""
            rows.append(("certifies", one_line(f"{p['meaning']}{alpha}")))
        tables.append(Table.build("certificate", ("", ""), rows, layout="list"))
    checks = [
        (
            verdict(c["ok"], one_line(c["name"]), word="ok   " if c["ok"] else "FAILS"),
            one_line(c["detail"]),
        )
        for c in doc["checks"]
    ]
    tables.append(Table.build("checks", ("", ""), checks, [doc["digest_note"]], layout="list"))
    return tables


__all__ = [
    "verification_tables",
    "About",
    "Check",
    "ModeAbout",
    "Verification",
    "integrity_checks",
    "same_theta",
    "same_topology",
    "scheduled_described",
]
