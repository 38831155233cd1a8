"""Tests of :mod:`ntc_design.simulate.spec`."""

import dataclasses
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.model.paper import THETA
from ntc_design.simulate import (
    NoiseModel,
    SaveAt,
    SimulationSpec,
    UniformInitial,
    simulate,
)
from ntc_design.simulate.scenario import load_scenario
from ntc_design.simulate.spec import OPTION_KEYS, SCENARIO_KEYS
from tests.cli_helpers import assert_input_error
from tests.conftest import ROOT, X0
from tests.support.simulate import write_scenario


def test_implicit_needs_intrinsic_stepping(g1):
    with pytest.raises(nd.InputError, match=r"scheme: implicit needs stepping: intrinsic"):
        simulate(g1, THETA, T=0.1, paths=4, scheme="implicit")
    with pytest.raises(nd.InputError, match=r"scheme: must be explicit or implicit"):
        simulate(g1, THETA, T=0.1, paths=4, scheme="magic")


@pytest.mark.hostile
@pytest.mark.parametrize("bad", ["mt19937", "", 3, None])
def test_an_unknown_generator_is_refused(g1, bad):
    with pytest.raises(nd.InputError, match="rng"):
        simulate(g1, [1, 2, -1], T=0.1, paths=4, rng=bad)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "options, needle",
    [
        ({"device": "tpu"}, "device: expected cpu or gpu, got 'tpu'"),
        ({"device": 1}, "device: expected cpu or gpu, got 1"),
        ({"device": "gpu", "rng": "numpy"}, "rng: numpy stays on the CPU"),
        (
            {"device": "gpu", "scheme": "implicit", "stepping": "intrinsic", "ds": 0.01},
            "scheme: implicit runs on the CPU only",
        ),
        ({"device": "gpu", "noise": NoiseModel(0.4, np.tanh)}, "noise.f: a callable f runs"),
    ],
)
def test_what_the_gpu_does_not_run_is_refused_before_any_device(options, needle):
    # checked with the spec: no GPU, no numba-cuda needed to say so
    with pytest.raises(InputError, match=f"^{needle}"):
        SimulationSpec.build(THETA, **options)


def test_device_is_a_monte_carlo_option_and_a_scenario_key():
    spec = SimulationSpec.build(THETA, device="gpu")
    assert spec.mc.device == "gpu" and spec.options()["device"] == "gpu"
    assert SimulationSpec.build(THETA).mc.device == "cpu"
    assert "device" in SCENARIO_KEYS and "device" in OPTION_KEYS


@pytest.mark.parametrize(
    "over, needles",
    [
        ({"dt": 0}, ["dt", "positive"]),
        ({"dt": -0.1}, ["dt", "positive"]),
        ({"T": 0}, ["T", "positive"]),
        ({"paths": 0}, ["paths", "positive integer"]),
        ({"topology": "nope.yaml"}, ["topology", "no such file"]),
        ({"initial": [[1, 2, 3]] * 6}, ["initial", "expected 7 states"]),
        ({"gain": "0.1 - t"}, ["gain", "negative"]),
        ({"gain": "1/(1+"}, ["gain", "cannot parse"]),
        ({"method": "magic"}, ["method"]),
        ({"colour": 1}, ["colour", "unknown field"]),
    ],
)
def test_bad_scenarios(tmp_path, capsys, monkeypatch, over, needles):
    sc = write_scenario(tmp_path, **over)
    out = tmp_path / "never"
    assert_input_error(["simulate", sc, "--out", out], capsys, monkeypatch, *needles)
    assert not out.exists()


def test_scenario_and_keywords_build_the_same_spec(tmp_path):
    doc = {
        "topology": str(ROOT / "examples" / "g1.yaml"),
        "theta": THETA,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": [{"from": 2, "to": 1, "sigma": 0.1}]},
        "initial": {"uniform": [-3, 3], "seed": 1},
        "T": 0.5,
        "dt": 0.002,
        "paths": 30,
        "seed": 4,
        "save_times": [0.1, 0.5],
        "stepping": "intrinsic",
        "ds": 0.003,
        "workers": 1,
    }
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(doc))
    _, a, _ = load_scenario(p)
    b = SimulationSpec.build(
        THETA,
        gain="1/(1+t)",
        noise=NoiseModel(0.4, 0.3, {(2, 1): 0.1}),
        initial=UniformInitial(-3, 3, 1),
        T=0.5,
        dt=0.002,
        paths=30,
        seed=4,
        save_times=[0.1, 0.5],
        stepping="intrinsic",
        ds=0.003,
        workers=1,
    )
    assert a.options() == b.options()
    assert a.mc == b.mc and a.stepping == b.stepping and a.initial == b.initial
    assert a.stepping.intrinsic_ds == 0.003 and a.stepping.max_step == 1.0
    assert set(OPTION_KEYS) < set(SCENARIO_KEYS)


def test_spec_is_frozen_and_rechecked_on_replace():
    s = SimulationSpec.build(THETA, paths=10)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.T = 3.0  # type: ignore[misc]
    with pytest.raises(InputError, match=r"^T: must be a positive number"):
        s.replace(T=-1.0)
    assert not s.theta.flags.writeable


# ------------------------------------------------------- property: any scenario document

_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
)


_values = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=12,
)


_keys = st.sampled_from([k for k in SCENARIO_KEYS if k != "topology"] + ["colour", "noise.f"])


@pytest.mark.hostile
@settings(max_examples=150, deadline=None)
@given(
    doc=st.dictionaries(_keys, _values, max_size=6),
    theta=st.one_of(st.just([1, 2, -1]), _values),
)
def test_any_scenario_document_gives_a_spec_or_one_line(doc, theta):
    """Whatever a scenario holds, the parser returns a valid spec or raises InputError
    with one line naming a field; never another exception."""
    doc = {**doc, "theta": theta}
    try:
        spec = SimulationSpec.from_document(doc, "sc.yaml")
    except InputError as exc:
        msg = str(exc)
        assert msg.startswith("sc.yaml: ") and "\n" not in msg
        field = msg.split(": ")[1].split(" ")[0].strip("'")
        assert field.split("[")[0].split(".")[0] in (*SCENARIO_KEYS, "colour", "noise.f"), msg
        return
    assert isinstance(spec, SimulationSpec) and np.all(np.isfinite(spec.theta))
    assert spec.mc.paths >= 1 and spec.T > 0


def test_scenario_with_a_schedule_gain_simulates_it(tmp_path, g1):
    """gain: {schedule: FILE, tail} in a scenario: the exact moments equal those of the
    expression the table tabulates (a constant, so the table is exact)."""
    (tmp_path / "s.csv").write_text("# tail: 0.8\nt,c\n0,0.8\n1,0.8\n", encoding="utf-8")
    doc = {
        "topology": "g1.yaml",
        "theta": THETA,
        "gain": {"schedule": "s.csv"},
        "initial": X0.tolist(),
        "T": 2.0,
        "method": "exact",
    }
    spec_s = SimulationSpec.from_document(doc, str(tmp_path / "sc.yaml"))
    assert isinstance(spec_s.gain, ScheduleGain)
    a = simulate(g1, spec=spec_s.replace(save=SaveAt(times=np.array([0.0, 2.0]))))
    b = simulate(g1, spec=spec_s.replace(gain="0.8", save=SaveAt(times=np.array([0.0, 2.0]))))
    assert np.allclose(a.exact.ms_error, b.exact.ms_error, rtol=1e-12)
    assert spec_s.options()["gain"]["tail"] == "0.8"


def test_initial_takes_the_scenario_mapping_form(g1):
    """``simulate(top, θ, initial={"uniform": [lo, hi], "seed": S})``, as a scenario
    writes it, is the same x(0) as ``UniformInitial(lo, hi, S)`` (it was refused with
    'expected a list of numbers, got dict')."""

    a = simulate(g1, THETA, initial={"uniform": [-3, 3], "seed": 1}, T=0.1, method="exact")
    b = simulate(g1, THETA, initial=UniformInitial(-3, 3, 1), T=0.1, method="exact")
    assert np.array_equal(a.exact.ms_error, b.exact.ms_error)
    spec = SimulationSpec.build(THETA, initial={"uniform": (-3, 3), "seed": 1})
    assert spec.initial == UniformInitial(-3.0, 3.0, 1)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "initial, needle",
    [
        ({"uniform": [3, -3], "seed": 1}, "initial.uniform: need lo < hi"),
        ({"uniform": [-3, 3]}, "UniformInitial(lo, hi, seed) in Python"),
        ({"normal": [0, 1], "seed": 1}, "UniformInitial(lo, hi, seed) in Python"),
        ({"uniform": [-3], "seed": 1}, "initial.uniform: expected [lo, hi]"),
        ({"uniform": [-3, 3], "seed": -1}, "initial.seed: must be an integer >= 0"),
    ],
)
def test_a_bad_initial_mapping_is_one_line_naming_it(initial, needle):
    with pytest.raises(InputError) as err:
        SimulationSpec.build(THETA, initial=initial)
    assert needle in str(err.value) and "\n" not in str(err.value)
