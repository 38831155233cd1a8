"""The certificates bundled in certificates/, reading and writing them, the paper's
designs and one honest certificate of every kind as session fixtures."""

import copy
import json
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.certify import KINDS, certify, verify
from ntc_design.certify.kinds import IssueOptions
from ntc_design.certify.kinds.hurwitz_scale import scale_certificate
from ntc_design.certify.kinds.robust import robust_certificate
from ntc_design.certify.kinds.switching_scale import switching_scale_certificate
from ntc_design.certify.robust import robust
from ntc_design.gain.conditions import analyse_gain
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.model.timevarying import from_document
from ntc_design.protocol import design
from ntc_design.protocol.digital import Digital
from ntc_design.protocol.timevarying import TimeVaryingDesign
from tests.conftest import ROOT
from tests.support.shared import once_per_run

CERTS = ROOT / "certificates"


@pytest.fixture(scope="session")
def paper_designs():
    return {
        g: nd.design(nd.load(ROOT / "examples" / f"{g}.yaml"), THETA) for g in ("g1", "g2", "g3")
    }


def _load(name):
    return json.loads((CERTS / name).read_text())


def _write(tmp_path, doc, name="c.json"):
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


def _tv_topology() -> dict:
    """A 3-agent path whose antagonistic weight varies with t (period 2π)."""
    w = {
        "1->2": {"diag": ["-1 - 0.5*sin(t)", -2]},
        "2->3": [[2, 0], [0, 1]],
        "3->1": {"identity": 1},
        "2->1": {"identity": 1},
    }
    edges = [{"from": int(k[0]), "to": int(k[-1]), "weight": v} for k, v in w.items()]
    return {"dim": 2, "agents": 3, "edges": edges, "period": "2*pi"}


@pytest.fixture(scope="session")
def g1_digital_d1(g1):
    """``certify(G1, θ, "1/(1+t)", digital=Digital(0.1, 1))``: the delay line's certificate
    (about 7 s of SDP solves), issued once per worker for the modules that read it (it was
    issued once in each). Copy its certificate before editing it."""
    return certify(g1, THETA, gain="1/(1+t)", digital=Digital(0.1, 1))


@pytest.fixture(scope="session")
def honest_certificates(tmp_path_factory) -> dict[str, dict]:
    """One honest certificate of every kind (two of hurwitz-scale; the digital kinds with and
    without a delay), each verified: the
    forgery property test mutates them, the kind-swap test relabels them. Copy before
    editing. Built once per run (about 15 s), whichever xdist worker asks first."""
    return once_per_run(tmp_path_factory, "honest_certificates", _honest_certificates)


def _honest_certificates() -> dict[str, dict]:
    g1 = _load("g1.json")
    sw = _load("switching.json")
    theta3 = [1.0, 2.0, -1.0]
    scale_rand = scale_certificate(design(random_network(12, 2, seed=3), [1.0, -1.0], 0.1))
    scale_g1 = scale_certificate(design(nd.load(ROOT / "examples" / "g1.yaml"), theta3, 0.1))
    with pytest.warns(Warning):  # G3 fails Assumption 2 (the paper's own example)
        sd = design(nd.load(ROOT / "examples" / "switching.yaml"), theta3, 0.1)
    sws = switching_scale_certificate(sd)
    tv = from_document(_tv_topology(), "tv")
    tvc = KINDS["time_varying"].issue(
        TimeVaryingDesign(tv, np.array([1.0, 2.0]), 0.1),
        IssueOptions(gain=analyse_gain("1/(1+t)")),
    )
    rdes = design(random_network(4, 2, seed=1), [1.0, -1.0], 0.1, thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rob = json.loads(json.dumps(robust_certificate(robust(rdes, 0.1, starts=2))))
    g1t = nd.load(ROOT / "examples" / "g1.yaml")
    # the delay line (D = 1) and the lossy delay line on a 3-agent signed cycle (d = 1):
    # 0.2 s each and a cheap verify per mutant (G1's: tests/certify/kinds/test_digital.py,
    # test_digital_loss_delay.py and the shipped certificates/g1_digital.json)
    one = np.ones((1, 1))
    cycle = nd.Topology.from_edges(3, 1, [(1, 2, one), (2, 3, -one), (3, 1, one)])
    dig = certify(cycle, [1.0], gain="1/(1+t)", digital=Digital(0.1, 1)).certificate
    lossy = Digital(0.1, 0, 0.1)  # lossy links, skip: the contraction and the offset
    digl = certify(g1t, theta3, gain="1/(1+t)", digital=lossy).certificate
    # lossy links with a delay, the lossy delay line, on a 3-agent signed cycle (d = 1):
    # 0.2 s, G1's 9 s (G1's is tests/certify/kinds/test_digital_loss_delay.py's, slow)
    lossy_d1 = Digital(0.1, 1, 0.1)
    digld = certify(cycle, [1.0], gain="1/(1+t)", digital=lossy_d1).certificate
    with pytest.warns(Warning):  # G3 fails Assumption 2
        sw_top = nd.load(ROOT / "examples" / "switching.yaml")
        digsw = certify(sw_top, theta3, gain="1/(1+t)", digital=Digital(0.013, 0)).certificate
    out = {
        "digital": json.loads(json.dumps(dig)),
        "digital_switching": json.loads(json.dumps(digsw)),
        "digital_loss": json.loads(json.dumps(digl)),
        "digital_loss-delay": json.loads(json.dumps(digld)),
        "robust": rob,
        "hurwitz": g1,
        "switching": sw,
        "hurwitz-scale": scale_rand,
        "hurwitz-scale-g1": scale_g1,
        "switching-scale": sws,
        "time_varying": tvc,
    }
    for name, doc in out.items():
        assert verify(copy.deepcopy(doc)).valid, name
    return out
