"""Execution engines: Monte Carlo blocks and sweep points as tasks, on this machine or on
a Dask cluster (``dask.distributed``).

:class:`LocalEngine` runs everything in this process (Monte Carlo blocks on the local
process pool of :func:`ntc_design.simulate.montecarlo.run`), with no cluster to start.
:class:`DaskEngine` submits the same work to a running scheduler (``dask scheduler``,
``dask worker ADDRESS``): one task per chunk of Monte Carlo blocks, or one task per sweep
point. What a task receives ships by value (the gain as its expression text, never a
lambda; see :class:`ntc_design.simulate.ExpressionGain`) and a spec is scattered once,
replicated on every worker, so a task carries only a reference and the loss of one worker
loses no input. Blocks keep their ``SeedSequence`` children and are merged in block order,
so the result is bit-identical on any number of workers and with any chunking. A worker
lost mid-run only makes the scheduler run its tasks elsewhere (``retries`` covers errors
raised inside a task as well).
"""

from __future__ import annotations

import queue
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ..errors import InputError, Option, optional_module
from ..simulate.montecarlo import MonteCarloSpec, PartialStats, merge, run, run_chunk
from ..simulate.options import check_workers

RETRIES = 3  # re-runs of a task that raised (a lost worker is re-scheduled regardless)
CONNECT_TIMEOUT = 30.0  # seconds to reach a scheduler (generous: a loaded scheduler is slow)
PROGRESS_EVERY = 0.5  # seconds between progress events sent by one task


#: glibc's mmap threshold in a Dask worker (bytes; glibc's largest, 32 MiB on 64 bits).
MMAP_THRESHOLD = 32 * 2**20
_heap_set: bool | None = None


def heap_allocations() -> bool:
    """Let glibc serve large allocations from the heap in this process (once).

    Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_`` set, which also pins
    glibc's mmap threshold at 128 KiB: every temporary vector of a big network (2.4 MB
    at Nd = 3·10⁵) is then a fresh ``mmap`` that page-faults on first touch, and an
    implicit run at 10⁵ agents took 2.3× as long as on the local process pool. The
    setting stays for the worker's later tasks (it only changes where glibc takes memory).

    Returns
    -------
    bool
        True when glibc accepted the threshold (False on other C libraries).
    """
    global _heap_set
    if _heap_set is None:
        import ctypes

        try:
            libc = ctypes.CDLL(None)
            _heap_set = bool(libc.mallopt(ctypes.c_int(-3), ctypes.c_int(MMAP_THRESHOLD)))
        except (
            OSError,
            AttributeError,
            TypeError,
        ):  # no mallopt (not glibc); CDLL(None) on Windows
            _heap_set = False
    return _heap_set


def _mc_chunk(spec: MonteCarloSpec, blocks: list[int]) -> list[PartialStats]:
    """One task: integrate some blocks with one BLAS thread (the workers are the
    parallelism), large temporaries from the heap (:func:`heap_allocations`)."""
    from threadpoolctl import threadpool_limits

    heap_allocations()
    with threadpool_limits(limits=1):
        return run_chunk(spec, blocks)


class TaskProgress:
    """A picklable progress callback for code running inside a Dask task: sends
    ``(key, done, total)`` to the client as a worker event on ``topic``, at most every
    :data:`PROGRESS_EVERY` seconds (and always when done == total)."""

    def __init__(self, topic: str, key: str):
        self.topic, self.key, self._last = topic, key, 0.0

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        if done < total and now - self._last < PROGRESS_EVERY:
            return
        self._last = now
        try:
            get_worker = optional_module("distributed", "cluster", "a Dask worker").get_worker
            get_worker().log_event(self.topic, (self.key, int(done), int(total)))
        except ValueError:  # not inside a worker: nobody to tell
            pass


class LocalEngine:
    """Everything on this machine: items one after the other in this process, Monte Carlo
    blocks on ``workers`` local processes (checked here: 0 used to become 2 silently, and
    a sweep ran every point into the same error)."""

    def __init__(self, workers: int | None = None):
        self.workers = None if workers is None else check_workers(workers, str(Option("workers")))

    def describe(self) -> dict:
        """What runs the work, for summaries.

        Returns
        -------
        dict
            ``engine`` ("local") and ``workers``.
        """
        return {"engine": "local", "workers": self.workers}

    def run_mc(self, spec: MonteCarloSpec, progress=None) -> PartialStats:
        """Every Monte Carlo block of ``spec`` on the local process pool.

        Parameters
        ----------
        spec : MonteCarloSpec
            The run.
        progress : callable(done, total), optional
            Called with path-steps done.

        Returns
        -------
        PartialStats
            Merged in block order.
        """
        return run(spec, workers=self.workers or 2, progress=progress)

    def map_unordered(
        self,
        fn: Callable,
        items: Sequence[tuple[str, tuple]],
        progress: Callable[[str, int, int], None] | None = None,
    ) -> Iterator[tuple[str, Any, BaseException | None]]:
        """Run ``fn(*args)`` for each ``(key, args)`` in order, in this process.

        Parameters
        ----------
        fn : callable
            Called as ``fn(*args, progress=..., remote=False)``.
        items : sequence of (str, tuple)
            Keys and arguments.
        progress : callable(key, done, total), optional
            Called as the items progress.

        Yields
        ------
        tuple
            ``(key, result, None)`` per item.
        """
        for key, args in items:

            def tick(done: int, total: int, key=key) -> None:
                if progress is not None:
                    progress(key, done, total)

            yield key, fn(*args, progress=tick, remote=False), None

    def scatter(self, obj):
        """Nothing to ship locally.

        Parameters
        ----------
        obj : Any
            Any object.

        Returns
        -------
        Any
            ``obj`` itself.
        """
        return obj

    def close(self) -> None:
        """Nothing to release."""
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class DaskEngine:
    """Tasks on a Dask cluster reached through ``client`` (see :meth:`connect`)."""

    def __init__(self, client, *, retries: int = RETRIES, blocks_per_chunk: int = 1, own=False):
        if retries < 0 or blocks_per_chunk < 1:
            raise InputError("retries must be >= 0 and blocks_per_chunk >= 1", field="engine")
        self.client, self.retries, self.blocks_per_chunk = client, retries, blocks_per_chunk
        self._own = own

    @classmethod
    def connect(cls, address: str, **kw) -> DaskEngine:
        """Connect to the scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

        Parameters
        ----------
        address : str
            The scheduler's address.
        **kw
            ``retries`` and ``blocks_per_chunk`` of the engine.

        Returns
        -------
        DaskEngine
            An engine that closes its client on :meth:`close`.

        Raises
        ------
        InputError
            When the address is malformed, no scheduler answers within
            :data:`CONNECT_TIMEOUT` seconds, or what answers is not a Dask scheduler.
        """
        Client = optional_module("distributed", "cluster", str(Option("scheduler"))).Client

        if not isinstance(address, str) or not address.strip() or len(address) > 1000:
            raise InputError(
                "expected an address such as tcp://127.0.0.1:8786", field="scheduler", option=True
            )
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT)
        except MemoryError:  # something answered, but not in Dask's protocol: its reply
            # was read as a frame length of exabytes
            raise InputError(
                f"{address} answered, but not as a Dask scheduler", field="scheduler", option=True
            ) from None
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            msg = str(exc).splitlines()[0] if str(exc) else exc.__class__.__name__
            raise InputError(
                f"cannot reach a Dask scheduler at {address} ({msg})",
                field="scheduler",
                option=True,
            ) from None
        return cls(client, own=True, **kw)

    @property
    def address(self) -> str:
        """The scheduler's address."""
        return self.client.scheduler.address

    def n_workers(self) -> int:
        """The number of workers connected now.

        Returns
        -------
        int
            The count reported by the scheduler.
        """
        return len(self.client.scheduler_info(n_workers=-1)["workers"])

    def describe(self) -> dict:
        """What runs the work, for summaries.

        Returns
        -------
        dict
            ``engine`` ("dask"), ``scheduler`` and ``workers``.
        """
        return {"engine": "dask", "scheduler": self.address, "workers": self.n_workers()}

    def scatter(self, obj):
        """Ship ``obj`` to the cluster once (a copy on every worker).

        Parameters
        ----------
        obj : Any
            A picklable object.

        Returns
        -------
        distributed.Future
            Pass it to tasks instead of the object.
        """
        return self.client.scatter(obj, broadcast=True, hash=False)

    def run_mc(self, spec: MonteCarloSpec, progress=None) -> PartialStats:
        """Every Monte Carlo block of ``spec`` as tasks (``blocks_per_chunk`` per task).

        Parameters
        ----------
        spec : MonteCarloSpec
            The run (scattered once).
        progress : callable(done, total), optional
            Called with path-steps done.

        Returns
        -------
        PartialStats
            Merged in block order: the same as a local run.
        """
        as_completed = optional_module(
            "distributed", "cluster", str(Option("scheduler"))
        ).as_completed

        blocks = list(range(spec.n_blocks))
        k = self.blocks_per_chunk
        chunks = [blocks[i : i + k] for i in range(0, len(blocks), k)]
        remote_spec = self.scatter(spec)
        tag = uuid.uuid4().hex[:12]
        futs = [
            self.client.submit(
                _mc_chunk, remote_spec, ch, key=f"ntc-mc-{tag}-{i}", retries=self.retries
            )
            for i, ch in enumerate(chunks)
        ]
        steps, total, done = spec.grid.n_steps, spec.paths * spec.grid.n_steps, 0
        parts: list[PartialStats] = []
        try:
            for fut in as_completed(futs):
                got = fut.result()
                parts += got
                done += sum(q.count for q in got) * steps
                if progress is not None:
                    progress(done, total)
        finally:
            self.client.cancel([*futs, remote_spec])
        return merge(parts)

    def map_unordered(
        self,
        fn: Callable,
        items: Sequence[tuple[str, tuple]],
        progress: Callable[[str, int, int], None] | None = None,
    ) -> Iterator[tuple[str, Any, BaseException | None]]:
        """Submit ``fn(*args)`` per ``(key, args)`` and yield results as tasks finish.

        Parameters
        ----------
        fn : callable
            Called on a worker as ``fn(*args, progress=TaskProgress(...), remote=True)``.
        items : sequence of (str, tuple)
            Keys and arguments.
        progress : callable(key, done, total), optional
            Called (in this thread) with the tasks' progress events.

        Yields
        ------
        tuple
            ``(key, result, None)``, or ``(key, None, error)`` when the cluster gave up on
            a task (e.g. its workers kept dying).
        """
        wait = optional_module("distributed", "cluster", str(Option("scheduler"))).wait

        topic = f"ntc-progress-{uuid.uuid4().hex[:12]}"
        events: queue.SimpleQueue = queue.SimpleQueue()
        if progress is not None:
            # the handler runs on the client's event loop: only queue the event there and
            # call ``progress`` from this thread
            self.client.subscribe_topic(topic, lambda ev: events.put(ev[1]))
        by_future = {}
        for key, args in items:
            fut = self.client.submit(
                fn,
                *args,
                progress=TaskProgress(topic, key),
                remote=True,
                key=f"ntc-{key}-{uuid.uuid4().hex[:8]}",
                retries=self.retries,
                pure=False,
            )
            by_future[fut] = key
        pending = set(by_future)
        try:
            while pending:
                try:
                    finished, pending = wait(
                        pending, timeout=PROGRESS_EVERY, return_when="FIRST_COMPLETED"
                    )
                except TimeoutError:
                    finished = set()
                while progress is not None and not events.empty():
                    progress(*events.get())
                for fut in sorted(finished, key=lambda f: f.key):
                    key = by_future[fut]
                    try:
                        got = fut.result()
                    except Exception as exc:  # noqa: BLE001 - the cluster's verdict on one task
                        yield key, None, exc
                    else:
                        yield key, got, None
                    fut.release()
        finally:
            self.client.cancel(list(pending))
            if progress is not None:
                self.client.unsubscribe_topic(topic)

    def close(self) -> None:
        """Close the client if this engine opened it."""
        if self._own:
            self.client.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def engine_for(scheduler: str | None, workers: int | None = None, **kw):
    """The engine for a ``--scheduler`` option.

    Parameters
    ----------
    scheduler : str or None
        A Dask scheduler's address, or None for this machine.
    workers : int, optional
        Local worker processes.
    **kw
        Options of :meth:`DaskEngine.connect`.

    Returns
    -------
    DaskEngine or LocalEngine
        Connected to ``scheduler``, or local.

    Raises
    ------
    InputError
        A bad number of workers, or a scheduler address that is malformed (an empty one
        too: it is not "no scheduler") or cannot be reached.
    """
    if scheduler is None:
        return LocalEngine(workers)
    if workers is not None:  # not used on a cluster, but not silently wrong either
        check_workers(workers, str(Option("workers")))
    return DaskEngine.connect(scheduler, **kw)
