"""Every choice the toolkit takes as a string, written once as a ``Literal`` type.

A signature that takes a choice says so with its alias (``method: SimulateMethod``), so
mypy refuses a misspelt one (``method="exat"``) before anything runs; the runtime checks,
for the values that come from files and flags, read the allowed values back from the same
alias with :func:`choices` (``typing.get_args``), so the set is written once. The ground
layer: it imports nothing of the package, and every layer may import it.
"""

from __future__ import annotations

from typing import Any, Literal, get_args

#: What ``simulate`` computes: Monte Carlo paths, the exact moments, or both.
SimulateMethod = Literal["mc", "exact", "both"]
#: The objective ``tune`` minimises (auto: exact moments where they apply).
TuneMethod = Literal["auto", "exact", "mc"]
#: The normals of the Monte Carlo: xoshiro256** per path, or NumPy's PCG64 per block.
Rng = Literal["xoshiro", "numpy"]
#: Where the Monte Carlo paths run.
Device = Literal["cpu", "gpu"]
#: The Euler–Maruyama step: explicit, or implicit in the drift.
Scheme = Literal["explicit", "implicit"]
#: The step sizes: h <= dt between events, or constant c·h.
SteppingKind = Literal["uniform", "intrinsic"]
#: The GPU kernels' layout of the modes.
Layout = Literal["auto", "fused", "sparse"]
#: The implicit step's linear solver.
Solver = Literal["auto", "lu", "jacobi", "gmres"]
#: How the Hurwitz certificate finds the rate: a Lyapunov equation or an LMI.
RateMethod = Literal["lyapunov", "lmi"]
#: What ``tune`` tunes: the power law a·(b + t)^(−γ), or the optimal schedule.
Schedule = Literal["power", "optimal"]
#: The gain family of the power-law tuner (the only one).
Family = Literal["power"]
#: The theorems a tuned gain must satisfy.
Require = Literal["both", "mean-square"]
#: What an agent does with a lost message.
LossPolicy = Literal["skip", "rescale", "hold"]
#: How a tabulated gain is read between its rows.
Interpolation = Literal["linear", "previous"]
#: The languages ``ntc export`` writes.
Language = Literal["c", "python"]


def choices(alias: Any) -> tuple[str, ...]:
    """The values a ``Literal`` alias allows, in its order (what a runtime check and its
    message list).

    Parameters
    ----------
    alias : typing.Literal
        One of this module's aliases.

    Returns
    -------
    tuple of str

    Raises
    ------
    TypeError
        ``alias`` is not a ``Literal`` of strings.

    Examples
    --------
    >>> choices(Device)
    ('cpu', 'gpu')
    """
    values = get_args(alias)
    if not values or not all(isinstance(v, str) for v in values):
        raise TypeError(f"not a Literal of strings: {alias!r}")
    return values


__all__ = [
    "Device",
    "Family",
    "Interpolation",
    "Language",
    "Layout",
    "LossPolicy",
    "RateMethod",
    "Require",
    "Rng",
    "Schedule",
    "Scheme",
    "SimulateMethod",
    "Solver",
    "SteppingKind",
    "TuneMethod",
    "choices",
]
