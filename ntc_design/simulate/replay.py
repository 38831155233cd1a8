"""The toolkit's reference for the exported agents: :func:`replay` runs THE AGENT LAW of
:mod:`ntc_design.protocol.agents` on given normals, with the same operations in the same
order as the exported C and Python (NumPy vectorised over paths, agents and edges; each
element's arithmetic is the scalar law's), so the three agree bit for bit.

The normals come in the exported programs' order: step by step, for each edge of that
step's mode in file order, its additive ξ1 then its multiplicative ξ2 (2·E per step).
:func:`kernel_normals` re-orders them into the layout of the simulator's compiled kernel
(:func:`~ntc_design.simulate.kernels.em_steps`: ξ1 of the sorted edges, then their ξ2),
and :func:`kernel_replay` runs that kernel on them: the simulator and the law agree to
rounding (1e-12 relative over 1000 steps of G1, in the tests).

On lossy links (:attr:`AgentLaw.lossy`) each step also reads E arrival flags (0 or 1), one
per edge of its mode in file order; the exported programs read them from stdin after the
step's 2E normals, :func:`replay` takes them as a separate array. Under ``hold`` the
replay keeps each edge's held measurement (the noiseless measurement of x(0) first, then a
copy of each arrived one) and every slot adds its held value.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import InputError
from ..protocol.agents import AgentLaw
from .system import ModeSystem


def _normals(law: AgentLaw, normals, steps: int, paths: int) -> tuple[np.ndarray, np.ndarray]:
    """The normals as (paths, M) and each step's offset into them; M checked."""
    counts = law.normals_per_step(steps)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    z = np.asarray(normals, dtype=float)
    z = z.reshape(1, -1) if z.ndim == 1 else z
    if z.ndim != 2 or z.shape[0] != paths:
        raise InputError(
            f"expected {paths} row(s) of normals, one per path, got shape {z.shape}",
            field="normals",
        )
    if z.shape[1] != offsets[-1]:
        raise InputError(
            f"{steps} steps need {int(offsets[-1])} normals per path (2 per edge of "
            f"each step's mode), got {z.shape[1]}",
            field="normals",
        )
    return z, offsets


def _arrivals(law: AgentLaw, arrivals, steps: int, paths: int) -> tuple[np.ndarray, np.ndarray]:
    """The arrival flags as (paths, F) booleans and each step's offset; F and the values
    (0 or 1 only) checked."""
    counts = law.flags_per_step(steps)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    if not law.lossy:
        if arrivals is not None:
            raise InputError("the law is lossless; it reads no arrival flags", field="arrivals")
        return np.ones((paths, 0), dtype=bool), offsets
    if arrivals is None:
        raise InputError(
            f"the law runs on lossy links ({law.policy}); give E flags per step", field="arrivals"
        )
    a = np.asarray(arrivals)
    a = a.reshape(1, -1) if a.ndim == 1 else a
    if a.ndim != 2 or a.shape[0] != paths or a.shape[1] != offsets[-1]:
        raise InputError(
            f"{steps} steps need {int(offsets[-1])} flags per path (1 per edge of "
            f"each step's mode), got shape {a.shape}",
            field="arrivals",
        )
    if a.dtype.kind not in "biuf" or not np.all((a == 0) | (a == 1)):
        raise InputError("an arrival flag is not 0 or 1", field="arrivals")
    return a == 1, offsets


def _states(law: AgentLaw, x_init) -> tuple[np.ndarray, bool]:
    x = np.asarray(x_init, dtype=float)
    nd_ = law.n * law.dim
    if x.shape[-1:] != (nd_,) or x.ndim > 2:
        raise InputError(
            f"expected N·d = {nd_} numbers (a row per path), got {x.shape}", field="initial"
        )
    return x.reshape(-1, law.n, law.dim).copy(), x.ndim == 1


class _Mode:
    """One mode's arrays, gathered once for the vectorised steps."""

    def __init__(self, law: AgentLaw, m: int):
        ml = law.modes[m]
        d = law.dim
        self.e = ml.n_edges
        self.src, self.dst = ml.src, ml.dst
        self.sign = ml.sign[None, :, None]
        self.sigma = ml.sigma[None, :, None]
        self.keep = None if ml.keep is None else ml.keep[None, :, None]
        self.u = ml.u
        self.informed = np.array(ml.informed, dtype=np.int64)
        self.bd = [ml.bd[self.informed][None, :, :, b] for b in range(d)]
        self.slots = [
            (agents, edges, [ml.weight[edges][None, :, :, b] for b in range(d)])
            for agents, edges in ml.slots
        ]


def _noiseless(md: _Mode, x: np.ndarray, f: np.ndarray, sqrth: float) -> np.ndarray:
    """Each edge's measurement of the states x with z1 = z2 = 0.0 (the law's arithmetic)."""
    d = x.shape[2]
    xj, xi = x[:, md.src, :], x[:, md.dst, :]
    diff = xj - xi
    fd = f[None, None, :, 0] * diff[:, :, 0, None]
    for b in range(1, d):
        fd = fd + f[None, None, :, b] * diff[:, :, b, None]
    zero = np.zeros((x.shape[0], md.e, 1))
    return (md.sign * xj - xi) + (md.sigma * zero + fd * zero) / sqrth


def replay(
    law: AgentLaw,
    x_init,
    normals,
    steps: int,
    record: bool = False,
    arrivals=None,
) -> np.ndarray:
    """Run the agents' law for K steps on given normals (the exported programs' order).

    Parameters
    ----------
    law : AgentLaw
        The agents' tables.
    x_init : array_like
        x(0), N·d numbers agent by agent, or one row per path (P, N·d).
    normals : array_like
        The normals, M = Σ_k 2·E_{mode(k)} per path: (M,), or (P, M).
    steps : int
        K.
    record : bool, optional
        Return every state x_0 … x_K, not only the last.
    arrivals : array_like, optional
        On lossy links (and only there): the arrival flags, 0 or 1, Σ_k E_{mode(k)} per
        path, step by step, each step's edges in file order: (F,) or (P, F).

    Returns
    -------
    numpy.ndarray
        x_K, shaped as ``x_init``; with ``record`` (K+1, …) with x_k first.

    Raises
    ------
    InputError
        A state, normals or flags of the wrong size, a flag other than 0 or 1, a negative
        K, or c(t_k) not finite.
    """
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"expected an integer K >= 0, got {steps!r}", field="steps")
    steps = int(steps)
    x, single = _states(law, x_init)
    paths, n, d = x.shape
    z, offsets = _normals(law, normals, steps, paths)
    chi, flag_at = _arrivals(law, arrivals, steps, paths)
    rescale = law.policy == "rescale"
    hold = law.policy == "hold"
    modes = law.step_modes(steps)
    prepared: dict[int, _Mode] = {}
    h = law.digital.period
    lag = law.digital.delay
    sqrth = law.sqrt_period
    f = law.noise_f
    ring = [x] * (lag + 1)  # x_{k−j} before the start: the initial state, held
    held: dict[int, np.ndarray] = {}  # hold: each mode's held measurements (paths, E, d)
    kept = [x.copy()] if record else []
    for k in range(steps):
        t = float(k) * h
        c = law.gain.value(t)
        if not math.isfinite(c):
            raise InputError(f"c(t) = {c!r} is not finite at t = {t!r} (step {k})", field="gain")
        hc = h * c
        mi = int(modes[k])
        md = prepared.get(mi)
        if md is None:
            md = prepared[mi] = _Mode(law, mi)
        now = ring[k % (lag + 1)]
        xd = ring[(k + 1) % (lag + 1)] if lag else now
        zk = z[:, offsets[k] : offsets[k + 1]].reshape(paths, md.e, 2)
        z1, z2 = zk[:, :, 0, None], zk[:, :, 1, None]
        xj, xi = xd[:, md.src, :], xd[:, md.dst, :]
        diff = xj - xi
        fd = f[None, None, :, 0] * diff[:, :, 0, None]
        for b in range(1, d):
            fd = fd + f[None, None, :, b] * diff[:, :, b, None]
        m = (md.sign * xj - xi) + (md.sigma * z1 + fd * z2) / sqrth
        if hold:  # before the first arrival, the noiseless measurement of x(0)
            if mi not in held:
                held[mi] = _noiseless(md, x, f, sqrth)
            held[mi] = np.where(chi[:, flag_at[k] : flag_at[k + 1], None], m, held[mi])
            m = held[mi]
        if rescale:  # a received measurement over keep_e = 1 − p_e
            m = m / md.keep
        got = chi[:, flag_at[k] : flag_at[k + 1], None] if law.lossy and not hold else None
        acc = np.broadcast_to(md.u, (paths, n, d)).copy()
        if md.informed.size:
            xdi = xd[:, md.informed, :]
            part = acc[:, md.informed, :]
            for b in range(d):
                part = part - md.bd[b] * xdi[:, :, None, b]
            acc[:, md.informed, :] = part
        for agents, edges, wb in md.slots:
            me = m[:, edges, :]
            part = acc[:, agents, :]
            if got is None:
                for b in range(d):
                    part = part + wb[b] * me[:, :, None, b]
            else:  # a lost message adds nothing (the law's `continue`)
                arrived = got[:, edges, :]
                for b in range(d):
                    part = np.where(arrived, part + wb[b] * me[:, :, None, b], part)
            acc[:, agents, :] = part
        ring[(k + 1) % (lag + 1)] = now + hc * acc
        if record:
            kept.append(ring[(k + 1) % (lag + 1)])
    shape = (n * d,) if single else (paths, n * d)
    if record:
        return np.stack([s.reshape(shape) for s in kept])
    return ring[steps % (lag + 1)].reshape(shape)


def kernel_normals(law: AgentLaw, normals, steps: int) -> np.ndarray:
    """The normals of :func:`replay`'s order in the compiled kernel's layout: per step,
    ξ1 of the mode's edges in sorted order (:attr:`Topology.edges`), then their ξ2, padded
    to the widest mode's 2·E.

    Parameters
    ----------
    law : AgentLaw
        The agents' tables.
    normals : array_like
        (M,) or (P, M), as :func:`replay` takes them.
    steps : int
        K.

    Returns
    -------
    numpy.ndarray
        (K, P, 2·E_max), what :func:`~ntc_design.simulate.kernels.em_steps` reads as ``xi``.

    Raises
    ------
    InputError
        Normals of the wrong size.
    """
    z0 = np.asarray(normals, dtype=float)
    paths = 1 if z0.ndim == 1 else z0.shape[0]
    z, offsets = _normals(law, normals, steps, paths)
    modes = law.step_modes(steps)
    e_max = max(m.n_edges for m in law.modes)
    out = np.zeros((steps, paths, 2 * e_max))
    for k in range(steps):
        ml = law.modes[int(modes[k])]
        e = ml.n_edges
        zk = z[:, offsets[k] : offsets[k + 1]].reshape(paths, e, 2)
        out[k][:, ml.sorted_index] = zk[:, :, 0]
        out[k][:, e + ml.sorted_index] = zk[:, :, 1]
    return out


def kernel_replay(
    law: AgentLaw,
    systems: Sequence[ModeSystem],
    gain: Callable[[np.ndarray], np.ndarray],
    x_init,
    normals,
    steps: int,
) -> np.ndarray:
    """The simulator's own compiled kernel (with its shift register for the delay) on the
    normals of :func:`replay`, with c_k·h and c_k·√h as the Monte Carlo computes them (the
    vectorised gain on the grid t_k = k·h, and its step sizes): what the law must agree
    with to rounding.

    Parameters
    ----------
    law : AgentLaw
        The agents' tables (the schedule, h, D and the normals' order).
    systems : sequence of ModeSystem
        The modes' systems, in ``law.modes`` order (compiled f).
    gain : callable
        Vectorised c(t).
    x_init : array_like
        x(0), (N·d,) or (P, N·d).
    normals : array_like
        As :func:`replay` takes them.
    steps : int
        K.

    Returns
    -------
    numpy.ndarray
        x_K, shaped as ``x_init``.

    Raises
    ------
    InputError
        Normals of the wrong size, systems that do not match the law's modes, or a lossy
        law (this kernel has no lost messages; :mod:`.loss_kernels` has).
    """
    from .kernels import em_steps, kernel_arrays, tile_width

    if law.lossy:
        raise InputError("kernel_replay runs the lossless kernel; the law is lossy", field="law")

    if len(systems) != len(law.modes):
        raise InputError(f"{len(systems)} given for {len(law.modes)} modes", field="systems")
    x0 = np.asarray(x_init, dtype=float)
    single = x0.ndim == 1
    xs = x0.reshape(-1, law.n * law.dim)
    xi = kernel_normals(law, normals, steps)
    t = np.arange(steps + 1, dtype=float) * law.digital.period
    c = np.asarray(gain(t[:-1]), dtype=float) * np.ones(steps)
    hk = np.diff(t)
    ch, cs = c * hk, c * np.sqrt(hk)
    lag = law.digital.delay
    x = np.tile(xs, (1, lag + 1))
    args = [kernel_arrays(s) for s in systems]
    modes = law.step_modes(steps)
    tile = tile_width(x.shape[0], x.shape[1])
    k = 0
    while k < steps:  # one call per run of steps in one mode
        stop = k + 1
        while stop < steps and modes[stop] == modes[k]:
            stop += 1
        em_steps(x, xi, k, stop, ch, cs, *args[int(modes[k])], True, tile, lag)
        k = stop
    nd_ = law.n * law.dim
    slot = (steps % (lag + 1)) * nd_  # x_K's slot of the kernel's ring
    out = x[:, slot : slot + nd_]
    return out[0].copy() if single else out.copy()


__all__ = ["kernel_normals", "kernel_replay", "replay"]
