"""A(t) given as expressions on the GPU: Lemma 1 and the weights are evaluated on the host
for each batch of steps, as the CPU does (:func:`.timevarying._run_block_tv`: batched
Cholesky and eigenvalues, which a GPU thread per path would repeat for every path), and
the batch's matrices go to the device as one "mode" per step (L_B(t) dense, u(t), K_e(t),
g_e(t)); the device integrates every path through them with the fixed topology's kernels.
So every A(t) that the CPU simulates runs here too (a callable f excepted, refused with
one line by :func:`.gpu.check_supported`), with the CPU's blocks, streams, dense sums,
check and save points: the same paths to rounding.
"""

from __future__ import annotations

import numpy as np

from .gpu_run import DeviceRun, ModeArrays, Schedule, run_chunks
from .montecarlo import PartialStats
from .timevarying import TimeVaryingMonteCarloSpec, TimeVaryingSystem, batch_size


def batch_modes(sys_: TimeVaryingSystem, ts: np.ndarray) -> ModeArrays:
    """One mode per time of ``ts``: the CPU's dense arrays of L_B(t) (CSR over every
    entry and, for d = 3, every 3×3 block), u(t), K_e(t) = |A_ij(t)| F and
    g_e(t) = σ_ji |A_ij(t)| 1.

    Parameters
    ----------
    sys_ : TimeVaryingSystem
        The system with A(t).
    ts : numpy.ndarray
        The steps' times.

    Returns
    -------
    ModeArrays
    """
    st = sys_.structure
    n, d = st.n, st.d
    nd = n * d
    b_t = sys_.design.at(ts)
    lap = b_t.lap_b(st).reshape(ts.size, -1)
    u = b_t.input_vector()
    absw = b_t.abs_w[:, sys_.live]
    kmat = absw @ sys_.fmat
    gvec = sys_.sigma[None, :, None] * absw.sum(axis=3)
    src = np.ascontiguousarray(st.jj[sys_.live], dtype=np.int64)
    dst = np.ascontiguousarray(st.ii[sys_.live], dtype=np.int64)
    indptr = np.arange(0, nd * nd + 1, nd, dtype=np.int64)
    indices = np.tile(np.arange(nd, dtype=np.int64), nd)
    if d == 3:
        bptr = np.arange(0, n * n + 1, n, dtype=np.int64)
        bind = np.tile(np.arange(n, dtype=np.int64), n)
    else:
        bptr, bind = np.zeros(1, np.int64), np.zeros(0, np.int64)
    parts = []
    for kk in range(ts.size):
        blocks = (
            lap[kk].reshape(n, 3, n, 3).transpose(0, 2, 1, 3).reshape(-1, 3, 3)
            if d == 3
            else np.zeros((0, 3, 3))
        )
        parts.append(
            (indptr, indices, lap[kk], bptr, bind, blocks, u[kk], src, dst, kmat[kk], gvec[kk])
        )
    return ModeArrays.build(parts, n, d)


def run_time_varying(cuda, spec: TimeVaryingMonteCarloSpec, layout: str, progress) -> PartialStats:
    """Every path of an A(t) run on the GPU (see the module docstring).

    Parameters
    ----------
    cuda : module
        ``numba.cuda``.
    spec : TimeVaryingMonteCarloSpec
        The run.
    layout : str
        ``auto``, ``fused`` or ``sparse`` (:mod:`.gpu_run`).
    progress : callable(done, total) or None
        Called with path-steps done.

    Returns
    -------
    PartialStats
        Merged over the CPU's blocks.
    """
    sys_, grid = spec.system, spec.grid
    batch = batch_size(sys_)
    sched = Schedule.of(grid, spec.steps, batch)
    k_total = grid.n_steps
    # step k uses mode k − k0 of its batch [k0, k0 + batch): batches start at multiples
    sched = Schedule(
        grid, sched.ch, sched.cs, np.arange(k_total, dtype=np.int64) % batch, sched.stops,
        sched.checks, sched.saves,
    )  # fmt: skip
    first = batch_modes(sys_, grid.t[: min(batch, k_total)])
    run = DeviceRun(cuda, spec, first, sched, layout, 0)
    first_dev = run.dev

    def go(chunk, tick) -> None:
        run.dev = first_dev  # every chunk starts at step 0
        if not chunk.at(0):
            return
        k = 0
        for stop in sched.stops.tolist():
            if k % batch == 0 and k:  # a new batch: its matrices
                kb = min(batch, k_total - k)
                run.dev = batch_modes(sys_, grid.t[k : k + kb]).device(cuda)
            chunk.advance(k, stop)
            tick((stop - k) * chunk.p)
            k = stop
            if not chunk.at(k):
                return

    return run_chunks(run, spec, spec.block_paths, progress, go)


__all__ = ["batch_modes", "run_time_varying"]
