"""The optimal schedule of the digital protocol (``ntc tune`` with a period h, a delay D
and the optimal schedule): optimal control of the sampled recursion's exact second moments.

The same problem as :mod:`.optimal` with the recursion in place of the moment equations:
c is piecewise linear on K pieces of [0, T] and enters the recursion through its samples
c_k = c(kh) (at the finest level, one node per sample: a sampled schedule); with the
augmented state z_k = (e_k, …, e_{k−D}) and Z_k = E[z_k z_kᵀ],

    Z_{k+1} = A_k Z_k A_kᵀ + h c_k² E₀ (Q + 𝓐₂(Z_DD)) E₀ᵀ,   A_k = S − h c_k E₀ L E_Dᵀ,

(S the shift, E₀ and E_D the first and last blocks), J = tr (Z_K)₀₀. The gradient is the
exact discrete adjoint Λ_k = A_kᵀ Λ_{k+1} A_k + h c_k² E_D 𝓐₂*(Λ_{k+1,00}) E_Dᵀ with
∂J/∂c_k = ⟨Λ_{k+1}, ∂Z_{k+1}/∂c_k⟩ (a finite-difference test checks it). The class has the
interface :func:`.optimal.solve` and :func:`.optimal.optimise_schedule` use.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, Option, format_bytes
from ..protocol.digital import Digital
from ..simulate.digital import check_digital_moments
from ..simulate.grid import TimeGrid
from ..simulate.moments import MomentRhs
from ..simulate.prepare import PreparedModes
from .schedule_problem import BIG, MAX_STORE, Forward, MomentProblem


@dataclass(frozen=True, eq=False)
class SamplePlan:
    """The samples: the node interval k of each sample time, its position θ ∈ [0, 1]
    there (a (K, 1) column), the sample's end time and mode."""

    k: np.ndarray
    theta: np.ndarray
    t_end: np.ndarray
    mode: np.ndarray
    pieces: np.ndarray
    nodes: int

    @property
    def steps(self) -> int:
        """K, the samples."""
        return int(self.k.size)


class SampledScheduleProblem(MomentProblem):
    """J(c) = E Σ‖x_i(Kh) − θ‖² of the sampled recursion for a piecewise-linear c on K
    pieces, its exact gradient and the traces for the peak aggregate (see the module).

    Parameters
    ----------
    prepared : PreparedModes
        The continuous design's modes.
    grid : TimeGrid
        The sampling grid (its modes per sample).
    digital : Digital
        The period and delay.
    """

    def __init__(self, prepared: PreparedModes, grid: TimeGrid, digital: Digital) -> None:
        n, d = prepared.n, prepared.d
        self.nd, self.delay, self.h = n * d, digital.delay, digital.period
        check_digital_moments(self.nd, self.delay, grid.n_steps)
        w = (self.delay + 1) * self.nd
        need = grid.n_steps * w * w * 8.0
        if need > MAX_STORE:
            raise InputError(
                f"{grid.n_steps} samples of a {w}×{w} second moment "
                f"would store {format_bytes(need)} for the adjoint (limit "
                f"{format_bytes(MAX_STORE)}); raise ",
                Option("period"),
                " or shorten T",
                field="schedule",
                value="optimal",
            )
        self.grid = grid
        self.horizon = float(grid.t[-1])
        # each step's τ/c and noise factor: h, h; a last partial step s: s, s²/h
        self.hs = np.full(grid.n_steps, self.h)
        self.qs = np.full(grid.n_steps, self.h)
        if grid.noise_last is not None:
            self.hs[-1], self.qs[-1] = float(grid.h[-1]), grid.noise_last
        self.rhs = [MomentRhs(s, n, d) for s in prepared.systems]
        self.laps = [
            np.asarray(r.l.toarray() if hasattr(r.l, "toarray") else r.l) for r in self.rhs
        ]
        z = np.tile(prepared.eps0, self.delay + 1)
        self.z0 = np.outer(z, z)
        self.initial = float(prepared.eps0 @ prepared.eps0)
        self.evaluations = 0

    def plan(self, c: np.ndarray, kappa: float = 0.0) -> SamplePlan:
        """Where each sample lies among the nodes (the same for any node values).

        Parameters
        ----------
        c : numpy.ndarray
            Node values (their number fixes the pieces).
        kappa : float, optional
            Unused (the recursion has no step control).

        Returns
        -------
        SamplePlan
        """
        kk = c.size - 1
        t = self.grid.t[:-1]
        width = self.horizon / kk
        k = np.clip(np.floor(t / width).astype(np.int64), 0, kk - 1)
        theta = np.clip((t - k * width) / width, 0.0, 1.0)[:, None]
        return SamplePlan(k, theta, self.grid.t[1:], self.grid.mode, np.ones(kk, np.int64), c.size)

    def _gains(self, c: np.ndarray, plan: SamplePlan) -> np.ndarray:
        th = plan.theta[:, 0]
        return c[plan.k] * (1 - th) + c[plan.k + 1] * th

    def _adjoint_noise(self, r: MomentRhs, lam: np.ndarray) -> np.ndarray:
        """𝓐₂*(Λ) = Σ_e G_eᵀ Λ G_e (Λ's diagonal blocks of the edges' agents i)."""
        n, d = self.nd // r.d, r.d
        blocks = np.zeros((n * n, d, d))  # block (p, q) of the result at p·n + q
        if r.k.size:
            l4 = lam.reshape(n, d, n, d)
            li = l4[r.ii, :, r.ii, :]  # (E, d, d)
            v = np.einsum("eba,ebc,ecf->eaf", r.k, li, r.k)  # K_eᵀ Λ_ii K_e
            for p, q, sgn in (
                (r.jj, r.jj, 1.0),
                (r.jj, r.ii, -1.0),
                (r.ii, r.jj, -1.0),
                (r.ii, r.ii, 1.0),
            ):
                np.add.at(blocks, p * n + q, sgn * v)
        out = blocks.reshape(n, n, d, d).transpose(0, 2, 1, 3)
        return out.reshape(self.nd, self.nd)

    def forward(self, c: np.ndarray, plan: SamplePlan, store: bool = True) -> Forward | None:
        """The recursion from the held initial state; None when it overflows.

        Parameters
        ----------
        c : numpy.ndarray
            Node values.
        plan : SamplePlan
            The samples.
        store : bool, optional
            Keep every Z_k (the adjoint needs them).

        Returns
        -------
        Forward or None
            ``stages`` holds the Z_k (K, w, w), ``gains`` the c_k.
        """
        self.evaluations += 1
        n, lo = self.nd, self.delay * self.nd
        ck = self._gains(c, plan)
        zz = self.z0.copy()
        steps = plan.steps
        traces = np.empty(steps)
        zs = np.empty((steps, *zz.shape)) if store else None
        with np.errstate(all="ignore"):
            for j in range(steps):
                if zs is not None:
                    zs[j] = zz
                lap, r = self.laps[plan.mode[j]], self.rhs[plan.mode[j]]
                cc = float(ck[j])
                tau = self.hs[j] * cc
                rr = zz[:n, :] - tau * (lap @ zz[lo:, :])
                top = (
                    rr[:, :n]
                    - tau * (rr[:, lo:] @ lap.T)
                    + (self.qs[j] * cc * cc) * r.noise(zz[lo:, lo:])
                )
                nxt = np.empty_like(zz)
                nxt[:n, :n] = 0.5 * (top + top.T)
                if self.delay:
                    nxt[:n, n:] = rr[:, :lo]
                    nxt[n:, :n] = rr[:, :lo].T
                    nxt[n:, n:] = zz[:lo, :lo]
                zz = nxt
                traces[j] = float(np.trace(zz[:n, :n]))
            if not np.all(np.isfinite(traces)) or traces.max() > BIG * max(self.initial, 1.0):
                return None
        return Forward(float(traces[-1]), traces, zs, ck[:, None])

    def adjoint(
        self, plan: SamplePlan, fwd: Forward, sources: np.ndarray | None = None
    ) -> np.ndarray:
        """The gradient, with respect to the node values, of Σ_j sources_j·tr (Z_{j+1})₀₀
        (default: the last alone), by the discrete adjoint of the recursion.

        Parameters
        ----------
        plan : SamplePlan
            The samples.
        fwd : Forward
            What :meth:`forward` returned (with ``store=True``).
        sources : numpy.ndarray, optional
            Weights on the traces after each sample.

        Returns
        -------
        numpy.ndarray
            ∂/∂c at the nodes.
        """
        zs, ck = fwd.stages, fwd.gains[:, 0]
        assert zs is not None, "forward(..., store=True) keeps what the adjoint needs"
        n, lo = self.nd, self.delay * self.nd
        steps = plan.steps
        if sources is None:
            sources = np.zeros(steps)
            sources[-1] = 1.0
        w = zs.shape[1]
        lam = np.zeros((w, w))
        dc = np.zeros(steps)
        eye = np.eye(n)
        for j in range(steps - 1, -1, -1):
            lam[:n, :n] += sources[j] * eye  # ∂ tr (Z_{j+1})₀₀ / ∂Z_{j+1}
            lap, r = self.laps[plan.mode[j]], self.rhs[plan.mode[j]]
            cc = float(ck[j])
            h, q = float(self.hs[j]), float(self.qs[j])
            tau = h * cc
            zz = zs[j]
            # A = S − τ E₀ L E_Dᵀ (S the shift): A Z, for ∂/∂c
            az = _shift(zz, n, lo)
            az[:n, :] -= tau * (lap @ zz[lo:, :])
            # ∂/∂c: 2⟨Λ, (∂A/∂c) Z Aᵀ⟩ + ⟨Λ₀₀, 2hc (Q + 𝓐₂(Z_DD))⟩, ∂A/∂c = −h E₀ L E_Dᵀ
            m1 = lam[:, :n] @ lap  # Λ E₀ L  (w × n)
            dc[j] = -2 * h * float(np.sum(m1 * az[:, lo:])) + 2 * q * cc * float(
                np.sum(lam[:n, :n] * r.noise(zz[lo:, lo:]))
            )
            # Λ_j = Aᵀ Λ A + h c² E_D 𝓐₂*(Λ₀₀) E_Dᵀ
            la = _shift_t(lam, n, lo).T  # Λ S = (Sᵀ Λ)ᵀ
            la[:, lo:] -= tau * m1  # Λ A
            new = _shift_t(la, n, lo)  # Sᵀ (Λ A)
            new[lo:, :] -= tau * (lap.T @ la[:n, :])  # − τ E_D Lᵀ E₀ᵀ (Λ A)
            new[lo:, lo:] += (q * cc * cc) * self._adjoint_noise(r, lam[:n, :n])
            lam = 0.5 * (new + new.T)
        out = np.zeros(plan.nodes)
        th = plan.theta[:, 0]
        np.add.at(out, plan.k, dc * (1 - th))
        np.add.at(out, plan.k + 1, dc * th)
        return out


def _shift(m: np.ndarray, n: int, lo: int) -> np.ndarray:
    """S·m, S the shift of the augmented state (block 0 stays, block a + 1 takes block a;
    the identity without a delay)."""
    out = np.empty_like(m)
    out[:n] = m[:n]
    out[n:] = m[:lo]
    return out


def _shift_t(m: np.ndarray, n: int, lo: int) -> np.ndarray:
    """Sᵀ·m: block 0 gets blocks 0 and 1, block b gets block b + 1, the last block 0."""
    out = np.zeros_like(m)
    out[:lo] = m[n:]
    out[:n] += m[:n]
    return out


__all__ = ["SamplePlan", "SampledScheduleProblem"]
