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

**Normals.** The 128-layer ziggurat as in Doornik ("An improved ziggurat method to
generate normal random samples", 2005): one 64-bit word gives the layer (its low 7 bits)
and a 53-bit uniform (its high bits), accepted at once with probability 0.989; the base
layer's tail by Marsaglia's exponential method. The ``numpy`` generator (``rng: numpy``)
keeps NumPy's PCG64 streams for who needs them.
"""

from __future__ import annotations

import math

import numpy as np

GENERATORS = ("xoshiro", "numpy")

_C = 128
_R = 3.442619855899
_V = 9.91256303526217e-3


def _tables() -> tuple[np.ndarray, np.ndarray]:
    """Doornik's ZIGNOR tables: layer edges X (129) and ratios X[i+1]/X[i] (128), computed
    (what :data:`ZIG_X` was written from; a test compares them within a few ulps)."""
    x = np.zeros(_C + 1)
    f = math.exp(-0.5 * _R * _R)
    x[0] = _V / f
    x[1] = _R
    for i in range(2, _C):
        x[i] = math.sqrt(-2.0 * math.log(_V / x[i - 1] + f))
        f = math.exp(-0.5 * x[i] * x[i])
    x[_C] = 0.0
    return x, x[1:] / x[:-1]


# The layer edges as exact binary values (written once from _tables() with glibc's libm):
# the normals do not depend on another platform's last-bit differences in exp and log.
ZIG_X = np.array(
    [float.fromhex(h) for h in (
        "0x1.db4668fe7e4a4p+1",
        "0x1.b8a7c476d2be8p+1",
        "0x1.9c8e0c7c8098fp+1",
        "0x1.8aa73e440ffbcp+1",
        "0x1.7d45eb36eb842p+1",
        "0x1.7279dd4ac3f9dp+1",
        "0x1.695c2be68edc9p+1",
        "0x1.616dff7c8f54ap+1",
        "0x1.5a61edf7e8f32p+1",
        "0x1.54052012a04a4p+1",
        "0x1.4e3456b0e3a1bp+1",
        "0x1.48d61806d6010p+1",
        "0x1.43d75b60bca1dp+1",
        "0x1.3f29848d3b416p+1",
        "0x1.3ac11b8e206d6p+1",
        "0x1.3694f3a3740d9p+1",
        "0x1.329d9725e32f7p+1",
        "0x1.2ed4df8099571p+1",
        "0x1.2b35aa5ebee3ep+1",
        "0x1.27bba2b5dbc92p+1",
        "0x1.246317a6b53c0p+1",
        "0x1.2128dd36bdf09p+1",
        "0x1.1e0a342cf08f6p+1",
        "0x1.1b04b731f6bccp+1",
        "0x1.18164be0c1c39p+1",
        "0x1.153d16d45743dp+1",
        "0x1.12777201834f3p+1",
        "0x1.0fc3e4d95f278p+1",
        "0x1.0d211dd28b00fp+1",
        "0x1.0a8ded0ec371ap+1",
        "0x1.08093fe3e40e1p+1",
        "0x1.05921d1c4d769p+1",
        "0x1.0327a1cc4cf5ep+1",
        "0x1.00c8fea1720d4p+1",
        "0x1.fceaeb2ca5f17p+0",
        "0x1.f858aff31cbf0p+0",
        "0x1.f3da097460823p+0",
        "0x1.ef6dcddc7d392p+0",
        "0x1.eb12e91486bbcp+0",
        "0x1.e6c85a849b015p+0",
        "0x1.e28d331c6723cp+0",
        "0x1.de609397e09b9p+0",
        "0x1.da41aaf79a344p+0",
        "0x1.d62fb52580b86p+0",
        "0x1.d229f9bfeefdbp+0",
        "0x1.ce2fcb05f8c34p+0",
        "0x1.ca4084e091e34p+0",
        "0x1.c65b8c04dbac2p+0",
        "0x1.c2804d2c6b16fp+0",
        "0x1.beae3c60cd0e4p+0",
        "0x1.bae4d457ee119p+0",
        "0x1.b72395df5b73bp+0",
        "0x1.b36a075498d64p+0",
        "0x1.afb7b428fe7a1p+0",
        "0x1.ac0c2c6fc6382p+0",
        "0x1.a867047516e4fp+0",
        "0x1.a4c7d45d01a31p+0",
        "0x1.a12e37c983369p+0",
        "0x1.9d99cd86b58b4p+0",
        "0x1.9a0a373c73f21p+0",
        "0x1.967f1924c7b06p+0",
        "0x1.92f819c682bf5p+0",
        "0x1.8f74e1b37c6b8p+0",
        "0x1.8bf51b49ef337p+0",
        "0x1.88787278810a6p+0",
        "0x1.84fe9484873b9p+0",
        "0x1.81872fd21db73p+0",
        "0x1.7e11f3adaeb92p+0",
        "0x1.7a9e90168b8eep+0",
        "0x1.772cb58a39dd6p+0",
        "0x1.73bc14d01a2c9p+0",
        "0x1.704c5ec50cb81p+0",
        "0x1.6cdd4426b88a5p+0",
        "0x1.696e755e16b84p+0",
        "0x1.65ffa248e016dp+0",
        "0x1.62907a0176ebfp+0",
        "0x1.5f20aaa4dfc1ap+0",
        "0x1.5bafe11654817p+0",
        "0x1.583dc8bff3219p+0",
        "0x1.54ca0b4ffd349p+0",
        "0x1.515450720f455p+0",
        "0x1.4ddc3d83a5b84p+0",
        "0x1.4a617543306ccp+0",
        "0x1.46e39778de063p+0",
        "0x1.436240982ad9dp+0",
        "0x1.3fdd09591d2a4p+0",
        "0x1.3c538647ef792p+0",
        "0x1.38c54749b9033p+0",
        "0x1.3531d7146a43ep+0",
        "0x1.3198ba982d911p+0",
        "0x1.2df97057e7efbp+0",
        "0x1.2a536fae30e33p+0",
        "0x1.26a627fb9d120p+0",
        "0x1.22f0ffbaa1e55p+0",
        "0x1.1f335374a10f8p+0",
        "0x1.1b6c7492c9735p+0",
        "0x1.179ba80463fecp+0",
        "0x1.13c024b2c7ec6p+0",
        "0x1.0fd911b97f236p+0",
        "0x1.0be58456ff4aep+0",
        "0x1.07e47d87a40f6p+0",
        "0x1.03d4e7391c5b7p+0",
        "0x1.ff6b21fffe31ap-1",
        "0x1.f70a5866c8f46p-1",
        "0x1.ee848e956826fp-1",
        "0x1.e5d6909f51b6ap-1",
        "0x1.dcfccc51c59f0p-1",
        "0x1.d3f340dda611cp-1",
        "0x1.cab56ac6a38d3p-1",
        "0x1.c13e2b014e85cp-1",
        "0x1.b787a7c516f3bp-1",
        "0x1.ad8b2506a137cp-1",
        "0x1.a340d1baf5b18p-1",
        "0x1.989f85c753b2cp-1",
        "0x1.8d9c6a9d35e3dp-1",
        "0x1.822a858af0e7dp-1",
        "0x1.763a1600eec74p-1",
        "0x1.69b7b213f3f69p-1",
        "0x1.5c8afdbf0217bp-1",
        "0x1.4e94c08c0bab7p-1",
        "0x1.3fabee1911cd7p-1",
        "0x1.2f98d6bb4f41fp-1",
        "0x1.1e0ce6b5969b3p-1",
        "0x1.0a936da5e55adp-1",
        "0x1.e8e576e43fbefp-2",
        "0x1.b4c8fece48e83p-2",
        "0x1.73949184db9dfp-2",
        "0x1.16db47e193e1ap-2",
        "0x0.0p+0"
    )]
)  # fmt: skip
ZIG_R = ZIG_X[1:] / ZIG_X[:-1]

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
            from .kernels import fill_normals  # numba: only when drawing

            fill_normals(self.states, out, ZIG_X, ZIG_R)


__all__ = ["GENERATORS", "ZIG_R", "ZIG_X", "NormalSource", "normals", "path_states"]
