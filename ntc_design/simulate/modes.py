"""Where the steps of a Monte Carlo block get their modes: a :class:`ModeSource`.

:class:`FixedModes` holds the mode systems of one topology, a switching set or a sampled
A(t) (one :class:`Stepper` per mode, kept for every block of a chunk; a run of steps
stops where the mode changes or a save point falls); :class:`.timevarying.ExpressionModes`
makes one mode per step of each batch from A(t) given as expressions. The block loop
(:func:`.montecarlo.run_block`) and the GPU (:mod:`.gpu_run`) read the modes only through
this interface.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .grid import TimeGrid
from .implicit import SolverCache
from .system import ModeSystem

if TYPE_CHECKING:  # the kernels' module compiles Numba code when imported
    from .kernels import KernelArrays

BATCH = 64  # steps whose normals are drawn at once (fewer when they would pass XI_BYTES)
XI_BYTES = 16 * 2**20  # bound on the buffer of normals of one batch


def run_ends(grid: TimeGrid) -> np.ndarray:
    """``ends[k]``: the first grid index after k where a run of steps must stop (a save
    point, or a step of another mode); each run has one mode and records at its end.

    Parameters
    ----------
    grid : TimeGrid
        The run's grid.

    Returns
    -------
    numpy.ndarray
        K + 1 grid indices.
    """
    k_total = grid.n_steps
    cut = np.zeros(k_total + 1, dtype=bool)
    cut[grid.save_steps] = True
    cut[k_total] = True
    if k_total > 1:
        cut[1:k_total][grid.mode[1:] != grid.mode[:-1]] = True
    where = np.flatnonzero(cut)
    return where[
        np.searchsorted(where, np.arange(k_total + 1), side="right").clip(max=where.size - 1)
    ]


class Stepper:
    """One mode's arrays for the kernels, and the implicit scheme's solvers (one per
    distinct c·h: with intrinsic stepping c·h = ds except next to events), kept for every
    block of a chunk."""

    def __init__(
        self,
        s: ModeSystem | None,
        implicit: bool,
        delay: int = 0,
        args: KernelArrays | None = None,
    ):
        self.s, self.delay = s, delay
        self.compiled = s is None or s.f is None
        if args is not None:
            self.args = args
        elif s is not None and self.compiled:
            from .kernels import kernel_arrays

            self.args = kernel_arrays(s)
        self.solver = SolverCache(s.lap_b, s.dim) if implicit and s is not None else None

    @classmethod
    def of_arrays(cls, args: KernelArrays) -> Stepper:
        """An explicit stepper on given kernel arrays (a mode of one step of A(t)).

        Parameters
        ----------
        args : tuple
            :func:`.kernels.kernel_arrays`' (indptr, indices, data, bptr, bind, bdata, u,
            src, dst, kmat, gvec).

        Returns
        -------
        Stepper
        """
        return cls(None, False, 0, args)

    @property
    def mode(self) -> ModeSystem:
        """The mode system (a stepper on a callable f has one)."""
        assert self.s is not None, "a stepper on kernel arrays has no mode system"
        return self.s

    @property
    def fused(self) -> bool:
        """Whether the kernel draws its own normals (compiled and explicit)."""
        return self.compiled and self.solver is None

    def advance_drawing(self, x, states, m_draw, k_from, k_to, ch, cs, k_base=0) -> None:
        """:meth:`advance` with the normals drawn in the kernel from ``states`` (``m_draw``
        per path and step, the widest mode's 2·E, so every mode consumes the same)."""
        from .kernels import em_steps_rng, tile_width

        tile = tile_width(x.shape[0], x.shape[1])
        em_steps_rng(
            x, states, m_draw, k_from, k_to, ch, cs, *self.args, True, tile, self.delay, k_base
        )

    def advance(self, x, xi, k_from, k_to, ch, cs, k_base=0) -> None:
        """Steps ``k_from .. k_to − 1`` of the batch (normals ``xi[k]``), in place."""
        from .kernels import em_steps, numpy_step, tile_width  # numba: only when simulating

        tile = tile_width(x.shape[0], x.shape[1])
        if self.solver is None:
            if self.compiled:
                em_steps(x, xi, k_from, k_to, ch, cs, *self.args, True, tile, self.delay, k_base)
            else:
                for k in range(k_from, k_to):
                    numpy_step(x, xi[k], ch[k], cs[k], self.mode, delay=self.delay, step=k_base + k)
            return
        solver = self.solver
        for k in range(k_from, k_to):
            if self.compiled:
                em_steps(x, xi, k, k + 1, ch, cs, *self.args, False, tile)
            else:
                numpy_step(x, xi[k], ch[k], cs[k], self.mode, drift=False)
            x[...] = solver(ch[k]).solve(x.T).T


class ModeSource:
    """The modes of a run's steps, as the block loop asks for them: the steppers of a
    chunk, and per batch of steps the stepper of each step."""

    fusable = True  # whether the kernel may draw its own normals (:meth:`Stepper.fused`)

    def kernel_systems(self) -> tuple[ModeSystem, ...]:
        """The mode systems whose compiled kernel is loaded before the workers fork.

        Returns
        -------
        tuple of ModeSystem
            None for modes made step by step.
        """
        return ()

    def callable_f(self) -> bool:
        """Whether f is a callable (the GPU needs a linear one).

        Returns
        -------
        bool
        """
        raise NotImplementedError

    def e_max(self) -> int:
        """The edges of the widest mode (a path draws 2·e_max normals per step).

        Returns
        -------
        int
        """
        raise NotImplementedError

    def batch(self, paths: int) -> int:
        """The steps between two checks of a block (and whose normals are drawn at once):
        BATCH, fewer when a batch of normals would pass XI_BYTES.

        Parameters
        ----------
        paths : int
            The block's paths.

        Returns
        -------
        int
        """
        return int(np.clip(XI_BYTES // (8 * paths * max(2 * self.e_max(), 1)), 1, BATCH))

    def ends(self, grid: TimeGrid) -> np.ndarray:
        """``ends[k]``: where a run of steps from k must stop (:func:`run_ends`).

        Parameters
        ----------
        grid : TimeGrid
            The run's grid.

        Returns
        -------
        numpy.ndarray
            K + 1 grid indices.
        """
        return run_ends(grid)

    def steppers(self, implicit: bool, delay: int) -> list[Stepper]:
        """The steppers kept for every block of a chunk.

        Parameters
        ----------
        implicit : bool
            The implicit scheme (one sparse LU per mode and c·h).
        delay : int
            The sampled protocol's D.

        Returns
        -------
        list of Stepper
        """
        return []

    def for_batch(
        self, steppers: list[Stepper], grid: TimeGrid, k0: int, kb: int
    ) -> tuple[list[Stepper], np.ndarray]:
        """The steppers of the steps k0 … k0 + kb − 1 and the index of each step's.

        Parameters
        ----------
        steppers : list of Stepper
            The chunk's (:meth:`steppers`).
        grid : TimeGrid
            The run's grid.
        k0, kb : int
            The batch's first step and its length.

        Returns
        -------
        (list of Stepper, numpy.ndarray)
            The steppers and, per step of the batch, its stepper's index.
        """
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class FixedModes(ModeSource):
    """The mode systems of one topology, a switching set or a sampled A(t), stepped by
    the grid's mode of each step."""

    systems: tuple[ModeSystem, ...]

    def kernel_systems(self) -> tuple[ModeSystem, ...]:
        """The mode systems.

        Returns
        -------
        tuple of ModeSystem
        """
        return self.systems

    def callable_f(self) -> bool:
        """Whether a mode's f is a callable.

        Returns
        -------
        bool
        """
        return any(s.f is not None for s in self.systems)

    def e_max(self) -> int:
        """The edges of the widest mode.

        Returns
        -------
        int
        """
        return max(s.n_edges for s in self.systems)

    def steppers(self, implicit: bool, delay: int) -> list[Stepper]:
        """One stepper per mode (the implicit solvers built once per chunk).

        Parameters
        ----------
        implicit : bool
            The implicit scheme.
        delay : int
            The sampled protocol's D.

        Returns
        -------
        list of Stepper
        """
        return [Stepper(s, implicit, delay) for s in self.systems]

    def for_batch(
        self, steppers: list[Stepper], grid: TimeGrid, k0: int, kb: int
    ) -> tuple[list[Stepper], np.ndarray]:
        """The chunk's steppers, by the grid's mode of each step.

        Parameters
        ----------
        steppers : list of Stepper
            One per mode.
        grid : TimeGrid
            The run's grid.
        k0, kb : int
            The batch.

        Returns
        -------
        (list of Stepper, numpy.ndarray)
        """
        return steppers, grid.mode[k0 : k0 + kb]


__all__ = ["BATCH", "XI_BYTES", "FixedModes", "ModeSource", "Stepper", "run_ends"]
