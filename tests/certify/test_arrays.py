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
