"""Simulation with a continuously time-varying topology: A(t) and the Lemma 1 protocol
re-evaluated at every Euler–Maruyama step and inside the moment equations (Niu & Wu,
eq. (5) with a time-varying G(t)).

Per batch of steps the weights are evaluated by the compiled expressions and Lemma 1 by
:func:`ntc_design.protocol.timevarying.lemma1_batch` (batched Cholesky/eigenvalues), giving for each
step the drift matrix −L_B(t)ᵀ, the input u(t) = (Δ(t)⊗I)B(t)x0(t), the additive-noise
directions G(t) and the multiplicative weights |A_ij(t)|; the step itself is the fixed
topology's (one matrix product for drift and edge differences). The moment equations

    dm/dt = −c L_B(t) m,  dS/dt = −c (L_B(t) S + S L_B(t)ᵀ) + c² (G(t)G(t)ᵀ + Σ_e K_e(t)…)

are integrated by classical RK4 with the matrices evaluated at t, t + h/2 and t + h.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..model.timevarying import ExpressionTopology
from ..protocol import design_topology
from ..protocol.timevarying import Lemma1Structure, TimeVaryingDesign
from .budget import check_exact_work, check_gain, estimate_exact_steps, gain_samples
from .grid import TimeGrid
from .modes import ModeSource, Stepper
from .moments import KAPPA, MomentRecorder, Moments
from .montecarlo import MonteCarloSpec
from .noise import NoiseModel
from .steps import Runs, finish_run, run_exact, run_monte_carlo, run_parameters, spec_grid

BATCH = 256  # steps whose matrices and normals are made at once (Lemma 1 per batch is ~6 ms)
MAX_BATCH_BYTES = 32 * 2**20


@dataclass(frozen=True, eq=False)
class TimeVaryingSystem:
    """The SAN with A(t): constant edge-difference matrix, per-edge σ, f and the design."""

    design: TimeVaryingDesign
    dmat: np.ndarray  # Ed×Nd edge differences (F applied when f is linear)
    sigma: np.ndarray  # (E,) σ_ji per live edge
    fmat: np.ndarray  # d×d
    f: Callable[[np.ndarray], np.ndarray] | None
    live: np.ndarray  # indices of the edges with a non-zero sign

    @property
    def structure(self) -> Lemma1Structure:
        """The design's fixed Lemma 1 structure."""
        return self.design.structure

    @property
    def n_edges(self) -> int:
        """The number of live edges E (non-zero sign)."""
        return int(self.live.size)

    def matrices(self, ts: np.ndarray) -> tuple[np.ndarray, ...]:
        """The step matrices at K times.

        Parameters
        ----------
        ts : numpy.ndarray
            K times.

        Returns
        -------
        tuple of numpy.ndarray
            M1 = [−L_Bᵀ | Dᵀ] (K, Nd, Nd+Ed), Gᵀ (K, E, Nd), Wᵀ (K, Ed, Nd), u (K, Nd),
            L_B (K, Nd, Nd) and |A_ij(t)| (K, E, d, d).
        """
        st = self.structure
        b = self.design.at(ts)
        lap = b.lap_b(st)
        u = b.input_vector()
        k_n, nd_ = lap.shape[0], lap.shape[1]
        d = st.d
        absw = b.abs_w[:, self.live]  # (K, E, d, d)
        e_n = absw.shape[1]
        ii = st.ii[self.live]
        m1 = np.empty((k_n, nd_, nd_ + e_n * d))
        m1[:, :, :nd_] = -np.swapaxes(lap, 1, 2)
        m1[:, :, nd_:] = self.dmat.T
        gt = np.zeros((k_n, e_n, st.n, d))
        gt[:, np.arange(e_n), ii] = self.sigma[None, :, None] * absw.sum(axis=3)
        wt = np.zeros((k_n, e_n, d, st.n, d))
        wt[:, np.arange(e_n), :, ii, :] = np.swapaxes(absw, 2, 3).transpose(1, 0, 2, 3)
        return (
            m1,
            gt.reshape(k_n, e_n, nd_),
            wt.reshape(k_n, e_n * d, nd_),
            u,
            lap,
            absw,
        )


def time_varying_system(des: TimeVaryingDesign, noise: NoiseModel) -> TimeVaryingSystem:
    """The SAN with A(t) for a design and a noise model.

    Parameters
    ----------
    des : TimeVaryingDesign
        Lemma 1 at every instant.
    noise : NoiseModel
        σ_ji (per edge where given) and f.

    Returns
    -------
    TimeVaryingSystem
        Edge-difference matrix, per-edge σ and the design.

    Raises
    ------
    InputError
        A per-edge σ names an edge the topology does not have.
    """
    tv = des.topology
    st = des.structure
    d = tv.dim
    live = np.nonzero(st.sign != 0)[0]
    term = noise.term
    fmat = term.matrix(d)
    dmat = np.zeros((live.size * d, tv.nd))
    lab = tv.labels
    sig_by = {(str(a), str(b)): float(s) for (a, b), s in noise.sigma_edges.items()}
    sig = np.empty(live.size)
    for k, e in enumerate(live):
        i, j = int(st.ii[e]), int(st.jj[e])
        dmat[k * d : (k + 1) * d, j * d : (j + 1) * d] = fmat
        dmat[k * d : (k + 1) * d, i * d : (i + 1) * d] = -fmat
        sig[k] = sig_by.pop((str(lab[j]), str(lab[i])), noise.sigma)
    if sig_by:
        a, b_ = next(iter(sig_by))
        raise InputError(
            f"no edge {a}->{b_} in {tv.name or 'the topology'}", field="noise.sigma_edges"
        )
    return TimeVaryingSystem(des, dmat, sig, fmat, term.function, live)


def batch_size(sys_: TimeVaryingSystem) -> int:
    """The paths integrated together: BATCH, fewer where their states would pass
    MAX_BATCH_BYTES."""
    nd_ = sys_.structure.n * sys_.structure.d
    per = 8 * nd_ * (2 * nd_ + 2 * sys_.n_edges * sys_.structure.d + sys_.n_edges)
    return int(max(1, min(BATCH, MAX_BATCH_BYTES // max(per, 1))))


class DenseStep(Stepper):
    """One step of A(t) with a callable f: NumPy on the step's dense matrices."""

    def __init__(self, sys_: TimeVaryingSystem, m1, gt, wt, u):
        super().__init__(None, False)
        self.compiled = False
        self.sys, self.m1, self.gt, self.wt, self.u = sys_, m1, gt, wt, u

    def advance(self, x, xi, k_from, k_to, ch, cs, k_base=0) -> None:
        """Steps ``k_from .. k_to − 1`` of the batch (normals ``xi[k]``), in place."""
        sys_, nd_ = self.sys, x.shape[1]
        ne, d = sys_.n_edges, sys_.structure.d
        for k in range(k_from, k_to):
            y = x @ self.m1
            drift = y[:, :nd_]
            drift += self.u
            diff = y[:, nd_:].reshape(x.shape[0], ne, d)
            if sys_.f is not None:
                diff = sys_.f(diff)
            z = (diff * xi[k, :, ne : 2 * ne, None]).reshape(x.shape[0], ne * d)
            noise = xi[k, :, :ne] @ self.gt
            noise += z @ self.wt
            x += ch[k] * drift + cs[k] * noise


@dataclass(frozen=True, eq=False)
class ExpressionModes(ModeSource):
    """A(t) given as expressions: one mode per step, made for each batch of steps by the
    compiled expressions and Lemma 1 (batched): the dense arrays of L_B(t) for the
    compiled kernel (shared with the GPU, :func:`.gpu_timevarying.batch_modes`), or the
    dense step matrices for a callable f."""

    system: TimeVaryingSystem
    fusable = False  # the normals of a batch are drawn before its matrices are made

    def callable_f(self) -> bool:
        """Whether f is a callable.

        Returns
        -------
        bool
        """
        return self.system.f is not None

    def e_max(self) -> int:
        """The live edges E.

        Returns
        -------
        int
        """
        return self.system.n_edges

    def batch(self, paths: int) -> int:
        """:func:`batch_size` (Lemma 1 per batch is the cost to share).

        Parameters
        ----------
        paths : int
            The block's paths (the batch does not depend on them).

        Returns
        -------
        int
        """
        return batch_size(self.system)

    def ends(self, grid: TimeGrid) -> np.ndarray:  # doc: ModeSource.ends
        # every step is a mode of its own: a run is one step
        return np.arange(1, grid.n_steps + 2)

    def step_arrays(self, ts: np.ndarray) -> list:
        """The compiled kernel's arrays at each time of ``ts``: L_B(t) as a dense CSR
        pattern (its nonzeros move with t; Nd is small here) and, for d = 3, as dense
        3×3 blocks, u(t), the edges, K_e(t) = |A_ij(t)| F and g_e(t) = σ_ji |A_ij(t)| 1.

        Parameters
        ----------
        ts : numpy.ndarray
            The steps' times.

        Returns
        -------
        list of tuple
            Per time, :func:`.kernels.kernel_arrays`' (indptr, indices, data, bptr,
            bind, bdata, u, src, dst, kmat, gvec).
        """
        sys_ = self.system
        st = sys_.structure
        n, d = st.n, st.d
        nd_ = n * d
        b_t = sys_.design.at(ts)
        lap = np.ascontiguousarray(b_t.lap_b(st).reshape(ts.size, -1))
        u = np.ascontiguousarray(b_t.input_vector())
        absw = b_t.abs_w[:, sys_.live]
        kmat = np.ascontiguousarray(absw @ sys_.fmat)  # K_e(t) = |A_ij(t)| F
        gvec = np.ascontiguousarray(sys_.sigma[None, :, None] * absw.sum(axis=3))  # σ|A|1
        src = np.ascontiguousarray(st.jj[sys_.live], dtype=np.int64)
        dst = np.ascontiguousarray(st.ii[sys_.live], dtype=np.int64)
        indptr = np.arange(0, nd_ * nd_ + 1, nd_, dtype=np.int64)
        indices = np.tile(np.arange(nd_, dtype=np.int64), nd_)
        if d == 3:
            bptr = np.arange(0, n * n + 1, n, dtype=np.int64)
            bind = np.tile(np.arange(n, dtype=np.int64), n)
        else:
            bptr, bind = np.zeros(1, np.int64), np.zeros(0, np.int64)
        parts = []
        for kk in range(ts.size):
            blocks = (
                np.ascontiguousarray(
                    lap[kk].reshape(n, 3, n, 3).transpose(0, 2, 1, 3).reshape(-1, 3, 3)
                )
                if d == 3
                else np.zeros((0, 3, 3))
            )
            parts.append(
                (indptr, indices, lap[kk], bptr, bind, blocks, u[kk], src, dst, kmat[kk], gvec[kk])
            )
        return parts

    def for_batch(
        self, steppers: list[Stepper], grid: TimeGrid, k0: int, kb: int
    ) -> tuple[list[Stepper], np.ndarray]:
        """One stepper per step of the batch, from A(t) at its start.

        Parameters
        ----------
        steppers : list of Stepper
            Unused (the modes are made per batch).
        grid : TimeGrid
            The run's grid.
        k0, kb : int
            The batch.

        Returns
        -------
        (list of Stepper, numpy.ndarray)
        """
        ts = grid.t[k0 : k0 + kb]
        made: list[Stepper]
        if self.system.f is None:  # a linear f: the compiled edge kernel of the fixed case
            made = [Stepper.of_arrays(a) for a in self.step_arrays(ts)]
        else:
            m1, gt, wt, u, _, _ = self.system.matrices(ts)
            made = [DenseStep(self.system, m1[i], gt[i], wt[i], u[i]) for i in range(kb)]
        return made, np.arange(kb)


def _noise_term(s: np.ndarray, q: np.ndarray, kmat: np.ndarray, ii, jj, n: int, d: int):
    """``G Gᵀ + Σ_e K_e (S_jj − S_ji − S_ij + S_ii) K_eᵀ`` into the (i, i) blocks."""
    out = q.copy()
    if kmat.size:
        s4 = s.reshape(n, d, n, d)
        delta = s4[jj, :, jj, :] - s4[jj, :, ii, :] - s4[ii, :, jj, :] + s4[ii, :, ii, :]
        val = np.einsum("eab,ebc,edc->ead", kmat, delta, kmat)
        acc = np.zeros((n, d, d))
        np.add.at(acc, ii, val)
        ar = np.arange(n)
        out.reshape(n, d, n, d)[ar, :, ar, :] += acc
    return out


def generator_radius_tv(sys_: TimeVaryingSystem, t_end: float) -> tuple[float, float]:
    """(ρ_L, ρ_Q) of :func:`.moments.generator_radius` over [0, T]: sampled finely (the
    weights are smooth) with a 25 % allowance.

    Parameters
    ----------
    sys_ : TimeVaryingSystem
        The system.
    t_end : float
        The horizon T.

    Returns
    -------
    (float, float)
        ρ_L and ρ_Q.
    """
    probe = np.linspace(0.0, t_end, 801)
    _, _, _, _, lap, absw = sys_.matrices(probe)
    rho_l = 2 * float(np.max(np.abs(np.linalg.eigvals(lap)))) * 1.25
    with np.errstate(over="ignore", invalid="ignore"):
        kn = np.linalg.norm(absw @ sys_.fmat, ord=2, axis=(2, 3))
        rho_q = 4 * float(np.max(np.sum(kn**2, axis=1))) * 1.25 if kn.size else 0.0
    return rho_l, rho_q


def exact_moments_tv(
    sys_: TimeVaryingSystem,
    gain: Callable[[np.ndarray], np.ndarray],
    eps0: np.ndarray,
    save_times: np.ndarray,
    t_end: float,
) -> Moments:
    """Integrate the moment equations with A(t) from m(0) = ε0, S(0) = ε0ε0ᵀ by RK4 with
    steps h <= κ / (c(t) ρ), ρ bounding the generator's spectral radius over [0, T].

    Parameters
    ----------
    sys_ : TimeVaryingSystem
        The system (f linear).
    gain : callable
        Vectorised c(t).
    eps0 : numpy.ndarray
        ε(0) = x(0) − 1⊗θ, length Nd.
    save_times : numpy.ndarray
        Where to record the moments.
    t_end : float
        The horizon T.

    Returns
    -------
    Moments
        The moments at the save times.
    """
    st = sys_.structure
    n, d = st.n, st.d
    ii, jj = st.ii[sys_.live], st.jj[sys_.live]
    rho_l, rho_q = generator_radius_tv(sys_, t_end)
    saves = np.asarray(save_times, dtype=float)
    # the step grid: through every save time
    steps = [0.0]
    t = 0.0
    stops = list(saves[saves > 0]) + ([t_end] if t_end > saves[-1] else [])
    for stop in stops:
        while stop - t > 1e-14 * max(1.0, stop):
            c0 = float(gain(np.array([t]))[0])
            rho = rho_l + c0 * rho_q
            h = min(stop - t, KAPPA / (c0 * rho)) if c0 * rho > 0 else stop - t
            if stop - t - h < 0.25 * h:
                h = stop - t
            t = stop if h == stop - t else t + h
            steps.append(t)
    ts = np.array(steps)
    m = eps0.astype(float).copy()
    s = np.outer(eps0, eps0)
    rec = MomentRecorder(saves, n, d)
    rec.at(0.0, m, s)
    chunk = 256
    fm = sys_.fmat
    for c0 in range(0, ts.size - 1, chunk):
        ta = ts[c0 : min(c0 + chunk, ts.size - 1) + 1]
        hs = np.diff(ta)
        tq = np.concatenate([ta[:-1], ta[:-1] + hs / 2, ta[1:]])
        _, gtq, _, _, lq, aq = sys_.matrices(tq)
        qq = np.einsum("kea,keb->kab", gtq, gtq)
        kq = aq @ fm
        cq = np.asarray(gain(tq), dtype=float) * np.ones(tq.size)
        kn_ = hs.size

        def f(idx: int, m_: np.ndarray, s_: np.ndarray, lq=lq, cq=cq, qq=qq, kq=kq):
            lb = lq[idx]
            c = cq[idx]
            ls = lb @ s_
            return -c * (lb @ m_), -c * (ls + ls.T) + c * c * _noise_term(
                s_, qq[idx], kq[idx], ii, jj, n, d
            )

        for k in range(kn_):
            h = hs[k]
            k1m, k1s = f(k, m, s)
            k2m, k2s = f(kn_ + k, m + h / 2 * k1m, s + h / 2 * k1s)
            k3m, k3s = f(kn_ + k, m + h / 2 * k2m, s + h / 2 * k2s)
            k4m, k4s = f(2 * kn_ + k, m + h * k3m, s + h * k3s)
            m = m + h / 6 * (k1m + 2 * k2m + 2 * k3m + k4m)
            s = s + h / 6 * (k1s + 2 * k2s + 2 * k3s + k4s)
            s = 0.5 * (s + s.T)
            rec.at(float(ta[k + 1]), m, s)
    return rec.result(s, int(ts.size - 1))


def stability_ratio(sys_: TimeVaryingSystem, grid: TimeGrid, c_grid: np.ndarray) -> tuple:
    """max over steps of c·h / (2 Re λ / |λ|²) for L_B(t) (explicit Euler on ε' = −c L_B ε),
    evaluated on up to 2000 steps (every k-th) and at the worst one found."""
    k_n = grid.n_steps
    idx = np.unique(np.linspace(0, k_n - 1, min(k_n, 2000)).astype(np.int64))
    lap = sys_.matrices(grid.t[idx])[4]
    lam = np.linalg.eigvals(lap)
    with np.errstate(divide="ignore", invalid="ignore"):
        bnd = np.where(lam.real > 0, 2 * lam.real / np.abs(lam) ** 2, 0.0).min(axis=1)
    ratio = c_grid[idx] * grid.h[idx] / bnd
    w = int(np.argmax(ratio))
    return float(ratio[w]), float(grid.t[idx[w]]), float(bnd[w]), float(grid.h[idx[w]])


def tv_designs(tv: ExpressionTopology, theta: np.ndarray, margin: float) -> dict:
    """The design shown for an A(t) run: Lemma 1 at t = 0.

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.
    theta : numpy.ndarray
        θ.
    margin : float
        ΔC of Lemma 1.

    Returns
    -------
    dict
        One :class:`~ntc_design.protocol.ProtocolDesign`, keyed by the name at t = 0.
    """
    return {
        f"{tv.name or 'topology'} at t=0": design_topology(
            tv.at(0.0), theta, margin, thresholds=False
        )
    }


TV_NOTE = (
    "time-varying topology: A(t), C(t), δ(t), B_i(t), x0(t) re-evaluated at every step "
    "(Lemma 1 at each instant); the design table shows t = 0"
)


def _step_guard(
    sys_: TimeVaryingSystem, grid: TimeGrid, c_grid: np.ndarray, notes: list[str]
) -> None:
    """Refuse an unstable Euler–Maruyama grid for L_B(t); note one within a factor 2."""
    ratio, tw, bnd, hw = stability_ratio(sys_, grid, c_grid)
    if ratio >= 1.0:
        raise InputError(
            f"Euler–Maruyama is unstable: at t = {tw:.4g}, c·h exceeds 2·Re λ/|λ|² = "
            f"{bnd:.4g} for L_B(t); use dt < {hw / ratio:.3g}",
            field="dt",
        )
    if ratio > 0.5:
        notes.append(
            f"Euler–Maruyama step within a factor {1 / ratio:.2f} of instability at "
            f"t = {tw:.4g}; expect a step-size bias"
        )


def _check_exact_work_tv(sys_: TimeVaryingSystem, spec, cfun, gain_text: str) -> None:
    """Refuse, before the grid is built, RK4 moments with A(t) that would take too long."""
    ts = gain_samples(spec.T)
    c = check_gain(cfun, gain_text, ts)
    rho_l, rho_q = generator_radius_tv(sys_, spec.T)
    steps = estimate_exact_steps(ts, c, rho_l, rho_q, spec.save.count(spec.T))
    check_exact_work(steps, sys_.design.topology.n * sys_.design.topology.dim)


def simulate_expression(
    tv: ExpressionTopology, spec, cfun, gain_text: str, workers: int, progress, engine=None
):
    """The driver's path for an :class:`ExpressionTopology` (``simulate`` dispatches here):
    grid, checks, Monte Carlo and exact moments with A(t), and the result; the grid, the
    parameters, the runs and the divergence check are the fixed topology's
    (:mod:`.steps`, :func:`.result.finish`).

    Parameters
    ----------
    tv : ExpressionTopology
        The topology.
    spec : SimulationSpec
        The checked simulation options.
    cfun : callable
        Vectorised c(t).
    gain_text : str
        The gain as written, for messages and the summary.
    workers : int
        Processes.
    progress : callable(done, total) or None
        Called with path-steps done.
    engine : GpuEngine, optional
        Runs the paths on the GPU (``device: gpu``); None: on local processes.

    Returns
    -------
    SimulationResult
        The curves, design at t = 0, parameters and statistics.

    Raises
    ------
    InputError
        A wrong initial state, a gain negative or not finite on [0, T], an unstable
        Euler–Maruyama step, exact moments asked for a non-linear f.
    SimulationDiverged
        NaN or overflow in a path (the partial result is attached).
    """
    x_init, notes = spec.initial_state(tv.n, tv.dim)
    th = np.asarray(spec.theta, dtype=float)
    sys_ = time_varying_system(TimeVaryingDesign(tv, th, float(spec.margin)), spec.noise)
    if spec.method != "mc" and spec.noise.linear:
        _check_exact_work_tv(sys_, spec, cfun, gain_text)
    grid = spec_grid(spec, cfun, None)
    c_grid = check_gain(cfun, gain_text, grid.t[:-1])
    notes.append(TV_NOTE)
    designs = tv_designs(tv, th, spec.margin)
    if spec.method != "exact":
        _step_guard(sys_, grid, c_grid, notes)
    mspec = MonteCarloSpec(
        modes=ExpressionModes(sys_),
        grid=grid,
        gain=cfun,
        theta=th,
        x_init=x_init,
        n_agents=tv.n,
        dim=tv.dim,
        paths=spec.mc.paths,
        seed=spec.mc.seed,
        rng=spec.mc.rng,
        block_size=spec.mc.block_size,
        store_paths=spec.mc.store_paths,
    )
    part, mc_stats = run_monte_carlo(spec, mspec, workers, progress, engine, notes)
    exact, exact_stats = run_exact(
        spec,
        notes,
        lambda: exact_moments_tv(
            sys_, cfun, x_init - np.tile(th, tv.n), grid.save_times, float(grid.t[-1])
        ),
    )
    params = run_parameters(spec, th, gain_text, x_init, workers, grid, list(designs))
    params["time_varying"] = {
        "period": str(tv.period) if tv.period is not None else None,
        "constant_after": str(tv.constant_after) if tv.constant_after is not None else None,
        "topology": tv.to_dict(),
    }
    runs = Runs(part=part, exact=exact, mc_stats=mc_stats, exact_stats=exact_stats)
    return finish_run(tuple(tv.labels), th, grid, designs, params, spec, runs, notes)


__all__ = [
    "DenseStep",
    "ExpressionModes",
    "batch_size",
    "simulate_expression",
    "TimeVaryingSystem",
    "exact_moments_tv",
    "generator_radius_tv",
    "tv_designs",
    "time_varying_system",
]
