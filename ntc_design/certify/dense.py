"""Dense re-derivation and proofs for the ``hurwitz`` and ``switching`` kinds.

* L_B of every mode is re-derived exactly from its topology, informed agents (= U),
  B_i (= Σ_{Ω_i}|A_ij|) and δ (dyadic rational arithmetic, :mod:`ntc_design.rigorous.exact`),
  ``k1 = 1 + 2/δ`` and ``x0 = k1·θ``;
* every claim is proven exactly (Sylvester's criterion on integers) while that is
  affordable, else with a rigorous floating-point test; every number entering a proof
  must have a magnitude in ``[2^-NUMBER_EXP, 2^NUMBER_EXP]`` (or be 0), so neither
  arithmetic can blow up, overflow or underflow.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.files import parse_topology
from ..model import Topology, antagonistic_in_weight
from ..numerics.linalg import DENSE_MAX_BYTES, RANGE_TEXT, DenseRefused, out_of_range
from ..protocol import ProtocolDesign
from ..protocol.lemma1 import coupling_matrix
from ..rigorous.exact import (
    EXACT_MAX_N,
    Dyadic,
    PDProof,
    exact_affordable,
    exact_pd,
    gamma,
    verified_float_pd,
)
from .arrays import margin_check
from .checks import Check
from .claims import Claim, ClaimKind
from .fields import matrix, need, number, vector
from .format import topology_hash
from .lyapunov import hurwitz_by_lyapunov


def min_eig(m: np.ndarray) -> float:
    """λ_min of the symmetric part of m (NaN when m is not finite).

    Parameters
    ----------
    m : numpy.ndarray
        A square matrix.

    Returns
    -------
    float
    """
    if not np.all(np.isfinite(m)):
        return float("nan")
    return float(np.linalg.eigvalsh(0.5 * (m + m.T))[0])


def eig_bound(lap_b: np.ndarray) -> float:
    """−max Re λ(−L_B) = min Re λ(L_B): the best decay rate of ε̇ = −L_B ε.

    Parameters
    ----------
    lap_b : numpy.ndarray
        L_B.

    Returns
    -------
    float
        NaN for a non-finite or empty matrix.
    """
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
    solve holds about 16 of them (n = 150 was measured at 14.6 GB), so 128·m² bytes.

    Parameters
    ----------
    n : int
        The size of P.
    what : str
        What needs the LMI, for the message.

    Raises
    ------
    DenseRefused
        It would not fit.
    """

    m = n * (n + 1) / 2
    need = 128.0 * m * m
    if need > DENSE_MAX_BYTES:
        raise DenseRefused(
            f"a dense {n}×{n} P needs about {need / 2**30:.0f} GiB "
            f"(limit {DENSE_MAX_BYTES / 2**30:.1f} GiB); refused — the component-wise "
            "certificate (ntc_design.certify.scale) applies at this size",
            field=what,
        )


def mode_subject(d: ProtocolDesign) -> dict:
    """A design as a dense certificate's subject mode: topology, hash, θ, ΔC, δ, k1, x0,
    informed agents and B_i.

    Parameters
    ----------
    d : ProtocolDesign
        The design.

    Returns
    -------
    dict
    """
    lab = d.topology.labels
    top = d.topology.to_dict()
    # the edges in the topology file's order (its weights mapping's), so that an export of
    # the certificate lists them as an export of the file does (the hash sorts them itself)
    top["edges"] = [
        {"from": lab[j], "to": lab[i], "weight": np.asarray(a).tolist()}
        for (i, j), a in d.topology.weights.items()
    ]
    return {
        "topology": top,
        "topology_hash": topology_hash(d.topology),
        "theta": d.theta.tolist(),
        "margin": d.lemma1_margin,
        "delta": d.delta,
        "k1": d.k1,
        "x0": d.x0.tolist(),
        "informed": [lab[i] for i in d.informed],
        "B": {str(lab[i]): b.tolist() for i, b in sorted(d.B.items())},
    }


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


def lap_b_float(
    top: Topology, b: Mapping[int, np.ndarray], delta: float
) -> tuple[np.ndarray, np.ndarray]:
    """``L_B`` in floating point and an entrywise bound on its distance from the exact
    L_B: each entry is a sum of at most N+1 products of doubles, so the error is at most
    γ_{N+2} times the same sum taken in absolute values.

    Parameters
    ----------
    top : Topology
        The topology.
    b : mapping of int to numpy.ndarray
        B_i of the informed agents.
    delta : float
        δ.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The float L_B and the entrywise bound on its error.
    """
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


def prove_pd_expr(
    p: np.ndarray,
    lap_exact: Dyadic | None,
    lap_f: np.ndarray | None,
    alpha: float,
    err_l: np.ndarray | None,
    exact: bool,
) -> PDProof:
    """Prove P ≻ 0 (no L_B) or P L_B + L_Bᵀ P − 2αP ≻ 0: exactly when asked and the
    bit lengths allow it (:func:`~ntc_design.rigorous.exact.exact_affordable`), else by the
    verified-float test.

    Parameters
    ----------
    p : numpy.ndarray
        P.
    lap_exact : Dyadic or None
        L_B exactly (None: only the float test applies).
    lap_f : numpy.ndarray or None
        L_B in floating point; None to prove P ≻ 0 itself.
    alpha : float
        The rate α.
    err_l : numpy.ndarray or None
        An entrywise bound on |L_B exact − lap_f|.
    exact : bool
        Try the exact test first.

    Returns
    -------
    PDProof
    """
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

    t0 = time.perf_counter()
    n = lap_b.shape[0]
    exact = n <= EXACT_MAX_N if exact is None else exact
    p = hurwitz_by_lyapunov(lap_b).p
    if not np.all(np.isfinite(p)):
        bad = PDProof(False, "none", "the Lyapunov equation has no finite solution")
        return HurwitzProof(False, p, bad, bad, time.perf_counter() - t0)
    lap_exact = Dyadic.of(lap_b) if exact else None
    p1 = prove_pd_expr(p, None, None, 0.0, None, exact)
    p2 = prove_pd_expr(p, lap_exact, lap_b, 0.0, np.zeros_like(lap_b), exact)
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
                raise InputError(f"missing {name!r}", field=f"{self.source}: matrices.P")
            a = matrix(self.ps[name], self.n, f"{self.source}: matrices.P.{name}")
            self._p[name] = None if out_of_range(a) else a
        return self._p[name]


def _unproven(why: str) -> PDProof:
    return PDProof(False, "not attempted", why)


def _prove_pd(c: Claim, ctx: DenseContext) -> PDProof:
    p = ctx.p(c.p or "")
    if p is None:
        return _unproven(f"matrices.P.{c.p} has {RANGE_TEXT}")
    return prove_pd_expr(p, None, None, 0.0, None, ctx.exact)


def _prove_lyapunov(c: Claim, ctx: DenseContext) -> PDProof:
    p = ctx.p(c.p or "")
    mode = ctx.modes.get(c.mode or "")
    if mode is None:
        return _unproven(f"the certificate does not describe mode {c.mode!r}")
    if p is None:
        return _unproven(f"matrices.P.{c.p} has {RANGE_TEXT}")
    if not mode.in_range or out_of_range(c.alpha):
        return _unproven(f"mode {mode.name} or α has {RANGE_TEXT}")
    return prove_pd_expr(p, mode.exact, mode.lap, c.alpha, mode.err, ctx.exact)


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
        raise InputError(f"must be between 1 and the certificate size {size}", field=f"{where}.dim")
    n = agents if isinstance(agents, int) else len(agents) if isinstance(agents, list) else 0
    if n > size:
        raise InputError(f"more agents than the certificate size {size}", field=f"{where}.agents")
    if isinstance(edges, list) and len(edges) > max(n * (n - 1), 0):
        raise InputError("more edges than N(N−1)", field=f"{where}.edges")


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
        raise InputError("expected an object", field=where)
    tdoc = need(sub, "topology", dict, where)
    _check_topology_fields(tdoc, n, f"{where}.topology")
    top = Topology.from_data(parse_topology(tdoc, f"{where}.topology"))
    if top.nd != n:
        raise InputError(f"topology has Nd={top.nd}, certificate size is {n}", field=where)
    d = top.dim
    theta = vector(need(sub, "theta", list, where), d, f"{where}.theta")
    delta = number(need(sub, "delta", (int, float), where), f"{where}.delta")
    if not delta > 0:
        raise InputError("must be positive", field=f"{where}.delta")
    k1 = number(need(sub, "k1", (int, float), where), f"{where}.k1")
    x0 = vector(need(sub, "x0", list, where), d, f"{where}.x0")
    stated_hash = need(sub, "topology_hash", str, where)
    informed_l = need(sub, "informed", list, where)
    try:
        informed = [top.index(x) for x in informed_l]
    except InputError:
        raise InputError("lists an unknown agent", field=f"{where}.informed") from None
    bd = need(sub, "B", dict, where)
    try:
        b = {top.index(k): matrix(v, d, f"{where}.B.{k}") for k, v in bd.items()}
    except InputError as exc:
        if "unknown agent" in str(exc):
            raise InputError("lists an unknown agent", field=f"{where}.B") from None
        raise

    h = topology_hash(top)
    checks += margin_check(name, sub, where, top, delta)
    checks += _mode_checks(name, top, h, stated_hash, informed, b, delta, k1, x0, theta)
    in_range = checks[-1].ok
    if in_range:
        lap, err = lap_b_float(top, b, delta)
        exact = _lap_b_exact(top, b, delta) if n <= EXACT_MAX_N else None
    else:
        lap, err, exact = np.zeros((n, n)), np.zeros((n, n)), None
    return DenseMode(name, top, theta, delta, b, h, lap, err, exact, in_range)


def _mode_checks(name, top, h, stated_hash, informed, b, delta, k1, x0, theta) -> list[Check]:
    """What a mode's subject must satisfy: its hash, V_I = U, B_i = Σ_Ω|A_ij| exactly,
    k1 and x0 from δ and θ; the last check is whether every number is within range."""
    checks = []
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
    return checks


__all__ = [
    "DENSE_CERT_MAX_ND",
    "DenseContext",
    "DenseMode",
    "HurwitzProof",
    "PROVERS",
    "eig_bound",
    "lap_b_float",
    "min_eig",
    "mode_subject",
    "parse_mode",
    "prove_hurwitz",
    "prove_pd_expr",
    "require_lmi",
]
