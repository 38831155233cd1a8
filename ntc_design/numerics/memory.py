"""The memory every size check assumes: ``NTC_AVAILABLE_MEMORY`` when it is set (so a
check gives the same answer on every machine), else what the machine has free; never more
than the process may still map under its own limit (``ulimit -v``, RLIMIT_AS). The
simulation budget, the network generator, the table readers and the number of parallel
proofs (:func:`ntc_design.numerics.linalg.proof_workers`) read it here."""

from __future__ import annotations

import math
import os
import re

from ..errors import InputError

MEMORY_ENV = "NTC_AVAILABLE_MEMORY"  # set: the memory every size check assumes (bytes)
_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def available_memory() -> float:
    """Memory available now: the value of the environment variable ``NTC_AVAILABLE_MEMORY``
    when it is set (bytes, or with a binary suffix: ``8G``, ``512M``), so that the size
    checks give the same answer on every machine (the test suite sets it: an 8 GB laptop
    and a 64 GB server refuse the same runs); else MemAvailable from /proc/meminfo. Either
    way no more than the process's own limit leaves (:func:`address_space_left`): under
    ``ulimit -v 4G`` a run that needs 5 GB is refused, not killed half-way.

    Returns
    -------
    float
        Bytes: the smaller of the address space left under RLIMIT_AS and the
        environment's value, else MemAvailable, else the physical memory from os.sysconf,
        else 4 GiB.

    Raises
    ------
    InputError
        ``NTC_AVAILABLE_MEMORY`` is not a positive size.
    """
    return min(_machine_memory(), address_space_left())


def address_space_left() -> float:
    """What the process may still map under its soft RLIMIT_AS (``ulimit -v``): the limit
    less the address space it holds now (VmSize), at least one byte; infinity without a
    limit (or where the platform has none).

    Returns
    -------
    float
        Bytes.
    """
    try:
        import resource  # POSIX only
    except ImportError:  # pragma: no cover - Windows
        return math.inf
    try:
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ValueError, OSError):  # pragma: no cover - a platform without RLIMIT_AS
        return math.inf
    if soft == resource.RLIM_INFINITY or soft < 0:
        return math.inf
    return max(float(soft) - _address_space_used(), 1.0)


def _address_space_used() -> float:
    """VmSize of this process (what RLIMIT_AS counts), 0 where /proc does not say."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmSize:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return 0.0


def _machine_memory() -> float:
    """The pinned size, else what the machine has free (see :func:`available_memory`)."""
    pinned = os.environ.get(MEMORY_ENV)
    if pinned is not None:
        m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]+)?)\s*([KMGT]?)(?:i?B)?\s*", pinned, re.I)
        value = float(m.group(1)) * _UNITS[m.group(2).upper()] if m else 0.0
        if not value > 0 or not math.isfinite(value):
            raise InputError(
                f"expected a positive size such as 8G or 8589934592, got {pinned[:40]!r}",
                field=MEMORY_ENV,
            )
        return value
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 4.0 * 2**30


__all__ = ["MEMORY_ENV", "address_space_left", "available_memory"]
