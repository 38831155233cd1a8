"""The certificates bundled in certificates/, reading and writing them, and the
paper's designs as a session fixture."""

import json

import pytest

import ntc_design as nd
from ntc_design.paper import THETA  # the paper's θ, defined once
from tests.conftest import ROOT

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
