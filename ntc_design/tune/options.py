"""What a tuning run is asked, written once: :class:`PowerOptions` for the power law
(:func:`.power.tune_power`) and :class:`ScheduleOptions` for the optimal schedule
(:func:`.schedule.tune_schedule`), both with the options they share
(:class:`TuneOptions`). Each validates itself on construction (the pattern of diffrax's
``SaveAt``), so a bad option is refused before any work, and :func:`.entry.tune` picks the
tuner by the options' type.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from ..choices import Family, Require, TuneMethod, choices
from ..errors import InputError, require_positive
from .family import gamma_range
from .objective import check_method
from .optimal import check_max_gain
from .schedule_problem import DEFAULT_MAX_GAIN, LEVELS

#: The power family's default search budget (evaluations of the objective).
MAX_EVALUATIONS = 160
#: The optimal schedule's default Monte Carlo paths for its evidence.
CHECK_PATHS = 200


@dataclass(frozen=True)
class TuneOptions:
    """What both tuners take.

    Attributes
    ----------
    require : {"both", "mean-square"}
        The theorems the power law must satisfy: γ ∈ [0.51, 1] for both (mean square and
        almost sure), γ ∈ [0.05, 1] for mean square only (the schedule's tail satisfies
        both).
    tune_delta : bool
        Also choose a common δ (:func:`.power.delta_range`).
    eps : float or None
        Report when each gain first reaches E Σ‖x_i − θ‖² ≤ ε.
    certificate : bool
        Certify the tuned design.
    """

    require: Require = "both"
    tune_delta: bool = False
    eps: float | None = None
    certificate: bool = True

    def __post_init__(self) -> None:
        gamma_range(self.require)  # one line naming require
        if self.eps is not None:
            require_positive("eps", self.eps)


@dataclass(frozen=True)
class PowerOptions(TuneOptions):
    """The power law c(t) = a·(b + t)^(−γ) (and δ): the search's objective, budget and
    ranges, beside :class:`TuneOptions`.

    Attributes
    ----------
    method : {"auto", "exact", "mc"}
        The objective (auto: exact moments where they apply).
    max_evaluations : int
        The search's budget, in [10, 10000].
    landscape : bool
        Evaluate the objective over (a, γ) for the contour map.
    bounds : mapping of str to (float, float) or None
        Narrower ranges for ``a``, ``b``, ``gamma`` (inside the required theorems' range)
        or ``delta``; lo = hi fixes the parameter.
    family : {"power"}
        The gain family (the only one).

    Examples
    --------
    >>> PowerOptions(max_evaluations=30, landscape=False).method
    'auto'
    """

    method: TuneMethod = "auto"
    max_evaluations: int = MAX_EVALUATIONS
    landscape: bool = True
    bounds: Mapping[str, tuple[float, float]] | None = None
    family: Family = "power"

    def __post_init__(self) -> None:
        if self.family not in choices(Family):
            raise InputError(
                f"only 'power' (a·(b + t)^(−γ)) is available, got {self.family!r}", field="family"
            )
        super().__post_init__()
        check_method(self.method)
        n = self.max_evaluations
        if not isinstance(n, int) or isinstance(n, bool) or not 10 <= n <= 10_000:
            raise InputError(
                f"expected an integer in [10, 10000], got {n!r}", field="max_evaluations"
            )


@dataclass(frozen=True)
class ScheduleOptions(TuneOptions):
    """The optimal schedule c(t) on [0, T] with an admissible tail (:mod:`.optimal`),
    beside :class:`TuneOptions`.

    Attributes
    ----------
    max_gain : float
        The upper bound on c.
    max_peak : float or None
        The bound M on sup_t E Σ‖x_i(t) − θ‖².
    check_paths : int
        Monte Carlo paths of the evidence, in [0, 100000] (0: none).
    levels : tuple of int
        The refinement's pieces.

    Examples
    --------
    >>> ScheduleOptions(check_paths=0).max_gain
    50.0
    """

    max_gain: float = DEFAULT_MAX_GAIN
    max_peak: float | None = None
    check_paths: int = CHECK_PATHS
    levels: tuple[int, ...] = LEVELS

    def __post_init__(self) -> None:
        super().__post_init__()
        check_max_gain(self.max_gain)
        if self.max_peak is not None:
            require_positive("max_peak", self.max_peak)
        n = self.check_paths
        if not isinstance(n, int) or isinstance(n, bool) or not 0 <= n <= 100_000:
            raise InputError(f"expected an integer in [0, 100000], got {n!r}", field="check_paths")


__all__ = ["CHECK_PATHS", "MAX_EVALUATIONS", "PowerOptions", "ScheduleOptions", "TuneOptions"]
