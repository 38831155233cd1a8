"""The deadline figures in a certificate: issued, re-derived by verify, and forgeries
(a bound lowered by 1 %, T raised, the initial state changed, each re-sealed) rejected."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from ntc_design.certify import verify
from ntc_design.certify.deadline_subject import add_deadline
from ntc_design.certify.format import finish


@pytest.fixture(scope="module")
def deadline_cert(g1, g1_digital_d1):
    # certify(g1, theta, 0.1, "1/(1+t)", digital=Digital(0.1, 1)), issued once per worker
    doc = copy.deepcopy(g1_digital_d1.certificate)
    section = {
        "T": 1.0,
        "period": 0.1,
        "delay": 1,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": []},
        "initial": {"x0": np.linspace(-3, 3, g1.nd).tolist()},
    }
    bound = add_deadline(doc, section)
    return doc, bound


def _resealed(doc):
    doc.pop("digest", None)
    return finish(doc, doc.get("verification_method"))


def test_issued_figures_verify(deadline_cert):
    doc, bound = deadline_cert
    ver = verify(copy.deepcopy(doc))
    assert ver.valid
    assert doc["results"]["deadline"]["ms_error_bound"] == bound.ms_error_bound
    assert any(c.name.startswith("deadline T = 1") and c.ok for c in ver.checks)


@pytest.mark.parametrize(
    "forge",
    [
        lambda d: d["results"]["deadline"].update(
            ms_error_bound=0.99 * d["results"]["deadline"]["ms_error_bound"]
        ),
        lambda d: d["results"]["deadline"].update(
            peak_bound=0.99 * d["results"]["deadline"]["peak_bound"]
        ),
        lambda d: d["subject"]["deadline"].update(T=2.0),
        lambda d: d["subject"]["deadline"]["initial"].update(
            x0=[0.5 * v for v in d["subject"]["deadline"]["initial"]["x0"]]
        ),
        lambda d: d["results"]["deadline"].update(
            ms_error_bound=1.5 * d["results"]["deadline"]["ms_error_bound"]
        ),
    ],
    ids=["bound", "peak", "T", "initial", "not-this-subject"],
)
def test_forged_deadline_fields_are_rejected(deadline_cert, forge):
    doc = copy.deepcopy(deadline_cert[0])
    forge(doc)
    assert not verify(_resealed(doc)).valid


def test_unproven_deadline_numbers_fail_the_audit(deadline_cert):
    doc = copy.deepcopy(deadline_cert[0])
    del doc["subject"]["deadline"]
    assert not verify(_resealed(doc)).valid  # results.deadline left unaccounted for
