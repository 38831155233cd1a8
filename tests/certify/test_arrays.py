"""Tests of :mod:`ntc_design.certify.arrays`."""

import copy

import numpy as np
import pytest

from ntc_design.certify import verify
from ntc_design.errors import InputError
from tests.support.switching_scale import _refresh


def test_tiny_weights_are_bad_input_not_a_proof(big_cert):
    from ntc_design.certify.arrays import pack

    doc = copy.deepcopy(big_cert)
    t = doc["subject"]["modes"]["A"]["topology"]
    from ntc_design.certify.arrays import unpack

    w = unpack(t["weights"], "w", "f8", (t["edges"], 3, 3))
    w[0] = np.eye(3) * 2.0**-1074  # a subnormal weight
    t["weights"] = pack(w, "f8")
    with pytest.raises(InputError, match="weights"):
        verify(_refresh(doc))


# -- the Lemma 1 margin ΔC is tied to δ: δ = C + ΔC, C re-derived from the topology ----

MARGIN_KINDS = (
    "hurwitz",
    "switching",
    "digital",
    "digital_switching",
    "robust",
    "hurwitz-scale",
    "hurwitz-scale-g1",
    "switching-scale",
)


def _resealed(doc):
    from ntc_design.certify.format import digest, document_hash

    doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


@pytest.mark.hostile
@pytest.mark.parametrize("which", MARGIN_KINDS)
@pytest.mark.parametrize("change", [lambda m: m + 0.05, lambda m: 10 * m], ids=["+0.05", "x10"])
def test_a_resealed_margin_that_does_not_give_delta_does_not_verify(
    honest_certificates, which, change
):
    doc = copy.deepcopy(honest_certificates[which])
    ok = verify(copy.deepcopy(doc))
    tied = [c for c in ok.checks if "δ = C + ΔC" in c.name]
    assert ok.valid and tied and all(c.ok for c in tied)  # the honest one re-derives δ
    mode = next(iter(doc["subject"]["modes"]))
    sub = doc["subject"]["modes"][mode]
    sub["margin"] = change(sub["margin"])  # δ, k1, x0 unchanged: only the margin's word
    ver = verify(_resealed(doc))
    assert not ver.valid
    assert [c.name for c in ver.failed] == [f"{mode}: δ = C + ΔC (C from the topology)"]
    assert "stated δ = " in ver.failed[0].detail


def test_no_margin_stated_makes_no_lemma1_claim(honest_certificates):
    doc = copy.deepcopy(honest_certificates["hurwitz"])
    sub = next(iter(doc["subject"]["modes"].values()))
    sub["margin"] = None  # δ given directly: nothing to tie it to
    ver = verify(_resealed(doc))
    assert ver.valid and not [c for c in ver.checks if "δ = C + ΔC" in c.name]
