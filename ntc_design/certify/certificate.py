"""Certificate files: what was certified (kind, properties, subject), the matrices to
re-check it, the claims it needs, the solver log and package versions, and a digest.

``verify`` re-checks a certificate with no SDP solver and trusts nothing it lists:

* what must be proven is derived from the certificate's *kind*, the *properties* it
  certifies and its *subject* (:mod:`ntc_design.certify.claims`); the listed claims are
  only compared with the derived ones;
* the subject is re-derived: L_B of every mode exactly from its topology, informed agents
  (= U), B_i (= Σ_{Ω_i}|A_ij|) and δ (dyadic rational arithmetic,
  :mod:`ntc_design.certify.exact`), ``k1 = 1 + 2/δ`` and ``x0 = k1·θ``, and a canonical
  hash of each topology (:func:`topology_hash`) that ``ntc verify --topology FILE``
  compares with the user's own file;
* every claim is proven exactly (Sylvester's criterion on integers) while that is
  affordable, else with a rigorous floating-point test; every number entering a proof
  must have a magnitude in ``[2^-NUMBER_EXP, 2^NUMBER_EXP]`` (or be 0), so neither
  arithmetic can blow up, overflow or underflow;
* every reported result (eigenvalue bound, α, residuals) is recomputed.

The digest is a SHA-256 checksum of the file's content. Anyone can recompute it: it
detects accidental damage, it does not authenticate anyone (it is not a signature).
"""

from __future__ import annotations

import hashlib
import json
import math
import platform
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from ..design import ProtocolDesign, SwitchingDesign, coupling_matrix
from ..errors import InputError
from ..files import parse_topology
from ..model import SwitchingTopology, Topology, antagonistic_in_weight
from ..outputs import write_atomic
from .claims import PROPERTY_TEXT, Claim, ClaimKind, Property, derive_claims
from .exact import (
    EXACT_MAX_N,
    Dyadic,
    PDProof,
    exact_affordable,
    exact_pd,
    gamma,
    verified_float_pd,
)
from .lyapunov import common_lyapunov, decay_rate_lmi, hurwitz_by_lyapunov

FORMAT = "ntc-design/certificate"
VERSION = 2
SUPPORTED_VERSIONS = (2,)
MAX_SIZE = 2000  # Nd of the largest certificate verify reads (its P alone is 32 MB)
MAX_MODES = 64
MAX_SCHEDULE = 10_000
MAX_CERT_BYTES = 256 * 2**20
#: Every nonzero number entering a proof has 2^-NUMBER_EXP <= |x| <= 2^NUMBER_EXP: a
#: product of three such numbers neither overflows nor underflows a double, and exact
#: entries stay a few hundred bits long.
NUMBER_EXP = 250
#: Reported floating-point results (eigenvalues, residuals) are recomputed and must agree
#: within RESULT_RTOL relative to the norm of the matrix they come from: eigenvalue
#: solvers differ in the last digits between machines.
RESULT_RTOL = 1e-8

DIGEST_NOTE = (
    "the digest is a SHA-256 checksum anyone can recompute: it detects accidental damage, "
    "it is not a signature; validity comes from the proofs, re-derived from the content"
)


def package_versions() -> dict[str, str]:
    """Versions of Python and of the packages a certificate depends on.

    Returns
    -------
    dict
        Package name -> version (``"not installed"`` when missing).
    """
    out = {"python": platform.python_version()}
    for pkg in (
        "ntc-design",
        "numpy",
        "scipy",
        "sympy",
        "cvxpy",
        "clarabel",
        "control",
        "python-flint",
    ):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def canonical(obj: Any) -> bytes:
    """The canonical JSON bytes that digests are taken of (sorted keys, no spaces).

    Parameters
    ----------
    obj : Any
        A JSON-compatible value.

    Returns
    -------
    bytes
    """
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode()


def _sha(obj: Any) -> str:
    return document_hash(obj)


def document_hash(doc: Any) -> str:
    """``sha256:`` and the SHA-256 of a document's canonical JSON (the hash of a
    time-varying topology, whose weights are expressions).

    Parameters
    ----------
    doc : Any
        A JSON-ready document.

    Returns
    -------
    str
    """
    return "sha256:" + hashlib.sha256(canonical(doc)).hexdigest()


def digest(doc: dict) -> str:
    """SHA-256 of everything in a certificate but its ``digest`` field: a checksum
    anyone can recompute, not a signature.

    Parameters
    ----------
    doc : dict
        A certificate.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    return _sha({k: v for k, v in doc.items() if k != "digest"})


#: Edges hashed per chunk by :func:`topology_hash` (its memory does not grow with E).
HASH_CHUNK = 20_000


def topology_hash(top: Topology) -> str:
    """A canonical hash of a topology: the same network gives the same hash whatever the
    file's layout (named matrices, ``diag``, edge order, its name).

    Hashed: the agent labels in order, d, and every edge with a nonzero weight as
    ``[from, to, weight]`` sorted by (to, from) index, each entry as the exact hex form of
    its double (``float.hex``; −0.0 is written as 0.0).

    Parameters
    ----------
    top : Topology
        A fixed topology.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    # the canonical JSON of {"dim", "edges", "labels"} written directly from the edge
    # arrays (one pass, no per-edge dict): the same bytes as json.dumps(..., sort_keys=True,
    # separators=(",", ":"), ensure_ascii=True) of the nested lists, and so the same hash
    ea = top.edge_arrays
    keep = np.any(ea.w != 0, axis=(1, 2))
    order = np.lexsort((ea.cols, ea.rows))
    order = order[keep[order]]
    d = top.dim
    lab = [
        json.dumps(x, ensure_ascii=True, sort_keys=True, separators=(",", ":")) for x in top.labels
    ]
    h = hashlib.sha256(f'{{"dim":{d},"edges":['.encode())
    for k0 in range(0, order.size, HASH_CHUNK):  # in chunks: memory stays small at any E
        part = order[k0 : k0 + HASH_CHUNK]
        hexes = [float.hex(x) for x in (ea.w[part] + 0.0).ravel().tolist()]
        rows = [",".join(f'"{x}"' for x in hexes[k : k + d]) for k in range(0, len(hexes), d)]
        mats = ["[[" + "],[".join(rows[k : k + d]) + "]]" for k in range(0, len(rows), d)]
        text = ",".join(
            f"[{lab[j]},{lab[i]},{m}]"
            for j, i, m in zip(ea.cols[part].tolist(), ea.rows[part].tolist(), mats, strict=True)
        )
        h.update((("," if k0 else "") + text).encode())
    h.update(f'],"labels":[{",".join(lab)}]}}'.encode())
    return "sha256:" + h.hexdigest()


def switching_hash(mode_hashes: Mapping[str, str], schedule) -> str:
    """A canonical hash of a switching topology: the hash of every mode by name and the
    schedule as ``[mode, duration.hex()]`` pairs in order.

    Parameters
    ----------
    mode_hashes : mapping
        Mode name -> :func:`topology_hash` of its topology.
    schedule : sequence of (str, float)
        The periodic schedule.

    Returns
    -------
    str
        ``"sha256:<hex>"``.
    """
    return _sha(
        {
            "modes": dict(sorted(mode_hashes.items())),
            "schedule": [[m, float(t).hex()] for m, t in schedule],
        }
    )


# ---------------------------------------------------------------------------- issue


def _mode_subject(d: ProtocolDesign) -> dict:
    lab = d.topology.labels
    return {
        "topology": d.topology.to_dict(),
        "topology_hash": topology_hash(d.topology),
        "theta": d.theta.tolist(),
        "margin": d.margin,
        "delta": d.delta,
        "k1": d.k1,
        "x0": d.x0.tolist(),
        "informed": [lab[i] for i in d.informed],
        "B": {str(lab[i]): b.tolist() for i, b in sorted(d.B.items())},
    }


def _min_eig(m: np.ndarray) -> float:
    if not np.all(np.isfinite(m)):
        return float("nan")
    return float(np.linalg.eigvalsh(0.5 * (m + m.T))[0])


def finish(doc: dict, method: str | None = None) -> dict:
    """Seal a certificate: the subject's digest, package versions, the verification
    method (when given) and the digest of everything.

    Parameters
    ----------
    doc : dict
        The certificate without its digests.
    method : str, optional
        ``verification_method``, for the kinds that state it.

    Returns
    -------
    dict
        ``doc``, completed.
    """
    doc["subject_digest"] = _sha(doc["subject"])
    doc["versions"] = package_versions()
    if method is not None:
        doc["verification_method"] = method
    doc["digest"] = digest(doc)
    return doc


def _eig_bound(lap_b: np.ndarray) -> float:
    """−max Re λ(−L_B) = min Re λ(L_B): the best decay rate of ε̇ = −L_B ε."""
    if not np.all(np.isfinite(lap_b)) or lap_b.size == 0:
        return float("nan")
    return float(np.min(np.linalg.eigvals(lap_b).real))


#: The dense certificate (Lyapunov + decay-rate LMI on a dense P) is used up to this Nd;
#: ``certify`` uses the component-wise certificate (:mod:`.scale`) above it (at Nd = 90
#: the LMI already takes 2.2 GB and minutes; :func:`require_lmi` refuses it above 2 GiB).
DENSE_CERT_MAX_ND = 60


def require_lmi(n: int, what: str) -> None:
    """Refuse, in one line, an LMI on a dense n×n P whose interior-point solve would need
    more than ``linalg.DENSE_MAX_BYTES``: with m = n(n+1)/2 unknowns one dense m×m array
    is 8·m² bytes (the 51,456,320,000-byte abort at n = 400 is exactly that), and the
    solve holds about 16 of them (n = 150 was measured at 14.6 GB), so 128·m² bytes."""
    from ..linalg import DENSE_MAX_BYTES, DenseRefused

    m = n * (n + 1) / 2
    need = 128.0 * m * m
    if need > DENSE_MAX_BYTES:
        raise DenseRefused(
            f"{what}: a dense {n}×{n} P needs about {need / 2**30:.0f} GiB "
            f"(limit {DENSE_MAX_BYTES / 2**30:.1f} GiB); refused — the component-wise "
            "certificate (ntc_design.certify.scale) applies at this size"
        )


def hurwitz_certificate(d: ProtocolDesign, name: str | None = None, rate: bool = True) -> dict:
    """Certify −L_B Hurwitz for one design in two independent ways: (a) the Lyapunov
    equation P L_B + L_Bᵀ P = I with P ≻ 0; (b) the LMI maximising the decay rate α.

    Parameters
    ----------
    d : ProtocolDesign
        The Lemma 1 design whose L_B is certified.
    name : str, optional
        The mode's name (default: the topology's name, or ``"topology"``).
    rate : bool
        Also look for a decay rate with the LMI (needs an SDP solver).

    Returns
    -------
    dict
        The certificate (kind ``hurwitz``); it certifies ``hurwitz`` always and
        ``decay_rate`` when the LMI found a P. Check it with :func:`verify`: a
        non-Hurwitz −L_B gives a certificate that does not verify.
    """
    name = name or d.topology.name or "topology"
    if rate:  # estimated before any dense step: refused in one line, never an OOM kill
        require_lmi(d.topology.nd, "decay-rate LMI")
    lap_b = d.grounded_laplacian()
    lya = hurwitz_by_lyapunov(lap_b)
    eig_bound = _eig_bound(lap_b)
    matrices: dict[str, Any] = {"L_B": {name: lap_b.tolist()}, "P": {"lyapunov": lya.p.tolist()}}
    results: dict[str, Any] = {
        "eig_bound": eig_bound,
        "lyapunov": {
            "residual": lya.residual,
            "P_min_eig": lya.p_min_eig,
            "method": "Schur, blocked Bartels–Stewart",
        },
    }
    props = [Property.HURWITZ]
    alpha = 0.0
    solver: dict[str, Any] = {"name": None, "status": None}
    if rate:
        r = decay_rate_lmi(lap_b, eig_bound=eig_bound)
        if r.p is not None:
            props.append(Property.DECAY_RATE)
            alpha = r.alpha
            matrices["P"]["rate"] = r.p.tolist()
        results["lmi"] = {
            "alpha": alpha,
            "eig_bound": eig_bound,
            "gap": eig_bound - alpha,
            "status": r.status,
            "bisection_steps": r.iterations,
        }
        solver = {"name": "Clarabel (via cvxpy)", "status": r.status}
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "hurwitz",
        "certifies": [p.value for p in props],
        "size": int(lap_b.shape[0]),
        "subject": {"modes": {name: _mode_subject(d)}},
        "matrices": matrices,
        "claims": [c.to_dict() for c in derive_claims(props, [name], alpha)],
        "results": results,
        "solver": solver,
    }
    return finish(doc)


def scheduled_modes(schedule) -> tuple[str, ...]:
    """The modes a schedule uses, in order of first use.

    Parameters
    ----------
    schedule : sequence of (str, float)

    Returns
    -------
    tuple of str
    """
    return tuple(dict.fromkeys(m for m, _ in schedule))


def switching_certificate(
    sd: SwitchingDesign, structures=("identity", "block-diagonal", "dense")
) -> dict:
    """Certify a switching set: L_B(k) + L_B(k)ᵀ ≻ 0 for every scheduled mode k
    (Theorems 3-4), and a common Lyapunov matrix P for all of them when one is found.

    Parameters
    ----------
    sd : SwitchingDesign
        One Lemma 1 design per mode.
    structures : sequence of str
        Structures tried for the common P, cheapest first.

    Returns
    -------
    dict
        The certificate (kind ``switching``); it certifies ``symmetric_part`` always (a
        mode where it fails makes the certificate fail to verify) and
        ``common_lyapunov`` when a P was found.
    """
    used = scheduled_modes(sd.switching.schedule)
    laps = {k: d.grounded_laplacian() for k, d in sd.modes.items()}
    n = next(iter(laps.values())).shape[0]
    sym = {k: _min_eig(lap + lap.T) for k, lap in laps.items()}
    common = common_lyapunov({k: laps[k] for k in used}, sd.switching.dim, structures)
    matrices: dict[str, Any] = {"L_B": {k: v.tolist() for k, v in laps.items()}, "P": {}}
    props = [Property.SYMMETRIC_PART]
    if common.p is not None:
        matrices["P"]["common"] = common.p.tolist()
        props.append(Property.COMMON_LYAPUNOV)
    mode_hashes = {k: topology_hash(d.topology) for k, d in sd.modes.items()}
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "switching",
        "certifies": [p.value for p in props],
        "size": int(n),
        "subject": {
            "modes": {k: _mode_subject(d) for k, d in sd.modes.items()},
            "schedule": [{"mode": m, "duration": t} for m, t in sd.switching.schedule],
            "switching_hash": switching_hash(mode_hashes, sd.switching.schedule),
        },
        "matrices": matrices,
        "claims": [c.to_dict() for c in derive_claims(props, used, 0.0)],
        "results": {
            "symmetric_part_min_eig": sym,
            "common_lyapunov": {
                "structure": common.structure,
                "attempts": [
                    {"structure": s, "status": st, "seconds": sec} for s, st, sec in common.attempts
                ],
                "margin": common.margin,
            },
        },
        "solver": {"name": "Clarabel (via cvxpy)", "status": [a[1] for a in common.attempts]},
    }
    return finish(doc)


def write_certificate(doc: dict, path: str | Path) -> None:
    """Write a certificate atomically (:func:`ntc_design.outputs.write_atomic`): a reader
    never sees a half-written file.

    Parameters
    ----------
    doc : dict
        The certificate, as made by :func:`hurwitz_certificate` or
        :func:`switching_certificate`.
    path : str or pathlib.Path
        The JSON file to write.

    Raises
    ------
    InputError
        When the folder cannot be written, the path is a folder, or the certificate holds
        non-finite numbers.
    """
    try:
        text = json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    except ValueError:  # JSON has no NaN/Inf: such numbers prove nothing anyway
        raise InputError(
            f"{path}: the certificate holds non-finite numbers (nothing is proven); not written"
        ) from None
    write_atomic(path, text)


# ---------------------------------------------------------------------------- verify


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
    delta: float
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

    def to_dict(self) -> dict:
        """What is certified, as a JSON-ready mapping.

        Returns
        -------
        dict
            The kind, its description, each property with its meaning, the modes, the
            schedule, α and the switching hash.
        """
        return {
            "kind": self.kind,
            "description": self.description,
            "properties": [
                {"property": p.value, "meaning": PROPERTY_TEXT[p]} for p in self.properties
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

    def to_dict(self) -> dict:
        """The verification as a JSON-ready mapping (what ``ntc verify --json`` prints).

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


def _need(doc: dict, key: str, typ: type | tuple, where: str) -> Any:
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected an object")
    if key not in doc:
        raise InputError(f"{where}: missing field '{key}'")
    v = doc[key]
    if isinstance(v, bool) and bool not in (typ if isinstance(typ, tuple) else (typ,)):
        raise InputError(f"{where}: field '{key}' has the wrong type (bool)")
    if not isinstance(v, typ):
        raise InputError(f"{where}: field '{key}' has the wrong type ({type(v).__name__})")
    return v


def _number(x: Any, where: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise InputError(f"{where}: expected a number, got {type(x).__name__}")
    try:
        v = float(x)
    except OverflowError:
        raise InputError(f"{where}: number too large") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: must be finite")
    return v


def _vector(x: Any, n: int, where: str) -> np.ndarray:
    if not isinstance(x, list) or len(x) != n:
        raise InputError(f"{where}: expected a list of {n} numbers")
    return np.array([_number(v, where) for v in x], dtype=float)


def _matrix(x: Any, n: int, where: str) -> np.ndarray:
    """An n×n matrix of finite numbers (shape checked before anything is allocated)."""
    if (
        not isinstance(x, list)
        or len(x) != n
        or any(not isinstance(r, list) or len(r) != n for r in x)
    ):
        raise InputError(f"{where}: expected a {n}x{n} matrix")
    for r in x:
        for v in r:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise InputError(f"{where}: non-numeric entry")
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{where}: non-numeric or too large entry") from None
    if not np.all(np.isfinite(a)):
        raise InputError(f"{where}: non-finite entry")
    return a


def out_of_range(a: np.ndarray | float) -> bool:
    """Whether some nonzero entry lies outside ``[2^-NUMBER_EXP, 2^NUMBER_EXP]``.

    Parameters
    ----------
    a : ndarray or float

    Returns
    -------
    bool
    """
    x = np.abs(np.asarray(a, dtype=float))
    nz = x[x != 0]
    return bool(nz.size) and (
        float(nz.min()) < 2.0**-NUMBER_EXP or float(nz.max()) > 2.0**NUMBER_EXP
    )


RANGE_TEXT = f"a nonzero |entry| outside [2^-{NUMBER_EXP}, 2^{NUMBER_EXP}] (cannot be bounded)"


def _lap_b_exact(top: Topology, b: Mapping[int, np.ndarray], delta: float) -> Dyadic:
    """``L_B = L + δ·blockdiag(B_i)`` exactly. Every weight, B_i and δ is a double, i.e. a
    dyadic rational, so L_B is an integer matrix over one power of two: assembled block by
    block (O(E·d²) conversions, not O(E·N²d²))."""
    d, n = top.dim, top.nd
    w = {k: Dyadic.of(a) for k, a in top.weights.items()}
    dl = Dyadic.of(delta)
    db = {
        i: Dyadic(dl.num[0, 0] * Dyadic.of(bi).num, dl.exp + Dyadic.of(bi).exp)
        for i, bi in b.items()
    }
    e = max([x.exp for x in w.values()] + [x.exp for x in db.values()] + [0])
    num = np.full((n, n), 0, dtype=object)
    for (i, j), a in w.items():
        blk = a.num * (1 << (e - a.exp))
        num[i * d : (i + 1) * d, j * d : (j + 1) * d] -= blk
        num[i * d : (i + 1) * d, i * d : (i + 1) * d] += top.sign(i, j) * blk
    for i, x in db.items():
        num[i * d : (i + 1) * d, i * d : (i + 1) * d] += x.num * (1 << (e - x.exp))
    return Dyadic(num, e)


def _lap_b_float(
    top: Topology, b: Mapping[int, np.ndarray], delta: float
) -> tuple[np.ndarray, np.ndarray]:
    """``L_B`` in floating point and an entrywise bound on its distance from the exact
    L_B: each entry is a sum of at most N+1 products of doubles, so the error is at most
    γ_{N+2} times the same sum taken in absolute values."""
    d, n = top.dim, top.nd
    mag = np.zeros((n, n))
    for (i, j), a in top.weights.items():
        mag[i * d : (i + 1) * d, j * d : (j + 1) * d] += np.abs(a)
        mag[i * d : (i + 1) * d, i * d : (i + 1) * d] += np.abs(a)
    dmat = coupling_matrix(top, b)
    lap_b = top.laplacian() + delta * dmat
    return lap_b, gamma(top.n + 2) * (mag + delta * np.abs(dmat))


def _float_expr_pd(
    p: np.ndarray, lap_f: np.ndarray | None, alpha: float, err_l: np.ndarray | None
) -> PDProof:
    """Verified-float proof of P ≻ 0 (lap None) or P L_B + L_Bᵀ P − 2αP ≻ 0, where
    ``err_l`` bounds |L_B exact − lap_f| entrywise."""
    n = p.shape[0]
    if lap_f is None:
        return verified_float_pd(p, np.zeros_like(p))
    ap, al = np.abs(p), np.abs(lap_f)
    m = p @ lap_f + lap_f.T @ p - 2 * alpha * p
    err = gamma(n + 3) * (ap @ al + al.T @ ap + 2 * abs(alpha) * ap)
    if err_l is not None:
        err += ap @ err_l + err_l.T @ ap
    return verified_float_pd(m, 2 * err * (1 + 8 * gamma(n)))


def _exact_expr(p: np.ndarray, lap: Dyadic | None, alpha: float) -> Dyadic:
    pd_ = Dyadic.of(p)
    if lap is None:
        return pd_
    m = pd_ @ lap + lap.T @ pd_
    if alpha != 0.0:
        m = m - pd_.scale(Dyadic.of(2.0 * alpha))
    return m


def _prove_pd_expr(
    p: np.ndarray,
    lap_exact: Dyadic | None,
    lap_f: np.ndarray | None,
    alpha: float,
    err_l: np.ndarray | None,
    exact: bool,
) -> PDProof:
    """Prove P ≻ 0 (no L_B) or P L_B + L_Bᵀ P − 2αP ≻ 0: exactly when asked and the
    bit lengths allow it (:func:`exact_affordable`), else by the verified-float test."""
    if exact and (lap_f is None or lap_exact is not None):
        m = _exact_expr(p, lap_exact, alpha)
        if exact_affordable(m.num.shape[0], m.bits):
            return exact_pd(m)
    return _float_expr_pd(p, lap_f, alpha, err_l)


@dataclass(frozen=True)
class HurwitzProof:
    """−L_B Hurwitz proven from the Lyapunov-equation P: P ≻ 0 and P L_B + L_Bᵀ P ≻ 0."""

    holds: bool
    p: np.ndarray
    p_pd: PDProof
    lyapunov_pd: PDProof
    seconds: float


def prove_hurwitz(lap_b: np.ndarray, exact: bool | None = None) -> HurwitzProof:
    """Solve P L_B + L_Bᵀ P = I and prove both inequalities for the given float L_B.

    Parameters
    ----------
    lap_b : ndarray
        L_B, taken as exact.
    exact : bool, optional
        Force the exact (True) or verified-float (False) test; default: exact up to
        ``EXACT_MAX_N``.

    Returns
    -------
    HurwitzProof
    """
    import time

    t0 = time.perf_counter()
    n = lap_b.shape[0]
    exact = n <= EXACT_MAX_N if exact is None else exact
    p = hurwitz_by_lyapunov(lap_b).p
    if not np.all(np.isfinite(p)):
        bad = PDProof(False, "none", "the Lyapunov equation has no finite solution")
        return HurwitzProof(False, p, bad, bad, time.perf_counter() - t0)
    lap_exact = Dyadic.of(lap_b) if exact else None
    p1 = _prove_pd_expr(p, None, None, 0.0, None, exact)
    p2 = _prove_pd_expr(p, lap_exact, lap_b, 0.0, np.zeros_like(lap_b), exact)
    return HurwitzProof(p1.holds and p2.holds, p, p1, p2, time.perf_counter() - t0)


@dataclass(frozen=True, eq=False)
class DenseMode:
    """A mode of the subject, parsed and re-derived."""

    name: str
    top: Topology
    theta: np.ndarray
    delta: float
    b: Mapping[int, np.ndarray]
    hash: str
    lap: np.ndarray  # float L_B derived from topology, B and δ
    err: np.ndarray  # entrywise bound on |L_B exact − lap|
    exact: Dyadic | None  # exact L_B (None above EXACT_MAX_N or out of range)
    in_range: bool


class DenseContext:
    """What the provers need: the modes, the matrices P (parsed on demand), the method."""

    def __init__(self, source: str, n: int, modes: dict[str, DenseMode], ps: dict) -> None:
        self.source, self.n, self.modes, self.ps = source, n, modes, ps
        self.exact = n <= EXACT_MAX_N
        self._p: dict[str, np.ndarray | None] = {}
        self.methods: set[str] = set()

    def p(self, name: str) -> np.ndarray | None:
        """A matrix P of the certificate by name, parsed once.

        Parameters
        ----------
        name : str
            ``lyapunov``, ``rate`` or ``common``.

        Returns
        -------
        numpy.ndarray or None
            None when an entry is out of range (nothing can be proven with it).

        Raises
        ------
        InputError
            Missing or malformed.
        """
        if name not in self._p:
            if name not in self.ps:
                raise InputError(f"{self.source}: matrices.P: missing {name!r}")
            a = _matrix(self.ps[name], self.n, f"{self.source}: matrices.P.{name}")
            self._p[name] = None if out_of_range(a) else a
        return self._p[name]


def _unproven(why: str) -> PDProof:
    return PDProof(False, "not attempted", why)


def _prove_pd(c: Claim, ctx: DenseContext) -> PDProof:
    p = ctx.p(c.p or "")
    if p is None:
        return _unproven(f"matrices.P.{c.p} has {RANGE_TEXT}")
    return _prove_pd_expr(p, None, None, 0.0, None, ctx.exact)


def _prove_lyapunov(c: Claim, ctx: DenseContext) -> PDProof:
    p = ctx.p(c.p or "")
    mode = ctx.modes.get(c.mode or "")
    if mode is None:
        return _unproven(f"the certificate does not describe mode {c.mode!r}")
    if p is None:
        return _unproven(f"matrices.P.{c.p} has {RANGE_TEXT}")
    if not mode.in_range or out_of_range(c.alpha):
        return _unproven(f"mode {mode.name} or α has {RANGE_TEXT}")
    return _prove_pd_expr(p, mode.exact, mode.lap, c.alpha, mode.err, ctx.exact)


def _prove_symmetric(c: Claim, ctx: DenseContext) -> PDProof:
    mode = ctx.modes.get(c.mode or "")
    if mode is None:
        return _unproven(f"the certificate does not describe mode {c.mode!r}")
    if not mode.in_range:
        return _unproven(f"mode {mode.name} has {RANGE_TEXT}")
    if mode.exact is not None:
        m = mode.exact + mode.exact.T
        if exact_affordable(ctx.n, m.bits):
            return exact_pd(m)
    s = mode.lap + mode.lap.T
    return verified_float_pd(s, gamma(2) * np.abs(s) + mode.err + mode.err.T)


def _prove_positive_rate(c: Claim, ctx: DenseContext) -> PDProof:
    ok = c.alpha > 0 and not out_of_range(c.alpha)
    return PDProof(ok, "exact-rational", f"α = {c.alpha!r}" + (" > 0" if ok else " is not > 0"))


#: How each kind of claim is proven.
PROVERS: dict[ClaimKind, Callable[[Claim, DenseContext], PDProof]] = {
    ClaimKind.PD: _prove_pd,
    ClaimKind.LYAPUNOV: _prove_lyapunov,
    ClaimKind.SYMMETRIC_PART: _prove_symmetric,
    ClaimKind.POSITIVE_RATE: _prove_positive_rate,
}


def _check_topology_fields(t: dict, size: int, where: str) -> None:
    """Sizes of a subject topology before it is parsed (nothing large is allocated)."""
    dim, agents, edges = t.get("dim"), t.get("agents"), t.get("edges")
    if isinstance(dim, int) and not isinstance(dim, bool) and not 1 <= dim <= size:
        raise InputError(f"{where}.dim: must be between 1 and the certificate size {size}")
    n = agents if isinstance(agents, int) else len(agents) if isinstance(agents, list) else 0
    if n > size:
        raise InputError(f"{where}.agents: more agents than the certificate size {size}")
    if isinstance(edges, list) and len(edges) > max(n * (n - 1), 0):
        raise InputError(f"{where}.edges: more edges than N(N−1)")


def parse_mode(name: str, sub: Any, n: int, source: str, checks: list[Check]) -> DenseMode:
    """Read one mode of a dense certificate's subject and re-derive it: the topology and
    its hash, informed agents = U, B_i = Σ_{Ω_i}|A_ij| exactly, k1 and x0 from δ and θ,
    and L_B (float with an error bound, and exact while affordable).

    Parameters
    ----------
    name : str
        The mode's name.
    sub : Any
        Its subject entry.
    n : int
        The certificate's size Nd.
    source : str
        The certificate's name, for messages.
    checks : list of Check
        The subject checks are appended to it.

    Returns
    -------
    DenseMode
        The mode, parsed and re-derived.

    Raises
    ------
    InputError
        A missing or malformed field.
    """
    where = f"{source}: subject.modes.{name}"
    if not isinstance(sub, dict):
        raise InputError(f"{where}: expected an object")
    tdoc = _need(sub, "topology", dict, where)
    _check_topology_fields(tdoc, n, f"{where}.topology")
    top = Topology.from_data(parse_topology(tdoc, f"{where}.topology"))
    if top.nd != n:
        raise InputError(f"{where}: topology has Nd={top.nd}, certificate size is {n}")
    d = top.dim
    theta = _vector(_need(sub, "theta", list, where), d, f"{where}.theta")
    delta = _number(_need(sub, "delta", (int, float), where), f"{where}.delta")
    if not delta > 0:
        raise InputError(f"{where}.delta: must be positive")
    k1 = _number(_need(sub, "k1", (int, float), where), f"{where}.k1")
    x0 = _vector(_need(sub, "x0", list, where), d, f"{where}.x0")
    _number(_need(sub, "margin", (int, float), where), f"{where}.margin")
    stated_hash = _need(sub, "topology_hash", str, where)
    informed_l = _need(sub, "informed", list, where)
    try:
        informed = [top.index(x) for x in informed_l]
    except InputError:
        raise InputError(f"{where}.informed: lists an unknown agent") from None
    bd = _need(sub, "B", dict, where)
    try:
        b = {top.index(k): _matrix(v, d, f"{where}.B.{k}") for k, v in bd.items()}
    except InputError as exc:
        if "unknown agent" in str(exc):
            raise InputError(f"{where}.B: lists an unknown agent") from None
        raise

    h = topology_hash(top)
    checks.append(
        Check(
            f"{name}: topology hash",
            h == stated_hash,
            h if h == stated_hash else f"stated {stated_hash}, the topology hashes to {h}",
        )
    )
    ok_inf = sorted(informed) == sorted(top.antagonised) and set(b) == set(informed)
    checks.append(
        Check(
            f"{name}: informed agents are U",
            ok_inf,
            "V_I = U" if ok_inf else "V_I ≠ U, or B listed for other agents",
        )
    )
    in_range = not (
        any(out_of_range(a) for a in top.weights.values())
        or any(out_of_range(a) for a in b.values())
        or out_of_range(delta)
    )
    ok_b = ok_inf and all(
        Dyadic.of(b[i]).equals(Dyadic.of(antagonistic_in_weight(top, i))) for i in b
    )
    checks.append(
        Check(
            f"{name}: B_i = Σ_Ω|A_ij|",
            ok_b,
            "exact" if ok_b else "a B_i differs from Σ_{Ω_i}|A_ij| of the topology",
        )
    )
    # the issuer computed k1 = 1 + 2/δ and x0 = k1·θ in IEEE double: the same operations
    # give the same bits, so θ cannot change without x0 (or k1) changing too
    want_k1 = 1.0 + 2.0 / delta
    ok_x = k1 == want_k1 and bool(np.array_equal(x0, want_k1 * theta))
    checks.append(
        Check(
            f"{name}: k1 = 1 + 2/δ, x0 = k1·θ",
            ok_x,
            f"θ = {theta.tolist()}, x0 = {x0.tolist()}"
            if ok_x
            else f"k1 = {k1!r}, x0 = {x0.tolist()} do not follow from δ = {delta!r}, θ = {theta.tolist()}",
        )
    )
    checks.append(
        Check(
            f"{name}: numbers within range",
            in_range,
            "every weight, B_i and δ can be bounded" if in_range else f"{RANGE_TEXT}",
        )
    )
    if in_range:
        lap, err = _lap_b_float(top, b, delta)
        exact = _lap_b_exact(top, b, delta) if n <= EXACT_MAX_N else None
    else:
        lap, err, exact = np.zeros((n, n)), np.zeros((n, n)), None
    return DenseMode(name, top, theta, delta, b, h, lap, err, exact, in_range)


def finite_number(x: Any) -> float | None:
    """A JSON number as a finite float, else None (a bool, a string, NaN, or an integer
    beyond any double).

    Parameters
    ----------
    x : Any
        A value read from a certificate.

    Returns
    -------
    float or None
    """
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    try:
        xf = float(x)
    except OverflowError:
        return None
    return xf if math.isfinite(xf) else None


def _parse_schedule(subject: dict, where: str) -> tuple[tuple[str, float], ...]:
    sched = _need(subject, "schedule", list, where)
    if not sched or len(sched) > MAX_SCHEDULE:
        raise InputError(f"{where}.schedule: expected 1 to {MAX_SCHEDULE} entries")
    out = []
    for k, item in enumerate(sched):
        w = f"{where}.schedule[{k}]"
        if not isinstance(item, dict) or set(item) != {"mode", "duration"}:
            raise InputError(f"{w}: expected {{mode, duration}}")
        if not isinstance(item["mode"], str):
            raise InputError(f"{w}.mode: expected a mode name")
        t = _number(item["duration"], f"{w}.duration")
        if not 0 < t < 1e300:
            raise InputError(f"{w}.duration: must be positive and finite")
        out.append((item["mode"], t))
    return tuple(out)


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
    ok_s = _sha(subject) == doc.get("subject_digest")
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


def _same_topology(
    topology: Topology | SwitchingTopology,
    hashes: Mapping[str, str],
    schedule: tuple[tuple[str, float], ...] | None,
    sw_hash: str | None,
) -> Check:
    """Whether the user's own file is what the certificate is about (canonical hashes of
    every mode and of the schedule)."""
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


__all__ = [
    "DIGEST_NOTE",
    "About",
    "Check",
    "HurwitzProof",
    "ModeAbout",
    "Verification",
    "canonical",
    "digest",
    "document_hash",
    "finish",
    "finite_number",
    "integrity_checks",
    "hurwitz_certificate",
    "package_versions",
    "prove_hurwitz",
    "switching_certificate",
    "switching_hash",
    "topology_hash",
    "DenseContext",
    "parse_mode",
    "write_certificate",
]
