"""The measurement noise of Niu & Wu, eq. (5): σ_ji per edge (additive) and the
state-dependent f_ji (multiplicative), with Assumption 1's ‖f(x)‖ <= σ̄‖x‖.

:class:`NoiseModel` is what users write (σ, f, per-edge σ). Its ``f`` may be a number s
(f(x) = s·x), a d×d matrix F (f(x) = F x) or a callable on arrays of differences; each
form is a :class:`StateNoise` (:class:`ScalarNoise`, :class:`MatrixNoise`,
:class:`CallableNoise`) with one interface: whether it is linear (so that the exact
moments apply), the matrix the kernels multiply the edge differences by, the function
applied instead when it is not linear, and a check against the state dimension. The
kernels and the moment equations ask that interface, never the type of ``f``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, quote, require_number
from ..model.paper import F_SCALE, SIGMA


class StateNoise:
    """The state-dependent noise term f of one model: the base of the three forms."""

    #: Whether f(x) = F x, so that the moment equations are exact.
    linear: bool = True

    def matrix(self, d: int) -> np.ndarray:
        """The matrix the edge differences are multiplied by.

        Parameters
        ----------
        d : int
            The state dimension.

        Returns
        -------
        numpy.ndarray
            F (d×d) for a linear f; the identity when f is applied as a function.
        """
        return np.eye(d)

    @property
    def function(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """The function applied to the (F-multiplied) differences; None when linear.

        Returns
        -------
        callable or None
        """
        return None

    def check(self, d: int, n_edges: int) -> None:
        """Refuse an f that does not fit d-dimensional states (before a run).

        Parameters
        ----------
        d : int
            The state dimension.
        n_edges : int
            Edges of the largest mode (the shape the kernels call f with).

        Raises
        ------
        InputError
            f does not fit.
        """
        self.matrix(d)


@dataclass(frozen=True)
class ScalarNoise(StateNoise):
    """f(x) = s·x.

    Attributes
    ----------
    s : float
        The scale.
    """

    s: float

    def matrix(self, d: int) -> np.ndarray:
        """s·I.

        Parameters
        ----------
        d : int
            The state dimension.

        Returns
        -------
        numpy.ndarray
        """
        return float(self.s) * np.eye(d)


@dataclass(frozen=True, eq=False)
class MatrixNoise(StateNoise):
    """f(x) = F x.

    Attributes
    ----------
    f : numpy.ndarray
        F, d×d.
    """

    f: np.ndarray

    def matrix(self, d: int) -> np.ndarray:
        """F, checked against d.

        Parameters
        ----------
        d : int
            The state dimension.

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        InputError
            F is not d×d.
        """
        if self.f.shape != (d, d):
            raise InputError(
                f"expected a scalar or a {d}x{d} matrix, got shape {self.f.shape}", field="noise.f"
            )
        return self.f


@dataclass(frozen=True, eq=False)
class CallableNoise(StateNoise):
    """f given as a function on arrays of differences of shape (..., d); Monte Carlo only.

    Attributes
    ----------
    fn : callable
        The function; it must return an array of the shape it was given.
    """

    fn: Callable[[np.ndarray], np.ndarray]
    linear = False

    @property
    def function(self) -> Callable[[np.ndarray], np.ndarray]:
        """The user's function.

        Returns
        -------
        callable
        """
        return self.fn

    def check(self, d: int, n_edges: int) -> None:
        """Call f once on a probe of the kernels' shape and check what comes back.

        Parameters
        ----------
        d : int
            The state dimension.
        n_edges : int
            Edges of the largest mode.

        Raises
        ------
        InputError
            f fails on the probe or returns another shape.
        """
        probe = np.zeros((2, n_edges, d))
        try:
            with np.errstate(all="ignore"):
                out = np.asarray(self.fn(probe + 1.0))
        except Exception as exc:  # noqa: BLE001 - user code
            raise InputError(
                f"calling it on an array of shape {probe.shape} failed ({exc.__class__.__name__})",
                field="noise.f",
            ) from None
        if out.shape != probe.shape:
            raise InputError(
                f"returned shape {out.shape} for input shape {probe.shape}; it must "
                "return the same shape",
                field="noise.f",
            )


def state_noise(f: float | np.ndarray | Callable[[np.ndarray], np.ndarray]) -> StateNoise:
    """The :class:`StateNoise` of a user's f.

    Parameters
    ----------
    f : float, array_like or callable
        A number, a d×d matrix or a function.

    Returns
    -------
    StateNoise
    """
    if callable(f):
        return CallableNoise(f)
    arr = np.asarray(f, dtype=float)
    return ScalarNoise(float(arr)) if arr.ndim == 0 else MatrixNoise(arr)


# States and noise intensities (θ, x(0), σ, f) are squared and summed over agents, edges
# and paths (mean-square errors, noise covariances, f² in the moment equations): at most
# 1e100 in magnitude keeps every such sum far inside the float range (1.8e308), so a value
# like 1e300 is refused naming its field instead of overflowing deep inside a run.
MAX_MAGNITUDE = 1e100


@dataclass(frozen=True)
class NoiseModel:
    """σ_ji (a default and per-edge overrides keyed by (from, to) labels) and f_ji: a
    scalar s (f(x) = s·x), a d×d matrix F (f(x) = F x) or a callable acting on arrays of
    differences of shape (..., d) (it must satisfy Assumption 1: ‖f(x)‖ <= σ̄‖x‖)."""

    sigma: float = SIGMA  # the paper's σ and f(x) = 0.3x, defined once in ntc_design.model.paper
    f: float | np.ndarray | Callable[[np.ndarray], np.ndarray] = F_SCALE
    sigma_edges: Mapping[tuple, float] = field(default_factory=dict)

    @property
    def term(self) -> StateNoise:
        """f as a :class:`StateNoise`.

        Returns
        -------
        StateNoise
        """
        return state_noise(self.f)

    @property
    def linear(self) -> bool:
        """Whether f(x) = F x (a number or a matrix rather than a callable).

        Returns
        -------
        bool
        """
        return self.term.linear

    def f_matrix(self, d: int) -> np.ndarray:
        """The matrix F of a linear f(x) = F x.

        Parameters
        ----------
        d : int
            The state dimension.

        Returns
        -------
        numpy.ndarray
            F, d×d (s·I for a number s).

        Raises
        ------
        ValueError
            f is a callable.
        InputError
            f is a matrix of the wrong shape.
        """
        if not self.linear:
            raise ValueError("f is a callable")
        return self.term.matrix(d)


def noise_from_document(doc: Any) -> NoiseModel:
    """A scenario's (or a run summary's) ``noise`` mapping as a :class:`NoiseModel`: the one
    reading of it, with the defaults of :class:`NoiseModel` (the paper's σ and f).

    Parameters
    ----------
    doc : Any
        ``{sigma, f, sigma_edges}`` (each optional), or None for the defaults.

    Returns
    -------
    NoiseModel

    Raises
    ------
    InputError
        One line naming the field that is wrong.
    """
    if doc is None:
        return NoiseModel()
    if not isinstance(doc, Mapping):
        raise InputError("expected {sigma, f, sigma_edges}", field="noise")
    extra = sorted(str(k) for k in set(doc) - {"sigma", "f", "sigma_edges"})
    if extra:
        raise InputError(
            "unknown field (allowed: sigma, f, sigma_edges)", field=f"noise.{extra[0]}"
        )
    sigma = require_number("noise.sigma", doc.get("sigma", SIGMA), minimum=0.0, bound=MAX_MAGNITUDE)
    f = doc.get("f", F_SCALE)
    if isinstance(f, list):
        for r, row in enumerate(f):
            if not isinstance(row, list):
                raise InputError("expected a row (a list of numbers)", field=f"noise.f[{r}]")
            if len(row) != len(f):
                raise InputError(
                    f"expected a square matrix, row {r} has {len(row)} of {len(f)} entries",
                    field="noise.f",
                )
            for c, v in enumerate(row):
                require_number(f"noise.f[{r}][{c}]", v, bound=MAX_MAGNITUDE)
        f = np.asarray(f, dtype=float) if f else f
    elif isinstance(f, bool) or not isinstance(f, (int, float)):
        raise InputError(f"expected a number or a d×d matrix, got {f!r}"[:192], field="noise.f")
    else:
        require_number("noise.f", f, bound=MAX_MAGNITUDE)
    edges = doc.get("sigma_edges") or []
    if not isinstance(edges, list):
        raise InputError("expected a list of {from, to, sigma}", field="noise.sigma_edges")
    sig: dict[tuple, float] = {}
    for k, e in enumerate(edges):
        if not isinstance(e, Mapping) or set(e) != {"from", "to", "sigma"}:
            raise InputError("expected {from, to, sigma}", field=f"noise.sigma_edges[{k}]")
        for end in ("from", "to"):
            if isinstance(e[end], bool) or not isinstance(e[end], (int, str)):
                raise InputError("expected an agent label", field=f"noise.sigma_edges[{k}].{end}")
        key = (e["from"], e["to"])
        if key in sig:
            raise InputError(
                f"edge {quote(key[0])}->{quote(key[1])} listed twice",
                field=f"noise.sigma_edges[{k}]",
            )
        sig[key] = require_number(
            f"noise.sigma_edges[{k}].sigma", e["sigma"], minimum=0.0, bound=MAX_MAGNITUDE
        )
    return NoiseModel(sigma=sigma, f=f, sigma_edges=sig)


__all__ = [
    "MAX_MAGNITUDE",
    "noise_from_document",
    "CallableNoise",
    "MatrixNoise",
    "NoiseModel",
    "ScalarNoise",
    "StateNoise",
    "state_noise",
]
