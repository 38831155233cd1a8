"""Exact first and second moments of ε = x − 1⊗θ when the noise is linear.

With ``dε = −c L_B ε dt + c Σ_k (g_k + G_k ε) dw_k`` (Niu & Wu, eq. (12), with
f(x) = F x) Itô's formula gives, for
``m = E[ε]`` and ``S = E[εεᵀ]``,

    dm/dt = −c L_B m
    dS/dt = −c (L_B S + S L_Bᵀ) + c² Σ_k (g_k g_kᵀ + G_k S G_kᵀ)

(every noise has either g_k, additive, or G_k, multiplicative, so cross terms vanish).
Here ``Σ g_k g_kᵀ = G Gᵀ`` and ``G_e S G_eᵀ`` lands in block (i, i) as
``K_e (S_jj − S_ji − S_ij + S_ii) K_eᵀ`` with ``K_e = |A_ij| F`` for edge j -> i.
``E‖x_i − θ‖² = tr S_ii``. The ODE is integrated with classical RK4 on a grid through
every switching instant and save time, with steps ``h <= κ / (c(t) ρ)`` (ρ the spectral
radius of the S-equation's generator, κ = 0.2), so c·h·ρ stays in RK4's accurate range;
the tests compare it with SciPy's DOP853 at rtol 1e-11.

L_B is sparse, so one evaluation costs O(nnz(L_B)·Nd + E·d³) on top of the dense S
(Nd×Nd); up to Nd = ``NOISE_OPERATOR_MAX_ND`` the noise term is one sparse product with
a prebuilt operator of 4·E·d⁴ entries instead of the per-edge gathers, whose call overhead
dominates at small sizes. S and the RK4 stages hold about ``MOMENT_COPIES`` dense Nd×Nd matrices:
the moments are refused above ``MOMENTS_MAX_ND`` (3000, about 0.9 GB) with the
estimate, before anything is allocated.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..protocol import ProtocolDesign
from .implicit import SolverCache
from .system import ModeSystem

KAPPA = 0.2
MOMENTS_MAX_ND = 3000  # N = 1000 agents in d = 3
DENSE_MOMENTS_ND = 300  # L_B dense in the moment equations up to this Nd
# the noise term as one sparse operator up to these sizes; past Nd ≈ 120 the product over
# (Nd)² rows costs more than the per-edge gathers (benchmarked for d = 1, 3, 5)
NOISE_OPERATOR_MAX_ND = 120
NOISE_OPERATOR_MAX_NNZ = 2_000_000
MOMENT_COPIES = 12  # dense Nd×Nd matrices alive during an RK4 step (S, stages, products)


def moments_memory(nd_: int) -> int:
    """Bytes the exact moments need at this Nd (about).

    Parameters
    ----------
    nd_ : int
        N·d.

    Returns
    -------
    int
        ``MOMENT_COPIES`` dense Nd×Nd float matrices.
    """
    return MOMENT_COPIES * 8 * nd_ * nd_


def check_moments_size(nd_: int) -> None:
    """Refuse the exact moments above ``MOMENTS_MAX_ND`` (one line, with the estimate).

    Parameters
    ----------
    nd_ : int
        N·d.

    Raises
    ------
    InputError
        Nd is above the limit."""
    if nd_ > MOMENTS_MAX_ND:
        raise InputError(
            f"exact moments at Nd = {nd_} need about {moments_memory(nd_) / 2**30:.1f} GB "
            f"(dense Nd×Nd second moments; limit Nd <= {MOMENTS_MAX_ND}); use method: mc",
            field="method",
        )


@dataclass(frozen=True)
class Moments:
    """Exact moments at the save times: E[ε], E‖x_i − θ‖² per agent, the final second
    moment S and the number of RK4 steps."""

    t: np.ndarray  # save times
    mean: np.ndarray  # (S, Nd) E[ε]
    ms_error: np.ndarray  # (S, N) E‖x_i − θ‖²
    second: np.ndarray  # (Nd, Nd) S at the final time
    steps: int


@dataclass(frozen=True, eq=False)
class PreparedModes:
    """What every run over one topology, a switching set or a sampled A(t) shares before
    any time grid: the designs and linear systems per mode, the segments on [0, T), x(0),
    θ and the notes so far (:func:`~ntc_design.simulate.prepare.prepare_modes`). The
    moment engines (:func:`exact_moments`, :func:`em_moments`,
    :func:`~ntc_design.simulate.digital.digital_moments`) take it whole."""

    names: list[str]
    designs: dict[str, ProtocolDesign]
    systems: list[ModeSystem]
    segments: list[tuple[float, float, int]]
    x_init: np.ndarray
    theta: np.ndarray
    n: int
    d: int
    notes: list[str]

    @classmethod
    def of(
        cls,
        systems: Sequence[ModeSystem],
        eps0: np.ndarray,
        segments: Sequence[tuple[float, float, int]] = (),
    ) -> PreparedModes:
        """Modes from their systems and ε(0) alone, for the engines on systems built by
        hand: ε's moments do not depend on θ (linear f), so θ is taken as 0 and
        x(0) = ε(0); no designs.

        Parameters
        ----------
        systems : sequence of ModeSystem
            One system per mode.
        eps0 : numpy.ndarray
            ε(0) = x(0) − 1⊗θ, length Nd.
        segments : sequence of (float, float, int), optional
            (start, stop, mode index) covering the horizon (for :func:`exact_moments`).

        Returns
        -------
        PreparedModes
        """
        s0 = systems[0]
        eps = np.asarray(eps0, dtype=float)
        return cls(
            names=[s.name for s in systems],
            designs={},
            systems=list(systems),
            segments=list(segments),
            x_init=eps,
            theta=np.zeros(s0.dim),
            n=s0.n_agents,
            d=s0.dim,
            notes=[],
        )

    @property
    def eps0(self) -> np.ndarray:
        """ε(0) = x(0) − 1⊗θ."""
        return self.x_init - np.tile(self.theta, self.n)

    def moments(
        self,
        gain: Callable,
        save_times: np.ndarray,
        kappa: float = KAPPA,
        abort_above: float | None = None,
    ) -> Moments:
        """The exact moments of these modes under the gain ``gain`` (linear f):
        :func:`exact_moments`.

        Parameters
        ----------
        gain : callable
            Vectorised c(t).
        save_times : numpy.ndarray
            Where to record them.
        kappa : float, optional
            RK4's c·h·ρ (default :data:`KAPPA`).
        abort_above : float, optional
            Stop once tr S exceeds it (the rest +∞; :func:`exact_moments`).

        Returns
        -------
        Moments
        """
        return exact_moments(self, gain, save_times, kappa=kappa, abort_above=abort_above)


class MomentRecorder:
    """E[ε] and E‖x_i − θ‖² = tr of agent i's d×d block of S, recorded at the save times
    in order: by time (``at``, a save time within 1e-12 relative) or by slot (``put``)."""

    def __init__(self, saves: np.ndarray, n: int, d: int) -> None:
        self.saves, self.n, self.d = np.asarray(saves, dtype=float), n, d
        self.means = np.zeros((self.saves.size, n * d))
        self.ms = np.zeros((self.saves.size, n))
        self.k = 0

    def put(self, i: int, m: np.ndarray, s: np.ndarray) -> None:
        """Record the moments in save slot ``i``.

        Parameters
        ----------
        i : int
            The save slot.
        m : numpy.ndarray
            E[ε], length Nd.
        s : numpy.ndarray
            E[εεᵀ], Nd × Nd.
        """
        self.means[i] = m
        self.ms[i] = np.einsum("iaia->i", s.reshape(self.n, self.d, self.n, self.d))

    def at(self, t: float, m: np.ndarray, s: np.ndarray) -> None:
        """Record the moments in every save slot at time ``t`` (none if t is not one).

        Parameters
        ----------
        t : float
            The time reached.
        m : numpy.ndarray
            E[ε], length Nd.
        s : numpy.ndarray
            E[εεᵀ], Nd × Nd.
        """
        while self.k < self.saves.size and abs(self.saves[self.k] - t) <= 1e-12 * max(1.0, t):
            self.put(self.k, m, s)
            self.k += 1

    def stop(
        self, t: float, m: np.ndarray, s: np.ndarray, steps: int, abort_above: float | None
    ) -> bool:
        """Record at t if it is a save time; with ``abort_above``, every 8 steps, end the
        run once E‖ε‖² = tr S exceeds it (the remaining saves +∞).

        Parameters
        ----------
        t : float
            The time reached.
        m : numpy.ndarray
            E[ε], length Nd.
        s : numpy.ndarray
            E[εεᵀ], Nd × Nd.
        steps : int
            Steps taken so far.
        abort_above : float or None
            The bound on tr S.

        Returns
        -------
        bool
            Whether to stop.
        """
        if abort_above is not None and steps % 8 == 0 and not np.trace(s) <= abort_above:
            self.ms[self.k :] = np.inf
            self.means[self.k :] = np.nan
            return True
        self.at(t, m, s)
        return False

    def result(self, s: np.ndarray, steps: int) -> Moments:
        """The recorded curves.

        Parameters
        ----------
        s : numpy.ndarray
            The final E[εεᵀ].
        steps : int
            RK4 steps taken.

        Returns
        -------
        Moments
        """
        return Moments(self.saves, self.means, self.ms, s, steps)


def generator_radius(s: ModeSystem) -> tuple[float, float]:
    """(ρ_L, ρ_Q): the S-equation's generator has spectral radius at most ρ_L + c·ρ_Q with
    ρ_L = 2ρ(L_B) and ρ_Q = 4·Σ_e ‖K_e‖² (RK4 steps h <= κ / (c ρ); also the step-count
    estimate of :func:`.budget.estimate_exact_steps`). NumPy floats: a huge weight gives
    inf, which the estimate refuses, not an OverflowError.

    Parameters
    ----------
    s : ModeSystem
        One mode's system.

    Returns
    -------
    (float, float)
        ρ_L and ρ_Q.
    """
    k = s.k_blocks
    with np.errstate(over="ignore", invalid="ignore"):
        rho_q = 4 * float(np.sum(np.linalg.norm(k, ord=2, axis=(1, 2)) ** 2)) if k.size else 0.0
    return 2 * s.spectral_radius, rho_q


class MomentRhs:
    """The right-hand side of one mode's moment equations, with what it precomputes
    (L_B dense or sparse, G Gᵀ, the edges' K_e blocks and the generator's radius)."""

    def __init__(self, s: ModeSystem, n: int, d: int):
        # sparse products cost O(nnz·Nd); at small Nd a dense product is cheaper than
        # SciPy's call overhead (and gives the numbers of the earlier dense code)
        self.l = s.lap_b.toarray() if s.nd <= DENSE_MOMENTS_ND else s.lap_b.tocsr()
        self.q = (s.g @ s.g.T).toarray()
        self.n, self.d = n, d
        self.ii = np.array([i for i, _, _ in s.h_blocks], dtype=np.int64)
        self.jj = np.array([j for _, j, _ in s.h_blocks], dtype=np.int64)
        self.k = np.array([k for _, _, k in s.h_blocks]).reshape(-1, d, d)
        # generator's spectral radius bound: 2ρ(L_B) + c·Σ‖K_e‖²·4 (used with c <= c(t))
        self.rho_l, self.rho_q = generator_radius(s)
        self.ar = np.arange(n)
        # at small Nd the multiplicative part is one sparse product with a prebuilt
        # operator (an RK4 step calls it four times; the gathers cost 4x as much)
        small = s.nd <= NOISE_OPERATOR_MAX_ND and 4 * len(self.ii) * d**4 <= NOISE_OPERATOR_MAX_NNZ
        self.a2 = self.noise_operator() if small and self.k.size else None

    def noise_operator(self):
        """𝓐₂, the multiplicative part of the noise term as a sparse operator on the
        flattened S: ``vec(Σ_e G_e S G_eᵀ) = 𝓐₂ vec(S)``, with ``K_e[a, b] K_e[a', c]`` (±1
        by the four blocks S_jj, −S_ji, −S_ij, S_ii) from ``S[(p, b), (q, c)]`` to entry
        ``(i, a), (i, a')`` for each edge j -> i.

        Returns
        -------
        scipy.sparse.csr_matrix
            (Nd)² × (Nd)².
        """
        import scipy.sparse as sps

        d, nd_ = self.d, self.n * self.d
        ar = np.arange(d)
        kk = np.einsum("xab,xec->xaebc", self.k, self.k)  # edge, a, a', b, c

        def flat(p, q):  # (edge, u, v) -> index of S[(p, u), (q, v)] in vec(S)
            return (p[:, None, None] * d + ar[None, :, None]) * nd_ + (
                q[:, None, None] * d + ar[None, None, :]
            )

        i, j = self.ii, self.jj
        rows = np.broadcast_to(flat(i, i)[:, :, :, None, None], kk.shape).ravel()
        r, c, v = [], [], []
        for p, q, sign in ((j, j, 1.0), (j, i, -1.0), (i, j, -1.0), (i, i, 1.0)):
            r.append(rows)
            c.append(np.broadcast_to(flat(p, q)[:, None, None, :, :], kk.shape).ravel())
            v.append(sign * kk.ravel())
        size = nd_ * nd_
        op = sps.csr_matrix(
            (np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(size, size)
        )  # duplicates are summed
        op.eliminate_zeros()
        return op

    def noise(self, s: np.ndarray) -> np.ndarray:
        """The noise term ``Σ_k (g_k g_kᵀ + G_k S G_kᵀ)``.

        Parameters
        ----------
        s : numpy.ndarray
            E[εεᵀ], Nd × Nd.

        Returns
        -------
        numpy.ndarray
        """
        n, d = self.n, self.d
        if self.a2 is not None:
            return self.q + (self.a2 @ s.ravel()).reshape(s.shape)
        out = self.q.copy()
        if self.k.size:
            s4 = s.reshape(n, d, n, d)
            i, j = self.ii, self.jj
            delta = s4[j, :, j, :] - s4[j, :, i, :] - s4[i, :, j, :] + s4[i, :, i, :]
            val = np.einsum("eab,ebc,edc->ead", self.k, delta, self.k)
            acc = np.zeros((n, d, d))
            np.add.at(acc, i, val)
            out.reshape(n, d, n, d)[self.ar, :, self.ar, :] += acc
        return out

    def __call__(self, c: float, m: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ls = self.l @ s
        return -c * (self.l @ m), -c * (ls + ls.T) + c * c * self.noise(s)


def exact_moments(
    modes: PreparedModes,
    gain: Callable[[np.ndarray], np.ndarray],
    save_times: np.ndarray,
    kappa: float = KAPPA,
    abort_above: float | None = None,
) -> Moments:
    """Integrate the moment equations from m(0) = ε0, S(0) = ε0ε0ᵀ (a deterministic start).

    Parameters
    ----------
    modes : PreparedModes
        The systems per mode, the segments (start, stop, mode index) covering the
        horizon and ε(0) (:meth:`PreparedModes.of` for systems built by hand).
    gain : callable
        Vectorised c(t).
    save_times : numpy.ndarray
        Where to record the moments.
    kappa : float, optional
        The RK4 steps' c·h·ρ (default ``KAPPA`` = 0.2; RK4 is stable to 2.78, and a
        coarser κ only loses accuracy in modes that have decayed).
    abort_above : float, optional
        Stop as soon as E‖ε‖² = tr S exceeds this (checked every 8 steps): the moments
        at the remaining save times are then +∞ (a search discards such a candidate
        without integrating its growth to the end).

    Returns
    -------
    Moments
        The moments at the save times.

    Raises
    ------
    InputError
        Nd is above ``MOMENTS_MAX_ND``."""
    n, d, eps0 = modes.n, modes.d, modes.eps0
    check_moments_size(n * d)
    rhs = [MomentRhs(s, n, d) for s in modes.systems]
    m = eps0.astype(float).copy()
    s = np.outer(eps0, eps0)
    rec = MomentRecorder(save_times, n, d)
    rec.at(0.0, m, s)
    steps = 0

    for t, h, mode in march(
        modes.segments, rec.saves, lambda t, mode: _rk4_cap(rhs[mode], gain, t, kappa)
    ):
        f = rhs[mode]
        ch = np.asarray(gain(np.array([t, t + h / 2, t + h])), dtype=float) * np.ones(3)
        k1m, k1s = f(ch[0], m, s)
        k2m, k2s = f(ch[1], m + h / 2 * k1m, s + h / 2 * k1s)
        k3m, k3s = f(ch[1], m + h / 2 * k2m, s + h / 2 * k2s)
        k4m, k4s = f(ch[2], m + h * k3m, s + h * k3s)
        m = m + h / 6 * (k1m + 2 * k2m + 2 * k3m + k4m)
        s = s + h / 6 * (k1s + 2 * k2s + 2 * k3s + k4s)
        s = 0.5 * (s + s.T)
        steps += 1
        if rec.stop(t + h, m, s, steps, abort_above):
            break
    return rec.result(s, steps)


def _rk4_cap(f: MomentRhs, gain: Callable, t: float, kappa: float) -> float:
    """RK4's step bound κ / (c ρ) at t (∞ where c·ρ = 0)."""
    c0 = float(gain(np.array([t]))[0])
    rho = f.rho_l + c0 * f.rho_q
    return kappa / (c0 * rho) if c0 * rho > 0 else math.inf


def march(
    segments: Sequence[tuple[float, float, int]],
    saves: np.ndarray,
    cap: Callable[[float, int], float],
) -> Iterator[tuple[float, float, int]]:
    """The steps (t, h, mode) of a one-step integrator over the segments: every save time
    inside a segment and every segment's end is a step's end, a step is at most
    ``cap(t, mode)``, and a remainder under a quarter step is joined to the step before.

    Parameters
    ----------
    segments : sequence of (float, float, int)
        (start, stop, mode index) covering the horizon.
    saves : numpy.ndarray
        The save times, sorted.
    cap : callable(t, mode) -> float
        The largest step at t.

    Yields
    ------
    (float, float, int)
        The step's start, its length and the mode.
    """
    for a, b, mode in segments:
        stops = np.concatenate([saves[(saves > a) & (saves < b)], [b]])
        t = a
        for stop in stops:
            while stop - t > 1e-14 * max(1.0, stop):
                h = min(stop - t, cap(t, mode))
                if stop - t - h < 0.25 * h:
                    h = stop - t
                yield t, h, mode
                t = stop if h == stop - t else t + h


def em_moments(
    modes: PreparedModes,
    grid,
    gain: Callable[[np.ndarray], np.ndarray],
    scheme: str = "explicit",
) -> Moments:
    """Exact moments of the Euler–Maruyama *recursion* on ``grid`` (what the Monte Carlo
    estimates without time-discretisation error). Explicit, with A = I − c h L_B:

        m_{k+1} = A m_k,   S_{k+1} = A S_k Aᵀ + c² h (G Gᵀ + Σ_e G_e S_k G_eᵀ);

    drift-implicit (``scheme="implicit"``), with R = (I + c h L_B)^{-1}:

        m_{k+1} = R m_k,   S_{k+1} = R (S_k + c² h (G Gᵀ + Σ_e G_e S_k G_eᵀ)) Rᵀ.

    The difference from :func:`exact_moments` is the scheme's O(h) bias.

    Parameters
    ----------
    modes : PreparedModes
        The systems per mode and ε(0).
    grid : TimeGrid
        The Monte Carlo grid.
    gain : callable
        Vectorised c(t).
    scheme : {"explicit", "implicit"}, optional
        The Euler–Maruyama scheme.

    Returns
    -------
    Moments
        The recursion's moments at the grid's save times.

    Raises
    ------
    InputError
        Nd is above ``MOMENTS_MAX_ND``."""
    n, d, eps0, systems = modes.n, modes.d, modes.eps0, modes.systems
    check_moments_size(n * d)
    rhs = [MomentRhs(s, n, d) for s in systems]
    m = eps0.astype(float).copy()
    s = np.outer(eps0, eps0)
    c_all = np.asarray(gain(grid.t[:-1]), dtype=float) * np.ones(grid.n_steps)
    h_all = np.diff(grid.t)
    save_at = {int(k): i for i, k in enumerate(grid.save_steps)}
    rec = MomentRecorder(grid.save_times, n, d)
    solvers = [SolverCache(sy.lap_b, d) for sy in systems] if scheme == "implicit" else []
    if 0 in save_at:
        rec.put(save_at[0], m, s)
    for k in range(grid.n_steps):
        mode = grid.mode[k]
        f = rhs[mode]
        c, h = c_all[k], h_all[k]
        if scheme == "implicit":
            lu = solvers[mode](c * h)
            s = lu.solve(np.asfortranarray(s + c * c * h * f.noise(s)))
            s = lu.solve(np.asfortranarray(s.T))
            m = lu.solve(m)
        else:
            ls = f.l @ s
            # A S Aᵀ with A = I − c h L_B, plus the noise over one step
            s = s - c * h * (ls + ls.T) + (c * h) ** 2 * (f.l @ ls.T).T + c * c * h * f.noise(s)
            m = m - c * h * (f.l @ m)
        s = 0.5 * (s + s.T)
        if k + 1 in save_at:
            rec.put(save_at[k + 1], m, s)
    return rec.result(s, grid.n_steps)
