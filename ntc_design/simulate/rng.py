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

**Normals.** The 128-layer ziggurat as in Doornik ("An improved ziggurat method to
generate normal random samples", 2005): one 64-bit word gives the layer (its low 7 bits)
and a 53-bit uniform (its high bits), accepted at once with probability 0.989; the base
layer's tail by Marsaglia's exponential method. The ``numpy`` generator (``rng: numpy``)
keeps NumPy's PCG64 streams for who needs them.
"""

from __future__ import annotations

import math

import numpy as np

from ..linalg import numba_cache_dir

numba_cache_dir()  # before Numba reads its configuration
import numba  # noqa: E402

GENERATORS = ("xoshiro", "numpy")

_C = 128
_R = 3.442619855899
_V = 9.91256303526217e-3


def _tables() -> tuple[np.ndarray, np.ndarray]:
    """Doornik's ZIGNOR tables: layer edges X (129) and ratios X[i+1]/X[i] (128)."""
    x = np.zeros(_C + 1)
    f = math.exp(-0.5 * _R * _R)
    x[0] = _V / f
    x[1] = _R
    for i in range(2, _C):
        x[i] = math.sqrt(-2.0 * math.log(_V / x[i - 1] + f))
        f = math.exp(-0.5 * x[i] * x[i])
    x[_C] = 0.0
    return x, x[1:] / x[:-1]


ZIG_X, ZIG_R = _tables()
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


@numba.njit
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@numba.njit
def _next(s0, s1, s2, s3):
    """xoshiro256**: (word, new state), the state in four locals (registers)."""
    result = _rotl(s1 * np.uint64(5), 7) * np.uint64(9)
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    return result, s0, s1, s2, s3


_TO_UNIT = 1.0 / 9007199254740992.0  # 2⁻⁵³


@numba.njit
def _unit(w):
    """The top 53 bits of ``w`` as a double in [0, 1): converted through int64, which is
    one instruction (uint64 to double is several, and was 5x slower here)."""
    return np.int64(w >> np.uint64(11)) * _TO_UNIT


@numba.njit
def _slow(i, u, s0, s1, s2, s3, zx):
    """The ziggurat's rare branches (about 1 % of draws), kept out of the hot loop: the
    base layer's tail beyond R, or the wedge test of layer i. Returns (done, z, state)."""
    if i == 0:
        while True:
            w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            a = math.log(_unit(w) + 0.5 * _TO_UNIT) / zx[1]
            w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            b = math.log(_unit(w) + 0.5 * _TO_UNIT)
            if -2.0 * b >= a * a:
                return True, (a - zx[1] if u < 0 else zx[1] - a), s0, s1, s2, s3
    x = u * zx[i]
    f0 = math.exp(-0.5 * (zx[i] * zx[i] - x * x))
    f1 = math.exp(-0.5 * (zx[i + 1] * zx[i + 1] - x * x))
    w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    return f1 + _unit(w) * (f0 - f1) < 1.0, x, s0, s1, s2, s3


@numba.njit
def ziggurat_slow(i, u, s0, s1, s2, s3, zx, zr):
    """The draw after the fast test failed for word (layer ``i``, uniform ``u``): the tail
    or the wedge, then new words until one is accepted. Returns (z, state)."""
    while True:
        done, z, s0, s1, s2, s3 = _slow(i, u, s0, s1, s2, s3, zx)
        if done:
            return z, s0, s1, s2, s3
        w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        i = np.int64(w & np.uint64(127))
        u = 2.0 * _unit(w) - 1.0
        if abs(u) < zr[i]:
            return u * zx[i], s0, s1, s2, s3


# The hot path (xoshiro256** step, layer, fast acceptance) is written out in the two loops
# that draw (here and kernels.em_steps_rng): as a called function returning its state
# Numba ran it 4x slower. tests/test_rng.py checks both give the same numbers.


@numba.njit(cache=True, nogil=True)
def fill_normals(states, out, zx, zr):
    """``out[k, q, e]``: path q's normals in its stream order (step k, then e), for the
    kernels that take the normals as an array (the callable-f step, the implicit scheme,
    the time-varying path). The same numbers as the fused kernel
    :func:`ntc_design.simulate.kernels.em_steps_rng` draws.

    Parameters
    ----------
    states : numpy.ndarray
        (p, 4) uint64, updated in place.
    out : numpy.ndarray
        (K, p, m) float64, filled.
    zx, zr : numpy.ndarray
        :data:`ZIG_X`, :data:`ZIG_R`.
    """
    kk, p, m = out.shape
    for q in range(p):
        s0, s1, s2, s3 = states[q, 0], states[q, 1], states[q, 2], states[q, 3]
        for k in range(kk):
            for e in range(m):
                s5 = s1 * np.uint64(5)
                w = ((s5 << np.uint64(7)) | (s5 >> np.uint64(57))) * np.uint64(9)
                t = s1 << np.uint64(17)
                s2 ^= s0
                s3 ^= s1
                s1 ^= s2
                s0 ^= s3
                s2 ^= t
                s3 = (s3 << np.uint64(45)) | (s3 >> np.uint64(19))
                i = np.int64(w & np.uint64(127))
                u = 2.0 * (np.int64(w >> np.uint64(11)) * _TO_UNIT) - 1.0
                if abs(u) < zr[i]:
                    out[k, q, e] = u * zx[i]
                else:
                    out[k, q, e], s0, s1, s2, s3 = ziggurat_slow(i, u, s0, s1, s2, s3, zx, zr)
        states[q, 0], states[q, 1], states[q, 2], states[q, 3] = s0, s1, s2, s3


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
    out = np.empty((1, states.shape[0], count))
    fill_normals(states, out, ZIG_X, ZIG_R)
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
            fill_normals(self.states, out, ZIG_X, ZIG_R)


__all__ = [
    "GENERATORS",
    "ZIG_R",
    "ZIG_X",
    "NormalSource",
    "fill_normals",
    "normals",
    "path_states",
    "ziggurat_slow",
]
