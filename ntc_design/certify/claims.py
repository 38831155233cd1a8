"""What a certificate kind certifies: properties, the claims each property needs, typed.

A certificate names its *kind* (``hurwitz``, ``switching``) and the *properties* it
certifies. What must be proven is derived from these and from the subject (its modes and
schedule), never read from the certificate's list of claims: that list is only compared
with the derived one. A kind (:mod:`ntc_design.certify.kinds`) derives its claims from
these builders; a new property adds its claim builder to :data:`PROPERTY_CLAIMS`, a new
kind of inequality a :class:`ClaimKind` member and a prover.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum


class Property(StrEnum):
    """A property of the error dynamics ε̇ = −L_B ε a certificate can prove."""

    HURWITZ = "hurwitz"  # −L_B Hurwitz (Lemma 1's conclusion; Theorems 1-2)
    DECAY_RATE = "decay_rate"  # ‖ε(t)‖ <= κ e^{−αt} ‖ε(0)‖ with α > 0
    SYMMETRIC_PART = "symmetric_part"  # L_B(k) + L_B(k)ᵀ ≻ 0 for every mode (Theorems 3-4)
    COMMON_LYAPUNOV = "common_lyapunov"  # one P for every mode: stable under any switching
    UNIFORM_SYMMETRIC_PART = "uniform_symmetric_part"  # λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ > 0, all t
    ROBUST_MARGIN = "robust_margin"  # −L_B(A') Hurwitz for every A' within radius ρ_lower
    ROBUST_DECAY = "robust_decay"  # min Re λ(L_B(A')) > α_lower for every A' within ρ
    ROBUST_OFFSET = "robust_offset"  # ‖x*(A') − 1⊗θ‖² <= γ for every A' within ρ
    # the sampled protocol (period h, delay D) contracts in mean square from step k₀ on
    DIGITAL_MEAN_SQUARE = "digital_mean_square"


PROPERTY_TEXT = {
    Property.HURWITZ: "−L_B Hurwitz (Lemma 1's conclusion, used by Theorems 1-2)",
    Property.DECAY_RATE: "decay rate α > 0: ‖ε(t)‖ <= κ·e^(−αt)·‖ε(0)‖",
    Property.SYMMETRIC_PART: "L_B(k) + L_B(k)ᵀ ≻ 0 in every scheduled mode (Theorems 3-4)",
    Property.COMMON_LYAPUNOV: "a common Lyapunov matrix P for every scheduled mode",
    Property.UNIFORM_SYMMETRIC_PART: "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ > 0 for every t, with "
    "Assumption 3's bound D, Λ₁, p̄ and t₀ of μ₂ (Theorems 3-4)",
    Property.ROBUST_MARGIN: "−L_B(A') Hurwitz for every weight realisation A' within the "
    "margin radius",
    Property.ROBUST_DECAY: "min Re λ(L_B(A')) > α for every weight realisation within ρ",
    Property.ROBUST_OFFSET: "‖x*(A') − 1⊗θ‖ bounded for every weight realisation within ρ",
    Property.DIGITAL_MEAN_SQUARE: "the sampled protocol (period h, delay D) contracts in "
    "mean square from step k₀ on: E[eᵀPe] (D = 0) or its Razumikhin functional (D > 0)",
}


class ClaimKind(StrEnum):
    """The kind of inequality a claim states (what its prover checks)."""

    PD = "pd"  # P ≻ 0
    LYAPUNOV = "lyapunov"  # P·L_B + L_Bᵀ·P − 2α·P ≻ 0
    SYMMETRIC_PART = "symmetric_part"  # L_B + L_Bᵀ ≻ 0
    POSITIVE_RATE = "positive_rate"  # α > 0
    COMPONENTS = "components"  # every strongly connected component block (hurwitz-scale)
    LAMBDA2 = "lambda2"  # λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every t-interval (time_varying)
    WEIGHT_BOUND = "D"  # |a_kl(t)| <= D for every t (Assumption 3)
    LAMBDA1 = "lambda1"  # λ_max²(|A_ij(t)|) <= Λ₁ and the noise bound p̄
    T0 = "t0"  # μ₂(t) > 0 for t >= t₀ (the gain is small enough from t₀ on)
    ROBUST_LMI = "robust_lmi"  # the S-procedure matrix Ψ(P, τ; α, ρ) ≻ 0 (robust kind)
    ROBUST_OFFSET = "robust_offset"  # the S-procedure matrix Γ(γ, λ, Y; ρ) ≻ 0 (robust kind)
    DIGITAL_MS = "digital_ms"  # (PL + LᵀP − αP) − κ(h LᵀPL + N) ≻ 0 (digital kinds)
    DIGITAL_NOISE = "digital_noise"  # βP − N ≻ 0 (D > 0)
    DIGITAL_LIPSCHITZ = "digital_lipschitz"  # ℓ²P − LᵀPL ≻ 0 (D > 0)
    DIGITAL_LEVEL = "digital_level"  # ρ(κ) <= 1/2 (D > 0)
    DIGITAL_ADDITIVE = "digital_additive"  # γ >= Σ_e g_eᵀ P g_e
    DIGITAL_T0 = "digital_t0"  # c(t) < κ for every t >= t₀
    LOSS_MS = "loss_ms"  # the mean-square inequality over the arrivals (digital_loss)
    LOSS_OFFSET = "loss_offset"  # ‖x* − 1⊗θ‖ by an exact solve (digital_loss, skip)
    DIGITAL_DL_FORM = "digital_delay_line_form"  # S, T_j ≻ 0 and the R_j decrease (D > 0)
    DIGITAL_DL_STEP = "digital_delay_line_step"  # G(κ) ⪰ 0 for one mode (D > 0)
    DIGITAL_GROWTH = "digital_growth"  # (1/c)' < g from t₀ on, c(t₀) > 0 (D > 0)
    DIGITAL_DL_ADDITIVE = "digital_delay_line_additive"  # γ' >= γ(S) + Σ_j γ(T_j)
    LOSS_DL_STEP = "loss_delay_line_step"  # G(κ) ⪰ 0 with L̄ and N' (digital_loss, D > 0)


#: The statements of the digital kinds' claims ({m}: the mode).
DIGITAL_CLAIM_TEXT = {
    ClaimKind.DIGITAL_MS: "(P_d·L_B({m}) + L_B({m})ᵀ·P_d − α·P_d) − κ·(h·L_B({m})ᵀ·P_d·L_B({m}) + N({m})) ≻ 0",
    ClaimKind.DIGITAL_NOISE: "β·P_d − N({m}) ≻ 0",
    ClaimKind.DIGITAL_LIPSCHITZ: "ℓ²·P_d − L_B({m})ᵀ·P_d·L_B({m}) ≻ 0",
    ClaimKind.DIGITAL_LEVEL: "ρ(κ) <= 1/2 (the delayed bound)",
    ClaimKind.DIGITAL_ADDITIVE: "γ >= Σ_e g_eᵀ·P_d·g_e in every mode",
    ClaimKind.DIGITAL_T0: "c(t) < κ for every t >= t₀",
    ClaimKind.LOSS_MS: "(P_l·L̄({m}) + L̄({m})ᵀ·P_l − α·P_l) − κ·(h·(L̄ᵀ·P_l·L̄ + 2Σ_e v_e·L_eᵀ·P_l·L_e) + μ·Σ_e E[m_e²]·G_eᵀ·P_l·G_e) ≻ 0 over the arrivals",
    ClaimKind.LOSS_OFFSET: "the mean's limit x* (L̄ x* = u) is at the stated ‖x* − 1⊗θ‖, by an exact rational solve",
    ClaimKind.DIGITAL_DL_FORM: "S ≻ 0, T_j ≻ 0, R_j − R_{{j+1}} ≻ 0 and "
    "(1 − αhκ)R_j − (1 + ghκ)R_{{j+1}} − hκT_j ≻ 0 (the delay line's functional)",
    ClaimKind.DIGITAL_DL_STEP: "G_{m}(κ) ≻ 0: the delay line's step inequality for every c in (0, κ]",
    ClaimKind.DIGITAL_GROWTH: "(1/c)'(t) < g for every t >= t₀ and c(t₀) > 0",
    ClaimKind.DIGITAL_DL_ADDITIVE: "γ' >= Σ_e g_eᵀ·(S + Σ_j T_j)·g_e in every mode",
    ClaimKind.LOSS_DL_STEP: "G_{m}(κ) ≻ 0 with L̄ and N' = Σ_e E[m_e²]·G_eᵀ(·)G_e + "
    "h·Σ_e v_e·L_eᵀ(·)L_e: the delay line's step over the arrivals for every c in (0, κ]",
}

#: The statements of the time-varying kind's claims (their certificates list exactly these).
TV_CLAIM_TEXT = {
    ClaimKind.LAMBDA2: "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval",
    ClaimKind.WEIGHT_BOUND: "|a_kl(t)| <= D (Assumption 3)",
    ClaimKind.LAMBDA1: "λ_max²(|A_ij(t)|) <= Λ₁ and Σσ²Σ_l(Σ_k|a_lk|)² <= p̄",
    ClaimKind.T0: "μ₂(t) > 0 for t >= t₀",
}


@dataclass(frozen=True)
class Claim:
    """One inequality a property needs, with the mode and the matrix P it is about."""

    kind: ClaimKind
    prop: Property
    mode: str | None = None
    p: str | None = None
    alpha: float = 0.0
    radius: float | None = None  # the uncertainty radius ρ (robust kind)

    @property
    def id(self) -> str:
        """A readable statement of the inequality (not used to decide anything)."""
        m, p = self.mode, self.p
        if self.kind is ClaimKind.PD:
            return f"P_{p} ≻ 0"
        if self.kind is ClaimKind.SYMMETRIC_PART:
            return f"L_B({m}) + L_B({m})ᵀ ≻ 0"
        if self.kind is ClaimKind.POSITIVE_RATE:
            return "α > 0"
        if self.kind is ClaimKind.COMPONENTS:
            return f"−L_B({m}) Hurwitz: every component block certified"
        if self.kind in TV_CLAIM_TEXT:
            return TV_CLAIM_TEXT[self.kind]
        if self.kind in DIGITAL_CLAIM_TEXT:
            return DIGITAL_CLAIM_TEXT[self.kind].format(m=m)
        if self.kind is ClaimKind.ROBUST_LMI:
            return f"Ψ(P_{p}, τ_{p}; α, ρ) ≻ 0 for L_B({m}): every realisation within ρ"
        if self.kind is ClaimKind.ROBUST_OFFSET:
            return f"Γ(γ, λ, Y; ρ) ≻ 0 for L_B({m}), with every L_B(A') invertible within ρ"
        rate = f" − 2α·P_{p}" if self.prop is Property.DECAY_RATE else ""
        return f"P_{p}·L_B({m}) + L_B({m})ᵀ·P_{p}{rate} ≻ 0"

    def to_dict(self) -> dict:
        """The claim as it is stored in a certificate.

        Returns
        -------
        dict
            ``id``, ``kind``, ``property`` and, where they apply, ``mode``, ``P``, ``alpha``.
        """
        doc: dict = {"id": self.id, "kind": self.kind.value, "property": self.prop.value}
        if self.mode is not None:
            doc["mode"] = self.mode
        if self.p is not None:
            doc["P"] = self.p
        if self.kind in (ClaimKind.LYAPUNOV, ClaimKind.POSITIVE_RATE, ClaimKind.ROBUST_LMI):
            doc["alpha"] = self.alpha
        if self.radius is not None:
            doc["radius"] = self.radius
        return doc


def _hurwitz(modes: Sequence[str], alpha: float) -> list[Claim]:
    (m,) = modes
    return [
        Claim(ClaimKind.PD, Property.HURWITZ, p="lyapunov"),
        Claim(ClaimKind.LYAPUNOV, Property.HURWITZ, mode=m, p="lyapunov"),
    ]


def _rate(modes: Sequence[str], alpha: float) -> list[Claim]:
    (m,) = modes
    return [
        Claim(ClaimKind.POSITIVE_RATE, Property.DECAY_RATE, alpha=alpha),
        Claim(ClaimKind.PD, Property.DECAY_RATE, p="rate"),
        Claim(ClaimKind.LYAPUNOV, Property.DECAY_RATE, mode=m, p="rate", alpha=alpha),
    ]


def _symmetric(modes: Sequence[str], alpha: float) -> list[Claim]:
    return [Claim(ClaimKind.SYMMETRIC_PART, Property.SYMMETRIC_PART, mode=k) for k in modes]


def _common(modes: Sequence[str], alpha: float) -> list[Claim]:
    return [Claim(ClaimKind.PD, Property.COMMON_LYAPUNOV, p="common")] + [
        Claim(ClaimKind.LYAPUNOV, Property.COMMON_LYAPUNOV, mode=k, p="common") for k in modes
    ]


#: The claims a property needs for the modes it covers and the rate α it states.
PROPERTY_CLAIMS: dict[Property, Callable[[Sequence[str], float], list[Claim]]] = {
    Property.HURWITZ: _hurwitz,
    Property.DECAY_RATE: _rate,
    Property.SYMMETRIC_PART: _symmetric,
    Property.COMMON_LYAPUNOV: _common,
}


def derive_claims(
    properties: Sequence[Property], modes: Sequence[str], alpha: float
) -> tuple[Claim, ...]:
    """Every claim the given properties need for the given (scheduled) modes.

    Parameters
    ----------
    properties : sequence of Property
        What the certificate certifies.
    modes : sequence of str
        The modes covered: the one mode of a ``hurwitz`` certificate, or every mode a
        switching schedule uses.
    alpha : float
        The decay rate the certificate states (used by :attr:`Property.DECAY_RATE`).

    Returns
    -------
    tuple of Claim
        In the order of ``properties``.
    """
    return tuple(c for prop in properties for c in PROPERTY_CLAIMS[prop](modes, alpha))


__all__ = [
    "DIGITAL_CLAIM_TEXT",
    "PROPERTY_TEXT",
    "Claim",
    "ClaimKind",
    "Property",
    "derive_claims",
]
