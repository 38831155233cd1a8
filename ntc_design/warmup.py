"""Start the Monte Carlo workers early and warm them (see :mod:`ntc_design.pools`)."""

from __future__ import annotations

import multiprocessing as mp
import os
from concurrent.futures import ProcessPoolExecutor

from . import pools


def _warm(counter) -> None:  # runs in each worker as it starts
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    from .simulate.montecarlo import warm_worker

    warm_worker(counter)


def _ready() -> int:
    return os.getpid()


def start_workers(workers: int | None = None) -> None:
    """Fork ``workers`` processes now (default: 2, at most the CPUs), each loading the
    compiled kernel, and offer them to the next Monte Carlo run.

    Parameters
    ----------
    workers : int, optional
        Processes.
    """
    n = min(workers or 2, os.cpu_count() or 1)
    if n <= 1 or "fork" not in mp.get_all_start_methods():
        return
    ctx = mp.get_context("fork")
    counter = ctx.Value("q", 0)  # inherited by the workers, read by the parent
    ex = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_warm, initargs=(counter,))
    ex.submit(_ready)  # a fork pool starts all its processes at the first task
    pools.offer(ex, n, counter)


__all__ = ["start_workers"]
