"""The Monte Carlo kernels for an NVIDIA GPU (numba-cuda): the same recursion, the same
normals and the same arithmetic as the CPU kernels of :mod:`.kernels`, one path's
numbers equal to rounding (the GPU contracts a·b + c into one fused multiply-add).

**Normals.** Each path's xoshiro256** stream (:mod:`.rng`) is advanced by the thread that
owns the path, with the 1024-layer ziggurat of :func:`.kernels.ziggurat_slow` word for
word: a path draws ``m_draw`` normals per step (the widest mode's 2·E: the additive ξ1 of
edges 0 … E−1, then the multiplicative ξ2), scaled by c_k·√h, whatever its mode. The
tables live in shared memory (a layer is picked at random: a divergent look-up, which
constant memory would serialise).

**The recursion** (period h, delay D >= 0 samples; D = 0 is explicit Euler–Maruyama)::

    x_{k+1} = x_k + c_k h (u − L_B y) + c_k √h Σ_e (g_e ξ1_e + K_e (y_j − y_i) ξ2_e),  y = x_{k−D}

The state of a path is a ring of its last states: x_k in slot ``k mod R``.

**Two layouts.** :func:`fused_kernel` (small networks): one thread per path, its ring in
local memory, every step of a launch fused (draw, drift, noise, update), L_B (CSR, and
3×3 block-CSR for d = 3, as the CPU kernel sums it) and the edges read from global
memory by every thread at once (a broadcast through the cache); R = D + 1 slots, the new
state overwriting x_{k−D} once the increment is complete. :func:`draw_kernel` and
:func:`step_kernel` (large networks): one thread per path draws the step's normals into
a (m_draw, paths) buffer, then one thread per (row of the state, path) does that row's
drift and noise (L_B in CSR, the edges into the row's agent listed per agent in
ascending order, so every sum is in the CPU kernel's order); R = D + 2 slots, so that
no thread writes a slot another one reads.

Device arrays are laid out (row, path) with the path fastest: the threads of a warp read
consecutive addresses. :func:`stats_kernel` and :func:`sum_kernel` reduce Σ‖x_i − θ‖², its
square and Σx over the paths in a fixed order (deterministic: no atomics), so only the
sums per save time leave the device; :func:`check_kernel` finds the first path (then
agent) that is not finite or beyond 1e150, as the CPU's check does.

Import this module only once the device is chosen (:mod:`.gpu` sets
``NUMBA_ENABLE_CUDASIM`` first when the simulator is asked for).
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numba import cuda as _cuda
from numba import float64, uint64

from .ziggurat import LAYERS

# the device dialect (threadIdx, local and shared arrays) is not Python as a type checker
# reads it: typed as Any
cuda: Any = _cuda
MASK = np.uint64(LAYERS - 1)
ZX_SIZE, ZR_SIZE = LAYERS + 1, LAYERS  # the ziggurat's tables in shared memory
TO_UNIT = 1.0 / 9007199254740992.0  # 2⁻⁵³, as kernels.TO_UNIT
HALF_UNIT = 0.5 * TO_UNIT
BAD_LIMIT = 1e150  # a state beyond this is an overflow (montecarlo._first_bad)
NO_FAILURE = np.iinfo(np.int64).max
U5, U7, U9, U11 = np.uint64(5), np.uint64(7), np.uint64(9), np.uint64(11)
U17, U19, U45, U57 = np.uint64(17), np.uint64(19), np.uint64(45), np.uint64(57)


# -- xoshiro256** and the ziggurat, per thread --------------------------------------


@cuda.jit(device=True)
def next_word(s):
    """xoshiro256** on the state ``s`` (4 uint64, updated): the next word."""
    s0, s1, s2, s3 = s[0], s[1], s[2], s[3]
    a5 = s1 * U5
    w = ((a5 << U7) | (a5 >> U57)) * U9
    t = s1 << U17
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s[0] = s0
    s[1] = s1
    s[2] = s2
    s[3] = (s3 << U45) | (s3 >> U19)
    return w


@cuda.jit(device=True)
def unit(w):
    """The top 53 bits of ``w`` as a double in [0, 1) (kernels._unit)."""
    return np.int64(w >> U11) * TO_UNIT


@cuda.jit(device=True)
def ziggurat_tail(i, u, s, zx, zr):
    """The draw after the fast test failed (kernels.ziggurat_slow and kernels._slow, in
    the same order): the base layer's tail or layer i's wedge, then new words."""
    while True:
        if i == 0:
            while True:
                w = next_word(s)
                a = math.log(unit(w) + HALF_UNIT) / zx[1]
                w = next_word(s)
                b = math.log(unit(w) + HALF_UNIT)
                if -2.0 * b >= a * a:
                    return (a - zx[1]) if u < 0 else (zx[1] - a)
        x = u * zx[i]
        f0 = math.exp(-0.5 * (zx[i] * zx[i] - x * x))
        f1 = math.exp(-0.5 * (zx[i + 1] * zx[i + 1] - x * x))
        w = next_word(s)
        if f1 + unit(w) * (f0 - f1) < 1.0:
            return x
        w = next_word(s)
        i = np.int64(w & MASK)
        u = 2.0 * unit(w) - 1.0
        if abs(u) < zr[i]:
            return u * zx[i]


@cuda.jit(device=True)
def normal(s, zx, zr):
    """The next standard normal of the stream ``s`` (kernels.draw_lanes, one lane)."""
    w = next_word(s)
    li = np.int64(w & MASK)
    uu = 2.0 * (np.int64(w >> U11) * TO_UNIT) - 1.0
    if abs(uu) < zr[li]:
        return uu * zx[li]
    return ziggurat_tail(li, uu, s, zx, zr)


@cuda.jit(device=True)
def load_tables(zx_g, zr_g, zx, zr):
    """Copy the ziggurat's tables into the block's shared memory (then a barrier)."""
    t = cuda.threadIdx.x
    for i in range(t, LAYERS + 1, cuda.blockDim.x):
        zx[i] = zx_g[i]
    for i in range(t, LAYERS, cuda.blockDim.x):
        zr[i] = zr_g[i]
    cuda.syncthreads()


# -- one thread per path (small networks) ---------------------------------------------


@cache
def fused_kernel(nd: int, slots: int, m_draw: int, d3: bool):
    """The fused kernel for N·d = ``nd``, ``slots`` = D + 1 states per path, ``m_draw``
    normals per step, and d = 3 (block-CSR drift) or not; compiled once per shape.

    Parameters
    ----------
    nd : int
        N·d.
    slots : int
        D + 1.
    m_draw : int
        Normals drawn per step (>= 2·E of every mode, >= 1).
    d3 : bool
        Whether d = 3: the drift by 3×3 blocks, as the CPU kernel sums it.

    Returns
    -------
    numba.cuda kernel
        ``kernel[blocks, threads](x, st, k_from, k_to, ch, cs, mode, ...)``: see
        :func:`.gpu.FusedRunner`.
    """
    ring = nd * slots
    zsize = max(m_draw, 1)

    @cuda.jit
    def kernel(
        x, st, k_from, k_to, ch, cs, mode, iptr, ind, val, bptr, bind, bval, u,
        e_off, e_cnt, src, dst, kmat, gvec, d, zx_g, zr_g,
    ):  # fmt: skip
        zx = cuda.shared.array(ZX_SIZE, float64)
        zr = cuda.shared.array(ZR_SIZE, float64)
        load_tables(zx_g, zr_g, zx, zr)
        q = cuda.grid(1)
        if q >= x.shape[1]:
            return
        xs = cuda.local.array(ring, float64)
        dx = cuda.local.array(nd, float64)
        z = cuda.local.array(zsize, float64)
        s = cuda.local.array(4, uint64)
        for r in range(ring):
            xs[r] = x[r, q]
        for c in range(4):
            s[c] = st[c, q]
        for k in range(k_from, k_to):
            m = mode[k]
            c1 = ch[k]
            c2 = cs[k]
            for e in range(m_draw):
                z[e] = c2 * normal(s, zx, zr)
            cur = (k % slots) * nd
            y = ((k + 1) % slots) * nd  # x_{k−D}, the slot x_{k+1} replaces
            for r in range(nd):
                dx[r] = c1 * u[m, r]
            if d3:
                for i in range(nd // 3):
                    r = 3 * i
                    for bb in range(bptr[m, i], bptr[m, i + 1]):
                        jo = y + 3 * bind[bb]
                        y0, y1, y2 = xs[jo], xs[jo + 1], xs[jo + 2]
                        for a in range(3):
                            dx[r + a] -= (
                                c1 * bval[bb, a, 0] * y0
                                + c1 * bval[bb, a, 1] * y1
                                + c1 * bval[bb, a, 2] * y2
                            )
            else:
                for r in range(nd):
                    for b in range(iptr[m, r], iptr[m, r + 1]):
                        dx[r] -= c1 * val[b] * xs[y + ind[b]]
            ne = e_cnt[m]
            for e in range(ne):
                g = e_off[m] + e
                io = dst[g] * d
                jo = src[g] * d
                z1 = z[e]
                z2 = z[ne + e]
                for a in range(d):
                    mb = 0.0
                    for c in range(d):
                        mb += kmat[g, a, c] * (xs[y + jo + c] - xs[y + io + c])
                    dx[io + a] += gvec[g, a] * z1 + mb * z2
            for r in range(nd):
                xs[y + r] = xs[cur + r] + dx[r]
        for r in range(ring):
            x[r, q] = xs[r]
        for c in range(4):
            st[c, q] = s[c]

    return kernel


# -- a thread per (row, path) (large networks) ----------------------------------------


@cache
def draw_kernel():
    """The kernel that draws one step's normals of every path into the first ``m_draw``
    rows of ``z`` (rows, paths), scaled by c_k·√h:
    ``kernel[blocks, threads](st, z, m_draw, c2, zx, zr)``.

    Returns
    -------
    numba.cuda kernel
    """

    @cuda.jit
    def kernel(st, z, m_draw, c2, zx_g, zr_g):
        zx = cuda.shared.array(ZX_SIZE, float64)
        zr = cuda.shared.array(ZR_SIZE, float64)
        load_tables(zx_g, zr_g, zx, zr)
        q = cuda.grid(1)
        if q >= z.shape[1]:
            return
        s = cuda.local.array(4, uint64)
        for c in range(4):
            s[c] = st[c, q]
        for e in range(m_draw):
            z[e, q] = c2 * normal(s, zx, zr)
        for c in range(4):
            st[c, q] = s[c]

    return kernel


@cache
def step_kernel(d3: bool):
    """One step for every (row r of the state, path q), q fastest: reads the ring's slots
    ``cur`` (x_k) and ``y`` (x_{k−D}), writes x_{k+1} into slot ``nw``.

    Parameters
    ----------
    d3 : bool
        Whether d = 3 (the drift by 3×3 blocks, as the CPU kernel sums it).

    Returns
    -------
    numba.cuda kernel
        ``kernel[blocks, threads](x, z, cur, y, nw, c1, m, ...)``: see
        :func:`.gpu.SparseRunner`.
    """

    @cuda.jit
    def kernel(
        x, z, cur, y, nw, c1, m, nd, iptr, ind, val, bptr, bind, bval, u,
        e_off, e_cnt, eptr, eids, src, kmat, gvec, d,
    ):  # fmt: skip
        t = cuda.grid(1)
        p = z.shape[1]
        if t >= nd * p:
            return
        r = t // p
        q = t - r * p
        cr, yr, wr = cur * nd, y * nd, nw * nd
        dx = c1 * u[m, r]
        if d3:
            i, a = r // 3, r % 3
            for bb in range(bptr[m, i], bptr[m, i + 1]):
                jo = yr + 3 * bind[bb]
                dx -= (
                    c1 * bval[bb, a, 0] * x[jo, q]
                    + c1 * bval[bb, a, 1] * x[jo + 1, q]
                    + c1 * bval[bb, a, 2] * x[jo + 2, q]
                )
        else:
            for b in range(iptr[m, r], iptr[m, r + 1]):
                dx -= c1 * val[b] * x[yr + ind[b], q]
        i, a = r // d, r % d
        ne = e_cnt[m]
        io = yr + i * d
        for tt in range(eptr[m, i], eptr[m, i + 1]):
            e = eids[tt]  # the edge's index within its mode (ascending per agent)
            g = e_off[m] + e
            jo = yr + src[g] * d
            mb = 0.0
            for c in range(d):
                mb += kmat[g, a, c] * (x[jo + c, q] - x[io + c, q])
            dx += gvec[g, a] * z[e, q] + mb * z[ne + e, q]
        x[wr + r, q] = x[cr + r, q] + dx

    return kernel


# -- checks and statistics --------------------------------------------------------------


@cache
def check_kernel():
    """The first non-finite or overflowing entry of the rows ``row0 … row0 + nd − 1``:
    ``bad[0]`` = min over them of path·nd + row (atomic min: the result is the same
    whatever the order). ``kernel[blocks, threads](x, row0, nd, bad)``.

    Returns
    -------
    numba.cuda kernel
    """

    @cuda.jit
    def kernel(x, row0, nd, bad):
        t = cuda.grid(1)
        p = x.shape[1]
        if t >= nd * p:
            return
        r = t // p
        q = t - r * p
        v = x[row0 + r, q]
        if not abs(v) <= BAD_LIMIT:  # NaN compares false
            cuda.atomic.min(bad, 0, np.int64(q) * nd + r)

    return kernel


@cache
def stats_kernel():
    """Per agent i and group of ``ppt`` paths: Σ‖x_i − θ‖², the sum of squared deviations of
    ‖x_i − θ‖² from the group's mean, that mean, and Σx_i over the group, into
    ``part[group]`` (3N + Nd numbers: the N of each, then the Nd); the first ``n_store``
    paths copied into ``stored[save]``. The mean is the first path's value plus the mean
    offset from it, the deviations a second pass (as the CPU's
    :func:`.montecarlo.centred_spread`): equal paths give a spread of exactly 0.
    ``kernel[(⌈N/threads⌉, groups), threads](x, row0, theta, n, d, ppt, part, stored,
    n_store, save)``.

    Returns
    -------
    numba.cuda kernel
    """

    @cuda.jit(device=True)
    def err2(x, r0, theta, d, q):
        e2 = 0.0
        for c in range(d):
            v = x[r0 + c, q] - theta[c]
            e2 += v * v
        return e2

    @cuda.jit
    def kernel(x, row0, theta, n, d, ppt, part, stored, n_store, save):
        i = cuda.blockIdx.x * cuda.blockDim.x + cuda.threadIdx.x
        gy = cuda.blockIdx.y
        if i >= n:
            return
        p = x.shape[1]
        q0 = gy * ppt
        q1 = min(q0 + ppt, p)
        r0 = row0 + i * d
        base = err2(x, r0, theta, d, q0)
        s1 = 0.0
        off = 0.0
        for q in range(q0, q1):
            e2 = err2(x, r0, theta, d, q)
            s1 += e2
            off += e2 - base
        mean = base + off / (q1 - q0)
        m2 = 0.0
        for q in range(q0, q1):
            dev = err2(x, r0, theta, d, q) - mean
            m2 += dev * dev
        part[gy, i] = s1
        part[gy, n + i] = m2
        part[gy, 2 * n + i] = mean
        for c in range(d):
            sx = 0.0
            for q in range(q0, q1):
                sx += x[r0 + c, q]
            part[gy, 3 * n + i * d + c] = sx
        for q in range(q0, min(q1, n_store)):
            for c in range(d):
                stored[save, q, i * d + c] = x[r0 + c, q]

    return kernel


@cache
def sum_kernel():
    """``acc[save]`` from the groups' ``part`` rows in group order (one thread per column
    j): the sums added; for agent i (j = N + i) the groups' spreads and means merged by
    Chan's update (:func:`.montecarlo.merge_spread`), the group of ``ppt`` paths g holding
    min(ppt, p − g·ppt) of the chunk's ``p``. ``kernel[blocks, threads](part, groups, acc,
    save, n, ppt, p)``.

    Returns
    -------
    numba.cuda kernel
    """

    @cuda.jit
    def kernel(part, groups, acc, save, n, ppt, p):
        j = cuda.grid(1)
        if j >= part.shape[1] or (2 * n <= j < 3 * n):
            return
        if n <= j < 2 * n:
            cnt = 0.0
            mean = 0.0
            m2 = 0.0
            for g in range(groups):
                nb = float(min(ppt, p - g * ppt))
                tot = cnt + nb
                delta = part[g, j + n] - mean
                mean = mean + delta * (nb / tot)
                m2 = m2 + part[g, j] + delta * delta * (cnt * nb / tot)
                cnt = tot
            acc[save, j] = m2
            acc[save, j + n] = mean
            return
        s = 0.0
        for g in range(groups):
            s += part[g, j]
        acc[save, j] += s

    return kernel


__all__ = [
    "BAD_LIMIT",
    "NO_FAILURE",
    "check_kernel",
    "draw_kernel",
    "fused_kernel",
    "next_word",
    "normal",
    "stats_kernel",
    "step_kernel",
    "sum_kernel",
    "ziggurat_tail",
]
