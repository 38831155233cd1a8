"""Monte Carlo Euler–Maruyama for the SAN with compound noise, in bounded memory.

Paths are integrated in fixed *blocks* of ``block_paths = min(block_size, ⌈paths/2⌉)``
paths (at least two blocks, so that two workers both have work however few the paths;
the split depends on ``paths`` only); block b seeds its paths from
``SeedSequence(seed, spawn_key=(b,))`` (the b-th child of the run's SeedSequence): by
default one xoshiro256** stream per path, drawn inside the compiled kernel (:mod:`.rng`),
or with ``rng="numpy"`` NumPy's PCG64 for the block, step by step, rows (paths) of 2·E
normals (E additive, then E multiplicative). Either way a path's noise depends only on
(seed, block_paths, its index). The per-block kernel is the
compiled edge-list step of :mod:`.kernels` (a SciPy-sparse step for a callable f); with
``scheme="implicit"`` the drift is taken at the new point,
``x_{k+1} = (I + c h L_B)^{-1}(x_k + c h u + noise(x_k))``, with one sparse LU per mode
and value of c·h. Each
block streams its statistics at the save times (sums of ‖x_i − θ‖² and of its square,
the summed state, a few stored paths) and never keeps the trajectory; blocks are merged
in block order. Results are therefore identical whatever the number of workers and the
number of blocks per chunk. The chunk interface (:func:`run_chunk`: block indices in,
:class:`PartialStats` out; :func:`merge`) is what a distributed engine would call.
"""

from __future__ import annotations

import multiprocessing as mp
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import interrupt_seen
from .grid import StepGains, TimeGrid
from .modes import ModeSource, Stepper
from .system import ModeSystem

MIN_BLOCKS = 2  # paths are split into at least this many blocks (both cores busy)


class PathBlocks:
    """What every Monte Carlo spec shares (fixed modes, A(t), lossy links): one rule for
    the blocks of paths, and the steps' c·h and c·√h computed once per run from the
    gain on its grid. A subclass has ``grid``, ``gain``, ``paths`` and ``block_size``."""

    grid: TimeGrid
    gain: Callable[[np.ndarray], np.ndarray]
    paths: int
    seed: int
    block_size: int
    rng: str
    # a spec without these fields runs the explicit scheme with no delay
    scheme: str = "explicit"
    delay: int = 0

    def mode_systems(self) -> tuple[ModeSystem, ...]:
        """The modes whose compiled kernel :func:`prepare` loads before the workers fork
        (none: a spec whose blocks bring their own kernel).

        Returns
        -------
        tuple of ModeSystem
        """
        return ()

    def callable_f(self) -> bool:
        """Whether a mode's f is a callable (the GPU needs a linear one).

        Returns
        -------
        bool
        """
        return any(s.f is not None for s in self.mode_systems())

    def run_block(self, b: int, progress=None) -> PartialStats:
        """Integrate block b of the paths.

        Parameters
        ----------
        b : int
            The block (its streams from the b-th child of the seed).
        progress : callable(int), optional
            Called with path-steps done.

        Returns
        -------
        PartialStats
        """
        raise NotImplementedError

    def run_blocks(self, blocks: Sequence[int], progress=None) -> list[PartialStats]:
        """Integrate several blocks, in order.

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
        return [self.run_block(b, progress) for b in blocks]

    @property
    def chunk_blocks(self) -> int:
        """Blocks one task integrates together (1; a GPU run takes many at once). The
        result does not depend on it.

        Returns
        -------
        int
        """
        return 1

    @property
    def block_paths(self) -> int:
        """Paths per block: ``block_size``, or fewer so that there are at least
        MIN_BLOCKS blocks (a function of ``paths`` only, never of the workers)."""
        return max(1, min(self.block_size, -(-self.paths // MIN_BLOCKS)))

    @property
    def n_blocks(self) -> int:
        """The number of blocks of :attr:`block_paths` paths."""
        return -(-self.paths // self.block_paths)

    @cached_property
    def steps(self) -> StepGains:
        """c_k·h_k and c_k·√h_k on the grid (computed on first use, then kept: every
        block of the run, and a forked worker, reads the same arrays)."""
        return StepGains.of(self.grid, self.gain(self.grid.t[:-1]))


@dataclass(frozen=True, eq=False, kw_only=True)
class MonteCarloSpec(PathBlocks):
    """Everything a Monte Carlo run needs: the modes (:class:`.modes.FixedModes`, or
    A(t) as expressions: :class:`.timevarying.ExpressionModes`), the grid, c(t), θ, the
    initial state, the path count and seed (block b draws from the seed's b-th child),
    the block size, how many paths to store and the step scheme."""

    modes: ModeSource
    grid: TimeGrid
    gain: Callable[[np.ndarray], np.ndarray]
    theta: np.ndarray
    x_init: np.ndarray  # Nd
    n_agents: int
    dim: int
    paths: int
    seed: int
    block_size: int = 500
    store_paths: int = 10
    agent_labels: tuple = ()
    scheme: str = "explicit"  # or "implicit": x_{k+1} = (I + c h L_B)^{-1}(x_k + …)
    rng: str = "xoshiro"  # per-path streams drawn in the kernel (.rng), or "numpy"
    delay: int = 0  # the sampled protocol's D: feedback and noise at x_{k−D} (.digital)

    def mode_systems(self) -> tuple[ModeSystem, ...]:
        """The mode systems (:meth:`.modes.ModeSource.kernel_systems`).

        Returns
        -------
        tuple of ModeSystem
        """
        return self.modes.kernel_systems()

    def callable_f(self) -> bool:
        """Whether f is a callable (:meth:`.modes.ModeSource.callable_f`).

        Returns
        -------
        bool
        """
        return self.modes.callable_f()

    def run_block(self, b: int, progress=None) -> PartialStats:  # doc: PathBlocks.run_block
        return _run_block(self, b, progress)

    def run_blocks(self, blocks: Sequence[int], progress=None) -> list[PartialStats]:
        """Integrate several blocks with one set of steppers (the implicit solvers are
        built once).

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
        steppers = self.modes.steppers(self.scheme == "implicit", self.delay)
        return [_run_block(self, b, progress, steppers) for b in blocks]


@dataclass
class PartialStats:
    """Sums over some paths at the save times (mergeable). The spread of ‖x_i − θ‖² is
    kept as the sum of squared deviations from these paths' own mean (``m2``, beside that
    mean, ``centre``), merged by Chan's update (:func:`merge_spread`): a sum of fourth
    powers less a square lost the digits of a narrow band (3e-7 wide for identical paths)."""

    blocks: list[int]
    count: int
    sq: np.ndarray  # (S, N) Σ ‖x_i − θ‖²
    m2: np.ndarray  # (S, N) Σ (‖x_i − θ‖² − centre)²
    centre: np.ndarray  # (S, N) the mean of ‖x_i − θ‖² over these paths
    state: np.ndarray  # (S, Nd) Σ x
    stored: np.ndarray  # (k, S, Nd) stored paths (global indices 0..k-1)
    stored_index: list[int] = field(default_factory=list)
    failure: dict | None = None  # {"t", "agent", "path", "save_index"} on NaN/overflow
    valid_saves: int = 0  # save points computed for every path in these blocks


def centred_spread(e2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean of each column of ``e2`` and the sum of squared deviations from it, in two
    passes: the mean taken as the first row plus the mean offset from it, so that equal
    values give exactly their value and a spread of exactly 0.

    Parameters
    ----------
    e2 : numpy.ndarray
        (p, N), p >= 1 paths.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The (N,) mean and the (N,) sum of squared deviations.
    """
    base = e2[0]
    mean = base + (e2 - base).sum(axis=0) / e2.shape[0]
    dev = e2 - mean
    return mean, np.einsum("pn,pn->n", dev, dev)


def merge_spread(n_a, mean_a, m2_a, n_b, mean_b, m2_b):
    """Chan, Golub and LeVeque's merge of two sets' (count, mean, sum of squared
    deviations): the mean moves by δ·n_b/n and the sum gains δ²·n_a·n_b/n, δ = mean_b −
    mean_a. Sets with equal means (identical paths) merge with δ = 0: the spread stays 0.

    Parameters
    ----------
    n_a, n_b : int
        The sets' counts (n_a + n_b >= 1).
    mean_a, mean_b, m2_a, m2_b : numpy.ndarray or float
        Their means and sums of squared deviations.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The union's mean and sum of squared deviations.
    """
    n = n_a + n_b
    delta = mean_b - mean_a
    return mean_a + delta * (n_b / n), m2_a + m2_b + delta * delta * (n_a * n_b / n)


def _first_bad(x: np.ndarray, d: int) -> tuple[int, int] | None:
    """(path row, agent) of the first non-finite or overflowing entry, or None."""
    bad = ~np.isfinite(x) | (np.abs(x) > 1e150)
    if not bad.any():
        return None
    row, col = np.argwhere(bad)[0]
    return int(row), int(col // d)


def prepare(spec: PathBlocks) -> None:
    """Compile (or load from numba's cache) the kernel for this spec's array types in this
    process, so that forked workers inherit it instead of each compiling it. When the
    kernel is not in Numba's cache (a first run), say so first in one line on stderr.

    Parameters
    ----------
    spec : PathBlocks
        The run (a spec whose blocks bring their own kernel needs nothing).
    """
    from .kernels import fill_normals, kernel_cached, warm_kernel

    # only what the run calls: each kernel loaded from the cache costs about 0.1 s
    systems = spec.mode_systems()
    xoshiro = spec.rng == "xoshiro"
    explicit = spec.scheme == "explicit"
    fused = xoshiro and explicit and bool(systems) and all(s.f is None for s in systems)
    if xoshiro and not fused:
        fill_normals(np.zeros((0, 4), np.uint64), np.zeros((1, 0, 1)))
    delay = spec.delay
    for s in systems:
        if s.f is None:
            st = Stepper(s, False)
            width = s.nd * (delay + 1)
            if not kernel_cached(fused, width, st.args, delay):
                compiling_notice()
            warm_kernel(fused, width, st.args, delay)
            return


COMPILE_SECONDS = 3  # CPU seconds to compile the fused kernel here (3.0-3.8 s; bench_startup.py)


def compiling_notice() -> None:
    """Say on stderr, in one line, that the kernel is being compiled (a first run, or a
    new specialisation), and about how long it takes."""
    print(
        f"note: compiling the simulation kernels once, about {COMPILE_SECONDS} s of CPU",
        file=sys.stderr,
        flush=True,
    )


class BlockStats:
    """One block's streamed statistics at the save times (shared by the fixed and the
    time-varying blocks): Σ‖x_i − θ‖², its square, Σx, a few stored paths, and the first
    non-finite state (which stops the block)."""

    def __init__(self, spec, b: int, p0: int, p: int):
        grid = spec.grid
        s_n, nd_ = grid.save_steps.size, spec.x_init.size
        self.b, self.p0, self.p, self.d, self.n = b, p0, p, spec.dim, spec.n_agents
        self.save_times, self.t = grid.save_times, grid.t
        self.sq = np.zeros((s_n, self.n))
        self.m2 = np.zeros((s_n, self.n))
        self.centre = np.zeros((s_n, self.n))
        self.state = np.zeros((s_n, nd_))
        self.n_store = max(0, min(spec.store_paths - p0, p))
        self.stored = np.zeros((self.n_store, s_n, nd_))
        self.theta_t = np.tile(spec.theta, self.n)
        self.failure: dict | None = None
        self.valid = 0

    def _fail(self, where: tuple[int, int], t: float) -> None:
        self.failure = {
            "t": t,
            "agent": where[1],
            "path": self.p0 + where[0],
            "save_index": self.valid,
        }

    def record(self, x: np.ndarray, i: int) -> bool:
        """Add the state at save time i.

        Parameters
        ----------
        x : numpy.ndarray
            The block's states, (paths, Nd).
        i : int
            The save slot.

        Returns
        -------
        bool
            False (and the failure kept) when a state is not finite.
        """
        where = _first_bad(x, self.d)
        if where is not None:
            self._fail(where, float(self.save_times[i]))
            return False
        e = (x - self.theta_t).reshape(self.p, self.n, self.d)
        e2 = np.einsum("pnd,pnd->pn", e, e)
        self.sq[i] = e2.sum(axis=0)
        self.centre[i], self.m2[i] = centred_spread(e2)
        self.state[i] = x.sum(axis=0)
        if self.n_store:
            self.stored[:, i] = x[: self.n_store]
        self.valid = i + 1
        return True

    def check(self, x: np.ndarray, k: int) -> bool:
        """Check the states after step k − 1 (grid time t_k).

        Parameters
        ----------
        x : numpy.ndarray
            The block's states, (paths, Nd).
        k : int
            The grid index reached.

        Returns
        -------
        bool
            False, with the failure kept, when a state is not finite.
        """
        where = _first_bad(x, self.d)
        if where is not None:
            self._fail(where, float(self.t[k]))
            return False
        return True

    def result(self) -> PartialStats:
        """The block's sums.

        Returns
        -------
        PartialStats
        """
        idx = list(range(self.p0, self.p0 + self.n_store))
        return PartialStats(
            [self.b], self.p, self.sq, self.m2, self.centre, self.state, self.stored, idx,
            self.failure, self.valid,
        )  # fmt: skip


def _run_block(spec: MonteCarloSpec, b: int, progress=None, steppers=None) -> PartialStats:
    grid = spec.grid
    bp = spec.block_paths
    p0 = b * bp
    p = min(bp, spec.paths - p0)
    from .rng import NormalSource

    src = NormalSource(spec.rng, spec.seed, b, p)
    stats = BlockStats(spec, b, p0, p)
    nd_ = spec.x_init.size
    # the sampled protocol holds the initial state for k < 0: every slot of the ring
    ring = spec.delay + 1
    x = np.tile(spec.x_init, (p, ring))

    def now(k: int) -> np.ndarray:  # x_k: slot k mod (D + 1) of the ring (a view)
        slot = (k % ring) * nd_
        return x[:, slot : slot + nd_]

    modes = spec.modes
    e_max = modes.e_max()
    if steppers is None:
        steppers = modes.steppers(spec.scheme == "implicit", spec.delay)
    ch_all, cs_all = spec.steps.ch, spec.steps.cs
    save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
    ends = modes.ends(grid)
    if 0 in save_at and not stats.record(now(0), save_at[0]):
        return stats.result()
    # the normals of step k are rows (p, 2·e_max) drawn in step order: the batch size
    # changes how many are drawn per call, not which (Generator fills sequentially)
    batch = modes.batch(p)
    # xoshiro with compiled explicit steps: the kernel draws, no array of normals at all
    fused = src.states is not None and modes.fusable and all(st.fused for st in steppers)
    xi = np.empty((0 if fused else batch, p, 2 * e_max))
    k_total = grid.n_steps
    for k0 in range(0, k_total, batch):
        kb = min(batch, k_total - k0)
        if not fused:
            src.fill(xi[:kb])
        ch, cs = ch_all[k0 : k0 + kb], cs_all[k0 : k0 + kb]
        step_by, mode = modes.for_batch(steppers, grid, k0, kb)
        k = k0
        while k < k0 + kb:
            stop = min(int(ends[k]), k0 + kb)
            st = step_by[mode[k - k0]]
            if fused:
                st.advance_drawing(x, src.states, 2 * e_max, k - k0, stop - k0, ch, cs, k0)
            else:
                st.advance(x, xi, k - k0, stop - k0, ch, cs, k0)
            k = stop
            if k in save_at and not stats.record(now(k), save_at[k]):
                return stats.result()
        if progress is not None:
            progress(kb * p)
        if not stats.check(now(k0 + kb), k0 + kb):
            return stats.result()
    return stats.result()


def run_chunk(spec: PathBlocks, blocks: Sequence[int], progress=None) -> list[PartialStats]:
    """Integrate the given blocks (:meth:`PathBlocks.run_blocks`).

    Overflow is detected and reported by the kernel (``failure``), so NumPy's floating
    point warnings are silenced here.

    Parameters
    ----------
    spec : PathBlocks
        The run (fixed modes, A(t) or lossy links).
    blocks : sequence of int
        Block indices.
    progress : callable(done, total), optional
        Called with path-steps done.

    Returns
    -------
    list of PartialStats
        One per block (combine them with :func:`merge`).
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return spec.run_blocks(blocks, progress)


def merge(parts: Sequence[PartialStats]) -> PartialStats:
    """Sum partial statistics in block order (so the result does not depend on chunking).

    Parameters
    ----------
    parts : sequence of PartialStats
        Statistics of disjoint blocks (at least one).

    Returns
    -------
    PartialStats
        Their sums, the stored paths in block order and the earliest failure.
    """
    parts = sorted(parts, key=lambda q: q.blocks[0])
    first = parts[0]
    sq, state = first.sq.copy(), first.state.copy()
    count, centre, m2 = first.count, first.centre.copy(), first.m2.copy()
    for q in parts[1:]:  # in block order, one at a time: the same sums for any chunking
        sq += q.sq
        state += q.state
        centre, m2 = merge_spread(count, centre, m2, q.count, q.centre, q.m2)
        count += q.count
    stored = np.concatenate([q.stored for q in parts], axis=0)
    idx = [i for q in parts for i in q.stored_index]
    fails = [q.failure for q in parts if q.failure is not None]
    failure = min(fails, key=lambda f: f["t"]) if fails else None
    valid = min(q.valid_saves for q in parts)
    return PartialStats(
        [b for q in parts for b in q.blocks],
        count,
        sq,
        m2,
        centre,
        state,
        stored,
        idx,
        failure,
        valid,
    )


# -- parallel execution (fork: the spec, callables included, is inherited) -----------
#
# Chunks are submitted a few at a time (at most 2 per worker in flight) and their
# results are folded in block order as soon as the next one in order is in, so memory
# does not grow with the number of blocks. Workers ignore SIGINT: on Ctrl-C (or any
# error) the parent cancels what is queued, terminates the workers and re-raises, so an
# interrupt takes effect within a fraction of a second instead of at the end of the run.

_SPEC: PathBlocks | None = None
_COUNTER: Any = None  # a multiprocessing Value, made with the fork context


def _init_worker() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker(blocks: list[int]) -> list[PartialStats]:
    from threadpoolctl import threadpool_limits

    def tick(n: int) -> None:
        with _COUNTER.get_lock():
            _COUNTER.value += n

    # one BLAS thread per worker: the processes are the parallelism (2 workers × 2 BLAS
    # threads on 2 cores made the switching example 5× slower)
    assert _SPEC is not None  # set by run() before the fork
    with threadpool_limits(limits=1):
        return run_chunk(_SPEC, blocks, tick)


class _InOrder:
    """Fold PartialStats in block order as they arrive (bounded buffering)."""

    def __init__(self) -> None:
        self.acc: PartialStats | None = None
        self.waiting: dict[int, list[PartialStats]] = {}
        self.next = 0

    def add(self, index: int, parts: list[PartialStats]) -> None:
        self.waiting[index] = parts
        while self.next in self.waiting:
            got = self.waiting.pop(self.next)
            self.acc = merge(([self.acc] if self.acc is not None else []) + got)
            self.next += 1

    def result(self) -> PartialStats:
        """Everything folded (at least one chunk was added)."""
        assert self.acc is not None, "no chunk was folded"
        return self.acc


def _terminate(ex: ProcessPoolExecutor) -> None:
    """Cancel queued work and stop the workers now (not after their current chunk)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=2)
        if p.is_alive():
            p.kill()


def run(
    spec: PathBlocks,
    workers: int = 2,
    blocks_per_chunk: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> PartialStats:
    """Run every block, on ``workers`` processes (1: in this process).

    Parameters
    ----------
    spec : PathBlocks
        The run.
    workers : int
        Processes (capped by the caller at the machine's CPUs).
    blocks_per_chunk : int
        Blocks per task.
    progress : callable(done, total), optional
        Called with path-steps done.

    Returns
    -------
    PartialStats
        Merged in block order: identical for any ``workers`` and ``blocks_per_chunk``.

    Raises
    ------
    KeyboardInterrupt
        Re-raised after the workers are stopped.
    """
    global _SPEC, _COUNTER
    prepare(spec)
    n_chunks = -(-spec.n_blocks // blocks_per_chunk)

    def chunk(i: int) -> list[int]:
        return list(range(i * blocks_per_chunk, min((i + 1) * blocks_per_chunk, spec.n_blocks)))

    total = spec.paths * spec.grid.n_steps
    if workers <= 1 or n_chunks == 1 or "fork" not in mp.get_all_start_methods():
        done = 0

        def tick(n: int) -> None:
            nonlocal done
            done += n
            if progress:
                progress(done, total)

        fold = _InOrder()
        for i in range(n_chunks):
            fold.add(i, run_chunk(spec, chunk(i), tick))
            if interrupt_seen():  # a Ctrl-C whose exception a finaliser swallowed
                raise KeyboardInterrupt
        return fold.result()
    ctx = mp.get_context("fork")
    _SPEC, _COUNTER = spec, ctx.Value("q", 0)
    ex = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker)
    fold = _InOrder()
    try:
        pending: dict = {}
        submitted = 0
        while submitted < n_chunks or pending:
            while submitted < n_chunks and len(pending) < 2 * workers:
                pending[ex.submit(_worker, chunk(submitted))] = submitted
                submitted += 1
            finished, _ = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            if interrupt_seen():  # a Ctrl-C whose exception a finaliser swallowed
                raise KeyboardInterrupt
            for f in finished:
                fold.add(pending.pop(f), f.result())
            if progress is not None:
                progress(_COUNTER.value, total)
        ex.shutdown(wait=True)
        if progress:
            progress(total, total)
    except BaseException:
        _terminate(ex)
        raise
    finally:
        _SPEC, _COUNTER = None, None
    return fold.result()
