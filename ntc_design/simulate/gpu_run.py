"""The GPU run of a Monte Carlo spec: the modes' arrays on the device, the schedule of
launches, checks and saves (the CPU's), and the chunks of paths (:class:`Chunk`: whole
CPU blocks, seeded from :func:`.rng.path_states`, their sums reduced on the device).

A small network (``slots·N·d`` <= :data:`FUSED_MAX_STATE`) runs one thread per path with
every step fused, a larger one a thread per (row, path) (:mod:`.cuda_kernels`). Paths go
in chunks of whole blocks (:data:`CHUNK_BYTES` of state at most); only the sums per save
time, the stored paths and the failure come back to the host. The callers
(:mod:`.gpu`, :mod:`.gpu_timevarying`) import ``numba.cuda`` first and pass it in.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .grid import StepGains, TimeGrid
from .modes import BATCH, XI_BYTES
from .montecarlo import MonteCarloSpec, PartialStats, merge
from .rng import path_states
from .ziggurat import ZIG_R, ZIG_X

FUSED_MAX_STATE = 256  # slots·N·d of a thread-per-path state (local memory); to tune on a GPU
FUSED_MAX_DRAW = 512  # normals a thread keeps per step in the fused kernel
CHUNK_BYTES = 2 * 2**30  # device memory for the states of one chunk of paths
THREADS = 128  # threads per block of the path kernels
ROW_THREADS = 256  # threads per block of the (row, path) kernels
PATHS_PER_THREAD = 64  # paths one thread sums in the statistics (more past MAX_GRID_Y groups)
MAX_GRID_Y = 65535  # CUDA's limit on a grid's second dimension

# -- the modes' arrays, concatenated ----------------------------------------------------


@dataclass(frozen=True, eq=False)
class ModeArrays:
    """Every mode's L_B (CSR, and 3×3 block-CSR when d = 3), u and edges, concatenated
    with absolute offsets per mode (the arrays :mod:`.cuda_kernels` takes), and the edges
    into each agent in ascending order (``eptr``, ``eids``: the sparse layout's sums in
    the CPU kernel's order)."""

    iptr: np.ndarray  # (M, Nd+1)
    ind: np.ndarray
    val: np.ndarray
    bptr: np.ndarray  # (M, N+1), or (M, 1) when d != 3
    bind: np.ndarray
    bval: np.ndarray  # (·, 3, 3)
    u: np.ndarray  # (M, Nd)
    e_off: np.ndarray  # (M,)
    e_cnt: np.ndarray  # (M,)
    src: np.ndarray
    dst: np.ndarray
    kmat: np.ndarray  # (Etot, d, d)
    gvec: np.ndarray  # (Etot, d)
    eptr: np.ndarray  # (M, N+1)
    eids: np.ndarray
    n: int
    d: int

    @property
    def d3(self) -> bool:
        """Whether d = 3 (the drift by 3×3 blocks, as the CPU kernel sums it)."""
        return self.d == 3

    @property
    def e_max(self) -> int:
        """The edges of the widest mode."""
        return int(self.e_cnt.max(initial=0))

    @classmethod
    def build(cls, parts: Sequence[tuple], n: int, d: int) -> ModeArrays:
        """Concatenate the kernel arrays of several modes.

        Parameters
        ----------
        parts : sequence of tuple
            Per mode, :func:`.kernels.kernel_arrays`' (indptr, indices, data, bptr, bind,
            bdata, u, src, dst, kmat, gvec).
        n, d : int
            Agents and state dimension.

        Returns
        -------
        ModeArrays
        """
        nd = n * d
        iptr, ind, val, bptr, bind, bval, us = [], [], [], [], [], [], []
        e_off, e_cnt, src, dst, kmat, gvec, eptr, eids = [], [], [], [], [], [], [], []
        nz = nb = ne = 0
        for indptr, indices, data, bp, bi, bd, u, s, t, km, gv in parts:
            iptr.append(indptr + nz)
            ind.append(indices)
            val.append(data)
            nz += indices.size
            bptr.append(bp + nb if d == 3 else np.zeros(1, np.int64))
            bind.append(bi)
            bval.append(bd)
            nb += bi.size
            us.append(u)
            e_off.append(ne)
            e_cnt.append(s.size)
            src.append(s)
            dst.append(t)
            kmat.append(km.reshape(-1, d, d))
            gvec.append(gv.reshape(-1, d))
            order = np.argsort(t, kind="stable")  # per agent, its edges in ascending order
            eptr.append(np.concatenate([[0], np.cumsum(np.bincount(t, minlength=n))]) + ne)
            eids.append(order)
            ne += s.size

        def cat(xs, dtype, shape=()):
            a = np.concatenate(xs).astype(dtype) if xs else np.zeros(0, dtype)
            a = a.reshape((-1, *shape))
            return a if a.shape[0] else np.zeros((1, *shape), dtype)  # no empty device arrays

        return cls(
            iptr=np.stack(iptr).astype(np.int64),
            ind=cat(ind, np.int64),
            val=cat(val, float),
            bptr=np.stack(bptr).astype(np.int64),
            bind=cat(bind, np.int64),
            bval=cat(bval, float, (3, 3)),
            u=np.stack(us).astype(float).reshape(len(parts), nd),
            e_off=np.array(e_off, np.int64),
            e_cnt=np.array(e_cnt, np.int64),
            src=cat(src, np.int64),
            dst=cat(dst, np.int64),
            kmat=cat(kmat, float, (d, d)),
            gvec=cat(gvec, float, (d,)),
            eptr=np.stack(eptr).astype(np.int64),
            eids=cat(eids, np.int64),
            n=n,
            d=d,
        )

    @classmethod
    def of_systems(cls, systems) -> ModeArrays:
        """The arrays of the modes of a run.

        Parameters
        ----------
        systems : sequence of ModeSystem
            The modes (a compiled f).

        Returns
        -------
        ModeArrays
        """
        from .kernels import kernel_arrays  # numba: only when simulating

        s0 = systems[0]
        return cls.build([kernel_arrays(s) for s in systems], s0.n_agents, s0.dim)

    def device(self, cuda) -> tuple:
        """The arrays on the device, in the fused kernel's order.

        Parameters
        ----------
        cuda : module
            ``numba.cuda``.

        Returns
        -------
        tuple
            (iptr, ind, val, bptr, bind, bval, u, e_off, e_cnt, src, dst, kmat, gvec,
            eptr, eids) as device arrays.
        """
        names = (
            "iptr", "ind", "val", "bptr", "bind", "bval", "u", "e_off", "e_cnt", "src",
            "dst", "kmat", "gvec", "eptr", "eids",
        )  # fmt: skip
        return tuple(cuda.to_device(np.ascontiguousarray(getattr(self, k))) for k in names)


# -- the run ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Schedule:
    """Where a chunk stops: every save step and every check step of the CPU (the end of
    each batch of steps), in order; with the steps' c·h, c·√h and mode on the host."""

    grid: TimeGrid
    ch: np.ndarray
    cs: np.ndarray
    mode: np.ndarray
    stops: np.ndarray  # the grid indices > 0 where a launch ends
    checks: frozenset
    saves: dict  # grid index -> save slot

    @classmethod
    def of(cls, grid: TimeGrid, steps: StepGains, batch: int) -> Schedule:
        """The schedule of a grid with the CPU's check batch.

        Parameters
        ----------
        grid : TimeGrid
            The run's grid.
        steps : StepGains
            The steps' c·h and c·√h (the spec's, as the CPU blocks read them).
        batch : int
            Steps between the CPU's checks.

        Returns
        -------
        Schedule
        """
        k_total = grid.n_steps
        checks = set(range(batch, k_total, batch)) | {k_total}
        saves = {int(k): i for i, k in enumerate(grid.save_steps)}
        stops = np.array(sorted((checks | set(saves)) - {0}), dtype=np.int64)
        mode = grid.mode.astype(np.int64) if grid.mode.size else np.zeros(k_total, np.int64)
        return cls(grid, steps.ch, steps.cs, mode, stops, frozenset(checks), saves)


def check_batch(paths: int, e_max: int) -> int:
    """The CPU's steps between two checks of a block of ``paths`` paths
    (:func:`.montecarlo._run_block`).

    Parameters
    ----------
    paths : int
        The block's paths.
    e_max : int
        The edges of the widest mode.

    Returns
    -------
    int
    """
    return int(np.clip(XI_BYTES // (8 * paths * max(2 * e_max, 1)), 1, BATCH))


class Chunk:
    """One chunk of paths on the device: its ring of states, streams and sums."""

    def __init__(self, run: DeviceRun, g0: int, states: np.ndarray):
        cu, p, nd = run.cuda, states.shape[0], run.nd
        self.run, self.g0, self.p = run, g0, p
        self.x = cu.to_device(np.tile(run.x_init[:, None], (run.ring, p)))
        self.st = cu.to_device(np.ascontiguousarray(states.T))
        n_saves, q = run.sched.grid.save_steps.size, 3 * run.n + nd
        self.acc = cu.to_device(np.zeros((max(n_saves, 1), q)))
        self.n_store = max(0, min(run.store_paths - g0, p))
        self.stored = cu.to_device(np.zeros((max(n_saves, 1), max(self.n_store, 1), nd)))
        self.ppt = max(PATHS_PER_THREAD, -(-p // MAX_GRID_Y))
        self.groups = -(-p // self.ppt)
        self.part = cu.device_array((self.groups, q))
        self.bad = cu.to_device(np.array([np.iinfo(np.int64).max], np.int64))
        self.valid = 0
        self.failure: dict | None = None
        if run.sparse:
            self.z = cu.device_array((max(run.m_draw, 1), p))

    def at(self, k: int) -> bool:
        """Check and record at grid index k (when it is a check or a save point).

        Parameters
        ----------
        k : int
            The grid index reached.

        Returns
        -------
        bool
            False once a state is not finite (the failure kept).
        """
        run = self.run
        save = run.sched.saves.get(k)
        if save is None and k not in run.sched.checks:
            return True
        from .cuda_kernels import check_kernel, stats_kernel, sum_kernel  # numba-cuda: on a GPU

        row0, cells = (k % run.ring) * run.nd, run.nd * self.p
        check_kernel()[_blocks(cells, ROW_THREADS), min(ROW_THREADS, cells)](
            self.x, row0, run.nd, self.bad
        )
        code = int(self.bad.copy_to_host()[0])
        if code != np.iinfo(np.int64).max:
            q, r = divmod(code, run.nd)
            t = run.sched.grid.save_times[save] if save is not None else run.sched.grid.t[k]
            self.failure = {
                "t": float(t),
                "agent": r // run.d,
                "path": self.g0 + q,
                "save_index": self.valid,
            }
            return False
        if save is not None:
            tn = min(THREADS, run.n)
            stats_kernel()[(_blocks(run.n, tn), self.groups), tn](
                self.x, row0, run.theta, run.n, run.d, self.ppt, self.part,
                self.stored, self.n_store, save,
            )  # fmt: skip
            q = self.part.shape[1]
            sum_kernel()[_blocks(q, THREADS), min(THREADS, q)](
                self.part, self.groups, self.acc, save, run.n, self.ppt, self.p
            )
            self.valid = save + 1
        return True

    def advance(self, k_from: int, k_to: int) -> None:
        """Steps k_from … k_to − 1 of every path of the chunk.

        Parameters
        ----------
        k_from, k_to : int
            Grid indices.
        """
        from .cuda_kernels import draw_kernel, fused_kernel, step_kernel  # numba-cuda: on a GPU

        run, p = self.run, self.p
        if not run.sparse:
            kern = fused_kernel(run.nd, run.ring, run.m_draw, run.modes.d3)
            kern[_blocks(p, THREADS), min(THREADS, p)](
                self.x, self.st, k_from, k_to, run.ch, run.cs, run.mode, *run.dev[:13],
                run.d, run.zx, run.zr,
            )  # fmt: skip
            return
        draw, step = draw_kernel(), step_kernel(run.modes.d3)
        dv = run.dev
        cells = run.nd * p
        for k in range(k_from, k_to):
            draw[_blocks(p, THREADS), min(THREADS, p)](
                self.st, self.z, run.m_draw, float(run.sched.cs[k]), run.zx, run.zr
            )
            step[_blocks(cells, ROW_THREADS), min(ROW_THREADS, cells)](
                self.x, self.z, k % run.ring, (k - run.delay) % run.ring,
                (k + 1) % run.ring, float(run.sched.ch[k]), int(run.sched.mode[k]), run.nd,
                *dv[:9], dv[13], dv[14], dv[9], dv[11], dv[12], run.d,
            )  # fmt: skip

    def result(self, blocks: list[int]) -> PartialStats:
        """The chunk's sums, stored paths and failure.

        Parameters
        ----------
        blocks : list of int
            The CPU blocks the chunk holds.

        Returns
        -------
        PartialStats
        """
        run, n = self.run, self.run.n
        n_saves = run.sched.grid.save_steps.size
        acc = self.acc.copy_to_host()[:n_saves]
        stored = self.stored.copy_to_host()[:n_saves, : self.n_store]
        return PartialStats(
            blocks, self.p, acc[:, :n], acc[:, n : 2 * n], acc[:, 2 * n : 3 * n],
            acc[:, 3 * n :],
            np.ascontiguousarray(stored.transpose(1, 0, 2)),
            list(range(self.g0, self.g0 + self.n_store)), self.failure, self.valid,
        )  # fmt: skip


def _blocks(count: int, threads: int) -> int:
    return max(1, -(-count // max(threads, 1)))


class DeviceRun:
    """What every chunk of a run shares: the device, the modes, the schedule."""

    def __init__(self, cuda, spec, modes: ModeArrays, sched: Schedule, layout: str, delay: int):
        self.cuda, self.modes, self.sched, self.delay = cuda, modes, sched, delay
        self.n, self.d = modes.n, modes.d
        self.nd = self.n * self.d
        self.m_draw = 2 * modes.e_max
        small = (delay + 1) * self.nd <= FUSED_MAX_STATE and self.m_draw <= FUSED_MAX_DRAW
        self.sparse = layout == "sparse" or (layout == "auto" and not small)
        self.ring = delay + (2 if self.sparse else 1)
        self.x_init = np.asarray(spec.x_init, dtype=float)
        self.store_paths = int(spec.store_paths)
        self.theta = cuda.to_device(np.asarray(spec.theta, dtype=float))
        self.zx, self.zr = cuda.to_device(ZIG_X), cuda.to_device(ZIG_R)
        self.ch, self.cs = cuda.to_device(sched.ch), cuda.to_device(sched.cs)
        self.mode = cuda.to_device(sched.mode)
        self.dev = modes.device(cuda)

    def chunk_paths(self) -> int:
        """Paths whose states fit :data:`CHUNK_BYTES`.

        Returns
        -------
        int
            At least one.
        """
        per = 8 * (self.ring * self.nd + (self.m_draw if self.sparse else 0) + 4)
        return max(1, CHUNK_BYTES // per)


def drive(chunk: Chunk, sched: Schedule, tick: Callable[[int], None] | None = None) -> None:
    """Run a chunk over the whole grid, launch by launch, stopping at a failure.

    Parameters
    ----------
    chunk : Chunk
        The chunk.
    sched : Schedule
        Its stops.
    tick : callable(int), optional
        Called with the path-steps of each launch.
    """
    if not chunk.at(0):
        return
    k = 0
    for stop in sched.stops.tolist():
        chunk.advance(k, stop)
        if tick is not None:
            tick((stop - k) * chunk.p)
        k = stop
        if not chunk.at(k):
            return


def run_chunks(run: DeviceRun, spec, block_paths: int, progress, go) -> PartialStats:
    """Seed the CPU's blocks, group them into chunks that fit the device, run each chunk
    with ``go(chunk)`` and merge the chunks' sums in block order.

    Parameters
    ----------
    run : DeviceRun
        The run's shared arrays.
    spec : PathBlocks
        Paths, seed.
    block_paths : int
        The CPU's paths per block (a path's stream depends on its block).
    progress : callable(done, total) or None
        Called with path-steps done.
    go : callable(Chunk, tick)
        Integrates a chunk.

    Returns
    -------
    PartialStats
    """
    n_blocks = -(-spec.paths // block_paths)
    per_chunk = max(1, run.chunk_paths() // block_paths)
    total = spec.paths * run.sched.grid.n_steps
    done = 0
    parts = []
    for b0 in range(0, n_blocks, per_chunk):
        blocks = list(range(b0, min(b0 + per_chunk, n_blocks)))
        states = np.concatenate(
            [
                path_states(spec.seed, b, min(block_paths, spec.paths - b * block_paths))
                for b in blocks
            ]
        )
        chunk = Chunk(run, b0 * block_paths, states)

        def tick(n: int) -> None:
            nonlocal done
            done += n
            if progress is not None:
                progress(done, total)

        go(chunk, tick)
        parts.append(chunk.result(blocks))
    return merge(parts)


def run_modes(cuda, spec: MonteCarloSpec, layout: str, progress) -> PartialStats:
    """Every path of a :class:`.montecarlo.MonteCarloSpec` (fixed, switching or sampled
    modes; ``delay`` D >= 0 when the spec has one) on the device.

    Parameters
    ----------
    cuda : module
        ``numba.cuda``.
    spec : MonteCarloSpec
        The run.
    layout : str
        ``auto``, ``fused`` or ``sparse``.
    progress : callable(done, total) or None
        Called with path-steps done.

    Returns
    -------
    PartialStats
        Merged over the CPU's blocks.
    """
    modes = ModeArrays.of_systems(spec.mode_systems())
    bp = spec.block_paths
    sched = Schedule.of(spec.grid, spec.steps, check_batch(bp, modes.e_max))
    run = DeviceRun(cuda, spec, modes, sched, layout, spec.delay)
    return run_chunks(run, spec, bp, progress, lambda ch, tick: drive(ch, sched, tick))


__all__ = [
    "CHUNK_BYTES",
    "FUSED_MAX_STATE",
    "Chunk",
    "DeviceRun",
    "ModeArrays",
    "Schedule",
    "check_batch",
    "drive",
    "run_chunks",
    "run_modes",
]
