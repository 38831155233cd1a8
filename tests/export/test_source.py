"""Tests of :mod:`ntc_design.export.source`: a scenario's certified design and a verified
certificate become the agents' law; an uncertified design, a certificate that does not
verify, a kind without dense modes, a missing period or a gain outside Theorem 1 is
refused with one line naming the file or option."""

import copy
import json
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.export.source import from_certificate, from_scenario, is_certificate, load_source
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from tests.conftest import EXAMPLES, ROOT

DEADLINE = EXAMPLES / "scenarios" / "g1_deadline.yaml"
CERTS = ROOT / "certificates"


def _scenario(tmp_path, extra: str, topology: str | None = None) -> str:
    top = topology or str(EXAMPLES / "g1.yaml")
    p = tmp_path / "s.yaml"
    p.write_text(f"topology: {top}\ntheta: [1, 2, -1]\nT: 5\n{extra}")
    return str(p)


def test_a_scenario_gives_its_certified_design(tmp_path):
    src = from_scenario(DEADLINE, period=0.1, delay=1)
    law = src.law
    des = nd.design(nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], 0.1, thresholds=False)
    want = agent_law(des, Digital(0.1, 1), "1/(1+t)", 0.4, 0.3).modes[0]
    got = law.modes[0]
    for name in ("dst", "src", "sign", "weight", "sigma", "bd", "u"):
        assert (getattr(got, name) == getattr(want, name)).all(), name
    assert law.digital == Digital(0.1, 1) and law.gain.label == "1/(1+t)"
    assert src.initial.tolist() == np.linspace(-3, 3, 21).round(1).tolist()
    assert src.horizon == 10.0 and src.kind == "scenario" and law.name == "G1"
    assert "digital certificate valid" in src.notes[0] and "Theorem 1, 2" in src.notes[0]
    assert "for the sampled one (contracting from step k₀ = 24)" in src.notes[0]


def test_the_digital_block_and_the_noise_are_read_and_overridden(tmp_path):
    p = _scenario(
        tmp_path,
        "gain: 2/(2+t)\ndigital: {period: 0.05, delay: 2}\n"
        "noise: {sigma: 0.2, f: 0.1, sigma_edges: [{from: 5, to: 6, sigma: 0.7}]}\n",
    )
    law = from_scenario(p).law
    assert law.digital == Digital(0.05, 2) and law.gain.label == "2/(2+t)"
    assert sorted(set(law.modes[0].sigma.tolist())) == [0.2, 0.7]
    assert (law.noise_f == 0.1 * np.eye(3)).all()
    law = from_scenario(p, period=0.02, gain="1/(1+t)", sigma=0.3, f=0.25).law
    assert law.digital == Digital(0.02, 2) and law.gain.label == "1/(1+t)"
    assert sorted(set(law.modes[0].sigma.tolist())) == [0.3, 0.7]
    assert (law.noise_f == 0.25 * np.eye(3)).all()


def test_a_schedule_csv_gain(tmp_path):
    csv = tmp_path / "schedule.csv"
    g = ScheduleGain([0.0, 1.0, 2.0], [1.0, 0.6, 1 / 3], tail="1/(1+t)")
    csv.write_text(g.csv_text())
    law = from_scenario(DEADLINE, period=0.1, gain=str(csv)).law
    assert law.gain.is_schedule and law.gain.t == (0.0, 1.0, 2.0)


def test_a_switching_scenario(tmp_path):
    p = _scenario(tmp_path, "", str(EXAMPLES / "switching.yaml"))
    law = from_scenario(p, period=0.013).law
    assert law.mode_names == ["G1", "G2", "G3"] and [m for m, _ in law.schedule][:3] == [
        "G2",
        "G2",
        "G1",
    ]


def test_a_certificate_gives_its_subject():
    src = from_certificate(CERTS / "g1.json", period=0.1, delay=2)
    law = src.law
    assert src.kind == "certificate (hurwitz)" and "valid" in src.notes[0]
    doc = json.loads((CERTS / "g1.json").read_text())
    sub = doc["subject"]["modes"]["G1"]
    ml = law.modes[0]
    # the subject's edge order is the file order here
    order = [(e["from"], e["to"]) for e in sub["topology"]["edges"]]
    assert [(law.labels[j], law.labels[i]) for i, j in zip(ml.dst, ml.src, strict=True)] == order
    assert ml.delta == sub["delta"] and ml.informed == (1, 2)
    des = nd.design(nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], thresholds=False)
    assert (ml.u == des.input_vector().reshape(7, 3)).all()
    assert law.gain.label == "1/(1+t)" and (law.noise_f == 0.3 * np.eye(3)).all()
    assert ml.sigma.tolist() == [0.4] * 8 and (src.initial == 0).all()


def test_a_switching_certificate_gives_its_schedule():
    doc = json.loads((CERTS / "switching.json").read_text())
    law = from_certificate(CERTS / "switching.json", period=0.013).law
    assert list(law.schedule) == [(s["mode"], s["duration"]) for s in doc["subject"]["schedule"]]
    assert set(law.step_modes(400).tolist()) == {0, 1, 2}


def test_load_source_tells_the_two_apart():
    assert load_source(CERTS / "g1.json", period=0.1).kind.startswith("certificate")
    assert is_certificate({"format": "ntc-design/certificate"}) and not is_certificate([])


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, kwargs, needles",
    [
        ("", {}, ["--period:", "has no digital block"]),
        ("", {"period": 6.0}, ["--period: h = 6 is longer than the horizon T = 5"]),
        ("", {"period": 0.1, "delay": -1}, ["--delay: must be an integer >= 0"]),
        ("digital: {period: -1}\n", {}, ["s.yaml: digital.period: must be a positive number"]),
        ("gain: '1'\n", {"period": 0.1}, ["no theorem is guaranteed", "nothing exported"]),
        ("", {"period": 0.1, "sigma": -1.0}, ["--sigma: expected a finite number >= 0"]),
    ],
)
def test_scenario_refusals(tmp_path, extra, kwargs, needles):
    with pytest.raises(InputError) as err:
        from_scenario(_scenario(tmp_path, extra), **kwargs)
    msg = str(err.value)
    assert "\n" not in msg and all(n in msg for n in needles), msg


@pytest.mark.hostile
def test_an_uncertified_design_is_refused(tmp_path):
    top = tmp_path / "plain.yaml"  # no antagonistic edge: no informed agent, L_B singular
    top.write_text("dim: 1\nagents: 2\nedges:\n  - {from: 1, to: 2, weight: 1}\n")
    p = tmp_path / "s.yaml"
    p.write_text(f"topology: {top}\ntheta: [1]\nT: 5\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(
            InputError, match=r"s.yaml: the design's certificate .* does not verify"
        ):
            from_scenario(p, period=0.1)


@pytest.mark.hostile
def test_a_certificate_that_does_not_verify_is_refused(tmp_path):
    doc = json.loads((CERTS / "g1.json").read_text())
    bad = copy.deepcopy(doc)
    bad["subject"]["modes"]["G1"]["delta"] = 1.0
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(bad))
    with pytest.raises(
        InputError, match=r"bad.json: the certificate does not verify \(.*\); nothing"
    ):
        load_source(p, period=0.1)


@pytest.mark.hostile
def test_certificate_option_refusals(tmp_path):
    with pytest.raises(InputError, match=r"^--period: .*g1.json: subject has no digital block"):
        from_certificate(CERTS / "g1.json")
    with pytest.raises(InputError, match=r"^--gain: c\(t\) = 1 does not satisfy"):
        from_certificate(CERTS / "g1.json", period=0.1, gain="1")
    with pytest.raises(InputError, match=r"^--f: expected a number"):
        from_certificate(CERTS / "g1.json", period=0.1, f="x")  # type: ignore[arg-type]


@pytest.mark.hostile
def test_a_kind_without_dense_modes_is_refused(g1_robust, tmp_path):
    from ntc_design.certify.kinds.robust import robust_certificate

    doc = json.loads(json.dumps(robust_certificate(g1_robust[1])))
    with pytest.raises(InputError, match=r"kind: a robust certificate cannot be exported"):
        from_certificate(tmp_path / "r.json", period=0.1, doc=doc)


def _sealed(tmp_path, **subject):
    """certificates/g1.json with more subject fields (as a digital certificate states
    them), its digests sealed again: it still verifies."""
    from ntc_design.certify.format import finish

    doc = json.loads((CERTS / "g1.json").read_text())
    doc["subject"].update(subject)
    for key in ("digest", "subject_digest", "versions"):
        doc.pop(key, None)
    p = tmp_path / "sealed.json"
    p.write_text(json.dumps(finish(doc)))
    return p


def test_a_subject_that_states_period_gain_and_noise(tmp_path):
    p = _sealed(
        tmp_path,
        digital={"period": 0.05, "delay": 1},
        gain="2/(2+t)",
        noise={"sigma": 0.2, "f": 0.1, "sigma_edges": [{"from": 5, "to": 6, "sigma": 0.7}]},
    )
    law = load_source(p).law
    assert law.digital == Digital(0.05, 1) and law.gain.label == "2/(2+t)"
    assert sorted(set(law.modes[0].sigma.tolist())) == [0.2, 0.7]
    assert (law.noise_f == 0.1 * np.eye(3)).all()
    assert load_source(p, period=0.02, sigma=0.3).law.digital == Digital(0.02, 1)
    with pytest.raises(InputError, match=r"^--gain: the certificate states its gain"):
        load_source(p, gain="1/(1+t)")


@pytest.mark.hostile
def test_a_time_varying_scenario_is_refused():
    with pytest.raises(InputError, match=r"only a fixed topology or a switching set"):
        from_scenario(EXAMPLES / "scenarios" / "g1_tv.yaml", period=0.1)


def test_the_option_replaces_a_file_period_that_would_be_refused(tmp_path):
    p = _scenario(tmp_path, "digital: {period: 20, delay: 1}\n")  # longer than T = 5
    with pytest.raises(InputError, match=r"s.yaml: digital.period: h = 20 is longer"):
        from_scenario(p)
    assert from_scenario(p, period=0.1).law.digital == Digital(0.1, 1)
