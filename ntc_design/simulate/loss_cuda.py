"""The lossy-link step (:mod:`.loss_kernels`) on an NVIDIA GPU (numba-cuda): one thread per
path, the same streams (each step's ``m_draw`` normals by the ziggurat of
:mod:`.cuda_kernels`, then E words as uniforms, one per edge in the topology's order) and
the same arithmetic in the same order as :func:`.loss_kernels.loss_steps`, so a path's
numbers equal the CPU's to rounding (the GPU contracts a·b + c into a fused multiply-add).

Device arrays are laid out (row, path), the path fastest, so that a warp's threads read
consecutive addresses; the ziggurat's tables sit in shared memory and each thread keeps
its stream's state in registers. :func:`run_loss_blocks` runs every block of a run in one
launch per stretch between the CPU's save and check points (the paths of all blocks side
by side, each block's streams its own), and brings the states back only there. Import
this module only once the device is chosen (:func:`.gpu.load_cuda`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import cuda as _cuda
from numba import float64, uint64

from .cuda_kernels import ZR_SIZE, ZX_SIZE, load_tables, next_word, normal, unit
from .loss_kernels import POLICY_CODES
from .modes import BATCH, XI_BYTES
from .montecarlo import BlockStats, PartialStats
from .rng import path_states
from .ziggurat import ZIG_R, ZIG_X

cuda: Any = _cuda
THREADS = 128  # threads per block


@cuda.jit
def _loss_kernel(
    x, held, states, z, uni, dx, m_draw, k_from, k_to, ch, cs, rh, gdiag, u, src, dst, signed,
    absw, kmat, gvec, q, policy, delay, k_base, zx_g, zr_g,
):  # fmt: skip
    zx = cuda.shared.array(ZX_SIZE, float64)
    zr = cuda.shared.array(ZR_SIZE, float64)
    load_tables(zx_g, zr_g, zx, zr)
    t = cuda.grid(1)
    if t >= x.shape[1]:
        return
    s = cuda.local.array(4, uint64)
    for c in range(4):
        s[c] = states[t, c]
    ring = delay + 1
    nd = x.shape[0] // ring
    ne = src.shape[0]
    d = gvec.shape[1]
    n = nd // d
    for k in range(k_from, k_to):
        c1 = ch[k]
        c2 = cs[k]
        r2 = rh[k]
        cur = ((k_base + k) % ring) * nd
        nxt = ((k_base + k + 1) % ring) * nd
        for e in range(m_draw):
            z[e, t] = normal(s, zx, zr)
        for e in range(ne):
            uni[e, t] = unit(next_word(s))
        for i in range(n):
            for a in range(d):
                r = i * d + a
                acc = c1 * u[r]
                for b in range(d):
                    gab = c1 * gdiag[i, a, b]
                    if gab != 0.0:
                        acc -= gab * x[nxt + i * d + b, t]
                dx[r, t] = acc
        for e in range(ne):
            io = dst[e] * d
            jo = src[e] * d
            qe = q[e]
            hit = uni[e, t] < qe
            for a in range(d):
                av = 0.0
                for c in range(d):
                    av += signed[e, a, c] * x[nxt + jo + c, t] - absw[e, a, c] * x[nxt + io + c, t]
                mb = 0.0
                for c in range(d):
                    mb += kmat[e, a, c] * (x[nxt + jo + c, t] - x[nxt + io + c, t])
                nz = gvec[e, a] * z[e, t] + mb * z[ne + e, t]
                if policy == 2:
                    if hit:
                        held[e * d + a, t] = av + r2 * nz
                    dx[io + a, t] += c1 * held[e * d + a, t]
                elif hit:
                    term = c1 * av + c2 * nz
                    if policy == 1:
                        dx[io + a, t] += term / qe
                    else:
                        dx[io + a, t] += term
        for r in range(nd):
            x[nxt + r, t] = x[cur + r, t] + dx[r, t]
    for c in range(4):
        states[t, c] = s[c]


class LossDevice:
    """The lossy recursion's paths on the device: their rings, held measurements and
    streams, (row, path) laid out, and the constant arrays; :meth:`advance` runs steps,
    :meth:`rings` brings the states back.

    Parameters
    ----------
    xt : numpy.ndarray
        ((D+1)·Nd, p) rings, a path per column.
    heldt : numpy.ndarray
        (E·d, p) held measurements.
    states : numpy.ndarray
        (p, 4) uint64 xoshiro256** states.
    m_draw : int
        Normals per step (2·E).
    ch, cs, rh : numpy.ndarray
        c_k h, c_k √h and 1/√h per step (indexed by the step k of :meth:`advance`).
    arrays : tuple
        (gdiag, u, src, dst, signed, absw, kmat, gvec, q) of
        :meth:`.loss_mc.LossMonteCarloSpec.kernel_arrays`.
    policy : int
        0 skip, 1 rescale, 2 hold.
    delay, k_base : int
        D and the steps taken before ``ch[0]``.
    """

    def __init__(self, xt, heldt, states, m_draw, ch, cs, rh, arrays, policy, delay, k_base):
        p = xt.shape[1]
        ne = arrays[2].shape[0]
        nd = xt.shape[0] // (delay + 1)
        self.p, self.m_draw, self.policy, self.delay, self.k_base = p, m_draw, policy, delay, k_base
        self.x = cuda.to_device(np.ascontiguousarray(xt))
        self.held = cuda.to_device(np.ascontiguousarray(heldt))
        self.states = cuda.to_device(np.ascontiguousarray(states))
        self.scratch = (
            cuda.device_array((max(m_draw, 2 * ne, 1), max(p, 1))),
            cuda.device_array((max(ne, 1), max(p, 1))),
            cuda.device_array((nd, max(p, 1))),
        )
        self.consts = [cuda.to_device(np.ascontiguousarray(a)) for a in (ch, cs, rh, *arrays)]
        self.tables = (cuda.to_device(ZIG_X), cuda.to_device(ZIG_R))

    def advance(self, k_from: int, k_to: int) -> None:
        """Steps ``k_from .. k_to − 1`` of every path.

        Parameters
        ----------
        k_from, k_to : int
            The steps.
        """
        if self.p == 0 or k_to <= k_from:
            return
        blocks = -(-self.p // THREADS)
        _loss_kernel[blocks, THREADS](
            self.x, self.held, self.states, *self.scratch, self.m_draw, k_from, k_to,
            *self.consts, self.policy, self.delay, self.k_base, *self.tables,
        )  # fmt: skip

    def rings(self) -> np.ndarray:
        """The rings, ((D+1)·Nd, p), on the host.

        Returns
        -------
        numpy.ndarray
        """
        return self.x.copy_to_host()

    def copy_back(self, x: np.ndarray, held: np.ndarray, states: np.ndarray) -> None:
        """Rings, held measurements and streams into the host arrays (in place).

        Parameters
        ----------
        x, held, states : numpy.ndarray
            As given to the constructor.
        """
        x[...] = self.rings().T
        held[...] = self.held.copy_to_host().T
        states[...] = self.states.copy_to_host()


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
    if x.shape[0] == 0 or k_to <= k_from:
        return
    dev = LossDevice(x.T, held.T, states, m_draw, ch, cs, rh, arrays, policy, delay, k_base)
    dev.advance(k_from, k_to)
    dev.copy_back(x, held, states)


def run_loss_blocks(spec, blocks: Sequence[int], progress=None) -> list[PartialStats]:
    """The blocks of a lossy run on the GPU, side by side: each block's paths from its own
    streams (:func:`.rng.path_states`), recorded at the save times and checked where the
    CPU's :meth:`.loss_mc.LossMonteCarloSpec.run_block` checks (the end of each batch of
    its size), so a divergence is reported at the CPU's time, path and agent.

    Parameters
    ----------
    spec : LossMonteCarloSpec
        The run (``rng: xoshiro``).
    blocks : sequence of int
        Block indices.
    progress : callable(int), optional
        Called with path-steps done.

    Returns
    -------
    list of PartialStats
        One per block, in order.
    """
    grid, bp = spec.grid, spec.block_paths
    nd_, ne, ring = spec.x_init.size, spec.system.n_edges, spec.delay + 1
    k_total = grid.n_steps
    save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
    parts, checks, lo = [], [], 0
    for b in blocks:
        p0 = b * bp
        p = min(bp, spec.paths - p0)
        batch = int(np.clip(XI_BYTES // (8 * p * max(3 * ne, 1)), 1, BATCH))
        parts.append((BlockStats(spec, b, p0, p), lo, lo + p))
        checks.append({min(k0 + batch, k_total) for k0 in range(0, k_total, batch)})
        lo += p
    # the device's layout from the start: a path per column (no transpose of the whole)
    xt = np.repeat(np.tile(spec.x_init, ring)[:, None], lo, axis=1)
    heldt = np.repeat(spec.initial_held(1)[0][:, None], lo, axis=1)
    states = np.concatenate([path_states(spec.seed, st.b, st.p) for st, _, _ in parts])
    live = [True] * len(parts)

    def now(xs: np.ndarray, k: int, a: int, z: int) -> np.ndarray:
        slot = (k % ring) * nd_  # one block's states, (paths, Nd) as the CPU's
        return np.ascontiguousarray(xs[slot : slot + nd_, a:z].T)

    if 0 in save_at:
        for j, (st, a, z) in enumerate(parts):
            live[j] = st.record(now(xt, 0, a, z), save_at[0])
    root = np.sqrt(grid.noise_h())  # √h, or s/√h on the partial step
    dev = LossDevice(
        xt, heldt, states, 2 * ne, spec.steps.ch, spec.steps.cs, root / grid.h,
        spec.kernel_arrays(), POLICY_CODES[spec.policy], spec.delay, 0,
    )  # fmt: skip
    cuts = sorted({*save_at, *set().union(*checks), k_total} - {0})
    k = 0
    for stop in cuts:
        if not any(live):
            break
        dev.advance(k, stop)
        if progress is not None:
            progress((stop - k) * lo)
        k = stop
        xs = dev.rings()
        for j, (st, a, z) in enumerate(parts):
            if live[j] and k in save_at:
                live[j] = st.record(now(xs, k, a, z), save_at[k])
            if live[j] and k in checks[j]:
                live[j] = st.check(now(xs, k, a, z), k)
    return [st.result() for st, _, _ in parts]


__all__ = ["THREADS", "LossDevice", "gpu_loss_steps", "run_loss_blocks"]
