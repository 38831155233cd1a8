"""Tests of :mod:`ntc_design.reports.rundata`."""

import copy
import json

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.protocol.digital import Digital
from ntc_design.reports.rundata import RunSummary
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.scenario import write_outputs
from tests.cli_helpers import assert_input_error


def test_report_missing_files_are_named(tmp_path, capsys, monkeypatch):
    assert_input_error(
        ["report", tmp_path / "nothing"],
        capsys,
        monkeypatch,
        "no such directory",
        "ntc simulate SCENARIO --out",
    )
    (tmp_path / "partial").mkdir()
    (tmp_path / "partial" / "summary.json").write_text("{}")
    assert_input_error(
        ["report", tmp_path / "partial"],
        capsys,
        monkeypatch,
        "missing ms_error.csv",
        "ntc simulate SCENARIO --out",
    )
    assert not (tmp_path / "partial" / "report.html").exists()


# -- RunSummary.from_document: summary.json read back through its types -----------------------


@pytest.fixture(scope="module")
def lossy_summary(pair_topology, tmp_path_factory):
    """A digital run on lossy links whose horizon is not a whole number of periods
    (T = 1, h = 0.3: K = 3 and a partial step of 0.1), with a per-edge σ."""
    res = simulate(
        pair_topology, [1.0], T=1.0, dt=0.01, paths=8, seed=2, save_every=0.1, workers=1,
        margin=0.3, gain="2/(1+t)", initial=[3.0, -1.0],
        noise=NoiseModel(0.5, 0.2, sigma_edges={(2, 1): 0.7}),
        digital=Digital(0.3, 1, loss=0.1, policy="hold"),
    )  # fmt: skip
    out = tmp_path_factory.mktemp("lossy") / "run"
    write_outputs(res, out)
    return json.loads((out / "summary.json").read_text(encoding="utf-8"))


def test_from_document_reads_the_spec_the_partial_step_and_the_loss(lossy_summary):
    got = RunSummary.from_document(lossy_summary, "s.json")
    spec = got.spec
    np.testing.assert_array_equal(spec.theta, [1.0])
    assert (spec.margin, spec.gain, spec.T) == (0.3, "2/(1+t)", 1.0)
    assert spec.digital == Digital(0.3, 1, loss=0.1, policy="hold")
    assert spec.noise.sigma == 0.5 and spec.noise.f == 0.2
    assert dict(spec.noise.sigma_edges) == {("2", "1"): 0.7}  # from {"2->1": 0.7}
    np.testing.assert_array_equal(spec.initial, [3.0, -1.0])
    assert spec.mc.paths == 8 and spec.mc.seed == 2
    dg = got.digital
    assert (dg.period, dg.delay, dg.steps) == (0.3, 1, 3)
    assert dg.partial_step == pytest.approx(1.0 - 3 * 0.3, abs=1e-12)
    assert dg.loss["policy"] == "hold" and dg.loss["p"] == 0.1
    assert [str(a) for a in got.topology.labels] == ["1", "2"] and got.topology.dim == 1


def test_from_document_puts_a_stand_in_for_a_callable_f(lossy_summary):
    doc = copy.deepcopy(lossy_summary)
    doc["parameters"]["noise"]["f"] = "callable"
    del doc["parameters"]["digital"]
    f = RunSummary.from_document(doc).spec.noise.f
    assert callable(f)
    with pytest.raises(InputError, match="noise.f: the run's f was a Python callable"):
        f(np.zeros(2))


def _put(path, value):
    def change(doc):
        *up, last = path
        node = doc
        for k in up:
            node = node[k]
        node[last] = value

    return change


HOSTILE_SUMMARIES = [
    ("not-a-mapping", lambda d: d.clear() or d.update(x=1), "parameters"),
    ("partial-step", _put(("digital", "partial_step"), "x"), "digital.partial_step"),
    ("steps", _put(("digital", "steps"), 1.5), "digital.steps"),
    ("loss-policy", _put(("digital", "loss", "policy"), "drop"), "digital.loss.policy"),
    ("loss-p", _put(("digital", "loss", "p"), 2.0), "digital.loss.p"),
    ("loss-text", _put(("digital", "loss"), "x"), "digital.loss"),
    ("period", _put(("parameters", "digital", "period"), -1), "parameters.digital.period"),
    ("loss-param", _put(("parameters", "digital", "loss"), 1.0), "parameters.digital.loss"),
    (
        "sigma-edges",
        _put(("parameters", "noise", "sigma_edges"), {"ab": 1}),
        "parameters.noise.sigma_edges",
    ),
    ("seed", _put(("parameters", "seed"), "x"), "parameters.seed"),
    ("dim", _put(("parameters", "theta"), [1.0, 2.0]), "parameters.theta"),
]


@pytest.mark.hostile
@pytest.mark.parametrize(
    "change, field", [h[1:] for h in HOSTILE_SUMMARIES], ids=[h[0] for h in HOSTILE_SUMMARIES]
)
def test_from_document_names_the_file_and_the_field(lossy_summary, change, field):
    doc = copy.deepcopy(lossy_summary)
    change(doc)
    with pytest.raises(InputError) as info:
        RunSummary.from_document(doc, "run/summary.json")
    msg = str(info.value)
    assert msg.startswith(f"run/summary.json: {field}"), msg
    assert "\n" not in msg
