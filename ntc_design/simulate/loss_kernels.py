"""Compiled steps of the digital protocol on lossy links (numba): the sampled, delayed
recursion of :mod:`.loss` on each path, in x coordinates.

The arrivals come from the path's own xoshiro256** stream: at each step, after the
step's ``m_draw`` normals (2·E: ξ_{k,e,1} for every edge, then ξ_{k,e,2}), E more words,
one per edge in the topology's edge order; edge e's message arrives when the word's top
53 bits as a double in [0, 1) (U = (w >> 11)·2⁻⁵³) are below 1 − p_e. The normals are
the same numbers :func:`.kernels.fill_normals` gives (the same generator and order), so a
lossless edge (p_e = 0) still consumes its word and the streams stay aligned.

A step (x_D = the state D samples back, τ = c_k h, s = c_k √h, χ_e the arrival):

    skip:     x_{k+1} = x_k + τ (u − L_δ x_D) + Σ_e χ_e [τ a_e + s (g_e ξ1 + K_e Δ_e ξ2)]
    rescale:  the same with χ_e / q_e
    hold:     y_e ← a_e + (g_e ξ1 + K_e Δ_e ξ2)/√h when χ_e, then x_{k+1} = x_k + τ (u −
              L_δ x_D) + τ Σ_e y_e

with a_e = A_ij x_j − |A_ij| x_i and Δ_e = x_j − x_i at x_D, and L_δ block-diagonal (the
informed agents' grounding, never lost).
"""

from __future__ import annotations

import numpy as np

from ..numerics.linalg import numba_cache_dir

numba_cache_dir()  # before Numba reads its configuration
import numba  # noqa: E402

from .kernels import TO_UNIT, draw_lanes  # noqa: E402

#: The policies by code in the kernel.
POLICY_CODES = {"skip": 0, "rescale": 1, "hold": 2}


@numba.njit(nogil=True)
def _lanes(s0, s1, s2, s3, zt, ut, wl, m, ne):
    """Each lane's next ``m`` normals into ``zt[:m]`` (as :func:`.kernels.fill_normals`
    draws them), then its next ``ne`` words as uniforms in [0, 1) into ``ut``."""
    draw_lanes(s0, s1, s2, s3, zt, wl, 1.0, m)
    w = s0.size
    for e in range(ne):
        for q in range(w):
            a0, a1, a2, a3 = s0[q], s1[q], s2[q], s3[q]
            a5 = a1 * np.uint64(5)
            wd = ((a5 << np.uint64(7)) | (a5 >> np.uint64(57))) * np.uint64(9)
            t = a1 << np.uint64(17)
            a2 ^= a0
            a3 ^= a1
            a1 ^= a2
            a0 ^= a3
            a2 ^= t
            s0[q], s1[q], s2[q] = a0, a1, a2
            s3[q] = (a3 << np.uint64(45)) | (a3 >> np.uint64(19))
            ut[e, q] = np.int64(wd >> np.uint64(11)) * TO_UNIT


@numba.njit(cache=True, nogil=True)
def draw_arrivals(states, normals, uniforms):
    """Path q's draws in its stream order: ``normals[k, q]`` (m per step), then
    ``uniforms[k, q]`` (E per step); what :func:`loss_steps` draws itself.

    Parameters
    ----------
    states : numpy.ndarray
        (p, 4) uint64, updated in place.
    normals : numpy.ndarray
        (K, p, m) float64, filled.
    uniforms : numpy.ndarray
        (K, p, E) float64, filled.
    """
    kk, p, m = normals.shape
    ne = uniforms.shape[2]
    for q0 in range(0, p, 64):
        w = min(64, p - q0)
        st = np.empty((4, w), dtype=np.uint64)
        for q in range(w):
            for c in range(4):
                st[c, q] = states[q0 + q, c]
        zt = np.empty((m, w))
        ut = np.empty((ne, w))
        wl = np.empty(w, dtype=np.uint64)
        for k in range(kk):
            _lanes(st[0], st[1], st[2], st[3], zt, ut, wl, m, ne)
            for q in range(w):
                for e in range(m):
                    normals[k, q0 + q, e] = zt[e, q]
                for e in range(ne):
                    uniforms[k, q0 + q, e] = ut[e, q]
        for q in range(w):
            for c in range(4):
                states[q0 + q, c] = st[c, q]


@numba.njit(cache=True, nogil=True)
def loss_steps(
    x, held, states, xi, uni, m_draw, k_from, k_to, ch, cs, rh, gdiag, u, src, dst, signed,
    absw, kmat, gvec, q, policy, tile, delay, k_base,
):  # fmt: skip
    """Advance every path (a row of ``x``: the ring of D + 1 states, as in
    :func:`.kernels.em_steps`) over steps ``k_from .. k_to − 1`` on lossy links.

    The draws come from ``states`` (p, 4) when it has rows, else from ``xi`` (K, p, ≥ 2E)
    and ``uni`` (K, p, E). ``held`` (p, E·d) are the held measurements (hold only). ``ch``,
    ``cs``, ``rh``: c_k h, c_k √h and 1/√h per step; ``gdiag`` (N, d, d) the diagonal
    blocks of L_δ; ``signed``, ``absw`` A_ij and |A_ij|; ``kmat`` K_e; ``gvec`` g_e;
    ``q`` 1 − p_e; ``policy`` 0 skip, 1 rescale, 2 hold.

    Parameters
    ----------
    x : numpy.ndarray
        (p, (D+1)·Nd), updated in place.
    held : numpy.ndarray
        (p, E·d), updated in place (hold).
    states : numpy.ndarray
        (p, 4) uint64 or (0, 4).
    xi, uni : numpy.ndarray
        The draws when ``states`` is empty.
    m_draw : int
        Normals per step (>= 2·E).
    k_from, k_to : int
        The steps.
    ch, cs, rh : numpy.ndarray
        Per step.
    gdiag, u, src, dst, signed, absw, kmat, gvec, q : numpy.ndarray
        The mode.
    policy : int
        The policy's code.
    tile : int
        Paths together.
    delay, k_base : int
        D and the steps taken before ``ch[0]``.
    """
    p, width = x.shape
    ring = delay + 1
    nd = width // ring
    ne = src.size
    d = gvec.shape[1]
    n = nd // d
    drawing = states.shape[0] > 0
    for q0 in range(0, p, tile):
        w = min(tile, p - q0)
        xt = np.empty((width, w))
        for qq in range(w):
            for r in range(width):
                xt[r, qq] = x[q0 + qq, r]
        yt = np.empty((ne * d, w))
        if policy == 2:
            for qq in range(w):
                for r in range(ne * d):
                    yt[r, qq] = held[q0 + qq, r]
        dx = np.empty((nd, w))
        zt = np.empty((max(m_draw, 2 * ne), w))
        ut = np.empty((ne, w))
        df = np.empty((d, w))
        av = np.empty((d, w))
        mb = np.empty(w)
        st = np.empty((4, w if drawing else 0), dtype=np.uint64)
        for qq in range(st.shape[1]):
            for c in range(4):
                st[c, qq] = states[q0 + qq, c]
        wl = np.empty(w, dtype=np.uint64)
        for k in range(k_from, k_to):
            c1, c2, r2 = ch[k], cs[k], rh[k]
            cur = ((k_base + k) % ring) * nd
            nxt = ((k_base + k + 1) % ring) * nd
            if drawing:
                _lanes(st[0], st[1], st[2], st[3], zt, ut, wl, m_draw, ne)
            else:
                for qq in range(w):
                    for e in range(2 * ne):
                        zt[e, qq] = xi[k, q0 + qq, e]
                    for e in range(ne):
                        ut[e, qq] = uni[k, q0 + qq, e]
            for i in range(n):
                for a in range(d):
                    r = i * d + a
                    ur = c1 * u[r]
                    for qq in range(w):
                        dx[r, qq] = ur
                    for b in range(d):
                        gab = c1 * gdiag[i, a, b]
                        if gab != 0.0:
                            for qq in range(w):
                                dx[r, qq] -= gab * xt[nxt + i * d + b, qq]
            for e in range(ne):
                io = dst[e] * d
                jo = src[e] * d
                qe = q[e]
                # lane loops innermost and branch-free (selects), coefficients hoisted:
                # the sums keep the order of the recursion written out (bit for bit)
                for c in range(d):
                    for qq in range(w):
                        df[c, qq] = xt[nxt + jo + c, qq] - xt[nxt + io + c, qq]
                for a in range(d):
                    for qq in range(w):
                        av[a, qq] = 0.0
                        mb[qq] = 0.0
                    for c in range(d):
                        sa, aa, ka = signed[e, a, c], absw[e, a, c], kmat[e, a, c]
                        for qq in range(w):
                            av[a, qq] += sa * xt[nxt + jo + c, qq] - aa * xt[nxt + io + c, qq]
                            mb[qq] += ka * df[c, qq]
                    ga = gvec[e, a]
                    if policy == 2:
                        ya = e * d + a
                        for qq in range(w):
                            nz = ga * zt[e, qq] + mb[qq] * zt[ne + e, qq]
                            fresh = av[a, qq] + r2 * nz
                            yt[ya, qq] = fresh if ut[e, qq] < qe else yt[ya, qq]
                            dx[io + a, qq] += c1 * yt[ya, qq]
                    elif policy == 1:
                        for qq in range(w):
                            nz = ga * zt[e, qq] + mb[qq] * zt[ne + e, qq]
                            term = (c1 * av[a, qq] + c2 * nz) / qe
                            dx[io + a, qq] += term if ut[e, qq] < qe else 0.0
                    else:
                        for qq in range(w):
                            nz = ga * zt[e, qq] + mb[qq] * zt[ne + e, qq]
                            term = c1 * av[a, qq] + c2 * nz
                            dx[io + a, qq] += term if ut[e, qq] < qe else 0.0
            for r in range(nd):
                for qq in range(w):
                    xt[nxt + r, qq] = xt[cur + r, qq] + dx[r, qq]
        for qq in range(w):
            for r in range(width):
                x[q0 + qq, r] = xt[r, qq]
        if policy == 2:
            for qq in range(w):
                for r in range(ne * d):
                    held[q0 + qq, r] = yt[r, qq]
        for qq in range(st.shape[1]):
            for c in range(4):
                states[q0 + qq, c] = st[c, qq]


__all__ = ["POLICY_CODES", "TO_UNIT", "draw_arrivals", "loss_steps"]
