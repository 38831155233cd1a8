"""Lemma 1 at every instant of a time-varying topology: the fixed structure (U, Ω_i, the
positive-negative paths), batched evaluation at many times (batched Cholesky and symmetric
eigenvalues), and the design sampled over the domain."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import require_theta, require_x0
from ..model import antagonistic_in_weight, positive_negative_reachable
from ..model.timevarying import ExpressionTopology
from ..numerics.linalg import DEF_RTOL, pd
from ..present.rows import Table, fmt, set_text, verdict

# ----------------------------------------------------------------- Lemma 1 at every t


@dataclass(frozen=True)
class Lemma1Structure:
    """What Lemma 1 needs that does not move with t (the sign classes are fixed)."""

    n: int
    d: int
    ii: np.ndarray  # (E,) target of each edge
    jj: np.ndarray  # (E,) source
    sign: np.ndarray  # (E,) sgn A_ij
    informed: tuple[int, ...]  # V_I = U
    candidates: tuple[int, ...]  # agents whose Σ_Ω|A_ij| ≻ 0 (may be in V1)
    reach: np.ndarray  # (n_cand, N) bool: reached from the candidate by +- paths
    neg_in: np.ndarray  # (N, E) 1 where edge e is antagonistic into i
    in_inc: np.ndarray  # (N, E) 1 where edge e enters i
    out_inc: np.ndarray  # (N, E) 1 where edge e leaves i


def lemma1_structure(tv: ExpressionTopology) -> Lemma1Structure:
    """What Lemma 1 needs that does not move with t: incidence arrays, U, the V1
    candidates and the positive-negative reachability from each.

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.

    Returns
    -------
    Lemma1Structure
        The fixed structure.
    """
    top = tv.structure
    n, d = tv.n, tv.dim
    e_n = len(tv.edges)
    ii = np.array([e.i for e in tv.edges], dtype=np.int64)
    jj = np.array([e.j for e in tv.edges], dtype=np.int64)
    sign = np.array([e.sign for e in tv.edges], dtype=float)
    in_inc = np.zeros((n, e_n))
    out_inc = np.zeros((n, e_n))
    neg_in = np.zeros((n, e_n))
    for k in range(e_n):
        if sign[k] != 0:
            in_inc[ii[k], k] = 1
            out_inc[jj[k], k] = 1
            if sign[k] < 0:
                neg_in[ii[k], k] = 1

    cands = tuple(i for i in range(n) if pd(antagonistic_in_weight(top, i)))
    reach = np.zeros((len(cands), n), dtype=bool)
    for k, c in enumerate(cands):
        for a in positive_negative_reachable(top, [c]):
            reach[k, a] = True
    return Lemma1Structure(
        n, d, ii, jj, sign, tuple(top.antagonised), cands, reach, neg_in, in_inc, out_inc
    )


@dataclass(frozen=True)
class Lemma1Batch:
    """Lemma 1 at K times. Arrays are indexed by time first."""

    t: np.ndarray  # (K,)
    C: np.ndarray  # (K,) NaN where undefined (no candidate)
    C_i: np.ndarray  # (K, n_cand)
    delta: np.ndarray  # (K,)
    k1: np.ndarray  # (K,)
    x0: np.ndarray  # (K, d)
    B: np.ndarray  # (K, N, d, d) B_i (zero for naive agents)
    abs_w: np.ndarray  # (K, E, d, d) |A_ij(t)|
    weights: np.ndarray  # (K, E, d, d) A_ij(t)
    assumption_holds: np.ndarray  # (K,) bool
    v1_size: np.ndarray  # (K,)

    def lap_b(self, st: Lemma1Structure) -> np.ndarray:
        """L_B(t) = L(t) + δ(t)·blockdiag(B_i(t)) (Niu & Wu, eq. (8)) at each time.

        Parameters
        ----------
        st : Lemma1Structure
            The structure this batch was computed with.

        Returns
        -------
        numpy.ndarray
            Shape (K, Nd, Nd).
        """
        return grounded_laplacian_batch(st, self.weights, self.abs_w, self.delta, self.B)

    def input_vector(self) -> np.ndarray:
        """The drift from the external signal, u(t) = (Δ(t)⊗I) B(t) x0(t), at each time.

        Returns
        -------
        numpy.ndarray
            Shape (K, Nd).
        """
        u = np.einsum("knab,kb->kna", self.B, self.x0) * self.delta[:, None, None]
        return u.reshape(u.shape[0], -1)


def grounded_laplacian_batch(
    st: Lemma1Structure,
    weights: np.ndarray,
    abs_w: np.ndarray,
    delta: np.ndarray | float,
    b: np.ndarray,
) -> np.ndarray:
    """``L_B = L + δ·blockdiag(B_i)`` (Niu & Wu, eq. (8)) for a batch of times.

    Parameters
    ----------
    st : Lemma1Structure
        Edge incidence and signs.
    weights : numpy.ndarray
        A_ij(t), shape (K, E, d, d).
    abs_w : numpy.ndarray
        |A_ij(t)|, shape (K, E, d, d).
    delta : numpy.ndarray or float
        δ(t), shape (K,), or one δ.
    b : numpy.ndarray
        B_i(t), shape (K, N, d, d) (zero for naive agents).

    Returns
    -------
    numpy.ndarray
        Shape (K, Nd, Nd): blocks L_ij = −A_ij, L_ii = Σ|A_ik| + δ B_i.
    """
    k_n = weights.shape[0]
    n, d = st.n, st.d
    lap = np.zeros((k_n, n, n, d, d))
    live = st.sign != 0
    np.add.at(lap, (slice(None), st.ii[live], st.jj[live]), -weights[:, live])  # type: ignore[arg-type]  # numpy's stubs reject a slice in the index
    diag = np.einsum("ie,keab->kiab", st.in_inc, abs_w)
    diag = diag + np.asarray(delta, dtype=float).reshape(-1, 1, 1, 1) * b
    ar = np.arange(n)
    lap[:, ar, ar] += diag
    return lap.transpose(0, 1, 3, 2, 4).reshape(k_n, n * d, n * d)


def lemma1_batch(
    tv: ExpressionTopology,
    st: Lemma1Structure,
    ts: Sequence[float] | np.ndarray,
    theta: np.ndarray,
    margin: float,
) -> Lemma1Batch:
    """Lemma 1 at every time of ``ts`` (vectorised over the batch).

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.
    st : Lemma1Structure
        ``lemma1_structure(tv)``.
    ts : sequence of float or numpy.ndarray
        K times.
    theta : numpy.ndarray
        The target θ (d numbers).
    margin : float
        ΔC > 0: δ(t) = C(t) + ΔC.

    Returns
    -------
    Lemma1Batch
        C(t), δ(t), k1(t), x0(t), B_i(t) and whether Assumption 2 holds at each time.

    Raises
    ------
    InputError
        A weight is not finite at one of the times.
    """
    ts = np.asarray(ts, dtype=float).reshape(-1)
    k_n, n, d = ts.size, st.n, st.d
    w = tv.weights_at(ts)
    abs_w = st.sign[None, :, None, None] * w
    b = np.einsum("ie,keab->kiab", st.neg_in, abs_w)  # B_i = Σ_Ω|A_ij|
    inn = np.einsum("ie,keab->kiab", st.in_inc, abs_w)
    out = np.einsum("ie,keab->kiab", st.out_inc, abs_w)
    nc = len(st.candidates)
    holds = np.ones(k_n, dtype=bool)
    v1_size = np.zeros(k_n, dtype=np.int64)
    if nc:
        cand = np.array(st.candidates)
        s = 0.5 * (b[:, cand] + np.swapaxes(b[:, cand], -1, -2))
        m = out[:, cand] - inn[:, cand]
        m = 0.5 * (m + np.swapaxes(m, -1, -2))
        lc = np.linalg.cholesky(s)
        y = np.linalg.solve(lc, m)
        z = np.linalg.solve(lc, np.swapaxes(y, -1, -2))
        c_i = 0.5 * np.linalg.eigvalsh(0.5 * (z + np.swapaxes(z, -1, -2)))[..., -1]
        # in-degree-domination of every agent at every t (Definition 4, model tolerance)
        diff = inn - out
        lam = np.linalg.eigvalsh(0.5 * (diff + np.swapaxes(diff, -1, -2)))[..., 0]
        scale = np.maximum(
            np.linalg.norm(inn, 2, axis=(-2, -1)), np.linalg.norm(out, 2, axis=(-2, -1))
        )
        idd = (scale == 0) | (lam >= -DEF_RTOL * scale)
        c = np.empty(k_n)
        order = np.argsort(c_i, axis=1, kind="stable")
        for k in range(k_n):
            covered = np.zeros(n, dtype=bool)
            in_v1 = np.zeros(n, dtype=bool)
            found = None
            for r, q in enumerate(order[k]):
                covered |= st.reach[q]
                in_v1[cand[q]] = True
                nxt = order[k][r + 1] if r + 1 < nc else None
                if nxt is not None and c_i[k, nxt] == c_i[k, q]:
                    continue  # a level includes every tie (as design.assumption2)
                if covered.all() and np.all(idd[k] | in_v1):
                    found = c_i[k, q]
                    v1_size[k] = int(in_v1.sum())
                    break
            if found is None:
                holds[k] = False
                found = float(np.max(c_i[k]))
            c[k] = found
        dl = np.where(c + margin > 0, c + margin, margin)
    else:
        c_i = np.zeros((k_n, 0))
        c = np.full(k_n, np.nan)
        holds[:] = False
        dl = np.full(k_n, float(margin))
    k1 = 1.0 + 2.0 / dl
    require_x0(np.asarray(theta, dtype=float), k1)
    x0 = k1[:, None] * np.asarray(theta, dtype=float)[None, :]
    bfull = np.zeros((k_n, n, d, d))
    inf = list(st.informed)
    bfull[:, inf] = b[:, inf]
    return Lemma1Batch(ts, c, c_i, dl, k1, x0, bfull, abs_w, w, holds, v1_size)


DESIGN_SAMPLES = 721


@dataclass(frozen=True, eq=False)
class TimeVaryingDesign:
    """Lemma 1 at every instant for an :class:`ExpressionTopology` (evaluated on demand by
    :func:`lemma1_batch`); ``to_dict`` summarises it over a sample of its domain."""

    topology: ExpressionTopology
    theta: np.ndarray
    margin: float

    def __post_init__(self) -> None:
        # θ checked up front (its length against d), before any certificate or run
        object.__setattr__(self, "theta", require_theta(self.theta, self.topology.dim))

    @cached_property
    def structure(self) -> Lemma1Structure:
        """The topology's :class:`Lemma1Structure` (computed once)."""
        return lemma1_structure(self.topology)

    def at(self, ts: Sequence[float] | np.ndarray) -> Lemma1Batch:
        """Lemma 1 at the times ``ts``; see :func:`lemma1_batch`.

        Parameters
        ----------
        ts : sequence of float or numpy.ndarray
            K times.

        Returns
        -------
        Lemma1Batch
            The design at each time.
        """
        return lemma1_batch(self.topology, self.structure, ts, self.theta, self.margin)

    def sample_times(self, k: int = DESIGN_SAMPLES) -> np.ndarray:
        """Evenly spaced times over the domain ([0, 10] when it is every t >= 0).

        Parameters
        ----------
        k : int, optional
            How many.

        Returns
        -------
        numpy.ndarray
            The times, ends included.
        """
        a, b = self.topology.domain or (0.0, 10.0)
        return np.linspace(a, b, k)

    def table(self, title: str | None = None) -> Table:
        """The design's ranges over the domain as the table every face shows.

        Parameters
        ----------
        title : str, optional
            The table's title (default: Lemma 1 at every instant with θ and ΔC).

        Returns
        -------
        ntc_design.present.rows.Table
        """
        d = self.to_dict()
        dom = d["domain"]

        def span(r: dict, digits: int = 4) -> str:
            return f"{fmt(r['min'], digits)} .. {fmt(r['max'], digits)}"

        x0 = zip(d["x0"]["min"], d["x0"]["max"], strict=True)
        ok = d["assumption_holds"]
        rows = [
            (
                "domain",
                f"[{dom[0]:.6g}, {dom[1]:.6g}] ({d['samples']} samples)" if dom else "t >= 0",
            ),
            ("informed agents V_I = U", set_text(d["informed"])),
            ("C(t)", span(d["C"]) if d["C"] is not None else None),
            ("δ(t) = C(t) + ΔC", span(d["delta"])),
            ("x0(t) = k1(t)·θ", "[" + ", ".join(f"{fmt(a)} .. {fmt(b)}" for a, b in x0) + "]"),
            ("λ_min(L_B + L_Bᵀ)", span(d["sym_min_eig"], 6)),
            ("identity residual (max)", f"{d['identity_residual']:.2e}"),
            (
                "Assumption 2",
                verdict(ok, "at every sample" if ok else "at some t", "holds" if ok else "fails"),
            ),
        ]
        notes = []
        if not ok:
            ts = ", ".join(f"{x:.4g}" for x in d["assumption_fails_at"])
            notes.append(
                f"Assumption 2 fails at t = {ts}, ...; Lemma 1's design is used as given "
                "(certify the uniform bound Λ₂ before trusting it)"
            )
        if title is None:
            title = f"Lemma 1 at every instant, θ = {d['theta']}, ΔC = {d['margin']:g}"
        return Table.build(title, ("quantity", "range over the domain"), rows, notes)

    def _repr_html_(self) -> str:
        return self.table().html()

    def to_dict(self) -> dict:
        """The design summarised over a sample of the domain, as a JSON-ready mapping.

        Returns
        -------
        dict
            Ranges of C, δ, k1, x0 and λ_min(L_B + L_Bᵀ), whether Assumption 2 holds at
            every sample (and the first times it fails), the identity residual of
            eq. (11) and the edges with their classes.
        """
        tv, st = self.topology, self.structure
        # fewer samples and bounded batches for large networks (L_B is K×Nd×Nd)
        ts = self.sample_times(DESIGN_SAMPLES if tv.nd <= 100 else 181)
        per = max(1, int(64 * 2**20 // (8 * 2 * tv.n * tv.n * tv.dim * tv.dim)))
        parts = []
        one = np.tile(self.theta, tv.n)
        for chunk in np.array_split(ts, -(-ts.size // per)):
            bb = self.at(chunk)
            lap = bb.lap_b(st)
            u = bb.input_vector()
            res_ = -np.einsum("kij,j->ki", lap, one) + u
            scale = np.max(np.abs(lap).sum(axis=2), axis=1) * np.max(np.abs(self.theta))
            sym_ = np.linalg.eigvalsh(lap + np.swapaxes(lap, 1, 2))[:, 0]
            parts.append((bb, np.max(np.abs(res_), axis=1) / np.maximum(scale, 1e-300), sym_))
        joined = {
            f: np.concatenate([getattr(p[0], f) for p in parts])
            for f in ("C", "C_i", "delta", "k1", "x0", "assumption_holds", "v1_size")
        }
        b = Lemma1Batch(
            t=ts,
            B=parts[0][0].B[:1],
            abs_w=parts[0][0].abs_w[:1],
            weights=parts[0][0].weights[:1],
            **joined,
        )
        res = np.concatenate([p[1] for p in parts])
        sym = np.concatenate([p[2] for p in parts])
        lab = tv.labels

        def rng(x: np.ndarray) -> dict:
            return {"min": float(np.nanmin(x)), "max": float(np.nanmax(x))}

        return {
            "topology": tv.name,
            "time_varying": True,
            "domain": list(tv.domain) if tv.domain else None,
            "period": str(tv.period) if tv.period is not None else None,
            "constant_after": str(tv.constant_after) if tv.constant_after is not None else None,
            "samples": int(ts.size),
            "theta": self.theta.tolist(),
            "margin": self.margin,
            "informed": [lab[i] for i in st.informed],
            "candidates_V1": [lab[i] for i in st.candidates],
            "C": rng(b.C) if st.candidates else None,
            "delta": rng(b.delta),
            "k1": rng(b.k1),
            "x0": {"min": b.x0.min(axis=0).tolist(), "max": b.x0.max(axis=0).tolist()},
            "assumption_holds": bool(np.all(b.assumption_holds)),
            "assumption_fails_at": [float(t) for t in ts[~b.assumption_holds][:5]],
            "identity_residual": float(np.max(res)),
            "sym_min_eig": rng(sym),
            "edges": [
                {
                    "from": lab[e.j],
                    "to": lab[e.i],
                    "class": e.cls.value,
                    "constant": e.weight.constant,
                }
                for e in tv.edges
            ],
        }
