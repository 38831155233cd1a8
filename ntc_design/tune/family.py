"""The gain family that :func:`ntc_design.tune.tune` searches: c(t) = a·(b + t)^(−γ).

Every member with a > 0, b > 0 is continuous, positive and tends to 0. With γ ≤ 1 its
integral diverges (Theorems 1 and 3, Niu & Wu eqs. (13), (17)); with γ > 1/2 its square
is integrable as well (Theorems 2 and 4, eqs. (16), (20)). So the admissible exponents are
γ ∈ (1/2, 1] when both theorems are required and γ ∈ (0, 1] for mean square only; the
searched ranges are closed intervals inside those (:data:`GAMMA_RANGE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..choices import Require, choices
from ..errors import InputError

#: What a tuned gain must satisfy: both theorems (mean square and almost sure), or mean
#: square only.
REQUIRE = choices(Require)
#: Searched exponents: closed intervals inside (1/2, 1] and (0, 1].
GAMMA_RANGE = {"both": (0.51, 1.0), "mean-square": (0.05, 1.0)}
#: Searched scale a and offset b (c(0) = a·b^(−γ) is at most 200).
A_RANGE = (0.05, 20.0)
B_RANGE = (0.1, 10.0)
#: Significant digits of the written gain (the reported errors are those of the
#: rounded gain, re-computed).
SIGNIFICANT = 4


def _round(x: float, sig: int = SIGNIFICANT) -> float:
    return float(f"{x:.{sig}g}")


def _text(x: float) -> str:
    return f"{x:.{SIGNIFICANT}g}"


@dataclass(frozen=True)
class PowerGain:
    """c(t) = a·(b + t)^(−γ), a > 0, b > 0, γ > 0.

    Attributes
    ----------
    a, b, gamma : float
        Scale, offset and exponent.

    Examples
    --------
    >>> g = PowerGain(2.0, 1.0, 1.0)
    >>> g.text, float(g(np.array([1.0]))[0])
    ('2/(1 + t)', 1.0)
    """

    a: float
    b: float
    gamma: float

    def __post_init__(self) -> None:
        for name in ("a", "b", "gamma"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"expected a finite number > 0, got {v!r}", field=name)
            object.__setattr__(self, name, float(v))

    def __call__(self, t) -> np.ndarray:
        """c(t), vectorised."""
        t = np.asarray(t, dtype=float)
        return self.a * (self.b + t) ** (-self.gamma)

    @property
    def text(self) -> str:
        """The gain as an expression the rest of the toolkit reads (``ntc gain``, a
        scenario's ``gain``): 4 significant digits, as :meth:`rounded`."""
        a, b, g = _text(self.a), _text(self.b), _text(self.gamma)
        head = "" if a == "1" else f"{a}*"
        if g == "1":
            return f"{a}/({b} + t)"
        return f"{head}({b} + t)^(-{g})"

    def rounded(self) -> PowerGain:
        """The gain with a, b, γ at :data:`SIGNIFICANT` significant digits (what
        :attr:`text` writes).

        Returns
        -------
        PowerGain
        """
        return PowerGain(_round(self.a), _round(self.b), _round(self.gamma))

    def integrals(self, t_end: float) -> tuple[float, float]:
        """∫₀ᵀ c dt and ∫₀ᵀ c² dt in closed form.

        Parameters
        ----------
        t_end : float
            T.

        Returns
        -------
        (float, float)
        """
        a, b, g = self.a, self.b, self.gamma

        def power_integral(p: float) -> float:  # ∫₀ᵀ (b + t)^(−p) dt
            if abs(p - 1.0) < 1e-12:
                return math.log((b + t_end) / b)
            return ((b + t_end) ** (1 - p) - b ** (1 - p)) / (1 - p)

        return a * power_integral(g), a * a * power_integral(2 * g)


#: The toolkit's default gain, the baseline every tuned gain is compared with.
BASELINE = PowerGain(1.0, 1.0, 1.0)


def gamma_range(require: Require) -> tuple[float, float]:
    """The searched exponents for a requirement.

    Parameters
    ----------
    require : {"both", "mean-square"}
        The theorems the tuned gain must satisfy.

    Returns
    -------
    (float, float)

    Raises
    ------
    InputError
        An unknown requirement.
    """
    if require not in REQUIRE:
        raise InputError(f"expected one of {', '.join(REQUIRE)}, got {require!r}", field="require")
    return GAMMA_RANGE[require]
