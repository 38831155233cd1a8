"""Certificate files: what was certified, the matrices to re-check it, the claimed
inequalities, the solver and package versions, and a SHA-256 digest of all of it.

``verify`` re-checks a certificate with no SDP solver: it re-derives L_B of every mode
exactly from the stated topology, informed agents, B_i and δ (dyadic rational arithmetic,
:mod:`ntc_design.certify.exact`), checks it against the stated L_B, and proves every claim
exactly (Nd <= EXACT_MAX_N) or with a rigorous floating-point test (larger Nd); the
certificate records which was used. Any edit of the file breaks the digest.
"""

from __future__ import annotations

import hashlib
import json
import platform
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from ..design import ProtocolDesign, SwitchingDesign, coupling_matrix
from ..errors import InputError
from ..files import parse_topology
from ..model import Topology, antagonistic_in_weight
from .exact import EXACT_MAX_N, Dyadic, PDProof, exact_pd, gamma, verified_float_pd
from .lyapunov import common_lyapunov, decay_rate_lmi, hurwitz_by_lyapunov

FORMAT = "ntc-design/certificate"
VERSION = 1


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for pkg in ("ntc-design", "numpy", "scipy", "sympy", "cvxpy", "clarabel", "control"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def canonical(obj: Any) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode()


def digest(doc: dict) -> str:
    body = {k: v for k, v in doc.items() if k != "digest"}
    return "sha256:" + hashlib.sha256(canonical(body)).hexdigest()


def _mode_subject(d: ProtocolDesign) -> dict:
    lab = d.topology.labels
    return {
        "topology": d.topology.to_dict(),
        "theta": d.theta.tolist(),
        "margin": d.margin,
        "delta": d.delta,
        "informed": [lab[i] for i in d.informed],
        "B": {str(lab[i]): b.tolist() for i, b in sorted(d.B.items())},
    }


def _min_eig(m: np.ndarray) -> float:
    return float(np.linalg.eigvalsh(0.5 * (m + m.T))[0])


def _finish(doc: dict) -> dict:
    doc["subject_digest"] = "sha256:" + hashlib.sha256(canonical(doc["subject"])).hexdigest()
    doc["versions"] = package_versions()
    doc["verification_method"] = (
        "exact-rational" if doc["size"] <= EXACT_MAX_N else "verified-float"
    )
    doc["digest"] = digest(doc)
    return doc


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
    equation P L_B + L_Bᵀ P = I with P ≻ 0; (b) the LMI maximising the decay rate α."""
    name = name or d.topology.name or "topology"
    if rate:  # estimated before any dense step: refused in one line, never an OOM kill
        require_lmi(d.topology.nd, "decay-rate LMI")
    lap_b = d.grounded_laplacian()
    lya = hurwitz_by_lyapunov(lap_b)
    claims = [
        {"id": "P_lyapunov ≻ 0", "kind": "pd", "P": "lyapunov"},
        {
            "id": f"P_lyapunov·L_B({name}) + L_B({name})ᵀ·P_lyapunov ≻ 0",
            "kind": "lyapunov",
            "P": "lyapunov",
            "mode": name,
            "alpha": 0.0,
            "min_eig": _min_eig(lya.p @ lap_b + lap_b.T @ lya.p),
        },
    ]
    matrices: dict[str, Any] = {"L_B": {name: lap_b.tolist()}, "P": {"lyapunov": lya.p.tolist()}}
    eig_bound = float(np.min(np.linalg.eigvals(lap_b).real))
    results: dict[str, Any] = {
        "eig_bound": eig_bound,
        "lyapunov": {
            "residual": lya.residual,
            "P_min_eig": lya.p_min_eig,
            "method": "Schur, blocked Bartels–Stewart",
        },
    }
    solver = {"name": None, "status": None}
    if rate:
        r = decay_rate_lmi(lap_b, eig_bound=eig_bound)
        results["lmi"] = {
            "alpha": r.alpha,
            "eig_bound": r.eig_bound,
            "gap": r.eig_bound - r.alpha,
            "status": r.status,
            "bisection_steps": r.iterations,
        }
        solver = {"name": "Clarabel (via cvxpy)", "status": r.status}
        if r.p is not None:
            matrices["P"]["rate"] = r.p.tolist()
            m = r.p @ lap_b + lap_b.T @ r.p - 2 * r.alpha * r.p
            claims += [
                {"id": "P_rate ≻ 0", "kind": "pd", "P": "rate"},
                {
                    "id": f"P_rate·L_B({name}) + L_B({name})ᵀ·P_rate − 2α·P_rate ≻ 0",
                    "kind": "lyapunov",
                    "P": "rate",
                    "mode": name,
                    "alpha": r.alpha,
                    "min_eig": _min_eig(m),
                },
            ]
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "hurwitz",
        "size": int(lap_b.shape[0]),
        "subject": {"modes": {name: _mode_subject(d)}},
        "matrices": matrices,
        "claims": claims,
        "results": results,
        "solver": solver,
    }
    return _finish(doc)


def switching_certificate(
    sd: SwitchingDesign, structures=("identity", "block-diagonal", "dense")
) -> dict:
    """Certify a switching set: L_B(k) + L_B(k)ᵀ ≻ 0 per mode (Theorems 3-4) with its
    smallest eigenvalue, and a common Lyapunov matrix P for all modes when one is found."""
    laps = {k: d.grounded_laplacian() for k, d in sd.modes.items()}
    n = next(iter(laps.values())).shape[0]
    claims: list[dict] = []
    sym = {}
    for k, lap in laps.items():
        lam = _min_eig(lap + lap.T)
        sym[k] = lam
        if lam > 0:
            claims.append(
                {
                    "id": f"L_B({k}) + L_B({k})ᵀ ≻ 0",
                    "kind": "symmetric_part",
                    "mode": k,
                    "min_eig": lam,
                }
            )
    common = common_lyapunov(laps, sd.switching.dim, structures)
    matrices: dict[str, Any] = {"L_B": {k: v.tolist() for k, v in laps.items()}, "P": {}}
    if common.p is not None:
        matrices["P"]["common"] = common.p.tolist()
        claims.append({"id": "P_common ≻ 0", "kind": "pd", "P": "common"})
        for k, lap in laps.items():
            claims.append(
                {
                    "id": f"P_common·L_B({k}) + L_B({k})ᵀ·P_common ≻ 0",
                    "kind": "lyapunov",
                    "P": "common",
                    "mode": k,
                    "alpha": 0.0,
                    "min_eig": _min_eig(common.p @ lap + lap.T @ common.p),
                }
            )
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "kind": "switching",
        "size": int(n),
        "subject": {
            "modes": {k: _mode_subject(d) for k, d in sd.modes.items()},
            "schedule": [{"mode": m, "duration": t} for m, t in sd.switching.schedule],
        },
        "matrices": matrices,
        "claims": claims,
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
    return _finish(doc)


def write_certificate(doc: dict, path: str | Path) -> None:
    p = Path(path)
    text = json.dumps(doc, indent=1, ensure_ascii=False) + "\n"
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(p)  # nothing half-written


# ---------------------------------------------------------------------------- verify


@dataclass(frozen=True)
class Check:
    name: str
    ok: bool
    detail: str


@dataclass(frozen=True)
class Verification:
    valid: bool
    method: str
    checks: tuple[Check, ...] = field(default=())

    @property
    def failed(self) -> list[Check]:
        return [c for c in self.checks if not c.ok]


def _matrix(x: Any, n: int, where: str) -> np.ndarray:
    if (
        not isinstance(x, list)
        or len(x) != n
        or any(not isinstance(r, list) or len(r) != n for r in x)
    ):
        raise InputError(f"{where}: expected a {n}x{n} matrix")
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: non-numeric entry") from None
    if any(isinstance(v, (bool, str)) or v is None for r in x for v in r):
        raise InputError(f"{where}: non-numeric entry")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{where}: non-finite entry")
    return a


def _need(doc: dict, key: str, typ: type | tuple, where: str) -> Any:
    if key not in doc:
        raise InputError(f"{where}: missing field '{key}'")
    if not isinstance(doc[key], typ):
        raise InputError(f"{where}: field '{key}' has the wrong type")
    return doc[key]


def _lap_b_exact(top: Topology, b: dict[int, np.ndarray], delta: float) -> Dyadic:
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
    top: Topology, b: dict[int, np.ndarray], delta: float
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


def _prove_pd_expr(
    p: np.ndarray,
    lap_exact: Dyadic | None,
    lap_f: np.ndarray | None,
    alpha: float,
    err_l: np.ndarray | None,
    exact: bool,
) -> PDProof:
    """Prove P ≻ 0 (lap None) or P L_B + L_Bᵀ P − 2αP ≻ 0."""
    if exact:
        pd_ = Dyadic.of(p)
        if lap_exact is None:
            return exact_pd(pd_)
        m = pd_ @ lap_exact + lap_exact.T @ pd_
        if alpha != 0.0:
            m = m - pd_.scale(Dyadic.of(2.0 * alpha))
        return exact_pd(m)
    n = p.shape[0]
    if lap_f is None:
        return verified_float_pd(p, np.zeros_like(p))
    ap, al = np.abs(p), np.abs(lap_f)
    m = p @ lap_f + lap_f.T @ p - 2 * alpha * p
    err = gamma(n + 3) * (ap @ al + al.T @ ap + 2 * abs(alpha) * ap)
    err += ap @ err_l + err_l.T @ ap
    return verified_float_pd(m, 2 * err * (1 + 8 * gamma(n)))


@dataclass(frozen=True)
class HurwitzProof:
    """−L_B Hurwitz proven from the Lyapunov-equation P: P ≻ 0 and P L_B + L_Bᵀ P ≻ 0."""

    holds: bool
    p: np.ndarray
    p_pd: PDProof
    lyapunov_pd: PDProof
    seconds: float


def prove_hurwitz(lap_b: np.ndarray, exact: bool | None = None) -> HurwitzProof:
    """Solve P L_B + L_Bᵀ P = I and prove both inequalities for the given float L_B
    (exactly up to EXACT_MAX_N, else by the rigorous floating-point test)."""
    import time

    t0 = time.perf_counter()
    n = lap_b.shape[0]
    exact = n <= EXACT_MAX_N if exact is None else exact
    p = hurwitz_by_lyapunov(lap_b).p
    lap_exact = Dyadic.of(lap_b) if exact else None
    p1 = _prove_pd_expr(p, None, None, 0.0, None, exact)
    p2 = _prove_pd_expr(p, lap_exact, lap_b, 0.0, np.zeros_like(lap_b), exact)
    return HurwitzProof(p1.holds and p2.holds, p, p1, p2, time.perf_counter() - t0)


def verify(doc: Any, source: str = "certificate") -> Verification:
    """Re-check a certificate mapping. Raises InputError when it is malformed."""
    if not isinstance(doc, dict):
        raise InputError(f"{source}: expected a JSON object")
    if doc.get("format") != FORMAT:
        raise InputError(f"{source}: field 'format' must be {FORMAT!r}")
    if doc.get("kind") == "hurwitz-scale":
        from .scale import verify_scale

        return verify_scale(doc, source)
    n = _need(doc, "size", int, source)
    subject = _need(doc, "subject", dict, source)
    modes = _need(subject, "modes", dict, f"{source}: subject")
    mats = _need(doc, "matrices", dict, source)
    lbs = _need(mats, "L_B", dict, f"{source}: matrices")
    ps = _need(mats, "P", dict, f"{source}: matrices")
    claims = _need(doc, "claims", list, source)
    _need(doc, "digest", str, source)
    method = "exact-rational" if n <= EXACT_MAX_N else "verified-float"
    checks: list[Check] = []
    want = digest(doc)
    checks.append(
        Check(
            "digest",
            want == doc["digest"],
            "matches" if want == doc["digest"] else "the file was modified after it was issued",
        )
    )

    exact_l: dict[str, Dyadic] = {}
    float_l: dict[str, np.ndarray] = {}
    err_l: dict[str, np.ndarray] = {}
    for name, sub in modes.items():
        where = f"{source}: subject.modes.{name}"
        if not isinstance(sub, dict):
            raise InputError(f"{where}: expected an object")
        top = Topology.from_data(parse_topology(_need(sub, "topology", dict, where), where))
        if top.nd != n:
            raise InputError(f"{where}: topology has Nd={top.nd}, certificate size is {n}")
        delta = _need(sub, "delta", (int, float), where)
        if isinstance(delta, bool) or not delta > 0:
            raise InputError(f"{where}: delta must be a positive number")
        informed_l = _need(sub, "informed", list, where)
        try:
            informed = [top.index(x) for x in informed_l]
        except InputError:
            raise InputError(f"{where}: informed lists an unknown agent") from None
        bd = _need(sub, "B", dict, where)
        b = {top.index(k): _matrix(v, top.dim, f"{where}.B.{k}") for k, v in bd.items()}
        ok_inf = sorted(informed) == sorted(top.antagonised) and set(b) == set(informed)
        checks.append(
            Check(
                f"informed agents of {name} are U",
                ok_inf,
                "V_I = U" if ok_inf else "V_I ≠ U or B listed for other agents",
            )
        )
        ok_b = (
            all(Dyadic.of(b[i]).equals(Dyadic.of(antagonistic_in_weight(top, i))) for i in b)
            if ok_inf
            else False
        )
        checks.append(
            Check(
                f"B_i of {name} are Σ_Ω|A_ij|",
                ok_b,
                "exact" if ok_b else "a B_i differs from Σ_{Ω_i}|A_ij|",
            )
        )
        if name not in lbs:
            raise InputError(f"{source}: matrices.L_B: missing mode {name!r}")
        stated = _matrix(lbs[name], n, f"{source}: matrices.L_B.{name}")
        if method == "exact-rational":
            exact_l[name] = _lap_b_exact(top, b, float(delta))
            diff = np.abs(exact_l[name].to_float() - stated)
            err_l[name] = diff
        else:
            lap_b, bound = _lap_b_float(top, b, float(delta))
            diff = np.abs(lap_b - stated)
            err_l[name] = diff + bound  # bounds |L_B exact − stated|
        scale = max(float(np.max(np.abs(stated))), 1e-300)
        ok_l = float(np.max(diff)) <= 1e-12 * scale
        checks.append(
            Check(
                f"L_B({name}) matches its topology and δ", ok_l, f"max deviation {np.max(diff):.2e}"
            )
        )
        float_l[name] = stated
    for k, c in enumerate(claims):
        where = f"{source}: claims[{k}]"
        if not isinstance(c, dict):
            raise InputError(f"{where}: expected an object")
        cid = str(_need(c, "id", str, where))
        kind = _need(c, "kind", str, where)
        if kind == "symmetric_part":
            mode = _need(c, "mode", str, where)
            if mode not in float_l:
                raise InputError(f"{where}: unknown mode {mode!r}")
            if method == "exact-rational":
                proof = exact_pd(exact_l[mode] + exact_l[mode].T)
            else:
                s = float_l[mode] + float_l[mode].T
                proof = verified_float_pd(s, gamma(2) * np.abs(s) + err_l[mode] + err_l[mode].T)
        elif kind in ("pd", "lyapunov"):
            pname = _need(c, "P", str, where)
            if pname not in ps:
                raise InputError(f"{where}: matrices.P has no {pname!r}")
            p = _matrix(ps[pname], n, f"{source}: matrices.P.{pname}")
            if kind == "pd":
                proof = _prove_pd_expr(p, None, None, 0.0, None, method == "exact-rational")
            else:
                mode = _need(c, "mode", str, where)
                if mode not in float_l:
                    raise InputError(f"{where}: unknown mode {mode!r}")
                alpha = _need(c, "alpha", (int, float), where)
                proof = _prove_pd_expr(
                    p,
                    exact_l.get(mode),
                    float_l[mode],
                    float(alpha),
                    err_l[mode],
                    method == "exact-rational",
                )
        else:
            raise InputError(f"{where}: unknown claim kind {kind!r}")
        checks.append(Check(cid, proof.holds, f"{proof.method}: {proof.detail}"))
    return Verification(all(c.ok for c in checks), method, tuple(checks))


def verify_file(path: str | Path) -> Verification:
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: not valid JSON ({exc.__class__.__name__})") from None
    return verify(doc, str(p))
