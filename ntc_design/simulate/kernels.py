"""Compiled Euler–Maruyama steps on the edge list (numba), and the NumPy/SciPy step used
for a callable f.

A path-step costs O(nnz(L_B) + E·d²): the drift is a CSR product with L_B, the noise a
loop over the edges (gather x_j − x_i, one d×d product with K_e, scatter into agent i).
:func:`em_steps_rng` draws the normals itself from each path's xoshiro256** stream
(:mod:`.rng`, the default); :func:`em_steps` takes them as an array (NumPy's generator,
``rng: numpy``). Either way a path's normals depend only on its stream, whatever the kernel.
Paths are independent: a tile of paths is transposed to (Nd, tile) and run through all
steps of a run, so every inner loop runs over the tile's paths (SIMD) and the tile's
state stays in the cache. One thread: the worker processes are the
parallelism (and the results do not depend on their number).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.linalg import numba_cache_dir

numba_cache_dir()  # before Numba reads its configuration: not into site-packages
import hashlib  # noqa: E402
import math  # noqa: E402

import numba  # noqa: E402

from .ziggurat import LAYERS, ZIG_R, ZIG_X  # noqa: E402

# -- the generator of .rng: xoshiro256** and Doornik's ziggurat -------------------------

# The tables as module globals: Numba freezes a global array into the compiled code as a
# constant, and only then does LLVM vectorise the table lookups across paths (with an
# argument array it cannot rule out that the stores alias the table, and keeps the loop
# scalar: 4-6x slower). Numba's cache does not see a change to a frozen global, so the
# import below checks the tables against the digest written here (a changed table fails
# loudly instead of running a stale kernel).
_ZX = ZIG_X.copy()
_ZR = ZIG_R.copy()
_MASK = np.uint64(LAYERS - 1)  # the word's low bits: the layer
if hashlib.sha256(_ZX.tobytes()).hexdigest()[:16] != "9a7bfc00fed5c342":  # pragma: no cover
    raise RuntimeError("rng.ZIG_X changed: update the digest in kernels.py")


@numba.njit(error_model="numpy")
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@numba.njit(error_model="numpy")
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


TO_UNIT = 1.0 / 9007199254740992.0  # 2⁻⁵³


@numba.njit(error_model="numpy")
def _unit(w):
    """The top 53 bits of ``w`` as a double in [0, 1): converted through int64, which is
    one instruction (uint64 to double is several, and was 5x slower here)."""
    return np.int64(w >> np.uint64(11)) * TO_UNIT


@numba.njit(error_model="numpy")
def _slow(i, u, s0, s1, s2, s3):
    """The ziggurat's rare branches (about 1 % of draws), kept out of the hot loop: the
    base layer's tail beyond R, or the wedge test of layer i. Returns (done, z, state)."""
    if i == 0:
        while True:
            w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            a = math.log(_unit(w) + 0.5 * TO_UNIT) / _ZX[1]
            w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            b = math.log(_unit(w) + 0.5 * TO_UNIT)
            if -2.0 * b >= a * a:
                return True, (a - _ZX[1] if u < 0 else _ZX[1] - a), s0, s1, s2, s3
    x = u * _ZX[i]
    f0 = math.exp(-0.5 * (_ZX[i] * _ZX[i] - x * x))
    f1 = math.exp(-0.5 * (_ZX[i + 1] * _ZX[i + 1] - x * x))
    w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    return f1 + _unit(w) * (f0 - f1) < 1.0, x, s0, s1, s2, s3


@numba.njit(error_model="numpy")
def ziggurat_slow(i, u, s0, s1, s2, s3):
    """The draw after the fast test failed for word (layer ``i``, uniform ``u``): the tail
    or the wedge, then new words until one is accepted. Returns (z, state)."""
    while True:
        done, z, s0, s1, s2, s3 = _slow(i, u, s0, s1, s2, s3)
        if done:
            return z, s0, s1, s2, s3
        w, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        i = np.int64(w & _MASK)
        u = 2.0 * _unit(w) - 1.0
        if abs(u) < _ZR[i]:
            return u * _ZX[i], s0, s1, s2, s3


@numba.njit(nogil=True, error_model="numpy")
def draw_lanes(s0, s1, s2, s3, zt, wl, c2, m):
    """The next ``m`` normals of each lane's stream (lane q's state in s0[q] … s3[q]),
    scaled, into the first ``m`` rows of ``zt``: ``zt[e, q] = c2 · z``. One pass over
    the lanes per normal, xoshiro256** and the ziggurat's fast test with no branch (it
    vectorises across lanes); then, if any lane failed the fast test (for 128 lanes two
    passes in five), that lane's tail or wedge from the same stream, at once: each lane's
    words are consumed in the same order as :func:`fill_normals` consumes them. Shared by
    the kernels here and the lossy kernel (:mod:`.loss_kernels`), which draws its arrivals
    after the normals from the same stream.

    Parameters
    ----------
    s0, s1, s2, s3 : numpy.ndarray
        (lanes,) uint64: the four words of each lane's xoshiro256** state, updated.
    zt : numpy.ndarray
        (>= m, lanes) float64: the normals, written.
    wl : numpy.ndarray
        (lanes,) uint64: scratch (each lane's last word).
    c2 : float
        The scale (1.0: the normals themselves, to the bit).
    m : int
        Normals per lane.
    """
    w = s0.size
    for e in range(m):
        nb = np.int64(0)
        for q in range(w):
            a0, a1, a2, a3 = s0[q], s1[q], s2[q], s3[q]
            a5 = a1 * np.uint64(5)
            wd = ((a5 << np.uint64(7)) | (a5 >> np.uint64(57))) * np.uint64(9)
            t = a1 << np.uint64(17)
            a2 ^= a0
            a3 ^= a1
            a1 ^= a2
            a0 ^= a3
            a2 ^= t
            s0[q], s1[q], s2[q] = a0, a1, a2
            s3[q] = (a3 << np.uint64(45)) | (a3 >> np.uint64(19))
            li = np.int64(wd & _MASK)
            uu = 2.0 * (np.int64(wd >> np.uint64(11)) * TO_UNIT) - 1.0
            wl[q] = wd
            nb += np.int64(abs(uu) >= _ZR[li])
            zt[e, q] = c2 * (uu * _ZX[li])
        if nb:
            for q in range(w):
                wd = wl[q]
                li = np.int64(wd & _MASK)
                uu = 2.0 * (np.int64(wd >> np.uint64(11)) * TO_UNIT) - 1.0
                if abs(uu) >= _ZR[li]:
                    z, s0[q], s1[q], s2[q], s3[q] = ziggurat_slow(
                        li, uu, s0[q], s1[q], s2[q], s3[q]
                    )
                    zt[e, q] = c2 * z


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fill_normals(states, out):
    """``out[k, q, e]``: path q's normals in its stream order (step k, then e), for the
    kernels that take the normals as an array (the callable-f step, the implicit scheme,
    the time-varying path). The same numbers as the fused kernel
    :func:`em_steps_rng` draws.

    Parameters
    ----------
    states : numpy.ndarray
        (p, 4) uint64, updated in place.
    out : numpy.ndarray
        (K, p, m) float64, filled.
    """
    kk, p, m = out.shape
    lanes = 64
    for q0 in range(0, p, lanes):
        w = min(lanes, p - q0)
        st = np.empty((4, w), dtype=np.uint64)
        for q in range(w):
            for c in range(4):
                st[c, q] = states[q0 + q, c]
        zt = np.empty((m, w))
        wl = np.empty(w, dtype=np.uint64)
        for k in range(kk):
            draw_lanes(st[0], st[1], st[2], st[3], zt, wl, 1.0, zt.shape[0])
            for q in range(w):
                for e in range(m):
                    out[k, q0 + q, e] = zt[e, q]
        for q in range(w):
            for c in range(4):
                states[q0 + q, c] = st[c, q]


TILE_BYTES = 3 * 2**19  # a tile's state and increments (2·Nd·tile doubles) within this
TILE_MIN, TILE_MAX = 16, 128  # paths per tile: wide enough for SIMD, small enough for L1/L2


def tile_width(p: int, nd: int) -> int:
    """Paths integrated together (their states side by side, so the inner loops run over
    paths and vectorise). The result does not depend on it: every path's arithmetic is
    the same.

    Parameters
    ----------
    p : int
        Paths in the block.
    nd : int
        N·d.

    Returns
    -------
    int
        The tile width, between 1 and p.
    """
    return int(max(1, min(p, TILE_MAX, max(TILE_MIN, TILE_BYTES // (16 * max(nd, 1))))))


@numba.njit(nogil=True, error_model="numpy")
def _drift_noise_d3(xt, off, dx, zt, c1, bptr, bind, bdata, u, src, dst, kmat, gvec, drift):
    """dx = c1·(u − L_B x) + Σ_e (g_e ξ1_e + K_e (x_j − x_i) ξ2_e) for d = 3, on a tile,
    with x the rows ``off`` … ``off`` + Nd − 1 of ``xt``: L_B by 3×3 blocks (block-CSR
    bptr, bind, bdata), one pass over the tile per block and per edge. The rows are
    indexed from ``off``, not sliced: a slice of ``xt`` is a non-contiguous array to Numba,
    whose strided loads kept these loops scalar (the delay ring's view made G1's kernel
    1.7x slower)."""
    nd, w = dx.shape
    ne = src.size
    for i in range(nd // 3):
        r = 3 * i
        u0, u1, u2 = c1 * u[r], c1 * u[r + 1], c1 * u[r + 2]
        for q in range(w):
            dx[r, q] = u0
            dx[r + 1, q] = u1
            dx[r + 2, q] = u2
        if not drift:
            continue
        for bb in range(bptr[i], bptr[i + 1]):
            jo = off + 3 * bind[bb]
            l00, l01, l02 = c1 * bdata[bb, 0, 0], c1 * bdata[bb, 0, 1], c1 * bdata[bb, 0, 2]
            l10, l11, l12 = c1 * bdata[bb, 1, 0], c1 * bdata[bb, 1, 1], c1 * bdata[bb, 1, 2]
            l20, l21, l22 = c1 * bdata[bb, 2, 0], c1 * bdata[bb, 2, 1], c1 * bdata[bb, 2, 2]
            for q in range(w):
                y0, y1, y2 = xt[jo, q], xt[jo + 1, q], xt[jo + 2, q]
                dx[r, q] -= l00 * y0 + l01 * y1 + l02 * y2
                dx[r + 1, q] -= l10 * y0 + l11 * y1 + l12 * y2
                dx[r + 2, q] -= l20 * y0 + l21 * y1 + l22 * y2
    for e in range(ne):
        io, jo = 3 * dst[e], off + 3 * src[e]
        xo = off + io
        k00, k01, k02 = kmat[e, 0, 0], kmat[e, 0, 1], kmat[e, 0, 2]
        k10, k11, k12 = kmat[e, 1, 0], kmat[e, 1, 1], kmat[e, 1, 2]
        k20, k21, k22 = kmat[e, 2, 0], kmat[e, 2, 1], kmat[e, 2, 2]
        g0, g1, g2 = gvec[e, 0], gvec[e, 1], gvec[e, 2]
        for q in range(w):
            d0 = xt[jo, q] - xt[xo, q]
            d1 = xt[jo + 1, q] - xt[xo + 1, q]
            d2 = xt[jo + 2, q] - xt[xo + 2, q]
            z1, z2 = zt[e, q], zt[ne + e, q]
            dx[io, q] += g0 * z1 + (k00 * d0 + k01 * d1 + k02 * d2) * z2
            dx[io + 1, q] += g1 * z1 + (k10 * d0 + k11 * d1 + k12 * d2) * z2
            dx[io + 2, q] += g2 * z1 + (k20 * d0 + k21 * d1 + k22 * d2) * z2


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _em_core(
    x, xi, states, m_draw, k_from, k_to, ch, cs, indptr, indices, data, bptr, bind, bdata, u,
    src, dst, kmat, gvec, drift, tile, delay, k_base,
):  # fmt: skip
    """:func:`em_steps` and :func:`em_steps_rng` in one body: the normals are read from
    ``xi``, or drawn here from the paths' xoshiro streams ``states`` (exactly one of the
    two is None). For d = 3 (the paper's examples) ``bdata`` holds L_B's 3×3 blocks and
    ``data`` is None: one loop over the tile does a whole block of L_B or a whole edge, its
    nine coefficients in registers, a third of the memory traffic of the general loops
    (one per nonzero; ``data`` given, ``bdata`` None), 1.2x faster on G1; the sums are the
    same up to rounding.

    The branches test only ``arg is not None``: Numba prunes a branch on an argument typed
    None before typing it, so a run compiles (and caches) only the specialisation it calls
    (issue 47: every branch was compiled, 5 s of CPU on a first run).

    With ``delay`` D > 0 a row of ``x`` is a ring of D + 1 states of the sampled protocol
    (:mod:`.digital`): x_j in slot j mod (D + 1), where j = ``k_base`` + k counts the steps
    from the start; the drift and the noise are taken at x_{j−D}, the slot that x_{j+1}
    (= x_j + the increment) then overwrites, so a step costs the same whatever D. The
    slots are row offsets into the tile (``nxt``), never slices: a slice is a
    non-contiguous array to Numba and kept the inner loops scalar (1.7x slower on G1)."""
    p, width = x.shape
    ring = delay + 1
    nd = width // ring
    ne = src.size
    d = gvec.shape[1]
    for q0 in range(0, p, tile):
        w = min(tile, p - q0)
        xt = np.empty((width, w))
        for q in range(w):
            for r in range(width):
                xt[r, q] = x[q0 + q, r]
        dx = np.empty((nd, w))
        zt = np.empty((max(2 * ne, m_draw), w))  # rows past 2·E: drawn, not used
        df = np.empty((d, w))
        mb = np.empty(w)
        st = np.empty((4, w), dtype=np.uint64)
        if states is not None:
            for q in range(w):
                for c in range(4):
                    st[c, q] = states[q0 + q, c]
        wl = np.empty(w, dtype=np.uint64)
        for k in range(k_from, k_to):
            c1 = ch[k]
            c2 = cs[k]
            cur = ((k_base + k) % ring) * nd
            nxt = ((k_base + k + 1) % ring) * nd  # x_{j−D}'s slot (measured), then x_{j+1}'s
            if states is not None:
                draw_lanes(st[0], st[1], st[2], st[3], zt, wl, c2, zt.shape[0])
            if xi is not None:
                for q in range(w):
                    for e in range(2 * ne):
                        zt[e, q] = c2 * xi[k, q0 + q, e]
            if bdata is not None:
                _drift_noise_d3(
                    xt, nxt, dx, zt, c1, bptr, bind, bdata, u, src, dst, kmat, gvec, drift
                )
            if data is not None:
                for r in range(nd):
                    ur = c1 * u[r]
                    for q in range(w):
                        dx[r, q] = ur
                    if drift:
                        for b in range(indptr[r], indptr[r + 1]):
                            a = c1 * data[b]
                            jc = nxt + indices[b]
                            for q in range(w):
                                dx[r, q] -= a * xt[jc, q]
                for e in range(ne):
                    io = dst[e] * d
                    jo = nxt + src[e] * d
                    xo = nxt + io
                    for c in range(d):
                        for q in range(w):
                            df[c, q] = xt[jo + c, q] - xt[xo + c, q]
                    for a in range(d):
                        for q in range(w):
                            mb[q] = 0.0
                        for c in range(d):
                            kc = kmat[e, a, c]
                            for q in range(w):
                                mb[q] += kc * df[c, q]
                        ga = gvec[e, a]
                        for q in range(w):
                            dx[io + a, q] += ga * zt[e, q] + mb[q] * zt[ne + e, q]
            if ring == 1:  # D = 0: in place (no aliasing for LLVM to rule out at run time)
                for r in range(nd):
                    for q in range(w):
                        xt[r, q] += dx[r, q]
            else:
                for r in range(nd):
                    for q in range(w):
                        xt[nxt + r, q] = xt[cur + r, q] + dx[r, q]
        for q in range(w):
            for r in range(width):
                x[q0 + q, r] = xt[r, q]
        if states is not None:
            for q in range(w):
                for c in range(4):
                    states[q0 + q, c] = st[c, q]


def em_steps(
    x, xi, k_from, k_to, ch, cs, indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat,
    gvec, drift, tile, delay=0, k_base=0,
):  # fmt: skip
    """Advance every row of ``x`` (p, Nd) in place over the steps ``k_from .. k_to − 1``
    of the batch: ``x += ch[k]·(u − L_B x) + cs[k]·Σ_e (g_e ξ1_e + K_e (x_j − x_i) ξ2_e)``
    with ξ1_e = ``xi[k, path, e]``, ξ2_e = ``xi[k, path, E + e]`` (E = len(src)), L_B in
    CSR form (indptr, indices, data) and, for d = 3, in 3×3 block-CSR form (bptr, bind,
    bdata; :func:`kernel_arrays` makes both), K_e = ``kmat[e]`` and g_e = ``gvec[e]`` (agent
    ``dst[e]``'s rows). With ``drift`` False the L_B term is left out (the implicit
    scheme solves for it). Paths go ``tile`` at a time, transposed to (Nd, tile); every
    innermost loop runs over the tile (no array views inside: they cost per nonzero). With
    ``delay`` D > 0 each row is the ring of D + 1 states of :func:`_em_core` (``k_base``: the
    steps taken before ``ch[0]``).

    Parameters
    ----------
    x : numpy.ndarray
        (p, (D + 1)·Nd) float64, updated in place.
    xi : numpy.ndarray
        (K, p, >= 2E) float64: the normals of each step and path.
    k_from, k_to : int
        The steps to take (indices into ``ch``, ``cs`` and ``xi``).
    ch, cs : numpy.ndarray
        c(t_k)·h and c(t_k)·√h per step.
    indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat, gvec : numpy.ndarray
        :func:`kernel_arrays` of the mode.
    drift : bool
        Include −L_B x.
    tile : int
        Paths integrated together (:func:`tile_width`).
    delay, k_base : int, optional
        The ring's D and the steps taken before ``ch[0]``.
    """
    data, bdata = _one_layout(data, bdata, gvec)
    _em_core(
        x, xi, None, 0, k_from, k_to, ch, cs, indptr, indices, data, bptr, bind, bdata, u,
        src, dst, kmat, gvec, drift, tile, delay, k_base,
    )  # fmt: skip


def em_steps_rng(
    x, states, m_draw, k_from, k_to, ch, cs, indptr, indices, data, bptr, bind, bdata, u,
    src, dst, kmat, gvec, drift, tile, delay=0, k_base=0,
):  # fmt: skip
    """:func:`em_steps` with the normals drawn in the kernel, path by path from its
    xoshiro256** state ``states[path]`` (the same numbers as :func:`fill_normals` gives
    the array kernel; ``m_draw`` >= 2·E per step, the rest drawn and dropped), so no array of
    normals is written or read.

    Parameters
    ----------
    x : numpy.ndarray
        (p, (D + 1)·Nd) float64, updated in place.
    states : numpy.ndarray
        (p, 4) uint64 xoshiro256** states, updated in place.
    m_draw : int
        Normals drawn per path and step.
    k_from, k_to, ch, cs, indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat, gvec, drift, tile, delay, k_base
        As for :func:`em_steps`.
    """
    data, bdata = _one_layout(data, bdata, gvec)
    _em_core(
        x, None, states, m_draw, k_from, k_to, ch, cs, indptr, indices, data, bptr, bind,
        bdata, u, src, dst, kmat, gvec, drift, tile, delay, k_base,
    )  # fmt: skip


def _one_layout(data, bdata, gvec):
    """(None, the 3×3 blocks) when d = 3, else (L_B's CSR values, None): the argument
    typed None selects the kernel's loops."""
    return (None, bdata) if gvec.shape[1] == 3 else (data, None)


def _warm_args(fused: bool, width: int, arrays) -> tuple:
    """:func:`_em_core`'s arguments for no path and one step, of the types a run passes."""
    indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat, gvec = arrays
    one = np.ones(1)
    xi = None if fused else np.zeros((1, 0, 2 * src.size))
    states = np.zeros((0, 4), np.uint64) if fused else None
    data, bdata = _one_layout(data, bdata, gvec)
    return (
        np.zeros((0, width)), xi, states, 2 if fused else 0, 0, 1, one, one, indptr, indices,
        data, bptr, bind, bdata, u, src, dst, kmat, gvec, True, 1,
    )  # fmt: skip


def warm_kernel(fused: bool, width: int, arrays, delay: int = 0) -> None:
    """Compile, or load from Numba's cache, the kernel a run of this mode calls (no path is
    integrated), so that forked workers inherit it.

    Parameters
    ----------
    fused : bool
        Normals drawn in the kernel (:func:`em_steps_rng`), else read (:func:`em_steps`).
    width : int
        (D + 1)·N·d: a row of the state.
    arrays : tuple
        :func:`kernel_arrays` of the mode.
    delay : int, optional
        The ring's D.
    """
    core: Any = _em_core
    core(*_warm_args(fused, width, arrays), delay, 0)


def kernel_cached(fused: bool, width: int, arrays, delay: int = 0) -> bool:
    """Whether :func:`warm_kernel` will find its kernel compiled in this process or in
    Numba's cache (the index file of :func:`_em_core` lists its signature, for this source
    and machine), so that a run can say before it compiles. Nothing is compiled or loaded:
    the index is read, about a millisecond. When Numba's cache cannot be read as expected
    (another Numba version), True: nothing to say rather than a false warning.

    Parameters
    ----------
    fused, width, arrays, delay
        As for :func:`warm_kernel`.

    Returns
    -------
    bool
    """
    core: Any = _em_core
    args = (*_warm_args(fused, width, arrays), delay, 0)
    sig = tuple(numba.typeof(a) for a in args)
    if sig in core.overloads:
        return True
    try:  # Numba's own cache key: the signature, the machine and the function's bytecode
        cache = core._cache
        key = cache._index_key(sig, core.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # pragma: no cover - a Numba whose cache is laid out otherwise
        return True


# (indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat, gvec)
KernelArrays = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
]  # fmt: skip


def kernel_arrays(s) -> KernelArrays:
    """The arrays :func:`em_steps` and :func:`em_steps_rng` take after ``ch, cs``, for one
    mode: L_B in CSR (sorted, int64 indices), L_B in 3×3 blocks when d = 3 (else empty),
    u, the edges' source and destination agents, K_e and g_e.

    Parameters
    ----------
    s : ModeSystem
        The mode (a compiled f: ``s.f`` is None).

    Returns
    -------
    tuple
        (indptr, indices, data, bptr, bind, bdata, u, src, dst, kmat, gvec).
    """
    lap = s.lap_b.tocsr()
    lap.sort_indices()
    if s.dim == 3:
        bsr = lap.tobsr(blocksize=(3, 3))
        bsr.sort_indices()
        blocks = (
            bsr.indptr.astype(np.int64),
            bsr.indices.astype(np.int64),
            np.ascontiguousarray(bsr.data, dtype=float),
        )
    else:
        blocks = (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros((0, 3, 3)))
    return (
        lap.indptr.astype(np.int64),
        lap.indices.astype(np.int64),
        lap.data,
        *blocks,
        s.u,
        s.src,
        s.dst,
        s.k_blocks,
        s.g_edge.reshape(s.n_edges, s.dim),
    )


def numpy_step(x, xi_k, ch, cs, s, drift=True, delay=0, step=0):
    """One step of the same recursion with SciPy sparse products, in place (any f,
    callable ones included: f acts on the (p, E, d) array of differences).

    Parameters
    ----------
    x : numpy.ndarray
        States, shape (p, Nd); updated in place.
    xi_k : numpy.ndarray
        The step's normals, shape (p, 2E).
    ch : float
        c(t_k)·h.
    cs : float
        c(t_k)·√h.
    s : ModeSystem
        The mode's matrices.
    drift : bool, optional
        Include −L_B x (False for the implicit scheme, which solves for it).
    delay : int, optional
        D > 0: each row of ``x`` is the ring of D + 1 states of :func:`_em_core`; the drift
        and the noise are taken at x_{j−D}, whose slot x_{j+1} then takes.
    step : int, optional
        j, the steps taken so far (the ring's position).
    """
    p = x.shape[0]
    ne, d = s.n_edges, s.dim
    ring = delay + 1
    cur = (step % ring) * s.nd
    nxt = ((step + 1) % ring) * s.nd
    full, x = x, x[:, nxt : nxt + s.nd]
    x3 = x.reshape(p, s.n_agents, d)
    diff = x3[:, s.src] - x3[:, s.dst]
    if s.f is not None:
        diff = s.f(diff)
    else:
        diff = diff @ s.fmat.T
    z = (diff * xi_k[:, ne : 2 * ne, None]).reshape(p, ne * d)
    noise = (s.wmat @ z.T + s.g @ xi_k[:, :ne].T).T
    inc = ch * s.u + cs * noise
    if drift:
        inc -= ch * (s.lap_b @ x.T).T
    full[:, nxt : nxt + s.nd] = full[:, cur : cur + s.nd] + inc
