"""A(t) given as expressions on the GPU: Lemma 1 and the weights are evaluated on the host
for each batch of steps, as the CPU does (:class:`.timevarying.ExpressionModes`: batched
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
from .montecarlo import MonteCarloSpec, PartialStats
from .timevarying import ExpressionModes, TimeVaryingSystem, batch_size


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
    parts = ExpressionModes(sys_).step_arrays(ts)
    return ModeArrays.build(parts, st.n, st.d)


def run_time_varying(cuda, spec: MonteCarloSpec, layout: str, progress) -> PartialStats:
    """Every path of an A(t) run on the GPU (see the module docstring).

    Parameters
    ----------
    cuda : module
        ``numba.cuda``.
    spec : MonteCarloSpec
        The run (its modes :class:`.timevarying.ExpressionModes`).
    layout : str
        ``auto``, ``fused`` or ``sparse`` (:mod:`.gpu_run`).
    progress : callable(done, total) or None
        Called with path-steps done.

    Returns
    -------
    PartialStats
        Merged over the CPU's blocks.
    """
    assert isinstance(spec.modes, ExpressionModes), "an A(t) run"
    sys_, grid = spec.modes.system, spec.grid
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
