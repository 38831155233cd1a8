"""The robust certificate's matrices in exact dyadic arithmetic, as the verifier re-forms
them: the channels of each uncertain edge, Ψ of the decay S-procedure and Γ of the offset's
(:mod:`.lmi` forms them in floating point for the solver)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InputError
from ...model import Topology
from ...rigorous.exact import Dyadic, PDProof, exact_affordable, exact_pd, verified_float_pd
from .lmi import active_columns, perturbed
from .problem import uncertain_edges


def dyadic(x: float) -> Dyadic:
    """A float as an exact dyadic number."""
    return Dyadic.of(float(x))


def block_matrix(rows: list[list[Dyadic]]) -> Dyadic:
    """A block matrix of Dyadics, exactly (over the largest exponent)."""
    e = max(b.exp for r in rows for b in r)
    return Dyadic(np.vstack([np.hstack([b.num * (1 << (e - b.exp)) for b in r]) for r in rows]), e)


@dataclass(frozen=True, eq=False)
class ExactChannel:
    """One uncertain edge's channel matrices, exactly."""

    ewv: Dyadic  # E_i W V (Nd × r)
    dwd: Dyadic  # D W Dᵀ (Nd × Nd)
    vwv: Dyadic  # Vᵀ W V (r × r)


def exact_channels(top: Topology) -> list[ExactChannel]:
    """Every uncertain edge's channel (E_i W̄ V, D W̄ Dᵀ, Vᵀ W̄ V), as the issuer forms it."""
    ed = uncertain_edges(top)
    n, d = top.nd, top.dim
    out = []
    for e in range(ed.m):
        i, j = int(ed.dst[e]) * d, int(ed.src[e]) * d
        w = Dyadic.of(ed.channel_w[e])  # W̄_e, as the issuer's (robust.channel_bound)
        v = Dyadic.of(ed.basis(e))
        sel = np.zeros((n, d), dtype=object)
        sel[i : i + d] = np.eye(d, dtype=np.int64).astype(object)
        dm = sel.copy()
        dm[j : j + d] -= int(ed.s[e]) * np.eye(d, dtype=np.int64).astype(object)
        sel_d, dm_d = Dyadic(sel, 0), Dyadic(dm, 0)
        wv = w @ v
        out.append(ExactChannel(sel_d @ wv, dm_d @ w @ dm_d.T, v.T @ wv))
    return out


def prove_pd(m: Dyadic) -> PDProof:
    """Sylvester's criterion when affordable, else Rump's test on the correctly rounded
    floats (each entry within u·|x| + 2⁻¹⁰⁷⁴ of the exact one)."""
    if exact_affordable(m.num.shape[0], m.bits):
        return exact_pd(m)
    f = m.to_float()
    return verified_float_pd(f, np.abs(f) * 2.0**-53 + 2.0**-1074)


def psi_exact(lap: Dyadic, ch: list[ExactChannel], p: np.ndarray, tau, alpha: float, radius):
    """Ψ of the decay S-procedure, exactly (see :func:`ntc_design.certify.robust.lmi.decay_matrix`).

    Parameters
    ----------
    lap : Dyadic
        L_B exactly.
    ch : list
        The exact channels of the topology's edges.
    p : numpy.ndarray
        P.
    tau : sequence of float
        τ_e.
    alpha : float
        α.
    radius : sequence of float
        ρ_e per edge.

    Returns
    -------
    Dyadic
        On the edges of radius ρ_e > 0: an edge of radius 0 is not perturbed and has no
        channel (Ψ of a certificate that lists one is its principal submatrix).
    """
    pd_ = Dyadic.of(p)
    top = (
        pd_ @ lap + lap.T @ pd_ - pd_.scale(dyadic(2.0 * alpha))
        if alpha
        else pd_ @ lap + lap.T @ pd_
    )
    offs, diag = [], []
    for t, q, c in zip(tau, radius, ch, strict=True):
        if not q > 0:
            continue
        top = top - c.dwd.scale(dyadic(t) @ dyadic(q) @ dyadic(q))
        offs.append(pd_ @ c.ewv)
        diag.append(c.vwv.scale(dyadic(t)))
    if not offs:
        return top
    sizes = [o.num.shape[1] for o in offs]
    rows = [[top] + offs]
    for k, dk in enumerate(diag):
        row = [offs[k].T]
        for m, sz in enumerate(sizes):
            row.append(dk if m == k else Dyadic(np.zeros((sizes[k], sz), dtype=object), 0))
        rows.append(row)
    return block_matrix(rows)


def gamma_exact(lap, ch, target, r0, gamma, lam, y, radius) -> Dyadic:
    """Γ of the offset S-procedure, exactly (see
    :func:`ntc_design.certify.robust.lmi.offset_matrix`).

    Parameters
    ----------
    lap : Dyadic
        L_B exactly.
    ch : list
        The exact channels.
    target : numpy.ndarray
        1⊗θ.
    r0 : Dyadic
        u − L_B(1⊗θ) exactly (a column).
    gamma : float
        γ.
    lam : sequence of float
        λ_e.
    y : numpy.ndarray
        Finsler's multiplier.
    radius : sequence of float
        ρ_e per edge.

    Returns
    -------
    Dyadic

    Raises
    ------
    InputError
        Y is not Nd × (Nd + Σ rank W̄_e + 1).

    Notes
    -----
    Γ is built on ξ = (z, η_e of the edges of radius ρ_e > 0, 1): an edge of radius 0 is
    not perturbed and has no channel (the columns of Y for it are not used; Γ of a
    certificate that uses them is a principal submatrix of its own).
    """
    n = lap.num.shape[0]
    sizes = [c.vwv.num.shape[0] for c in ch]
    k = n + sum(sizes) + 1
    yd = Dyadic.of(y)
    if yd.num.shape != (n, k):
        raise InputError(
            f"expected {n}×{k}, got {yd.num.shape[0]}×{yd.num.shape[1]}", field="matrices.Y"
        )
    active = perturbed(np.asarray(radius, dtype=float), len(ch))
    yd = Dyadic(yd.num[:, active_columns(n, sizes, active)], yd.exp)
    ch = [ch[e] for e in active]
    lam = [lam[e] for e in active]
    radius = [radius[e] for e in active]
    sizes = [sizes[e] for e in active]
    c_ = Dyadic.of(np.asarray(target, dtype=float).reshape(n, 1))
    zz = Dyadic(np.zeros((n, n), dtype=object), 0)
    zc = Dyadic(np.zeros((n, 1), dtype=object), 0)
    cc = dyadic(gamma)
    eye = Dyadic(np.eye(n, dtype=np.int64).astype(object), 0)
    zz = zz - eye
    diag = []
    for le, rho, c in zip(lam, radius, ch, strict=True):
        q = c.dwd.scale(dyadic(rho) @ dyadic(rho) @ dyadic(le))
        qc = q @ c_
        zz = zz - q
        zc = zc - qc
        cc = cc - c_.T @ qc
        diag.append(c.vwv.scale(dyadic(le)))
    rows: list[list[Dyadic]] = []

    def zeros(a: int, b: int) -> Dyadic:
        return Dyadic(np.zeros((a, b), dtype=object), 0)

    rows.append([zz] + [zeros(n, s) for s in sizes] + [zc])
    for kk, dk in enumerate(diag):
        rows.append(
            [zeros(sizes[kk], n)]
            + [dk if m == kk else zeros(sizes[kk], s) for m, s in enumerate(sizes)]
            + [zeros(sizes[kk], 1)]
        )
    rows.append([zc.T] + [zeros(1, s) for s in sizes] + [cc])
    g = block_matrix(rows)
    a = block_matrix([[lap] + [c.ewv for c in ch] + [zeros(n, 1) - r0]])
    ay = a.T @ yd
    return g + ay + ay.T


# -- the kind ------------------------------------------------------------------------------


__all__ = [
    "ExactChannel",
    "block_matrix",
    "dyadic",
    "exact_channels",
    "gamma_exact",
    "prove_pd",
    "psi_exact",
]
