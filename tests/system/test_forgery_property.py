"""Forgery property test over all eight certificate kinds (and the deadline figures).

Every field of an honest certificate of each kind is mutated (numbers scaled, negated,
zeroed; strings and nulls replaced; list entries dropped; keys deleted and added), the
digests are recomputed, and a careful forger also lists exactly the claims verify derives
for the edited certificate. Whenever verify then answers VALID, every listed claim and
every reported number must be true, as decided here by independent dense computations
(numpy eigenvalues of L_B built in this file, networkx components, sampling of the
time-varying weights), never by the code under test.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import warnings
from fractions import Fraction

import networkx as nx
import numpy as np
import pytest

from ntc_design.certify import KINDS, verify
from ntc_design.certify.arrays import topology_from_subject
from ntc_design.certify.format import digest, document_hash, topology_hash
from ntc_design.errors import InputError
from ntc_design.io.files import parse_topology
from ntc_design.model import Topology
from ntc_design.model.generate import random_network
from ntc_design.model.timevarying import from_document
from ntc_design.protocol import design
from ntc_design.protocol.timevarying import TimeVaryingDesign
from tests.conftest import ROOT
from tests.support.shared import once_per_run

hostile = pytest.mark.hostile
SKIP_KEYS = {"digest", "subject_digest", "versions"}
MAX_LIST = 3  # entries mutated per list: the first, the middle and the last


# ------------------------------------------------------------------ honest certificates


@pytest.fixture(scope="module")
def honest(honest_certificates) -> dict[str, dict]:
    """One honest certificate of every kind (tests/support/certificates.py)."""
    return honest_certificates


# ------------------------------------------------------------------ the independent truth


def _sign(a: np.ndarray) -> int:
    """+1 for a PSD weight, −1 for an NSD one (tolerance relative to its norm)."""
    w = np.linalg.eigvalsh(a)
    tol = 1e-12 * max(np.max(np.abs(w)), 1e-300)
    if w[0] >= -tol:
        return 1
    if w[-1] <= tol:
        return -1
    raise ValueError("indefinite weight")


def _lap_b(top: Topology, delta: float) -> np.ndarray:
    """L_B = L + δ·blockdiag(B_i) with B_i = Σ_{j: A_ij ≺ 0}|A_ij| (written here, from the
    definitions: L_ij = −A_ij, L_ii = Σ_k |A_ik|)."""
    d = top.dim
    lap = np.zeros((top.n * d, top.n * d))
    for (i, j), a in top.weights.items():
        s = _sign(a)
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += s * a + (delta * -a if s < 0 else 0)
    return lap


def _antagonised(top: Topology) -> set[str]:
    return {str(top.labels[i]) for (i, _j), a in top.weights.items() if _sign(a) < 0}


def _pos(m: np.ndarray) -> bool:
    """m ≻ 0, with a margin for the rounding of this check itself."""
    s = 0.5 * (m + m.T)
    return bool(np.linalg.eigvalsh(s)[0] > 1e-10 * max(1.0, np.max(np.abs(s))))


def _at_least(x, y, rtol=1e-6, atol=1e-12) -> bool:
    """x >= y, but for a relative tolerance (an upper bound that is still true)."""
    return (
        isinstance(x, (int, float))
        and not isinstance(x, bool)
        and math.isfinite(x)
        and x >= y - rtol * max(abs(y), atol / rtol)
    )


def _close(x, y, rtol=1e-6, atol=1e-12) -> bool:
    return (
        isinstance(x, (int, float))
        and not isinstance(x, bool)
        and math.isfinite(x)
        and abs(x - y) <= rtol * max(abs(y), atol / rtol)
    )


def _truth_dense(doc: dict) -> list[str]:
    """What is false in a valid hurwitz or switching certificate."""
    bad: list[str] = []
    modes, laps = doc["subject"]["modes"], {}
    for k, m in modes.items():
        top = Topology.from_data(parse_topology(m["topology"], k))
        theta, delta = np.array(m["theta"]), m["delta"]
        if not np.any(theta):
            bad.append(f"{k}: θ = 0")
        if m["x0"] != ((1 + 2 / delta) * theta).tolist():
            bad.append(f"{k}: x0")
        if {str(x) for x in m["informed"]} != _antagonised(top):
            bad.append(f"{k}: informed ≠ U")
        if m["topology_hash"] != topology_hash(top):
            bad.append(f"{k}: topology hash")
        laps[k] = _lap_b(top, delta)
    sched = doc["subject"].get("schedule")
    used = list(dict.fromkeys(s["mode"] for s in sched)) if sched else list(modes)
    ps = {k: np.array(v) for k, v in doc["matrices"]["P"].items()}
    res = doc["results"]
    # the certified properties, whatever the claims list says
    if "symmetric_part" in doc["certifies"] and not all(_pos(laps[k] + laps[k].T) for k in used):
        bad.append("a scheduled mode with L_B + L_Bᵀ not ≻ 0")
    if "common_lyapunov" in doc["certifies"]:
        p = ps.get("common")
        if p is None or not _pos(p) or not all(_pos(p @ laps[k] + laps[k].T @ p) for k in used):
            bad.append("no common Lyapunov P")
    for c in doc["claims"]:
        kind, p = c["kind"], ps.get(c.get("P", ""))
        lap = laps.get(c.get("mode", ""))
        if kind == "pd":
            ok = _pos(p)
        elif kind == "lyapunov":
            ok = _pos(p @ lap + lap.T @ p - 2 * c.get("alpha", 0.0) * p)
        elif kind == "symmetric_part":
            ok = _pos(lap + lap.T)
        elif kind == "positive_rate":
            ok = c["alpha"] > 0
        else:
            ok = False
        if not ok:
            bad.append(f"claim {c['id']}")
    if doc["kind"] == "hurwitz":
        (lap,) = laps.values()
        eig = float(np.min(np.linalg.eigvals(lap).real))
        if not eig > 0:
            bad.append("not Hurwitz")
        if not _close(res["eig_bound"], eig):
            bad.append("eig_bound")
        if "lyapunov" in res:  # absent numbers state nothing
            p = ps["lyapunov"]
            r = p @ lap + lap.T @ p - np.eye(len(p))
            resid = float(np.linalg.norm(r) / np.sqrt(len(p)))
            if not _close(res["lyapunov"]["residual"], resid, 1e-3, 1e-12):
                bad.append("residual")
            if not _close(res["lyapunov"]["P_min_eig"], float(np.linalg.eigvalsh(p)[0])):
                bad.append("P_min_eig")
        lmi = res.get("lmi")
        if lmi is not None:
            if not (_close(lmi["eig_bound"], eig) and lmi["alpha"] <= eig * (1 + 1e-9)):
                bad.append("lmi")
            if not _close(lmi["gap"], eig - lmi["alpha"], 1e-6, 1e-9):
                bad.append("gap")
    else:
        for k, lap in laps.items():
            lam = float(np.linalg.eigvalsh(lap + lap.T)[0])
            if not _close(res["symmetric_part_min_eig"].get(k), lam):
                bad.append(f"symmetric_part_min_eig.{k}")
        if set(res["symmetric_part_min_eig"]) != set(laps):
            bad.append("symmetric_part_min_eig: modes")
    return bad


def _unpack_top(mode: dict, where: str) -> Topology:
    return topology_from_subject(mode["topology"], where)


def _truth_hurwitz_scale(doc: dict, honest_doc: dict) -> list[str]:
    bad: list[str] = []
    ((name, m),) = doc["subject"]["modes"].items()
    top = _unpack_top(m, name)
    if {str(x) for x in m["informed"]} != _antagonised(top) or not np.any(m["theta"]):
        bad.append("subject")
    lap = _lap_b(top, m["delta"])
    eig = float(np.min(np.linalg.eigvals(lap).real))
    if not eig > 0:
        bad.append("not Hurwitz")
    res = doc["results"]
    g = nx.DiGraph()
    g.add_nodes_from(range(top.n))
    g.add_edges_from((j, i) for (i, j), a in top.weights.items() if np.any(a))
    comps = list(nx.strongly_connected_components(g))
    if res["components"] != len(comps):
        bad.append("components")
    if res["largest_component_agents"] != max(len(c) for c in comps):
        bad.append("largest component")
    if res["methods"] != honest_doc["results"]["methods"]:
        bad.append("methods")
    if (
        not _close(res["rate_estimate"]["value"], eig)
        or res["eig_bound"] != res["rate_estimate"]["value"]
    ):
        bad.append("rate estimate")
    lower = res["rate_lower_bound"]["value"]
    if lower is not None and not lower <= eig:
        bad.append("rate lower bound above min Re λ")
    return bad


def _truth_switching_scale(doc: dict) -> list[str]:
    bad: list[str] = []
    res = doc["results"]
    sched = list(dict.fromkeys(s["mode"] for s in doc["subject"]["schedule"]))
    for k in sched:
        m = doc["subject"]["modes"][k]
        top = _unpack_top(m, k)
        if {str(x) for x in m["informed"]} != _antagonised(top) or not np.any(m["theta"]):
            bad.append(f"{k}: subject")
        lap = _lap_b(top, m["delta"])
        lam = float(np.linalg.eigvalsh(lap + lap.T)[0])
        lo = doc["proofs"].get(k, {}).get("lower")
        if lo is None or not lam > lo:
            bad.append(f"{k}: λ_min(L_B + L_Bᵀ) > ℓ")
        if res["symmetric_part_lower_bound"].get(k) != lo:
            bad.append(f"{k}: reported bound")
        est = res["symmetric_part_min_eig"].get(k)
        if est is not None and not _close(est, lam):
            bad.append(f"{k}: estimate")
    all_proven = all(k in doc["proofs"] for k in sched)
    if res["common_lyapunov"]["structure"] != ("identity" if all_proven else None):
        bad.append("common P")
    return bad


def _truth_time_varying(doc: dict) -> list[str]:
    """Sampled: λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂, |a_kl(t)| <= D, λ_max²(|A_ij(t)|) <= Λ₁ on
    a fine grid of the period; c(t) < κ after t₀; σ̄, κ, the gap and the domain."""
    bad: list[str] = []
    s = doc["subject"]
    tv = from_document(s["topology"], "tv")
    theta = np.array(s["theta"])
    if not np.any(theta):
        bad.append("θ = 0")
    r = doc["results"]["time_varying"]
    period = 2 * math.pi

    def sampled():
        # the period sampled at 1201 times (once per subject, _once)
        ts = np.linspace(0.0, period, 1201)
        des = TimeVaryingDesign(tv, theta, s["margin"])
        lap = des.at(ts).lap_b(des.structure)
        lam = np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0]
        w = tv.weights_at(ts)
        lmax = np.max(np.abs(np.linalg.eigvalsh(np.abs(w))), axis=-1)
        return lam, float(np.max(np.abs(w))), float(np.max(lmax**2))

    lam, w_max, lam1 = _once(("time_varying", s["topology"], s["theta"], s["margin"]), sampled)
    if not (r["lambda2"] > 0 and lam.min() >= r["lambda2"] * (1 - 1e-12)):
        bad.append("Λ₂")
    if not w_max <= r["D"] * (1 + 1e-12):
        bad.append("D")
    if not lam1 <= r["Lambda1"] * (1 + 1e-12):
        bad.append("Λ₁")
    sigma_bar = abs(float(s["noise"]["f"]))
    if not _close(r["sigma_bar"], sigma_bar, 1e-12, 1e-300):
        bad.append("σ̄")
    kappa = r["lambda2"] / (2 * sigma_bar * r["Lambda1"] * tv.n)
    if not _close(r["kappa"], kappa, 1e-9):
        bad.append("κ")
    t0 = r["t0"]
    if s["gain"] is not None:
        tt = t0 + np.geomspace(1e-9, 1e6, 2000)
        if t0 is None or not np.all(1 / (1 + tt) < kappa):
            bad.append("t₀")  # c(t) < κ from t₀ on (a later t₀ is still true)
    if not (r["lambda2"] <= r["sampled_inf"] and _close(r["sampled_inf"], float(lam.min()), 1e-3)):
        bad.append("sampled infimum")
    if not _close(r["relative_gap"], (r["sampled_inf"] - r["lambda2"]) / r["sampled_inf"], 1e-9):
        bad.append("relative gap")
    if r["domain"] != [0.0, doc["results"]["time_varying"]["domain"][1]] or not _close(
        r["domain"][1], period, 1e-12
    ):
        bad.append("domain")
    if r["intervals"] != len(doc["intervals"]):
        bad.append("intervals")
    return bad


_ONCE: dict[str, object] = {}


def _once(key: tuple, build):
    """``build()``, computed once per ``key`` in this process. The mutants of one honest
    certificate mostly keep its subject, so the oracle's costly independent quantities
    (sampled realisations, a sampled period) are shared by every mutant with the same
    subject; the key is the JSON of every input they are computed from, so an edited
    subject gets its own."""
    text = json.dumps(key, sort_keys=True, default=repr)
    if text not in _ONCE:
        _ONCE[text] = build()
    return _ONCE[text]


def _abs(a: np.ndarray) -> np.ndarray:
    lam, q = np.linalg.eigh(a)
    return (q * np.abs(lam)) @ q.T


def _robust_channels(top: Topology):
    """Per edge, ordered by (to, from): (E_i W V, D W Dᵀ, Vᵀ W V) with V an orthonormal
    basis of range(W) from eigh (any basis gives a congruent Ψ, so PD-ness is the same)."""
    n, d = top.n, top.dim
    out = []
    for (i, j), a in sorted(top.weights.items()):
        if not np.any(a):
            continue
        s = _sign(a)
        w = s * a
        lam, q = np.linalg.eigh(w)
        v = q[:, lam > 1e-12 * max(lam.max(), 1e-300)]
        e_i = np.zeros((n * d, d))
        e_i[i * d : (i + 1) * d] = np.eye(d)
        dm = e_i.copy()
        dm[j * d : (j + 1) * d] -= s * np.eye(d)
        out.append((e_i @ w @ v, dm @ w @ dm.T, v.T @ w @ v))
    return out


def _psi(lap, ch, p, tau, alpha, radii):
    n = lap.shape[0]
    top_left = p @ (lap - alpha * np.eye(n)) + (lap - alpha * np.eye(n)).T @ p
    cols, blocks = [], []
    for t, r, (ewv, dwd, vwv) in zip(tau, radii, ch, strict=True):
        top_left = top_left - t * r * r * dwd
        cols.append(p @ ewv)
        blocks.append(t * vwv)
    k = sum(b.shape[0] for b in blocks)
    out = np.zeros((n + k, n + k))
    out[:n, :n] = top_left
    c = n
    for col, b in zip(cols, blocks, strict=True):
        m = b.shape[0]
        out[:n, c : c + m] = col
        out[c : c + m, :n] = col.T
        out[c : c + m, c : c + m] = b
        c += m
    return out


def _lmi_holds(lap, ch, p, tau, alpha, radii) -> bool:
    """Ψ ≻ 0 up to Nd = 40; past it, the Schur complement of Ψ on its channel blocks,
    P(L_B − αI) + (L_B − αI)ᵀP − Σ τρ² D W Dᵀ − P (Σ E W Eᵀ/τ) P ≻ 0 (the block form is
    singular to rounding when a weight is nearly singular), with P ≻ 0 and τ > 0."""
    if not _pos(p):
        return False
    if lap.shape[0] <= 40:
        return _pos(_psi(lap, ch, p, tau, alpha, radii))
    tau = np.asarray(tau, dtype=float)
    if not np.all(tau > 0):
        return False
    sh = lap - alpha * np.eye(lap.shape[0])
    m = p @ sh + sh.T @ p
    for t, r, (ewv, dwd, vwv) in zip(tau, radii, ch, strict=True):
        m = m - t * r * r * dwd - p @ (ewv @ np.linalg.solve(vwv, ewv.T)) @ p / t
    return _pos(m)


def _sample_realisations(top: Topology, radii, rng, count):
    keys = [k for k, a in sorted(top.weights.items()) if np.any(a)]
    for _ in range(count):
        w = dict(top.weights)
        for key, r in zip(keys, radii, strict=True):
            a = top.weights[key]
            s = _sign(a)
            lw, qw = np.linalg.eigh(s * a)
            f = (qw * np.sqrt(np.clip(lw, 0, None))) @ qw.T
            d = a.shape[0]
            qr = np.linalg.qr(rng.normal(size=(d, d)))[0]
            e = qr @ np.diag(r * rng.choice([-1.0, 1.0], size=d)) @ qr.T
            b = s * (f @ (np.eye(d) + e) @ f)
            w[key] = 0.5 * (b + b.T)
        yield w


def _lap_with(top: Topology, w: dict, delta: float, b: dict) -> np.ndarray:
    d = top.dim
    lap = np.zeros((top.n * d, top.n * d))
    for (i, j), a in w.items():
        lap[i * d : (i + 1) * d, j * d : (j + 1) * d] -= a
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += _abs(a)
    for i, bi in b.items():
        lap[i * d : (i + 1) * d, i * d : (i + 1) * d] += delta * bi
    return lap


def _truth_robust(doc: dict) -> list[str]:
    """Robust certificates: the S-procedure matrices rebuilt here (independent channels),
    sampled realisations against every proven end, and the reported realisations."""
    bad: list[str] = []
    ((name, m),) = doc["subject"]["modes"].items()
    top = Topology.from_data(parse_topology(m["topology"], name))
    theta, delta = np.array(m["theta"]), m["delta"]
    if {str(x) for x in m["informed"]} != _antagonised(top) or not np.any(theta):
        bad.append("subject")
    if m["x0"] != ((1 + 2 / delta) * theta).tolist():
        bad.append("x0")
    b = {
        i: sum(-a for (ii, _j), a in top.weights.items() if ii == i and _sign(a) < 0)
        for i in range(top.n)
    }
    b = {i: v for i, v in b.items() if np.any(v)}
    lap = _lap_with(top, dict(top.weights), delta, b)
    ch = _robust_channels(top)
    r = doc["subject"]["radius"]
    radii = list(r) if isinstance(r, list) else [r] * len(ch)
    res, mats = doc["results"], doc["matrices"]
    props = doc["certifies"]
    u = delta * np.concatenate(
        [b.get(i, np.zeros((top.dim, top.dim))) @ m["x0"] for i in range(top.n)]
    )
    target = np.tile(theta, top.n)
    # 200 realisations within the radii (seed 7), their L_B and slowest decay: the same for
    # every mutant with this subject, so computed once per subject (_once)
    subject_key = ("robust", m["topology"], delta, radii)

    def sampled():
        rng = np.random.default_rng(7)
        laps = [_lap_with(top, w, delta, b) for w in _sample_realisations(top, radii, rng, 200)]
        worst = min(np.min(np.linalg.eigvals(lw).real) for lw in laps)
        return laps, worst, rng.bit_generator.state

    laps, worst_decay, after = _once(subject_key, sampled)
    if "robust_margin" in props:
        rm = res["margin"]["lower"]
        p = np.array(mats["P"]["robust_margin"])
        tau = mats["multipliers"]["robust_margin"]
        if not _lmi_holds(lap, ch, p, tau, 0.0, [rm] * len(ch)):
            bad.append("margin LMI")

        def within_margin():
            # 100 more realisations within the margin, drawn after those 200: is every one
            # of them Hurwitz (stopping at the first that is not)
            rng = np.random.default_rng()
            rng.bit_generator.state = after
            return all(
                np.min(np.linalg.eigvals(_lap_with(top, w, delta, b)).real) > 0
                for w in _sample_realisations(top, [rm] * len(ch), rng, 100)
            )

        if not _once((*subject_key, "margin", rm), within_margin):
            bad.append("a realisation within the margin is not Hurwitz")
    if "robust_decay" in props or "robust_offset" in props:
        al = res["decay"]["lower"]
        p = np.array(mats["P"]["robust_decay"])
        tau = mats["multipliers"]["robust_decay"]
        if not _lmi_holds(lap, ch, p, tau, al, radii):
            bad.append("decay LMI")
        if not worst_decay > al:
            bad.append("a sampled realisation decays slower than α_lower")
    if "robust_offset" in props:
        gam = res["offset"]["gamma"]
        worst = _once(
            (*subject_key, "offset", m["x0"], m["theta"]),
            lambda: max(np.linalg.norm(np.linalg.solve(lw, u) - target) for lw in laps),
        )
        # an upper bound: true when at or above √γ (a looser one is still true)
        if not worst**2 <= gam or not _at_least(res["offset"]["upper"], math.sqrt(gam)):
            bad.append("offset bound")
    eig = float(np.min(np.linalg.eigvals(lap).real))
    if not _close(res["nominal_decay"], eig):
        bad.append("nominal decay")
    reals = doc.get("realizations", {})
    for key, path in (("decay", ("decay", "upper")), ("offset", ("offset", "lower"))):
        if path[0] in res and path[1] in res[path[0]]:
            w = dict(top.weights)
            for e in reals[key]["edges"]:
                w[(top.index(e["to"]), top.index(e["from"]))] = np.array(e["weight"])
            lw = _lap_with(top, w, delta, b)
            got = (
                float(np.min(np.linalg.eigvals(lw).real))
                if key == "decay"
                else float(np.linalg.norm(np.linalg.solve(lw, u) - target))
            )
            # an eigenvalue is defined to a tolerance relative to the matrix's size; the
            # realisation's rate bounds the robust rate above, its offset the worst offset
            # below: the reported end is true on that side of it
            atol = 1e-6 * float(np.max(np.abs(lw))) if key == "decay" else 1e-12
            end = res[path[0]][path[1]]
            if not (_at_least(end, got, 1e-6, atol) if key == "decay" else _at_least(-end, -got)):
                bad.append(f"{key} realisation")
    return bad


def _truth_digital(doc: dict) -> list[str]:
    """The base kind's truth on the certificate without its digital section, then the
    sampled contraction's inequalities rebuilt here from the weights (G_e, g_e from their
    definitions), c(t) = 1/(1+t) sampled beyond t₀ and k₀ = ⌈t₀/h⌉ + D."""
    base = copy.deepcopy(doc)
    base["kind"] = {"digital": "hurwitz", "digital_switching": "switching"}[doc["kind"]]
    base["claims"] = [c for c in doc["claims"] if c.get("property") != "digital_mean_square"]
    base["certifies"] = [p for p in doc["certifies"] if p != "digital_mean_square"]
    base["matrices"]["P"].pop("digital", None)
    bad = _truth_dense(base)
    sub, res = doc["subject"]["digital"], doc["results"]["digital"]
    if "digital_mean_square" not in doc["certifies"]:
        return bad + ([] if set(res) == {"stopped"} else ["numbers of an uncertified section"])
    h, dl = sub["period"], sub["delay"]
    f = sub["noise"]["f"]
    sched = doc["subject"].get("schedule")
    used = list(dict.fromkeys(x["mode"] for x in sched)) if sched else list(doc["subject"]["modes"])
    if res.get("bound") == "delay_line":
        return bad + _truth_delay_line(doc, used)
    p = np.array(doc["matrices"]["P"]["digital"])
    al, kap, gam, t0 = res["alpha"], res["kappa"], res["gamma"], res["t0"]
    if not (_pos(p) and al > 0 and kap > 0):
        bad.append("P, α or κ")
        return bad
    own = {(e["from"], e["to"]): e["sigma"] for e in sub["noise"]["sigma_edges"]}
    for k in used:
        m = doc["subject"]["modes"][k]
        top = Topology.from_data(parse_topology(m["topology"], k))
        d, n = top.dim, top.n * top.dim
        fm = np.asarray(f, dtype=float) * np.eye(d) if not isinstance(f, list) else np.array(f)
        lap = _lap_b(top, m["delta"])
        nmat, energy = np.zeros((n, n)), 0.0
        for (i, j), a in top.weights.items():
            w = _sign(a) * a
            gm = np.zeros((n, n))
            gm[i * d : i * d + d, j * d : j * d + d] += w @ fm
            gm[i * d : i * d + d, i * d : i * d + d] -= w @ fm
            nmat += gm.T @ p @ gm
            g = np.zeros(n)
            sig = own.get((str(top.labels[j]), str(top.labels[i])), sub["noise"]["sigma"])
            g[i * d : i * d + d] = sig * w.sum(axis=1)
            energy += g @ p @ g
        mm, q = p @ lap + lap.T @ p, lap.T @ p @ lap
        if not _pos(mm - al * p - kap * (h * q + nmat)):
            bad.append(f"{k}: mean-square inequality")
        if dl and not (_pos(res["beta"] * p - nmat) and _pos(res["ell2"] * p - q)):
            bad.append(f"{k}: β or ℓ²")
        if not energy <= gam * (1 + 1e-12):
            bad.append(f"{k}: γ")
    if dl:
        be, l2 = res["beta"], res["ell2"]
        ell = math.sqrt(l2)
        rho = (2 / al) * ((2 / al) * (ell + kap * be) ** 2 + h * kap * l2 + kap * be)
        rho *= dl * dl * h * kap * kap * (h * l2 + be)
        if not rho <= 0.5 * (1 + 1e-9):
            bad.append("ρ(κ)")
    if sub["gain"] != "1/(1+t)":
        bad.append("gain")
    elif not np.all(1 / (1 + (t0 + np.concatenate([[0.0], np.geomspace(1e-9, 1e9, 3000)]))) < kap):
        bad.append("t₀")
    if res["k0"] != math.ceil(t0 / h - 1e-12) + dl:
        bad.append("k₀")
    return bad


def _truth_digital_loss(doc: dict) -> list[str]:
    """The hurwitz truth without the lossy section, then the inequality over the arrivals
    rebuilt here from the weights (L_e, G_e, the factors of skip and rescale from their
    definitions), c(t) = 1/(1+t) sampled beyond t₀, k₀ = ⌈t₀/h⌉ and the offset by a dense
    solve of (L_B − Σ p_e L_e) e* = Σ p_e L_e (1⊗θ)."""
    base = copy.deepcopy(doc)
    base["kind"] = "hurwitz"
    base["claims"] = [c for c in doc["claims"] if c.get("property") != "digital_mean_square"]
    base["certifies"] = [p for p in doc["certifies"] if p != "digital_mean_square"]
    base["matrices"]["P"].pop("loss", None)
    bad = _truth_dense(base)
    sub, res = doc["subject"]["digital"], doc["results"]["digital"]
    if "digital_mean_square" not in doc["certifies"]:
        return bad + ([] if set(res) == {"stopped"} else ["numbers of an uncertified section"])
    h, policy = sub["period"], sub["loss"]["policy"]
    if sub["delay"] == 0 and policy == "hold":
        return bad + _truth_hold(doc)
    if policy not in ("skip", "rescale") or (sub["delay"] != 0) != (res.get("bound") is not None):
        return [*bad, "delay or policy"]
    ((name, m),) = doc["subject"]["modes"].items()
    top = Topology.from_data(parse_topology(m["topology"], name))
    d, n = top.dim, top.n * top.dim
    f = sub["noise"]["f"]
    fm = np.asarray(f, dtype=float) * np.eye(d) if not isinstance(f, list) else np.array(f)
    lab = [str(x) for x in top.labels]
    loss = {(lab.index(e["to"]), lab.index(e["from"])): e["p"] for e in sub["loss"]["edges"]}
    p = np.array(doc["matrices"]["P"]["loss"])
    al, kap, t0 = res["alpha"], res["kappa"], res["t0"]
    if not (_pos(p) and al > 0 and kap > 0):
        return [*bad, "P, α or κ"]
    lap = _lap_b(top, m["delta"])
    lbar, s, nbar, rhs = lap.copy(), np.zeros((n, n)), np.zeros((n, n)), np.zeros(n)
    target = np.tile(np.array(m["theta"], dtype=float), top.n)
    for (i, j), a in top.weights.items():
        w = _sign(a) * a
        le = np.zeros((n, n))
        le[i * d : i * d + d, i * d : i * d + d] = w
        le[i * d : i * d + d, j * d : j * d + d] = -a
        pe = loss.get((i, j), 0.0)
        q = 1 - pe
        var, sq = (q * (1 - q), q) if policy == "skip" else ((1 - q) / q, 1 / q)
        if policy == "skip":
            lbar -= pe * le
            rhs += pe * le @ target
        s += var * le.T @ p @ le
        gm = np.zeros((n, n))
        gm[i * d : i * d + d, j * d : j * d + d] += w @ fm
        gm[i * d : i * d + d, i * d : i * d + d] -= w @ fm
        nbar += sq * gm.T @ p @ gm
    if sub["delay"]:
        bad += _truth_lossy_delay_line(doc, top, lap, loss, fm)
    else:
        mu = 2 if policy == "skip" else 1
        mm = p @ lbar + lbar.T @ p
        if not _pos(mm - al * p - kap * (h * (lbar.T @ p @ lbar + 2 * s) + mu * nbar)):
            bad.append("mean-square inequality over the arrivals")
    if sub["gain"] != "1/(1+t)":
        bad.append("gain")
    elif not np.all(1 / (1 + (t0 + np.concatenate([[0.0], np.geomspace(1e-9, 1e9, 3000)]))) < kap):
        bad.append("t₀")
    if res["k0"] != math.ceil(t0 / h - 1e-12) + sub["delay"]:
        bad.append("k₀")
    if res["p_max"] != max(loss.values(), default=0.0):
        bad.append("p_max")
    if policy == "skip":
        off = float(np.linalg.norm(np.linalg.solve(lbar, rhs)))
        if not _close(res["offset"], off, 1e-8, 1e-14):
            bad.append("offset")
    return bad


def _truth_hold(doc: dict) -> list[str]:
    """Hold's inequalities rebuilt here from the weights: the state z = (e, u), u = τ Q_d⁻¹ η,
    its step written out per arrival pattern (a sum over all 2^E, not the mean-plus-variance
    form of the code), Q = [[S, SΠP_d], [·, R]], G(κ) and G(0) on u, the coupling, the rate
    α <= α' − gβ/(1 − β), ghκβ <= 1 − β, c = 1/(1+t) below κ beyond t₀, k₀ and p_max."""
    import itertools
    from fractions import Fraction

    bad: list[str] = []
    sub, res = doc["subject"]["digital"], doc["results"]["digital"]
    h = sub["period"]
    ((name, md),) = doc["subject"]["modes"].items()
    top = Topology.from_data(parse_topology(md["topology"], name))
    d, n = top.dim, top.n * top.dim
    f = sub["noise"]["f"]
    fm = np.asarray(f, dtype=float) * np.eye(d) if not isinstance(f, list) else np.array(f)
    sig = sub["noise"]["sigma"]
    lab = [str(x) for x in top.labels]
    loss = {(lab.index(e["to"]), lab.index(e["from"])): e["p"] for e in sub["loss"]["edges"]}
    order = sorted(top.weights)  # the certificate's edge order (sorted (i, j))
    ne, m = len(order), len(order) * d
    try:
        s = np.array(doc["matrices"]["P"]["hold"], dtype=float)
        r = np.array(doc["matrices"]["P"]["hold_R"], dtype=float)
        al, a1, be, rho, g, kap, t0 = (
            float(res[k]) for k in ("alpha", "alpha_step", "beta", "rho", "g", "kappa", "t0")
        )
    except (KeyError, TypeError, ValueError):
        return ["hold matrices or numbers"]
    if s.shape != (n, n) or r.shape != (m, m) or not (0 < be < 1 and rho > 0 and kap > 0):
        return ["hold shapes or numbers"]
    lap = _lap_b(top, md["delta"])
    pi, gam = np.zeros((n, m)), np.zeros((m, n))
    kds, gs, p = [], [], np.zeros(m)
    for k, (i, j) in enumerate(order):
        a = top.weights[(i, j)]
        w = _sign(a) * a
        pi[i * d : i * d + d, k * d : k * d + d] = np.eye(d)
        gam[k * d : k * d + d, j * d : j * d + d] += a
        gam[k * d : k * d + d, i * d : i * d + d] -= w
        sel = np.zeros((d, n))
        sel[:, j * d : j * d + d], sel[:, i * d : i * d + d] = np.eye(d), -np.eye(d)
        kds.append(w @ fm @ sel)
        gs.append(sig * w.sum(axis=1))
        p[k * d : k * d + d] = loss.get((i, j), 0.0)
    q = 1 - p
    cm = s @ pi @ np.diag(p)
    qm = np.block([[s, cm], [cm.T, r]])
    w_ = n + m

    def expected(c: float) -> np.ndarray:
        tau = h * c
        out = np.zeros((w_, w_))
        for chi in itertools.product((0, 1), repeat=ne):
            x = np.repeat(np.array(chi, dtype=float), d)
            prob = float(np.prod([q[k * d] if v else p[k * d] for k, v in enumerate(chi)]))
            # e' = (I − τL)e + Π(I − X)Q_d u;  u' = Q_d⁻¹(I − τΓΠ)(I − X)Q_d u
            b = np.zeros((w_, w_))
            b[:n, :n] = np.eye(n) - tau * lap
            b[:n, n:] = pi @ np.diag((1 - x) * q)
            b[n:, n:] = np.diag(1 / q) @ (np.eye(m) - tau * gam @ pi) @ np.diag((1 - x) * q)
            out += prob * b.T @ qm @ b
        return out

    def g_of(c: float) -> np.ndarray:
        out = (1 - (a1 * h + rho) * c) * qm - expected(c)
        if c == 0:
            return out
        fmat = h * h * np.diag(1 / q) @ gam @ lap
        b0 = np.vstack([pi, np.diag(1 / q)])
        b1 = np.vstack([0 * pi, -np.diag(1 / q) @ gam @ pi])
        mm = (1 + h * kap) * (b0.T @ qm @ b0 + h * kap * b1.T @ qm @ b1)
        noise = sum(
            q[k * d] * kds[k].T @ mm[k * d : k * d + d, k * d : k * d + d] @ kds[k]
            for k in range(ne)
        )
        out[:n, :n] -= c * c * (kap * kap + kap / rho) * fmat.T @ r @ fmat + h * c * c * noise
        return out

    g0 = g_of(0.0)
    if not (np.allclose(g0[:n, :], 0, atol=1e-9 * np.max(np.abs(g0))) and _pos(g0[n:, n:])):
        bad.append("G₀")
    if not _pos(np.block([[be * s, cm], [cm.T, r]])) or not _pos(s):
        bad.append("coupling or S")
    gk = g_of(kap)  # the SDP keeps a margin of 1e-7·hκ here: rounding of this check is ~1e-14
    if not np.linalg.eigvalsh(0.5 * (gk + gk.T))[0] > 1e-12 * max(1.0, np.max(np.abs(gk))):
        bad.append("G(κ)")
    fb = Fraction(be)
    if not (al > 0 and Fraction(al) <= Fraction(a1) - Fraction(g) * fb / (1 - fb)):
        bad.append("α")
    if Fraction(g) * Fraction(h) * Fraction(kap) * fb > 1 - fb or not g > 1.0:
        bad.append("g or ghκβ")  # (1/c)' = 1 for c = 1/(1+t)
    if sub["gain"] != "1/(1+t)":
        bad.append("gain")
    elif not np.all(1 / (1 + (t0 + np.concatenate([[0.0], np.geomspace(1e-9, 1e9, 3000)]))) < kap):
        bad.append("t₀")
    if res["k0"] != math.ceil(t0 / h - 1e-12):
        bad.append("k₀")
    if res["p_max"] != max(loss.values(), default=0.0):
        bad.append("p_max")
    return bad


def _truth_lossy_delay_line(doc, top, lap, loss, fm) -> list[str]:
    """The delay line's step over the arrivals: E_χ[A_χᵀ W A_χ] for the augmented
    transition on (e_k, e_k − e_{k−1}, …) averaged over every arrival pattern edge by edge
    (the mean A plus each edge's variance term, the arrivals being independent), the noise
    scaled by E[m_e²]; the R_j decrease; (1/c)' = 1 < g; c_true >= κ."""
    bad: list[str] = []
    sub, res = doc["subject"]["digital"], doc["results"]["digital"]
    h, dl, policy = sub["period"], sub["delay"], sub["loss"]["policy"]
    mats = doc["matrices"]["P"]
    s = np.array(mats["loss"])
    rs = [np.array(mats[f"loss_R{j}"]) for j in range(dl)]
    ts = [np.array(mats[f"loss_T{j}"]) for j in range(dl)]
    al, kap, g = res["alpha"], res["kappa"], res["g"]
    if not (g > 1 and all(_pos(t) for t in ts)):
        return ["T or g"]
    n, d = s.shape[0], top.dim
    rn = [*rs, np.zeros((n, n))]
    tau = h * kap
    for j in range(dl):
        if not _pos(rs[j] - rn[j + 1]) or not _pos(
            (1 - al * tau) * rs[j] - (1 + g * tau) * rn[j + 1] - tau * ts[j]
        ):
            bad.append(f"R_{j} decrease")
    m = n * (dl + 1)
    blk = [np.zeros((n, m)) for _ in range(dl + 1)]
    for b in range(dl + 1):
        blk[b][:, b * n : (b + 1) * n] = np.eye(n)
    ey = blk[0] - sum(blk[1:])
    wt = 1 / tau + g
    wp = blk[0].T @ s @ blk[0] + sum(wt * blk[j + 1].T @ rs[j] @ blk[j + 1] for j in range(dl))
    lchi, extra = lap.copy(), np.zeros((m, m))  # the mean L̄ and the arrivals' variance
    for (i, j), a in top.weights.items():
        w = _sign(a) * a
        le = np.zeros((n, n))
        le[i * d : i * d + d, i * d : i * d + d] = w
        le[i * d : i * d + d, j * d : j * d + d] = -a
        q = 1 - loss.get((i, j), 0.0)
        mult = 1.0 if policy == "skip" else 1 / q
        lchi += (q * mult - 1) * le
        b = (blk[0].T + blk[1].T) @ (-tau * le @ ey)
        gm = np.zeros((n, n))
        gm[i * d : i * d + d, j * d : j * d + d] += w @ fm
        gm[i * d : i * d + d, i * d : i * d + d] -= w @ fm
        extra += q * (1 - q) * mult**2 * b.T @ wp @ b
        extra += h * kap**2 * q * mult**2 * ey.T @ gm.T @ (s + wt * rs[0]) @ gm @ ey
    a = blk[0].T @ (blk[0] - tau * lchi @ ey) + blk[1].T @ (-tau * lchi @ ey)
    for j in range(1, dl):
        a += blk[j + 1].T @ blk[j]
    lhs = a.T @ wp @ a + extra
    rhs = (1 - al * tau) * blk[0].T @ s @ blk[0]
    for j in range(dl):
        rhs += blk[j + 1].T @ (((1 + g * tau) * rn[j + 1] + tau * ts[j]) / tau) @ blk[j + 1]
    if not _pos(rhs - lhs):
        bad.append("the delay line's step over the arrivals")
    if "c_true" in res and not res["c_true"] >= kap * (1 - 1e-9):
        bad.append("c_true")
    return bad


def _truth_delay_line(doc: dict, used: list) -> list[str]:
    """The delay line's inequalities written out from x_{k+1} = A(τ)x_k + Bν (dense
    blocks), at c = κ and the stated g, G_e and g_e from the weights; (1/c)' = 1 < g,
    c(t) < κ beyond t₀, k₀ = ⌈t₀/h⌉ + D and c_true >= κ."""
    bad: list[str] = []
    sub, res = doc["subject"]["digital"], doc["results"]["digital"]
    h, dl = sub["period"], sub["delay"]
    mats = doc["matrices"]["P"]
    s = np.array(mats["digital"])
    rs = [np.array(mats[f"digital_R{j}"]) for j in range(dl)]
    ts = [np.array(mats[f"digital_T{j}"]) for j in range(dl)]
    al, kap, gam, t0, g = (res[k] for k in ("alpha", "kappa", "gamma", "t0", "g"))
    if not (al > 0 and kap > 0 and g > 1 and _pos(s) and all(_pos(t) for t in ts)):
        return ["S, T, α, κ or g"]
    n = s.shape[0]
    rn = [*rs, np.zeros((n, n))]
    tau = h * kap
    for j in range(dl):
        if not _pos(rs[j] - rn[j + 1]) or not _pos(
            (1 - al * tau) * rs[j] - (1 + g * tau) * rn[j + 1] - tau * ts[j]
        ):
            bad.append(f"R_{j} decrease")
    own = {(e["from"], e["to"]): e["sigma"] for e in sub["noise"]["sigma_edges"]}
    f = sub["noise"]["f"]
    m = n * (dl + 1)
    blk = [np.zeros((n, m)) for _ in range(dl + 1)]
    for b in range(dl + 1):
        blk[b][:, b * n : (b + 1) * n] = np.eye(n)
    ey = blk[0] - sum(blk[1:])
    for k in used:
        md = doc["subject"]["modes"][k]
        top = Topology.from_data(parse_topology(md["topology"], k))
        d = top.dim
        fm = np.asarray(f, dtype=float) * np.eye(d) if not isinstance(f, list) else np.array(f)
        lap = _lap_b(top, md["delta"])
        gms, energy = [], 0.0
        for (i, j), a in top.weights.items():
            w = _sign(a) * a
            gm = np.zeros((n, n))
            gm[i * d : i * d + d, j * d : j * d + d] += w @ fm
            gm[i * d : i * d + d, i * d : i * d + d] -= w @ fm
            gms.append(gm)
            gv = np.zeros(n)
            sig = own.get((str(top.labels[j]), str(top.labels[i])), sub["noise"]["sigma"])
            gv[i * d : i * d + d] = sig * w.sum(axis=1)
            energy += gv @ (s + sum(ts)) @ gv
        a = blk[0].T @ (blk[0] - tau * lap @ ey) + blk[1].T @ (-tau * lap @ ey)
        for j in range(1, dl):
            a += blk[j + 1].T @ blk[j]
        wt = 1 / tau + g
        wp = blk[0].T @ s @ blk[0] + sum(wt * blk[j + 1].T @ rs[j] @ blk[j + 1] for j in range(dl))
        lhs = a.T @ wp @ a + h * kap**2 * ey.T @ sum(x.T @ (s + wt * rs[0]) @ x for x in gms) @ ey
        rhs = (1 - al * tau) * blk[0].T @ s @ blk[0]
        for j in range(dl):
            rhs += blk[j + 1].T @ (((1 + g * tau) * rn[j + 1] + tau * ts[j]) / tau) @ blk[j + 1]
        if not _pos(rhs - lhs):
            bad.append(f"{k}: step inequality")
        if not energy <= gam * (1 + 1e-12):
            bad.append(f"{k}: γ'")
    if sub["gain"] != "1/(1+t)":
        bad.append("gain")
    elif not np.all(1 / (1 + (t0 + np.concatenate([[0.0], np.geomspace(1e-9, 1e9, 3000)]))) < kap):
        bad.append("t₀")
    if res["k0"] != math.ceil(t0 / h - 1e-12) + dl:
        bad.append("k₀")
    if "c_true" in res and not res["c_true"] >= kap * (1 - 1e-9):
        bad.append("c_true")
    return bad


def _truth_deadline(doc: dict) -> list[str]:
    """The dense truth without the deadline, then the sampled protocol's E‖e‖² at every
    sample and at T (the partial step: (s/√h)·c_K·ξ) in a written-out float recursion of
    the augmented moments from the subject's x(0), σ, f, h, D and T: the stated B_T and
    B_peak must be at or above it, T the subject's, the peak's time within [0, T]."""
    bad = _truth_dense(doc)
    sec, res = doc["subject"]["deadline"], doc["results"]["deadline"]
    if sec["gain"] != "1/(1+t)" or sec["noise"].get("sigma_edges"):
        return [*bad, "gain or σ per edge"]
    (mode,) = doc["subject"]["modes"].values()
    top = Topology.from_data(parse_topology(mode["topology"], "m"))
    lap, d, n = _lap_b(top, mode["delta"]), top.dim, top.n * top.dim
    theta = np.array(mode["theta"], dtype=float)
    e0 = np.array(sec["initial"]["x0"], dtype=float) - np.tile(theta, top.n)
    h, dl, t_end = sec.get("period"), sec.get("delay", 0), sec["T"]
    gs = []
    for (i, j), a in top.weights.items():
        w = _sign(a) * a
        gm, g = np.zeros((n, n)), np.zeros(n)
        gm[i * d : i * d + d, j * d : j * d + d] += w @ (sec["noise"]["f"] * np.eye(d))
        gm[i * d : i * d + d, i * d : i * d + d] -= w @ (sec["noise"]["f"] * np.eye(d))
        g[i * d : i * d + d] = sec["noise"]["sigma"] * w.sum(axis=1)
        gs.append((gm, g))
    if h is None:  # the continuous moment equations, by SciPy's DOP853
        from scipy.integrate import solve_ivp

        def rhs(t, y):
            sm, c = y.reshape(n, n), 1 / (1 + t)
            noise = sum(np.outer(g, g) + gm @ sm @ gm.T for gm, g in gs)
            return (-c * (lap @ sm + sm @ lap.T) + c * c * noise).ravel()

        sol = solve_ivp(rhs, (0, t_end), np.outer(e0, e0).ravel(), "DOP853", rtol=1e-11, atol=1e-11)
        values = list(np.einsum("iit->t", sol.y.reshape(n, n, -1)))
        h, dl = t_end, -1  # no sampled steps below
    big = (max(dl, 0) + 1) * n
    z = np.tile(np.outer(e0, e0), (max(dl, 0) + 1, max(dl, 0) + 1))
    m = np.zeros((big, big))
    m[:n, :n] = np.eye(n)
    m[n:, :-n] = np.eye(big - n)
    k_full = math.floor(t_end / h + 1e-9) if dl >= 0 else -1
    values = [np.trace(z[:n, :n])] if dl >= 0 else values
    for k in range(k_full + 1):
        c, zdd = 1 / (1 + k * h), z[-n:, -n:]
        noise = sum(np.outer(g, g) + gm @ zdd @ gm.T for gm, g in gs)
        s = min(h, t_end - k * h)
        if s <= 1e-9 * t_end:
            break
        step = m.copy()
        step[:n, -n:] -= s * c * lap
        z = step @ z @ step.T
        z[:n, :n] += s * s / h * c * c * noise
        values.append(np.trace(z[:n, :n]))
    if not _at_least(res["ms_error_bound"], values[-1], 1e-9, 0.0):
        bad.append("B_T")
    if not _at_least(res["peak_bound"], max(values), 1e-9, 0.0):
        bad.append("B_peak")
    if res["T"] != t_end or not 0 <= res["peak_time"] <= t_end:
        bad.append("T or the peak's time")
    return bad


def _truth_loss_deadline(doc: dict) -> list[str]:
    """The lossy certificate's truth, then E‖e‖² of the sampled protocol on lossy links at
    every sample and at T by a recursion written out here in error coordinates from the
    weights (L_δ = δ·blockdiag(B_i), b_e = (A_ij − |A_ij|)θ, each edge's step matrix as the
    coefficient of its arrival χ_e, E[χ_e χ_f] = q_e q_f or q_e): the stated B_T and B_peak
    must be at or above it, and the deadline's lossy links the subject's."""
    bad = _truth_digital_loss(doc)
    sec, res = doc["subject"]["deadline"], doc["results"]["deadline"]
    if sec["gain"] != "1/(1+t)" or sec["noise"].get("sigma_edges") or not sec.get("period"):
        return [*bad, "gain, σ per edge or no period"]
    ((name, mode),) = doc["subject"]["modes"].items()
    top = Topology.from_data(parse_topology(mode["topology"], name))
    lab, d, n = [str(x) for x in top.labels], top.dim, top.n * top.dim
    theta = np.array(mode["theta"], dtype=float)
    e0 = np.array(sec["initial"]["x0"], dtype=float) - np.tile(theta, top.n)
    h, dl, t_end = sec["period"], sec.get("delay", 0), sec["T"]
    policy, mine = sec["loss"]["policy"], sec["loss"]["edges"]
    theirs = doc["subject"]["digital"]["loss"]
    key = lambda es: sorted((e["from"], e["to"], e["p"]) for e in es)  # noqa: E731
    if theirs["policy"] != policy or key(theirs["edges"]) != key(mine):
        bad.append("the deadline's lossy links are not the subject's")
    loss = {(lab.index(e["to"]), lab.index(e["from"])): e["p"] for e in mine}
    edges = list(top.weights.items())
    ne, hold = len(edges), policy == "hold"
    one, lo = (dl + 1) * n, dl * n
    w = one + 1 + (ne * d if hold else 0)
    fm = sec["noise"]["f"] * np.eye(d)
    ground = np.zeros((n, n))
    for (i, _j), a in edges:
        if _sign(a) < 0:
            ground[i * d : i * d + d, i * d : i * d + d] -= mode["delta"] * a
    z0 = np.concatenate([np.tile(e0, dl + 1), [1.0], np.zeros(w - one - 1)])
    rows = []  # a_e (minus y_e for hold) as a d×w row block of z
    for k, ((i, j), a) in enumerate(edges):
        r = np.zeros((d, w))
        r[:, lo + j * d : lo + j * d + d] += a
        r[:, lo + i * d : lo + i * d + d] -= _sign(a) * a
        r[:, one] = (a - _sign(a) * a) @ theta
        if hold:
            z0[one + 1 + k * d : one + 1 + k * d + d] = r @ z0
            r[:, one + 1 + k * d : one + 1 + k * d + d] -= np.eye(d)
        rows.append(r)
    zz = np.outer(z0, z0)
    k_full = math.floor(t_end / h + 1e-9)
    values = [float(np.trace(zz[:n, :n]))]
    for k in range(k_full + 1):
        sk = min(h, t_end - k * h)
        if sk <= 1e-9 * t_end:
            break
        tau = sk / (1 + k * h)
        a0 = np.zeros((w, w))
        a0[:n, :n] = np.eye(n)
        a0[n:one, : one - n] = np.eye(one - n)
        a0[one:, one:] = np.eye(w - one)
        a0[:n, lo : lo + n] -= tau * ground
        new = np.zeros((w, w))
        mean = a0.copy()
        coef = []
        for k2, ((i, j), a) in enumerate(edges):
            q = 1 - loss.get((i, j), 0.0)
            ai, ce = np.zeros((w, w)), np.zeros((w, d))  # χ_e's coefficient, its noise's
            a0[i * d : i * d + d, one] -= tau * (a - _sign(a) * a) @ theta
            mean[i * d : i * d + d, one] -= tau * (a - _sign(a) * a) @ theta
            if hold:
                y = one + 1 + k2 * d
                a0[i * d : i * d + d, y : y + d] += tau * np.eye(d)
                mean[i * d : i * d + d, y : y + d] += tau * np.eye(d)
                ai[y : y + d] = rows[k2]
                ai[i * d : i * d + d] = tau * rows[k2]
                ce[y : y + d], ce[i * d : i * d + d] = np.eye(d), tau * np.eye(d)
            else:
                scale = 1 / q if policy == "rescale" else 1.0
                ai[i * d : i * d + d] = tau * scale * rows[k2]
                ce[i * d : i * d + d] = tau * scale * np.eye(d)
            mean += q * ai
            kk = (_sign(a) * a) @ fm
            diff = zz[lo + j * d : lo + j * d + d, lo + j * d : lo + j * d + d]
            diff = diff - zz[lo + j * d : lo + j * d + d, lo + i * d : lo + i * d + d]
            diff = diff - zz[lo + i * d : lo + i * d + d, lo + j * d : lo + j * d + d]
            diff = diff + zz[lo + i * d : lo + i * d + d, lo + i * d : lo + i * d + d]
            g = sec["noise"]["sigma"] * (_sign(a) * a).sum(axis=1)
            cov = (np.outer(g, g) + kk @ diff @ kk.T) / h
            coef.append((q, ai))
            new += q * ce @ cov @ ce.T
        new += mean @ zz @ mean.T
        for q, ai in coef:  # E[χ_e²] − E[χ_e]² = q(1 − q)
            new += q * (1 - q) * ai @ zz @ ai.T
        zz = new
        values.append(float(np.trace(zz[:n, :n])))
    if not _at_least(res["ms_error_bound"], values[-1], 1e-9, 0.0):
        bad.append("B_T")
    if not _at_least(res["peak_bound"], max(values), 1e-9, 0.0):
        bad.append("B_peak")
    if res["T"] != t_end or not 0 <= res["peak_time"] <= t_end:
        bad.append("T or the peak's time")
    if res.get("loss") != {"policy": policy, "p_max": max(loss.values(), default=0.0)}:
        bad.append("results.deadline.loss")
    return bad


def _truth_margin(doc: dict, honest_doc: dict) -> list[str]:
    """A stated ΔC must give the stated δ = C + ΔC. C depends on the topology only: the
    honest certificate's δ − ΔC for the same mode and topology (a mode whose topology was
    edited is compared by its own claims, not here)."""
    bad: list[str] = []
    honest = honest_doc.get("subject", {}).get("modes", {})
    for k, m in (doc.get("subject", {}).get("modes") or {}).items():
        h = honest.get(k)
        if not isinstance(m, dict) or not isinstance(h, dict) or m.get("margin") is None:
            continue
        if h.get("margin") is None or m.get("topology") != h.get("topology"):
            continue
        c = h["delta"] - h["margin"]
        if not _close(m["delta"], c + m["margin"], 1e-9, 1e-12):
            bad.append(f"{k}: δ ≠ C + ΔC")
    return bad


def truth(kind: str, doc: dict, honest_doc: dict) -> list[str]:
    """What is false in ``doc`` (empty: every claim and reported number is true)."""
    if kind == "time_varying":  # ΔC is what δ(t) is derived from: nothing to tie
        if doc.get("certifies") != honest_doc["certifies"]:
            return ["certifies"]
        return _truth_time_varying(doc)
    margin = _truth_margin(doc, honest_doc)
    if kind.startswith("robust"):
        return margin + _truth_robust(doc)
    if kind == "digital_loss-deadline":
        return margin + _truth_loss_deadline(doc)
    if kind.startswith("digital_loss"):
        return margin + _truth_digital_loss(doc)
    if kind.startswith("digital"):
        return margin + _truth_digital(doc)
    if kind == "hurwitz-deadline":
        return margin + _truth_deadline(doc)
    if doc.get("certifies") != honest_doc["certifies"] and kind not in ("hurwitz", "switching"):
        return ["certifies"]
    if kind in ("hurwitz", "switching"):
        return margin + _truth_dense(doc)
    if kind.startswith("hurwitz-scale"):
        return margin + _truth_hurwitz_scale(doc, honest_doc)
    return margin + _truth_switching_scale(doc)


# ------------------------------------------------------------------ the mutations


def _paths(x, path=()):
    """Every leaf and container path worth mutating (lists sampled)."""
    if isinstance(x, dict):
        yield path, x
        for k, v in x.items():
            if not (path == () and k in SKIP_KEYS):
                yield from _paths(v, (*path, k))
    elif isinstance(x, list):
        yield path, x
        idx = sorted({0, len(x) // 2, len(x) - 1}) if len(x) > MAX_LIST else range(len(x))
        for i in idx:
            yield from _paths(x[i], (*path, i))
    else:
        yield path, x


def _variants(x) -> list:
    if isinstance(x, bool):
        return [not x]
    if isinstance(x, int):
        return [x + 1, 0 if x else 1, -x - 1]
    if isinstance(x, float):
        return [v for v in (x * (1 + 1e-6), 2 * x + 1.0, -x, 0.0) if v != x]
    if isinstance(x, str):
        return [x[:-1] + ("A" if x[-1:] != "A" else "B"), ""]
    if x is None:
        return [1.0, "x"]
    if isinstance(x, list):
        return [x[:-1], []] if x else [[1.0]]
    return ["__drop__", "__extra__"]


def _mutants(doc):
    """Every mutant of ``doc`` as (label, build): ``build()`` makes it, so a test that
    tries every STRIDE-th copies only those (a copy of a large certificate per mutant was
    a quarter of the slow lane's forgery time)."""
    for path, value in list(_paths(doc)):
        if path == ():
            continue
        for i, v in enumerate(_variants(value)):
            if v == "__drop__":
                for key in list(value):
                    yield f"{path}-{key}", (lambda path=path, key=key: _dropped(doc, path, key))
                continue
            yield f"{path}={str(v)[:20]}", (lambda path=path, i=i: _replaced(doc, path, i))


def _dropped(doc: dict, path: tuple, key) -> dict:
    """``doc`` without ``key`` in the dict at ``path``."""
    m = copy.deepcopy(doc)
    parent = m
    for k in path:
        parent = parent[k]
    del parent[key]
    return m


def _replaced(doc: dict, path: tuple, i: int) -> dict:
    """``doc`` with the value at ``path`` replaced by its ``i``-th variant."""
    m = copy.deepcopy(doc)
    parent = m
    for k in path[:-1]:
        parent = parent[k]
    value = parent[path[-1]]
    v = _variants(value)[i]
    parent[path[-1]] = {**value, "forged": 1.0} if v == "__extra__" else v
    return m


def _redigest(doc):
    if isinstance(doc.get("subject"), dict):
        doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


def _careful(doc, ver):
    """A careful forger: lists exactly the claims verify derives for the edited file (``ver``,
    its verification)."""
    kind = KINDS.get(doc.get("kind"))
    if kind is not None and ver.about is not None:
        doc = copy.deepcopy(doc)
        doc["claims"] = [kind.record(c.claim) for c in ver.checks if c.claim is not None]
    return _redigest(doc)


def _share_enclosures(monkeypatch) -> None:
    """Verify re-encloses every interval of a time-varying certificate (50 here) for each
    mutant, though most mutants keep the topology, ΔC, σ and the intervals' ends: an
    enclosure is a function of exactly these (``Enclosures(tv, lemma1_structure(tv), margin,
    sigma).leaf(a, b)``), so each distinct one is computed once and shared by the mutants
    (about 11,000 enclosures, 900 of them distinct). Verify's verdicts are unchanged."""
    from ntc_design.certify.time_varying import Enclosures

    leaf, memo = Enclosures.leaf, {}

    def shared(self, a, b):
        key = (json.dumps(self.tv.to_dict(), sort_keys=True, default=repr), self.margin)
        key = (*key, self.sigma, a, b)
        if key not in memo:
            memo[key] = leaf(self, a, b)
        return memo[key]

    monkeypatch.setattr(Enclosures, "leaf", shared)


_SHARED: dict[str, dict] = {}


def _content(x):
    """A hashable key that is equal exactly when the values are (arrays by their bytes,
    dtype and shape; exact numbers by their digits); anything else is refused."""
    if isinstance(x, Topology):
        weights = sorted((k, np.asarray(a)) for k, a in x.weights.items())
        return ("Topology", repr(x.labels), x.dim, _content(weights))
    if isinstance(x, np.ndarray):
        if x.dtype == object:
            return ("O", x.shape, tuple(_content(v) for v in x.ravel().tolist()))
        return ("A", x.shape, x.dtype.str, x.tobytes())
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        fields = dataclasses.fields(x)
        return (type(x).__name__, tuple(_content(getattr(x, f.name)) for f in fields))
    if isinstance(x, (list, tuple)):
        return (type(x).__name__, tuple(_content(v) for v in x))
    if x is None or isinstance(x, (bool, int, str, Fraction)):
        return (type(x).__name__, x)
    if isinstance(x, float):
        return ("float", repr(x))  # -0.0 and 0.0 apart
    raise TypeError(f"no content key for {type(x).__name__}")


def _share(monkeypatch, module, name: str) -> None:
    """``module.name``, a pure function of its arguments, computed once per worker for
    each distinct content of them and shared by every mutant and kind that asks (most
    mutants keep the subject and the matrices, and the deadline kinds carry their base
    kind's). Its answer is an immutable value; a failure is not kept (raised again for
    each mutant). Verify's verdicts are unchanged."""
    pure, memo = getattr(module, name), _SHARED.setdefault(f"{module.__name__}.{name}", {})

    def shared(*args):
        key = _content(args)
        if key not in memo:
            memo[key] = pure(*args)
        return memo[key]

    monkeypatch.setattr(module, name, shared)


def _share_proofs(monkeypatch) -> None:
    """The costly pure steps of verify, shared across mutants: Sylvester's criterion on an
    integer matrix (``rigorous.exact.first_nonpositive_minor``, behind every exact
    ``m ≻ 0``), Lemma 1's δ = C + ΔC re-derived from a mode's topology
    (``certify.arrays.lemma1_delta``: Assumption 2's decomposition) and the lossy kinds'
    exact offset ‖e*‖² (``exact_offset``, as the digital_loss kind calls it)."""
    from ntc_design.certify import arrays
    from ntc_design.certify.kinds import digital_loss
    from ntc_design.rigorous import exact

    _share(monkeypatch, exact, "first_nonpositive_minor")
    _share(monkeypatch, arrays, "lemma1_delta")
    _share(monkeypatch, digital_loss, "exact_offset")


KIND_OF = {
    "digital": "digital",
    "digital_loss": "digital_loss",
    "digital_loss-delay": "digital_loss",
    "digital_switching": "digital_switching",
    "robust": "robust",
    "robust-riccati": "robust",
    "hurwitz": "hurwitz",
    "switching": "switching",
    "hurwitz-scale": "hurwitz-scale",
    "hurwitz-scale-g1": "hurwitz-scale",
    "switching-scale": "switching-scale",
    "time_varying": "time_varying",
    "hurwitz-deadline": "hurwitz",
    "digital_loss-deadline": "digital_loss",
}


STRIDE = {
    "robust-riccati": 4,
    "digital": 1,  # a 3-agent cycle at D = 1: every mutant
    "digital_loss": 3,
    "digital_loss-delay": 1,  # a 3-agent cycle: every mutant (the stride of 4 missed the bound)
    "digital_switching": 4,
    "hurwitz-deadline": 3,
    "digital_loss-deadline": 3,
}


def _riccati_certificate() -> dict:
    from ntc_design.certify.kinds.robust import robust_certificate
    from ntc_design.certify.robust import robust

    mid = design(random_network(14, 3, seed=4), [1.0, 2.0, -1.0], 0.1, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc = json.loads(json.dumps(robust_certificate(robust(mid, 0.05, starts=1))))
    assert doc["certifies"] == ["robust_margin", "robust_decay", "robust_offset"]
    assert verify(copy.deepcopy(doc)).valid and truth("robust", doc, doc) == []
    return doc


@pytest.fixture(scope="module")
def honest_all(honest, tmp_path_factory) -> dict[str, dict]:
    """Besides ``honest``, a robust certificate past the LMI's size (N = 14, d = 3:
    Riccati decay and margin, the offset with the equation eliminated); built for the
    slow lane only, once per run (tests/support/shared.py)."""
    doc = once_per_run(tmp_path_factory, "riccati_certificate", _riccati_certificate)
    return {
        **honest,
        "robust-riccati": doc,
        "hurwitz-deadline": _deadline_certificate(honest),
        "digital_loss-deadline": _loss_deadline_certificate(honest),
    }


def _deadline_certificate(honest) -> dict:
    """G1's hurwitz certificate with the sampled figures at T = 0.45 (h = 0.1, D = 0: a
    partial step at the end)."""
    from ntc_design.certify.deadline_subject import add_deadline

    doc = copy.deepcopy(honest["hurwitz"])
    (mode,) = doc["subject"]["modes"].values()
    n = len(mode["topology"]["agents"]) * len(mode["theta"])
    section = {
        "T": 0.45,
        "period": 0.1,
        "delay": 0,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
        "initial": {"x0": np.linspace(-3.0, 3.0, n).tolist()},
    }
    add_deadline(doc, section)
    doc = json.loads(json.dumps(doc))
    assert verify(copy.deepcopy(doc)).valid and truth("hurwitz-deadline", doc, doc) == []
    return doc


def _loss_deadline_certificate(honest) -> dict:
    """G1's lossy certificate (p = 0.1, skip, h = 0.1, D = 0) with the figures at T = 0.45
    on its lossy links (a partial step at the end)."""
    from ntc_design.certify.deadline_subject import add_deadline

    doc = copy.deepcopy(honest["digital_loss"])
    (mode,) = doc["subject"]["modes"].values()
    n = len(mode["topology"]["agents"]) * len(mode["theta"])
    section = {
        "T": 0.45,
        "period": 0.1,
        "delay": 0,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
        "initial": {"x0": np.linspace(-3.0, 3.0, n).tolist()},
        "loss": copy.deepcopy(doc["subject"]["digital"]["loss"]),
    }
    add_deadline(doc, section)
    doc = json.loads(json.dumps(doc))
    assert verify(copy.deepcopy(doc)).valid and truth("digital_loss-deadline", doc, doc) == []
    return doc


@hostile
@pytest.mark.slow
@pytest.mark.parametrize("which", list(KIND_OF))
def test_no_valid_forgery_states_something_false(which, honest_all, monkeypatch):
    base = honest_all[which]
    _share_proofs(monkeypatch)
    if which == "time_varying":
        _share_enclosures(monkeypatch)
    tried = accepted = 0
    for k, (label, build) in enumerate(_mutants(base)):
        if k % STRIDE.get(which, 1):
            continue  # a large certificate: every STRIDE-th of its ~1,200 mutants
        doc = _redigest(build())
        for careful in (False, True):
            tried += 1
            try:
                ver = verify(doc)
            except (InputError, RecursionError):
                break  # malformed: rejected with exit 2
            if not ver.valid:
                # a careful forger re-lists the claims when that is what failed
                if careful or "listed claims" not in " ".join(c.name for c in ver.failed):
                    break
                doc = _careful(doc, ver)
                continue
            accepted += 1
            try:
                wrong = truth(which, doc, base)
            except (InputError, KeyError, TypeError, ValueError, AttributeError) as exc:
                wrong = [f"{type(exc).__name__}: {exc}"]
            assert not wrong, (which, label, careful, wrong)
            break
    # the enumeration is not vacuous: many edits, most of them refused
    assert tried >= 60 and accepted < tried / 2, (tried, accepted)


@hostile
def test_truth_oracle_accepts_every_honest_certificate_and_catches_a_false_number(honest):
    for which, doc in honest.items():
        assert truth(which, doc, doc) == [], which
    forged = copy.deepcopy(honest["hurwitz-scale"])
    forged["results"]["rate_estimate"]["value"] = forged["results"]["eig_bound"] = 100.0
    assert "rate estimate" in truth("hurwitz-scale", forged, honest["hurwitz-scale"])


def test_mutants_cover_every_top_level_field(honest):
    for which, doc in honest.items():
        touched = {path[0] for path, _ in _paths(doc) if path}
        assert touched == set(doc) - SKIP_KEYS, which


# ------------------------------------------------------------------ named forgeries


def _cli_verify(doc, tmp_path, capsys, monkeypatch):
    from tests.cli_helpers import run_cli

    p = tmp_path / "forged.json"
    p.write_text(json.dumps(_redigest(doc)))
    code, out, err = run_cli(["verify", p], capsys, monkeypatch)
    assert "Traceback" not in err
    return code, out, err


TV = json.loads((ROOT / "certificates" / "g1_tv.json").read_text())


@hostile
def test_time_varying_claims_and_certifies_are_derived(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(TV)
    doc["claims"][0]["id"] = "λ_min(L_B(t) + L_B(t)ᵀ) >= 100 on every interval"
    doc["claims"].append({"id": "−L_B Hurwitz with decay rate 1000", "kind": "hurwitz"})
    doc["certifies"] += ["hurwitz", "symmetric_part"]
    code, out, err = _cli_verify(doc, tmp_path, capsys, monkeypatch)
    assert code == 1
    assert "certifies what kind 'time_varying' can" in err and "listed claims" in err
    assert "FAILS certifies what kind 'time_varying' can: unknown property 'hurwitz'" in out


@hostile
def test_time_varying_theta_zero_is_invalid(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(TV)
    doc["subject"]["theta"] = [0.0, 0.0, 0.0]
    code, out, err = _cli_verify(doc, tmp_path, capsys, monkeypatch)
    assert code == 1 and "θ ≠ 0" in err and "θ = 0" in out


@hostile
@pytest.mark.parametrize("key", ["sigma_bar", "kappa"])
def test_time_varying_reported_numbers_are_recomputed(key, tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(TV)
    doc["results"]["time_varying"][key] = 0.0
    code, out, err = _cli_verify(doc, tmp_path, capsys, monkeypatch)
    assert code == 1 and "reported results" in err
    assert f"time_varying.{key}: reported 0.0, recomputed" in out


@hostile
@pytest.mark.parametrize("recompute", [True, False])
def test_forged_scale_rate_estimate_is_invalid(recompute, honest, tmp_path, capsys, monkeypatch):
    """The estimate is redone where it is cheap, and bounded on both sides where it is not
    (min Re λ of a component is at most the mean of its eigenvalues, trace/(n·d))."""
    from ntc_design.certify.kinds import hurwitz_scale

    if not recompute:
        monkeypatch.setattr(hurwitz_scale, "RECOMPUTE_FLOPS", 0)
    doc = copy.deepcopy(honest["hurwitz-scale-g1"])
    true = doc["results"]["rate_estimate"]["value"]
    doc["results"]["eig_bound"] = doc["results"]["rate_estimate"]["value"] = 100.0
    code, out, err = _cli_verify(doc, tmp_path, capsys, monkeypatch)
    assert code == 1 and "reported results" in err
    want = "recomputed" if recompute else "above"
    assert "rate_estimate.value: " in out and want in out.split("rate_estimate.value:")[1][:80]
    assert 0 < true < 100


@hostile
def test_an_added_number_in_results_is_invalid(honest):
    for which, doc in honest.items():
        doc = copy.deepcopy(doc)
        doc["results"]["decay_rate_proven"] = 1000.0
        ver = verify(_redigest(doc))
        assert not ver.valid, which
        assert (
            "decay_rate_proven: a reported number this kind does not report"
            in ver.failed[-1].detail
        )
