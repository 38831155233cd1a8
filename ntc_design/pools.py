"""A worker pool started ahead of need, handed to the run that can use it.

``ntc simulate`` forks its Monte Carlo workers before it imports SciPy and designs the
protocol, and each worker loads Numba's compiled kernel while the parent is busy
(:mod:`ntc_design.warmup`): on two cores the kernel's 0.3-0.6 s of loading then overlaps
the parent's work instead of preceding the run. The pool waits here until
:func:`ntc_design.simulate.montecarlo.run` takes it (same number of workers, a picklable run);
otherwise :func:`close` stops it at exit. Nothing here imports the layers above.
"""

from __future__ import annotations

from typing import Any

_POOL: dict[str, Any] = {}


def offer(executor: Any, workers: int, counter: Any) -> None:
    """Leave a started pool for the next run.

    Parameters
    ----------
    executor : concurrent.futures.ProcessPoolExecutor
        The pool, its processes started.
    workers : int
        Its processes.
    counter : multiprocessing.Value
        The shared progress counter its workers inherited.
    """
    close()
    _POOL.update(executor=executor, workers=workers, counter=counter)


def take(workers: int) -> tuple[Any, Any] | None:
    """The waiting pool and its counter when it has ``workers`` processes (then it is the
    caller's), else None.

    Parameters
    ----------
    workers : int
        Processes wanted.

    Returns
    -------
    (ProcessPoolExecutor, multiprocessing.Value) or None
    """
    if _POOL.get("workers") != workers:
        return None
    ex, counter = _POOL.pop("executor"), _POOL.pop("counter")
    _POOL.clear()
    return ex, counter


def close() -> None:
    """Stop a pool nobody took (its workers only warmed up): now, not after their warm-up."""
    ex = _POOL.pop("executor", None)
    _POOL.clear()
    if ex is None:
        return
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=2)


__all__ = ["close", "offer", "take"]
