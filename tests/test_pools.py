"""ntc_design.pools: a pool started ahead is handed over only for its own size, and one that
nobody takes is stopped at once (not after its workers' warm-up)."""

import multiprocessing as mp
import os
import time
from concurrent.futures import ProcessPoolExecutor

import pytest

from ntc_design import pools


def _slow_start() -> None:
    time.sleep(30)  # a warm-up that would hold an orderly shutdown for half a minute


@pytest.mark.skipif("fork" not in mp.get_all_start_methods(), reason="needs fork")
def test_take_matches_the_size_and_close_stops_the_workers_now():
    ctx = mp.get_context("fork")
    ex = ProcessPoolExecutor(max_workers=2, mp_context=ctx, initializer=_slow_start)
    ex.submit(os.getpid)  # starts both processes
    deadline = time.monotonic() + 20
    while len(ex._processes) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    procs = list(ex._processes.values())
    assert len(procs) == 2 and all(p.is_alive() for p in procs)
    counter = ctx.Value("q", 0)
    pools.offer(ex, 2, counter)
    assert pools.take(3) is None  # another size: still waiting
    assert pools.take(2) == (ex, counter)
    assert pools.take(2) is None  # taken once
    pools.offer(ex, 2, counter)
    t0 = time.monotonic()
    pools.close()
    assert time.monotonic() - t0 < 10 and not any(p.is_alive() for p in procs)
    pools.close()  # nothing left: a no-op
