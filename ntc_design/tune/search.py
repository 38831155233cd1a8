"""A bounded, derivative-free search: a coarse grid, then Nelder–Mead from its best points.

The objective is smooth in the gain's parameters (and, with common random numbers, so is a
Monte Carlo estimate), but it may have flat valleys and +∞ where a candidate is too stiff
to integrate. A grid over the box finds the basin; SciPy's bounded Nelder–Mead
(``scipy.optimize.minimize``) refines from the best ``starts`` grid points (and any extra
starts, e.g. the baseline gain) in coordinates scaled to [0, 1], on log(value). Every
evaluation is cached and kept: the result lists them all.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize


@dataclass(frozen=True)
class Dimension:
    """One searched parameter: its range, and whether it is searched on a log scale."""

    name: str
    lo: float
    hi: float
    log: bool = False
    points: int = 4  # on the coarse grid

    def to_unit(self, x: float) -> float:
        """x in [lo, hi] to [0, 1] (log or linear).

        Parameters
        ----------
        x : float
            A value in [lo, hi].

        Returns
        -------
        float
        """
        if self.hi == self.lo:
            return 0.0
        if self.log:
            return math.log(x / self.lo) / math.log(self.hi / self.lo)
        return (x - self.lo) / (self.hi - self.lo)

    def from_unit(self, u: float) -> float:
        """[0, 1] to [lo, hi] (clipped).

        Parameters
        ----------
        u : float
            A unit coordinate.

        Returns
        -------
        float
        """
        u = min(1.0, max(0.0, float(u)))
        if self.log:
            return float(self.lo * (self.hi / self.lo) ** u)
        return float(self.lo + u * (self.hi - self.lo))

    def grid(self) -> np.ndarray:
        """The coarse grid's values: ``points`` equally spaced (in log for a log
        dimension), or the one value of a fixed dimension.

        Returns
        -------
        numpy.ndarray
        """
        if self.hi == self.lo or self.points < 2:
            return np.array([self.from_unit(0.5)])  # lo when the dimension is fixed
        return np.array([self.from_unit(u) for u in np.linspace(0.0, 1.0, self.points)])


@dataclass(frozen=True)
class Trace:
    """Every point evaluated (in order) with its value, and the best of them."""

    names: tuple[str, ...]
    points: tuple[tuple[float, ...], ...]
    values: tuple[float, ...]

    @property
    def best(self) -> tuple[tuple[float, ...], float]:
        """The point of least value, and that value."""
        k = int(np.argmin(self.values))
        return self.points[k], self.values[k]


def search(
    fun: Callable[[dict[str, float]], float],
    dims: Sequence[Dimension],
    extra_starts: Sequence[dict[str, float]] = (),
    starts: int = 2,
    max_evaluations: int = 200,
) -> Trace:
    """Minimise ``fun`` over the box ``dims``: the grid, then Nelder–Mead.

    Parameters
    ----------
    fun : callable(dict) -> float
        The objective at named parameter values (+∞ allowed).
    dims : sequence of Dimension
        The searched parameters.
    extra_starts : sequence of dict, optional
        Points evaluated with the grid and eligible as starts (inside the box).
    starts : int, optional
        Local refinements from the best grid points.
    max_evaluations : int, optional
        The whole budget, grid included.

    Returns
    -------
    Trace
    """
    names = tuple(d.name for d in dims)
    cache: dict[tuple[float, ...], float] = {}
    order: list[tuple[float, ...]] = []

    def at(x: Sequence[float]) -> float:
        key = tuple(float(f"{v:.10g}") for v in x)
        if key not in cache:
            if len(cache) >= max_evaluations:
                return math.inf
            cache[key] = float(fun(dict(zip(names, key, strict=True))))
            order.append(key)
        return cache[key]

    dims = _fit_grid(dims, max_evaluations // 2)
    grid = list(itertools.product(*(d.grid() for d in dims)))
    for x in [tuple(s[n] for n in names) for s in extra_starts] + grid:
        at(x)
    ranked = sorted((v, k) for k, v in cache.items() if math.isfinite(v))
    free = [d for d in dims if d.hi > d.lo]
    if free and ranked:
        per = max(10, (max_evaluations - len(cache)) // max(1, starts))
        for _, x0 in ranked[:starts]:
            _refine(at, dims, x0, per)
    return Trace(names, tuple(order), tuple(cache[k] for k in order))


def _fit_grid(dims: Sequence[Dimension], most: int) -> list[Dimension]:
    """Fewer grid points (the most numerous first) until the grid has at most ``most``."""
    pts = [d.points if d.hi > d.lo else 1 for d in dims]
    while math.prod(pts) > max(most, 1) and max(pts) > 2:
        k = int(np.argmax(pts))
        pts[k] -= 1
    return [replace(d, points=p) for d, p in zip(dims, pts, strict=True)]


def _refine(
    at: Callable[[Sequence[float]], float],
    dims: Sequence[Dimension],
    x0: tuple[float, ...],
    budget: int,
) -> None:
    """Nelder–Mead on log(value) in unit coordinates of the free dimensions."""
    free = [i for i, d in enumerate(dims) if d.hi > d.lo]

    def full(u: np.ndarray) -> list[float]:
        x = list(x0)
        for k, i in enumerate(free):
            x[i] = dims[i].from_unit(u[k])
        return x

    def f(u: np.ndarray) -> float:
        v = at(full(u))
        return math.log(v) if 0 < v < math.inf else (1e300 if v == math.inf else -1e300)

    u0 = np.array([dims[i].to_unit(x0[i]) for i in free])
    simplex = [u0] + [
        np.clip(u0 + np.eye(len(free))[k] * (0.15 if u0[k] < 0.85 else -0.15), 0, 1)
        for k in range(len(free))
    ]
    minimize(
        f,
        u0,
        method="Nelder-Mead",
        bounds=[(0.0, 1.0)] * len(free),
        options={
            "maxfev": budget,
            "xatol": 2e-3,
            "fatol": 1e-5,
            "initial_simplex": np.array(simplex),
        },
    )
