"""Tests of :mod:`ntc_design.certify.kinds.dense`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import hurwitz_certificate, switching_certificate, verify
from ntc_design.certify.format import digest
from ntc_design.model.paper import THETA
from tests.cli_helpers import run_cli
from tests.conftest import ROOT
from tests.support.certificates import _load, _write


@pytest.mark.hostile
def test_tampered_then_redigested_fails_on_the_inequality(tmp_path, capsys, monkeypatch):
    doc = _load("g1.json")
    p = np.array(doc["matrices"]["P"]["lyapunov"])
    p[0, 0] = -p[0, 0]
    doc["matrices"]["P"]["lyapunov"] = p.tolist()
    doc["digest"] = digest(doc)
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1
    assert "P_lyapunov ≻ 0" in err and "digest" not in err
    # an L_B that no longer matches the topology is caught even with a fresh digest
    doc = _load("g1.json")
    doc["matrices"]["L_B"]["G1"][0][0] += 1e-6
    doc["digest"] = digest(doc)
    code, out, err = run_cli(["verify", _write(tmp_path, doc)], capsys, monkeypatch)
    assert code == 1 and "L_B(G1) matches its topology" in err
    # changing δ (and L_B consistently) keeps the maths honest: a δ where L_B + L_Bᵀ is
    # not positive definite fails the symmetric claim
    sd = nd.design(nd.load(ROOT / "examples" / "switching.yaml"), THETA, delta=0.5)
    cert = switching_certificate(sd, structures=("identity",))
    assert "P_common ≻ 0" not in [c["id"] for c in cert["claims"]]
    assert cert["results"]["symmetric_part_min_eig"]["G1"] < 0


def test_verify_uses_verified_float_above_the_exact_size(examples):
    """Four disjoint copies of G1 (Nd = 84 > 80): the certificate is re-checked with the
    rigorous floating-point test, and a forged P still fails."""
    g1 = nd.load(examples / "g1.yaml")
    edges = [
        (7 * c + g1.labels[j], 7 * c + g1.labels[i], a)
        for c in range(4)
        for (i, j), a in g1.weights.items()
    ]
    big = nd.Topology.from_edges(28, 3, edges, name="4xG1")
    cert = hurwitz_certificate(nd.design(big, THETA, thresholds=False), rate=False)
    ver = verify(cert)
    assert ver.valid and ver.method == "verified-float", ver.failed
    p = np.array(cert["matrices"]["P"]["lyapunov"])
    p[5, 5] = -1.0
    cert["matrices"]["P"]["lyapunov"] = p.tolist()
    cert["digest"] = digest(cert)
    bad = verify(cert)
    assert not bad.valid and {c.name for c in bad.failed} >= {"P_lyapunov ≻ 0"}
