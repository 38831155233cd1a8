"""Monte Carlo of the digital protocol on lossy links: a spec that
:func:`.montecarlo.run` runs block by block (its own ``run_block``), with the compiled
kernel of :mod:`.loss_kernels` (the arrivals from each path's own stream) and the same
seeding, statistics and stored paths as the lossless blocks.

With ``rng: numpy`` block b's generator (PCG64 from the b-th child of the seed) fills, per
batch of steps, the normals (K, p, 2E) and then the uniforms (K, p, E).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .grid import TimeGrid
from .loss import edge_terms
from .modes import BATCH, XI_BYTES
from .montecarlo import (
    BlockStats,
    MonteCarloSpec,
    PartialStats,
    PathBlocks,
)
from .rng import path_states
from .system import ModeSystem

#: Device memory for one chunk of lossy paths on the GPU (their rings, held measurements
#: and draws; the host keeps a copy of the rings at each save and check point).
GPU_CHUNK_BYTES = 512 * 2**20


@dataclass(frozen=True, eq=False)
class LossMonteCarloSpec(PathBlocks):
    """What :func:`.montecarlo.run` needs for lossy links; ``run_block`` integrates one
    block of paths.

    Attributes
    ----------
    system : ModeSystem
        The mode (one topology, a linear f).
    grid : TimeGrid
        The sampling grid.
    gain : callable
        Vectorised c(t).
    theta : numpy.ndarray
        θ.
    x_init : numpy.ndarray
        x(0).
    n_agents, dim : int
        N and d.
    paths, seed : int
        Paths and the seed.
    loss : numpy.ndarray
        (E,) p_e.
    policy : str
        ``skip``, ``rescale`` or ``hold``.
    delay : int
        D.
    block_size, store_paths : int
        Paths per block (at most) and paths stored.
    rng : str
        ``xoshiro`` (drawn in the kernel) or ``numpy``.
    device : str
        ``cpu`` (:mod:`.loss_kernels`) or ``gpu`` (:mod:`.loss_cuda`, the same streams).
    """

    system: ModeSystem
    grid: TimeGrid
    gain: Callable[[np.ndarray], np.ndarray]
    theta: np.ndarray
    x_init: np.ndarray
    n_agents: int
    dim: int
    paths: int
    seed: int
    loss: np.ndarray
    policy: str
    delay: int = 0
    block_size: int = 500
    store_paths: int = 10
    rng: str = "xoshiro"
    device: str = "cpu"

    def kernel_arrays(self) -> tuple:
        """(gdiag, u, src, dst, signed, absw, kmat, gvec, q): the arrays
        :func:`.loss_kernels.loss_steps` takes after ``rh``.

        Returns
        -------
        tuple
        """
        s, d = self.system, self.dim
        et = edge_terms(s, self.theta)
        gd = np.stack(
            [et.grounding[i * d : (i + 1) * d, i * d : (i + 1) * d] for i in range(s.n_agents)]
        )
        return (
            np.ascontiguousarray(gd),
            np.ascontiguousarray(s.u, dtype=float),
            s.src.astype(np.int64),
            s.dst.astype(np.int64),
            np.ascontiguousarray(et.signed),
            np.ascontiguousarray(et.absw),
            np.ascontiguousarray(s.k_blocks),
            np.ascontiguousarray(s.g_edge.reshape(s.n_edges, d)),
            1.0 - np.asarray(self.loss, dtype=float),
        )

    def initial_held(self, p: int) -> np.ndarray:
        """The held measurements before the first arrival: the noiseless
        A_ij x_j(0) − |A_ij| x_i(0) of every edge, for ``p`` paths.

        Parameters
        ----------
        p : int
            Paths.

        Returns
        -------
        numpy.ndarray
            (p, E·d).
        """
        s, d = self.system, self.dim
        x3 = np.asarray(self.x_init, dtype=float).reshape(self.n_agents, d)
        et = edge_terms(s, self.theta)
        y = np.einsum("eab,eb->ea", et.signed, x3[s.src]) - np.einsum(
            "eab,eb->ea", et.absw, x3[s.dst]
        )
        return np.tile(y.reshape(-1), (p, 1))

    @property
    def chunk_blocks(self) -> int:
        """Blocks integrated together: 1 on the CPU; on the GPU as many as keep the
        device's arrays of a chunk within :data:`GPU_CHUNK_BYTES` (one launch for all).

        Returns
        -------
        int
        """
        if self.device != "gpu":
            return 1
        ne, width = self.system.n_edges, self.x_init.size * (self.delay + 1)
        per_path = 8 * (width + ne * self.dim + 3 * ne + self.x_init.size + 4)
        return max(1, GPU_CHUNK_BYTES // (per_path * self.block_paths))

    def run_blocks(self, blocks: Sequence[int], progress=None) -> list[PartialStats]:
        """Integrate several blocks: on the CPU one after the other, on the GPU side by
        side (:func:`.loss_cuda.run_loss_blocks`, the same numbers).

        Parameters
        ----------
        blocks : sequence of int
            Block indices.
        progress : callable(int), optional
            Called with path-steps done.

        Returns
        -------
        list of PartialStats
        """
        if self.device == "gpu":
            from .loss_cuda import run_loss_blocks  # numba-cuda: only on a GPU

            return run_loss_blocks(self, blocks, progress)
        return [self.run_block(b, progress) for b in blocks]

    def run_block(self, b: int, progress=None) -> PartialStats:  # doc: PathBlocks.run_block
        if self.device == "gpu":
            return self.run_blocks([b], progress)[0]
        from .loss_kernels import POLICY_CODES, loss_steps  # numba: only when simulating

        grid, bp = self.grid, self.block_paths
        p0 = b * bp
        p = min(bp, self.paths - p0)
        stats = BlockStats(self, b, p0, p)
        nd_, ne = self.x_init.size, self.system.n_edges
        ring = self.delay + 1
        x = np.tile(self.x_init, (p, ring))
        held = self.initial_held(p)

        def now(k: int) -> np.ndarray:
            slot = (k % ring) * nd_
            return x[:, slot : slot + nd_]

        k_total = grid.n_steps
        # a sampled run's last partial step s: the held noise of a period h, for s seconds
        root = np.sqrt(grid.noise_h())  # √h, or s/√h on the partial step
        ch_all, cs_all, rh_all = self.steps.ch, self.steps.cs, root / grid.h
        arrays = self.kernel_arrays()
        code = POLICY_CODES[self.policy]
        save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
        if 0 in save_at and not stats.record(now(0), save_at[0]):
            return stats.result()
        xoshiro = self.rng == "xoshiro"
        states = path_states(self.seed, b, p) if xoshiro else np.zeros((0, 4), np.uint64)
        gen = (
            None
            if xoshiro
            else np.random.Generator(
                np.random.PCG64(np.random.SeedSequence(self.seed, spawn_key=(b,)))
            )
        )
        batch = int(np.clip(XI_BYTES // (8 * p * max(3 * ne, 1)), 1, BATCH))
        xi = np.empty((0 if xoshiro else batch, p, 2 * ne))
        uni = np.empty((0 if xoshiro else batch, p, ne))
        from .kernels import tile_width

        tile = tile_width(p, nd_ * ring)
        cuts = sorted({*save_at, k_total})
        for k0 in range(0, k_total, batch):
            kb = min(batch, k_total - k0)
            if gen is not None:
                gen.standard_normal(out=xi[:kb])
                uni[:kb] = gen.random((kb, p, ne))
            ch, cs, rh = ch_all[k0 : k0 + kb], cs_all[k0 : k0 + kb], rh_all[k0 : k0 + kb]
            k = k0
            while k < k0 + kb:
                stop = min(next(c for c in cuts if c > k), k0 + kb)
                loss_steps(  # type: ignore[call-arg]
                    x, held, states, xi, uni, 2 * ne, k - k0, stop - k0, ch, cs, rh,
                    *arrays, code, tile, self.delay, k0,
                )  # fmt: skip
                k = stop
                if k in save_at and not stats.record(now(k), save_at[k]):
                    return stats.result()
            if progress is not None:
                progress(kb * p)
            if not stats.check(now(k0 + kb), k0 + kb):
                return stats.result()
        return stats.result()


def lossy_mc_spec(mspec: MonteCarloSpec, plan, device: str = "cpu") -> LossMonteCarloSpec:
    """The lossless run's spec on lossy links.

    Parameters
    ----------
    mspec : MonteCarloSpec
        The lossless spec (one mode).
    plan : LossPlan
        The losses and the policy (:mod:`.loss_run`).
    device : str, optional
        ``cpu`` or ``gpu``.

    Returns
    -------
    LossMonteCarloSpec

    Raises
    ------
    InputError
        A callable f (the compiled kernel needs a linear one).
    """
    s = mspec.mode_systems()[0]
    if s.f is not None:
        raise InputError(
            "lossy links need a linear f (f·x or F x) in the Monte Carlo", field="noise.f"
        )
    return LossMonteCarloSpec(
        system=s,
        grid=mspec.grid,
        gain=mspec.gain,
        theta=mspec.theta,
        x_init=mspec.x_init,
        n_agents=mspec.n_agents,
        dim=mspec.dim,
        paths=mspec.paths,
        seed=mspec.seed,
        loss=plan.loss,
        policy=plan.policy,
        delay=mspec.delay,
        block_size=mspec.block_size,
        store_paths=mspec.store_paths,
        rng=mspec.rng,
        device=device,
    )


__all__ = ["LossMonteCarloSpec", "lossy_mc_spec"]
