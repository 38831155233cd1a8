"""Tests of :mod:`ntc_design.certify.claims`."""

import dataclasses
import json

import pytest

from ntc_design.certify.claims import (
    PROPERTY_CLAIMS,
    PROPERTY_TEXT,
    TV_CLAIM_TEXT,
    Claim,
    ClaimKind,
    Property,
    derive_claims,
)

P = Property
K = ClaimKind


def test_every_property_has_a_statement_and_values_round_trip():
    assert set(PROPERTY_TEXT) == set(Property)
    assert all(isinstance(t, str) and t for t in PROPERTY_TEXT.values())
    # certificates store the values: no two members may share one (an alias would read
    # back as the other member)
    assert len(Property.__members__) == len(Property)
    assert len(ClaimKind.__members__) == len(ClaimKind)
    assert ClaimKind("D") is ClaimKind.WEIGHT_BOUND
    with pytest.raises(ValueError, match="bogus"):
        Property("bogus")


def test_builders_cover_the_nominal_properties_only():
    # the time-varying and robust kinds derive their claims themselves
    assert set(PROPERTY_CLAIMS) == {P.HURWITZ, P.DECAY_RATE, P.SYMMETRIC_PART, P.COMMON_LYAPUNOV}
    assert set(TV_CLAIM_TEXT) == {K.LAMBDA2, K.WEIGHT_BOUND, K.LAMBDA1, K.T0}
    with pytest.raises(KeyError):
        derive_claims([P.UNIFORM_SYMMETRIC_PART], ["G1"], 0.0)


def test_hurwitz_and_rate_claims_of_one_mode():
    got = derive_claims([P.HURWITZ, P.DECAY_RATE], ["G1"], 0.25)
    assert got == (
        Claim(K.PD, P.HURWITZ, p="lyapunov"),
        Claim(K.LYAPUNOV, P.HURWITZ, mode="G1", p="lyapunov"),
        Claim(K.POSITIVE_RATE, P.DECAY_RATE, alpha=0.25),
        Claim(K.PD, P.DECAY_RATE, p="rate"),
        Claim(K.LYAPUNOV, P.DECAY_RATE, mode="G1", p="rate", alpha=0.25),
    )
    # the hurwitz claims never carry the rate: α only enters the decay-rate claims
    assert all(c.alpha == 0.0 for c in got if c.prop is P.HURWITZ)


def test_switching_claims_follow_the_modes_in_order():
    modes = ["G3", "G1", "G2"]
    got = derive_claims([P.SYMMETRIC_PART, P.COMMON_LYAPUNOV], modes, 0.7)
    sym = [c for c in got if c.prop is P.SYMMETRIC_PART]
    common = [c for c in got if c.prop is P.COMMON_LYAPUNOV]
    assert [c.mode for c in sym] == modes and {c.kind for c in sym} == {K.SYMMETRIC_PART}
    # one P ≻ 0 first, then one Lyapunov inequality per mode, all with the same P
    assert common[0] == Claim(K.PD, P.COMMON_LYAPUNOV, p="common")
    assert [c.mode for c in common[1:]] == modes
    assert {(c.kind, c.p, c.alpha) for c in common[1:]} == {(K.LYAPUNOV, "common", 0.0)}
    # the order of the properties decides the order of the claims
    rev = derive_claims([P.COMMON_LYAPUNOV, P.SYMMETRIC_PART], modes, 0.7)
    assert rev == tuple(common + sym)
    assert derive_claims([], modes, 0.0) == ()


@pytest.mark.parametrize(
    ("claim", "text"),
    [
        (Claim(K.PD, P.COMMON_LYAPUNOV, p="common"), "P_common ≻ 0"),
        (Claim(K.SYMMETRIC_PART, P.SYMMETRIC_PART, mode="G2"), "L_B(G2) + L_B(G2)ᵀ ≻ 0"),
        (Claim(K.POSITIVE_RATE, P.DECAY_RATE, alpha=1.0), "α > 0"),
        (
            Claim(K.LYAPUNOV, P.HURWITZ, mode="G1", p="lyapunov"),
            "P_lyapunov·L_B(G1) + L_B(G1)ᵀ·P_lyapunov ≻ 0",
        ),
        (
            Claim(K.LYAPUNOV, P.DECAY_RATE, mode="G1", p="rate", alpha=0.5),
            "P_rate·L_B(G1) + L_B(G1)ᵀ·P_rate − 2α·P_rate ≻ 0",
        ),
        (
            Claim(K.COMPONENTS, P.HURWITZ, mode="big"),
            "−L_B(big) Hurwitz: every component block certified",
        ),
        (Claim(K.WEIGHT_BOUND, P.UNIFORM_SYMMETRIC_PART), "|a_kl(t)| <= D (Assumption 3)"),
        (Claim(K.T0, P.UNIFORM_SYMMETRIC_PART), "μ₂(t) > 0 for t >= t₀"),
    ],
)
def test_claim_id_states_the_inequality(claim, text):
    assert claim.id == text


def test_robust_claim_ids_name_the_mode_and_matrix():
    lmi = Claim(K.ROBUST_LMI, P.ROBUST_DECAY, mode="G1", p="decay", alpha=0.3, radius=0.05)
    off = Claim(K.ROBUST_OFFSET, P.ROBUST_OFFSET, mode="G1", radius=0.05)
    assert lmi.id.startswith("Ψ(P_decay, τ_decay; α, ρ) ≻ 0 for L_B(G1)")
    assert off.id.startswith("Γ(γ, λ, Y; ρ) ≻ 0 for L_B(G1)")
    assert "invertible" in off.id


def test_to_dict_keeps_only_the_fields_that_apply():
    pd = Claim(K.PD, P.HURWITZ, p="lyapunov").to_dict()
    assert pd == {"id": "P_lyapunov ≻ 0", "kind": "pd", "property": "hurwitz", "P": "lyapunov"}
    # α is recorded for the inequalities that use it, even when it is 0
    lyap = Claim(K.LYAPUNOV, P.HURWITZ, mode="G1", p="lyapunov").to_dict()
    assert lyap["alpha"] == 0.0 and lyap["mode"] == "G1"
    assert "alpha" not in Claim(K.SYMMETRIC_PART, P.SYMMETRIC_PART, mode="G1").to_dict()
    rob = Claim(K.ROBUST_LMI, P.ROBUST_MARGIN, mode="G1", p="margin", radius=0.1).to_dict()
    assert rob["alpha"] == 0.0 and rob["radius"] == 0.1
    off = Claim(K.ROBUST_OFFSET, P.ROBUST_OFFSET, mode="G1", radius=0.2).to_dict()
    assert "alpha" not in off and "P" not in off and off["radius"] == 0.2
    tv = Claim(K.LAMBDA1, P.UNIFORM_SYMMETRIC_PART).to_dict()
    assert set(tv) == {"id", "kind", "property"} and tv["id"] == TV_CLAIM_TEXT[K.LAMBDA1]


def test_to_dict_is_plain_json():
    claims = derive_claims(list(PROPERTY_CLAIMS), ["G1"], 0.5)
    docs = [c.to_dict() for c in claims]
    # StrEnum members must be stored as plain strings, equal after a JSON round trip
    assert json.loads(json.dumps(docs)) == docs
    assert all(type(d["kind"]) is str and type(d["property"]) is str for d in docs)


def test_claims_are_frozen_and_hashable():
    a = Claim(K.LYAPUNOV, P.DECAY_RATE, mode="G1", p="rate", alpha=0.5)
    b = Claim(K.LYAPUNOV, P.DECAY_RATE, mode="G1", p="rate", alpha=0.5)
    assert a == b and len({a, b}) == 1
    assert a != dataclasses.replace(a, alpha=0.6)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.alpha = 1.0  # type: ignore[misc]
