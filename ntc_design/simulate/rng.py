"""Normals for Monte Carlo, drawn in compiled code: one xoshiro256** stream per path and
the ziggurat method.

**Streams.** Block b of a run (:mod:`.montecarlo`) seeds its p paths from
``SeedSequence(seed, spawn_key=(b,)).generate_state(4·p, uint64)``: path q of the block
takes words 4q … 4q+3 as its xoshiro256** state (an all-zero state, probability 2⁻²⁵⁶, is
replaced by a fixed non-zero one). A path draws its normals in step order, 2·E per step
(E additive, then E multiplicative, as the NumPy stream is laid out), so a path's noise
depends only on (seed, block_paths, its index): not on the tile of paths the kernel
integrates together, the batch of steps, the workers or the machine.

**Generator.** xoshiro256** (Blackman & Vigna, "Scrambled linear pseudorandom number
generators", ACM TOMS 47(4), 2021): 256 bits of state, period 2²⁵⁶ − 1, passes BigCrush;
one 64-bit word is a few integer operations. Paths' streams start at independent
SeedSequence outputs (overlap probability for 10⁹ paths of 10¹² draws: < 2⁻¹⁵⁰).

The compiled code (the generator, the ziggurat, the fused kernel) is in
:mod:`.kernels`, one file, so that Numba's cache of the kernel is rebuilt whenever any of
it changes.

**Normals.** The ziggurat, its tables in :mod:`.ziggurat`. The ``numpy``
generator (``rng: numpy``) keeps NumPy's PCG64 streams for who needs them.
"""

from __future__ import annotations

import numpy as np

from ..choices import Rng, choices
from .ziggurat import ZIG_R, ZIG_X

GENERATORS = choices(Rng)


_NONZERO = np.array(
    [0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB, 0x2545F4914F6CDD1D],
    dtype=np.uint64,
)


def path_states(seed: int, block: int, p: int) -> np.ndarray:
    """The xoshiro256** states of block ``block``'s ``p`` paths (see the module docstring).

    Parameters
    ----------
    seed : int
        The run's seed.
    block : int
        The block index.
    p : int
        Paths in the block.

    Returns
    -------
    numpy.ndarray
        (p, 4) uint64, one state per path.
    """
    words = np.random.SeedSequence(seed, spawn_key=(block,)).generate_state(4 * p, np.uint64)
    st = words.reshape(p, 4).copy()
    zero = ~st.any(axis=1)
    st[zero] = _NONZERO
    return st


def normals(states: np.ndarray, count: int) -> np.ndarray:
    """The next ``count`` normals of each path's stream, (p, count) (for tests and for
    whoever wants the streams themselves).

    Parameters
    ----------
    states : numpy.ndarray
        (p, 4) uint64, advanced in place.
    count : int
        Normals per path.

    Returns
    -------
    numpy.ndarray
    """
    from .kernels import fill_normals  # numba: only when drawing

    out = np.empty((1, states.shape[0], count))
    fill_normals(states, out)
    return out[0]


class NormalSource:
    """Block ``b``'s normals: ``fill(out)`` fills (K, p, m) in each path's stream order,
    continuing where the last call stopped; ``states`` is the xoshiro state the fused
    kernel draws from (None for NumPy's generator)."""

    def __init__(self, generator: str, seed: int, block: int, p: int):
        if generator not in GENERATORS:
            raise ValueError(f"generator: {generator!r} is not one of {GENERATORS}")
        self.generator = generator
        if generator == "numpy":
            self.states = None
            self._rng = np.random.Generator(
                np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(block,)))
            )
        else:
            self.states = path_states(seed, block, p)

    def fill(self, out: np.ndarray) -> None:
        """Fill ``out`` (K, p, m) with the next K steps' normals of every path.

        Parameters
        ----------
        out : numpy.ndarray
            Filled in place.
        """
        if self.states is None:
            self._rng.standard_normal(out=out)
        else:
            from .kernels import fill_normals  # numba: only when drawing

            fill_normals(self.states, out)


__all__ = ["GENERATORS", "ZIG_R", "ZIG_X", "NormalSource", "normals", "path_states"]
