"""Tests of :mod:`ntc_design.certify.kinds.time_varying`."""

import copy
import json

import pytest
import yaml

from ntc_design.certify import verify
from ntc_design.certify.format import digest
from tests.cli_helpers import run_cli
from tests.support.time_varying import small


def test_cli_certify_json_and_verify(tmp_path, capsys, monkeypatch):
    out = tmp_path / "c.json"
    doc = small({"1->2": {"diag": ["-1 - 0.5*sin(t)", -2]}}, {"period": "2*pi"})
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(doc))
    code, text, err = run_cli(
        [
            "certify",
            tmp_path / "t.yaml",
            "--theta",
            "1,2",
            "--gain",
            "1/(1+t)",
            "--json",
            "--out",
            out,
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    tv = json.loads(text)["certificate"]["results"]["time_varying"]
    assert {"lambda2", "D", "t0"} <= set(tv) and tv["lambda2"] > 0 and tv["D"] == pytest.approx(2.0)
    code, text, _ = run_cli(["verify", out], capsys, monkeypatch)
    assert code == 0 and "VALID" in text
    cert = json.loads(out.read_text())
    # a re-digested forgery: Λ₂ raised above what the enclosures give
    forged = copy.deepcopy(cert)
    forged["results"]["time_varying"]["lambda2"] *= 1.5
    forged["digest"] = digest(forged)
    ver = verify(forged)
    assert not ver.valid and [c.name for c in ver.failed] == [
        "each interval's recorded bound lies between the claimed Λ₂ and its re-enclosed one",
        "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval",
        "reported results (each number recomputed, bounded or informational)",
    ]
    assert "lambda2: reported" in ver.failed[2].detail
    # an interval dropped: the cover fails
    gap = copy.deepcopy(cert)
    del gap["intervals"][len(gap["intervals"]) // 2]
    gap["digest"] = digest(gap)
    failed = verify(gap).failed
    assert [c.name for c in failed][:2] == [
        "the intervals cover the domain",
        "λ_min(L_B(t) + L_B(t)ᵀ) >= Λ₂ on every interval",
    ]
    assert "time_varying.intervals: reported" in failed[-1].detail
    # a weight edited: the digest breaks
    edited = copy.deepcopy(cert)
    edited["subject"]["topology"]["edges"][0]["weight"] = {"diag": ["-1 - 0.4*sin(t)", -2]}
    assert "digest" in [c.name for c in verify(edited).failed]


# -- reported bounds: checked in their sound direction ------------------------------------


@pytest.fixture(scope="module")
def small_tv_cert():
    from ntc_design.certify import certify
    from ntc_design.model.timevarying import from_document

    doc = small({"1->2": {"diag": ["-1 - 0.5*sin(t)", -2]}}, {"period": "2*pi"})
    res = certify(from_document(doc, "t.yaml"), [1.0, 2.0], gain="1/(1+t)")
    assert res.verification.valid
    return json.loads(json.dumps(res.certificate))


def _loosened(cert, factors: dict) -> dict:
    """The certificate as an older, looser enclosure would have written it: each bound in
    ``factors`` scaled, and what the issuer derives from them (κ, the gap, t₀) derived
    again, then re-sealed."""
    from ntc_design.certify.mu2 import mu2_t0, mu2_threshold, noise_sigma_bar

    doc = copy.deepcopy(cert)
    tv = doc["results"]["time_varying"]
    for key, f in factors.items():
        tv[key] *= f
    kappa = mu2_threshold(
        tv["lambda2"], tv["Lambda1"], noise_sigma_bar(doc["subject"]["noise"]["f"]), 3
    )
    tv["kappa"] = kappa
    tv["relative_gap"] = (tv["sampled_inf"] - tv["lambda2"]) / tv["sampled_inf"]
    tv["t0"] = mu2_t0(doc["subject"]["gain"], kappa)[0]
    doc["digest"] = digest(doc)
    return doc


@pytest.mark.parametrize(
    "factors",
    [
        {"D": 1.01},
        {"p_bar": 1.5},
        {"Lambda1": 1.01},
        {"lambda2": 0.99},
        {"lambda2": 0.5, "Lambda1": 2.0, "D": 1.1, "p_bar": 1.1},
        {"Lambda1": 1 + 4e-9},  # certificates/g1_tv.json's case: 4e-9 above today's
    ],
)
def test_a_looser_bound_still_verifies(small_tv_cert, factors):
    doc = _loosened(small_tv_cert, factors)
    ver = verify(doc)
    assert ver.valid, [(c.name, c.detail) for c in ver.failed]


def test_a_later_t0_still_verifies(small_tv_cert):
    doc = copy.deepcopy(small_tv_cert)
    tv = doc["results"]["time_varying"]
    assert tv["t0"] is not None
    tv["t0"] = tv["t0"] * 2 + 1  # μ₂ > 0 from t₀ on: a later t₀ is still true
    doc["digest"] = digest(doc)
    assert verify(doc).valid


@pytest.mark.hostile
@pytest.mark.parametrize(
    "key, factor, needle",
    [
        ("D", 0.999, "time_varying.D: reported upper bound"),
        ("p_bar", 0.999, "time_varying.p_bar: reported upper bound"),
        ("Lambda1", 1 - 1e-7, "time_varying.Lambda1: reported upper bound"),
        ("lambda2", 1 + 1e-7, "time_varying.lambda2: reported lower bound"),
        ("t0", 0.5, "time_varying.t0: reported upper bound"),
    ],
)
def test_a_bound_forged_in_the_unsound_direction_is_rejected(small_tv_cert, key, factor, needle):
    # re-sealed and with what depends on it derived again: only the direction is wrong
    if key == "t0":
        doc = copy.deepcopy(small_tv_cert)
        doc["results"]["time_varying"]["t0"] *= factor
        doc["digest"] = digest(doc)
    else:
        doc = _loosened(small_tv_cert, {key: factor})
    ver = verify(doc)
    assert not ver.valid
    audit = [c for c in ver.failed if c.name.startswith("reported results")]
    assert audit and needle in audit[0].detail, [(c.name, c.detail) for c in ver.failed]


def _interval_bound(cert, k: int, value) -> dict:
    doc = copy.deepcopy(cert)
    doc["intervals"][k][2] = value(doc["intervals"][k][2], doc["results"]["time_varying"])
    doc["digest"] = digest(doc)
    return doc


@pytest.mark.hostile
@pytest.mark.parametrize(
    "value",
    [
        lambda b, r: -b,  # negated: a lower bound still, but it states Λ₂ < 0 there
        lambda b, r: 0.5 * r["lambda2"],  # positive, below the claimed Λ₂
        lambda b, r: -1e300,
    ],
    ids=["negated", "below-lambda2", "huge-negative"],
)
def test_an_interval_bound_below_the_claimed_lambda2_is_rejected(small_tv_cert, value):
    doc = _interval_bound(small_tv_cert, 1, value)
    ver = verify(doc)
    assert not ver.valid
    (failed,) = [c for c in ver.failed if c.name.startswith("each interval's recorded bound")]
    assert failed.detail.startswith("interval 1: recorded")


def test_an_interval_bound_between_lambda2_and_its_enclosure_verifies(small_tv_cert):
    doc = _interval_bound(small_tv_cert, 1, lambda b, r: r["lambda2"])  # looser, still ≥ Λ₂
    assert verify(doc).valid
