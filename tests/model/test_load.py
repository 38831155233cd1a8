"""Tests of :mod:`ntc_design.model.load`."""

import numpy as np
import yaml

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.certify.time_varying import certify_lambda2
from ntc_design.model.paper import THETA
from ntc_design.model.timevarying import from_document
from ntc_design.protocol import design
from ntc_design.protocol.timevarying import TimeVaryingDesign
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.moments import PreparedModes, exact_moments
from ntc_design.simulate.system import mode_system
from ntc_design.simulate.timevarying import exact_moments_tv, time_varying_system
from tests.conftest import ROOT, X0


def constant_copy(path) -> dict:
    """The paper's G1 with every weight written as a constant expression (strings)."""
    doc = yaml.safe_load(path.read_text())

    def strings(x):
        if isinstance(x, list):
            return [strings(v) for v in x]
        if isinstance(x, dict):
            return {k: (v if k == "matrix" else strings(v)) for k, v in x.items()}
        return repr(x) if isinstance(x, float) else str(x)

    for e in doc["edges"]:
        e["weight"] = strings(e["weight"])
    doc["period"] = 1
    return doc


def test_constant_expressions_give_the_fixed_topology_exactly(tmp_path):
    fixed = nd.load(ROOT / "examples" / "g1.yaml")
    doc = constant_copy(ROOT / "examples" / "g1.yaml")
    (tmp_path / "g1c.yaml").write_text(yaml.safe_dump(doc))
    top = nd.load(tmp_path / "g1c.yaml")
    assert type(top) is type(fixed)
    for k, a in fixed.weights.items():
        assert np.array_equal(top.weights[k], a)
    assert design(top, THETA).to_dict() == design(fixed, THETA).to_dict()
    c1, c2 = certify(top, THETA, 0.1, "1/(1+t)"), certify(fixed, THETA, 0.1, "1/(1+t)")
    assert c1.certificate["matrices"] == c2.certificate["matrices"]
    assert c1.certificate["claims"] == c2.certificate["claims"]
    kw = dict(T=1.0, initial=X0, save_every=0.1, method="exact")
    assert np.array_equal(
        simulate(top, THETA, **kw).exact.ms_error, simulate(fixed, THETA, **kw).exact.ms_error
    )
    # and the time-varying machinery on the same constant weights agrees with them
    tv = from_document(doc, "g1c.yaml")
    des = TimeVaryingDesign(tv, np.array(THETA, float), 0.1)
    d = design(fixed, THETA)
    b = des.at([0.0, 0.7])
    assert np.all(np.abs(b.delta - d.delta) <= 1e-13 * d.delta)
    np.testing.assert_allclose(
        b.lap_b(des.structure)[1], np.asarray(d.grounded_laplacian()), atol=1e-13
    )
    lb = np.asarray(d.grounded_laplacian())
    lam = float(np.linalg.eigvalsh(lb + lb.T)[0])
    bound = certify_lambda2(tv, 0.1)
    assert bound.lambda2 <= lam and (lam - bound.lambda2) / lam < 1e-9
    sys_ = time_varying_system(des, NoiseModel())
    st = np.arange(0, 11) * 0.1
    m_tv = exact_moments_tv(sys_, lambda t: 1 / (1 + t), X0 - np.tile(THETA, 7), st, 1.0)
    fixed = PreparedModes.of(
        [mode_system(d, NoiseModel())], X0 - np.tile(THETA, 7), [(0.0, 1.0, 0)]
    )
    m_fx = exact_moments(fixed, lambda t: 1 / (1 + t), st)
    np.testing.assert_allclose(m_tv.ms_error, m_fx.ms_error, rtol=1e-7)
