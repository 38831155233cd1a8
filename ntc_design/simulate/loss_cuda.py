"""The lossy-link step (:mod:`.loss_kernels`) on an NVIDIA GPU (numba-cuda): one thread per
path, the same streams (each step's ``m_draw`` normals by the ziggurat of
:mod:`.cuda_kernels`, then E words as uniforms, one per edge in the topology's order) and
the same arithmetic in the same order as :func:`.loss_kernels.loss_steps`, so a path's
numbers equal the CPU's to rounding (the GPU contracts a·b + c into a fused multiply-add).

The state ring, the held measurements and the draws live in global memory, laid out
(path, row) as the CPU's: a first kernel, not tuned for speed (the lossless GPU kernels
of :mod:`.gpu_run` are). Import this module only once the device is chosen
(:func:`.gpu.load_cuda`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import cuda as _cuda

from .cuda_kernels import next_word, normal, unit
from .ziggurat import ZIG_R, ZIG_X

cuda: Any = _cuda
THREADS = 64  # threads per block


@cuda.jit
def _loss_kernel(
    x, held, states, z, uni, dx, m_draw, k_from, k_to, ch, cs, rh, gdiag, u, src, dst, signed,
    absw, kmat, gvec, q, policy, delay, k_base, zx, zr,
):  # fmt: skip
    t = cuda.grid(1)
    if t >= x.shape[0]:
        return
    ring = delay + 1
    nd = x.shape[1] // ring
    ne = src.shape[0]
    d = gvec.shape[1]
    n = nd // d
    s = states[t]
    for k in range(k_from, k_to):
        c1 = ch[k]
        c2 = cs[k]
        r2 = rh[k]
        cur = ((k_base + k) % ring) * nd
        nxt = ((k_base + k + 1) % ring) * nd
        for e in range(m_draw):
            z[t, e] = normal(s, zx, zr)
        for e in range(ne):
            uni[t, e] = unit(next_word(s))
        for i in range(n):
            for a in range(d):
                r = i * d + a
                acc = c1 * u[r]
                for b in range(d):
                    gab = c1 * gdiag[i, a, b]
                    if gab != 0.0:
                        acc -= gab * x[t, nxt + i * d + b]
                dx[t, r] = acc
        for e in range(ne):
            io = dst[e] * d
            jo = src[e] * d
            qe = q[e]
            hit = uni[t, e] < qe
            for a in range(d):
                av = 0.0
                for c in range(d):
                    av += signed[e, a, c] * x[t, nxt + jo + c] - absw[e, a, c] * x[t, nxt + io + c]
                mb = 0.0
                for c in range(d):
                    mb += kmat[e, a, c] * (x[t, nxt + jo + c] - x[t, nxt + io + c])
                nz = gvec[e, a] * z[t, e] + mb * z[t, ne + e]
                if policy == 2:
                    if hit:
                        held[t, e * d + a] = av + r2 * nz
                    dx[t, io + a] += c1 * held[t, e * d + a]
                elif hit:
                    term = c1 * av + c2 * nz
                    if policy == 1:
                        dx[t, io + a] += term / qe
                    else:
                        dx[t, io + a] += term
        for r in range(nd):
            x[t, nxt + r] = x[t, cur + r] + dx[t, r]


def gpu_loss_steps(
    x: np.ndarray,
    held: np.ndarray,
    states: np.ndarray,
    m_draw: int,
    k_from: int,
    k_to: int,
    ch: np.ndarray,
    cs: np.ndarray,
    rh: np.ndarray,
    arrays: tuple,
    policy: int,
    delay: int,
    k_base: int,
) -> None:
    """:func:`.loss_kernels.loss_steps` (drawing from ``states``) on the GPU: ``x``,
    ``held`` and ``states`` are updated in place.

    Parameters
    ----------
    x : numpy.ndarray
        (p, (D+1)·Nd) rings.
    held : numpy.ndarray
        (p, E·d) held measurements.
    states : numpy.ndarray
        (p, 4) uint64 xoshiro256** states.
    m_draw : int
        Normals per step (2·E).
    k_from, k_to : int
        The steps.
    ch, cs, rh : numpy.ndarray
        c_k h, c_k √h and 1/√h per step.
    arrays : tuple
        (gdiag, u, src, dst, signed, absw, kmat, gvec, q) of
        :meth:`.loss_mc.LossMonteCarloSpec.kernel_arrays`.
    policy : int
        0 skip, 1 rescale, 2 hold.
    delay, k_base : int
        D and the steps taken before ``ch[0]``.
    """
    p = x.shape[0]
    if p == 0 or k_to <= k_from:
        return
    ne = arrays[2].shape[0]
    nd = x.shape[1] // (delay + 1)
    dev = [cuda.to_device(np.ascontiguousarray(a)) for a in (x, held, states)]
    scratch = [
        cuda.device_array((p, max(m_draw, 2 * ne, 1))),
        cuda.device_array((p, max(ne, 1))),
        cuda.device_array((p, nd)),
    ]
    consts = [cuda.to_device(np.ascontiguousarray(a)) for a in (ch, cs, rh, *arrays)]
    tables = (cuda.to_device(ZIG_X), cuda.to_device(ZIG_R))
    blocks = -(-p // THREADS)
    _loss_kernel[blocks, THREADS](
        *dev, *scratch, m_draw, k_from, k_to, *consts, policy, delay, k_base, *tables
    )
    x[...] = dev[0].copy_to_host()
    held[...] = dev[1].copy_to_host()
    states[...] = dev[2].copy_to_host()


__all__ = ["THREADS", "gpu_loss_steps"]
