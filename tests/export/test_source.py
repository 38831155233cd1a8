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
from ntc_design.certify import verify
from ntc_design.errors import InputError
from ntc_design.export.source import (
    ExportOptions,
    from_certificate,
    from_scenario,
    is_certificate,
    load_source,
)
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from tests.conftest import EXAMPLES, ROOT
from tests.support.export import g1_d1_certified

DEADLINE = EXAMPLES / "scenarios" / "g1_deadline.yaml"
CERTS = ROOT / "certificates"


def _scenario(tmp_path, extra: str, topology: str | None = None) -> str:
    top = topology or str(EXAMPLES / "g1.yaml")
    p = tmp_path / "s.yaml"
    p.write_text(f"topology: {top}\ntheta: [1, 2, -1]\nT: 5\n{extra}")
    return str(p)


def _small(tmp_path, extra: str) -> str:
    """A scenario on a 3-agent signed cycle (d = 1): its D = 1 certificate takes about 0.2 s
    (G1's about 10 s), for the tests about reading the file, not about G1's numbers."""
    (tmp_path / "cycle.yaml").write_text(
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: 1}\n"
        "  - {from: 2, to: 3, weight: -1}\n  - {from: 3, to: 1, weight: 1}\n"
    )
    p = tmp_path / "s.yaml"
    p.write_text(f"topology: cycle.yaml\ntheta: [1]\nT: 5\n{extra}")
    return str(p)


@pytest.fixture(scope="module")
def g1_scenario_d1(g1, g1_digital_d1):
    """G1's scenario exported at h = 0.1, D = 1, once for the tests that read it. Its delay
    line's certificate (about 10 s) is the session's g1_digital_d1 = certify(G1, θ,
    "1/(1+t)", Digital(0.1, 1)) at the paper's noise (0.4, 0.3), which the scenario's file
    gives (tests/support/export.py's g1_d1_certified checks the call and answers it)."""
    with pytest.MonkeyPatch.context() as mp:
        g1_d1_certified(mp, g1, g1_digital_d1)
        return from_scenario(DEADLINE, ExportOptions(period=0.1, delay=1))


@pytest.fixture(scope="module")
def switching_json():
    """certificates/switching.json exported at h = 0.013 (its sampled protocol certified
    first, about 3 s), once for the tests that read it."""
    return from_certificate(CERTS / "switching.json", ExportOptions(period=0.013))


@pytest.fixture(scope="module")
def g1_json_d0():
    """certificates/g1.json (continuous) exported at h = 0.1, D = 0: the sampled protocol
    certified first (about 1 s; at D = 1 the scenario's test has G1's delay line), once for
    the tests that read it."""
    return from_certificate(CERTS / "g1.json", ExportOptions(period=0.1))


def test_a_scenario_gives_its_certified_design(g1_scenario_d1):
    src = g1_scenario_d1
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
    p = _small(
        tmp_path,
        "gain: 2/(2+t)\ndigital: {period: 0.05, delay: 1}\n"
        "noise: {sigma: 0.2, f: 0.1, sigma_edges: [{from: 2, to: 3, sigma: 0.7}]}\n",
    )
    law = from_scenario(p).law
    assert law.digital == Digital(0.05, 1) and law.gain.label == "2/(2+t)"
    assert law.modes[0].sigma.tolist() == [0.2, 0.7, 0.2]  # 1->2, 2->3, 3->1
    assert (law.noise_f == 0.1 * np.eye(1)).all()
    law = from_scenario(p, ExportOptions(period=0.02, gain="1/(1+t)", sigma=0.3, f=0.25)).law
    assert law.digital == Digital(0.02, 1) and law.gain.label == "1/(1+t)"
    assert law.modes[0].sigma.tolist() == [0.3, 0.7, 0.3]
    assert (law.noise_f == 0.25 * np.eye(1)).all()


def test_a_schedule_csv_gain(tmp_path):
    csv = tmp_path / "schedule.csv"
    g = ScheduleGain([0.0, 1.0, 2.0], [1.0, 0.6, 1 / 3], tail="1/(1+t)")
    csv.write_text(g.csv_text())
    law = from_scenario(DEADLINE, ExportOptions(period=0.1, gain=str(csv))).law
    assert law.gain.is_schedule and law.gain.t == (0.0, 1.0, 2.0)


def test_a_switching_scenario(tmp_path):
    """A switching scenario's modes and schedule as its files give them: two 3-agent
    cycles (certified at h = 0.013 in about 1 s; the paper's set, about 5 s, is
    switching_json's below)."""
    _small(tmp_path, "")  # writes cycle.yaml
    (tmp_path / "more.yaml").write_text(
        (tmp_path / "cycle.yaml").read_text() + "  - {from: 1, to: 3, weight: 1}\n"
    )
    (tmp_path / "sw.yaml").write_text(
        "modes: {A: cycle.yaml, B: more.yaml}\nschedule:\n  - {mode: B, duration: 0.02}\n"
        "  - {mode: B, duration: 0.02}\n  - {mode: A, duration: 0.02}\n"
    )
    p = tmp_path / "s.yaml"
    p.write_text("topology: sw.yaml\ntheta: [1]\nT: 5\n")
    law = from_scenario(p, ExportOptions(period=0.013)).law
    assert law.mode_names == ["A", "B"] and [m for m, _ in law.schedule] == ["B", "B", "A"]
    assert [m.n_edges for m in law.modes] == [3, 4]


def test_a_certificate_gives_its_subject(g1_json_d0):
    src = g1_json_d0
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


def test_a_switching_certificate_gives_its_schedule(switching_json):
    doc = json.loads((CERTS / "switching.json").read_text())
    law = switching_json.law
    assert list(law.schedule) == [(s["mode"], s["duration"]) for s in doc["subject"]["schedule"]]
    assert set(law.step_modes(400).tolist()) == {0, 1, 2}


def test_load_source_tells_the_two_apart():
    assert load_source(CERTS / "g1.json", ExportOptions(period=0.1)).kind.startswith("certificate")
    assert is_certificate({"format": "ntc-design/certificate"}) and not is_certificate([])


@pytest.mark.hostile
@pytest.mark.parametrize(
    "extra, kwargs, needles",
    [
        ("", {}, ["period:", "has no digital block"]),
        ("", {"period": 6.0}, ["period: h = 6 is longer than the horizon T = 5"]),
        ("", {"period": 0.1, "delay": -1}, ["delay: must be an integer >= 0"]),
        ("digital: {period: -1}\n", {}, ["s.yaml: digital.period: must be a positive number"]),
        ("gain: '1'\n", {"period": 0.1}, ["no theorem is guaranteed", "nothing exported"]),
        ("", {"period": 0.1, "sigma": -1.0}, ["sigma: expected a finite number >= 0"]),
        (
            "gain: 'exp(-t)'\ndigital: {period: 0.1, loss: 0.1, policy: hold}\n",
            {},
            ["s.yaml: lossy links with the hold policy are not proven", "nothing exported"],
        ),
        (  # (D+1)·Nd past the lossy delay line's SDP: not proven, not exported
            "digital: {period: 0.1, delay: 9, loss: 0.1}\n",
            {},
            ["no theorem is guaranteed", "D = 9", "nothing exported"],
        ),
        ("", {"period": 0.1, "loss": 1.5}, ["loss: a loss probability must be finite"]),
        ("", {"period": 0.1, "loss": 0.1, "policy": "drop"}, ["policy: unknown policy"]),
    ],
)
def test_scenario_refusals(tmp_path, extra, kwargs, needles):
    with pytest.raises(InputError) as err:
        from_scenario(_scenario(tmp_path, extra), ExportOptions(**kwargs))
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
        with pytest.raises(  # said as ntc design says it (#47 item 11), not P L + Lᵀ P
            InputError, match=r"s.yaml: the network has no informed agent .* makes it informed"
        ):
            from_scenario(p, ExportOptions(period=0.1))


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
        load_source(p, ExportOptions(period=0.1))


@pytest.mark.hostile
def test_certificate_option_refusals(tmp_path):
    with pytest.raises(
        InputError, match=r"^period: .*g1.json \(a hurwitz certificate\) has no digital block"
    ):
        from_certificate(CERTS / "g1.json")
    with pytest.raises(InputError, match=r"^gain: c\(t\) = 1 does not satisfy"):
        from_certificate(CERTS / "g1.json", ExportOptions(period=0.1, gain="1"))
    with pytest.raises(InputError, match=r"^f: expected a number"):
        from_certificate(CERTS / "g1.json", ExportOptions(period=0.1, f="x"))  # type: ignore[arg-type]


@pytest.mark.hostile
def test_a_kind_without_dense_modes_is_refused(tmp_path):
    from ntc_design.certify.kinds.robust import robust_certificate
    from ntc_design.certify.robust import robust

    # the kind is what is refused: a 3-agent cycle's robust study (G1's takes about 5 s)
    _small(tmp_path, "")
    des = nd.design(nd.load(tmp_path / "cycle.yaml"), [1], thresholds=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc = json.loads(json.dumps(robust_certificate(robust(des, 0.05))))
    assert doc["kind"] == "robust"
    with pytest.raises(InputError, match=r"kind: a robust certificate cannot be exported"):
        from_certificate(tmp_path / "r.json", ExportOptions(period=0.1), doc=doc)


def _sealed(tmp_path, name="g1.json", top=None, **subject):
    """A certificate with more fields (top-level ``top``, subject ``subject``), its digests
    sealed again as a forger would."""
    from ntc_design.certify.format import finish

    doc = json.loads((CERTS / name).read_text())
    doc["subject"].update(subject)
    doc.update(top or {})
    for key in ("digest", "subject_digest", "versions"):
        doc.pop(key, None)
    p = tmp_path / "sealed.json"
    p.write_text(json.dumps(finish(doc)))
    return p


@pytest.mark.hostile
@pytest.mark.parametrize(
    "name, top, subject, field",
    [
        ("g1_digital.json", {"gain": "50/(1+t)"}, {}, "gain"),
        ("g1_digital.json", {}, {"gain": "50/(1+t)"}, "subject.gain"),
        ("g1_digital.json", {}, {"noise": {"sigma": 0.0}}, "subject.noise"),
        ("g1.json", {}, {"digital": {"period": 0.05, "delay": 1}}, "subject.digital"),
        ("g1.json", {"note": 1}, {}, "note: unknown field"),
        ("switching.json", {}, {"gain": "2/(2+t)"}, "subject.gain: unknown field"),
    ],
)
def test_a_resealed_certificate_with_an_added_field_is_refused(tmp_path, name, top, subject, field):
    # verify refuses it, and so export: nothing is read that verify did not prove
    p = _sealed(tmp_path, name, top, **subject)
    doc = json.loads(p.read_text())
    for call in (
        lambda: verify(doc, "sealed.json"),
        lambda: load_source(p, ExportOptions(period=0.1)),
    ):
        with pytest.raises(InputError) as err:
            call()
        msg = str(err.value)
        assert "\n" not in msg and "sealed.json" in msg and field in msg, msg


def test_a_digital_certificate_exports_what_it_proves():
    doc = json.loads((CERTS / "g1_digital.json").read_text())
    sub = doc["subject"]["digital"]
    src = load_source(CERTS / "g1_digital.json")
    law = src.law
    assert law.digital == Digital(sub["period"], sub["delay"]) == Digital(0.1, 1)
    assert law.gain.label == sub["gain"] == "1/(1+t)"
    assert law.modes[0].sigma.tolist() == [sub["noise"]["sigma"]] * 8
    assert (law.noise_f == sub["noise"]["f"] * np.eye(3)).all()
    assert "sampled protocol proven" in src.notes[0]
    # equal options are fine
    same = load_source(
        CERTS / "g1_digital.json", ExportOptions(period=0.1, delay=1, sigma=0.4, f=0.3)
    )
    assert same.law.digital == law.digital


@pytest.mark.hostile
@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"period": 0.5}, "period: 0.5 differs from the certified value 0.1"),
        ({"delay": 0}, "delay: 0 differs from the certified value 1"),
        ({"sigma": 0.2}, "sigma: 0.2 differs from the certified value 0.4"),
        ({"f": 0.25}, "f: 0.25 differs from the certified value"),
        ({"gain": "50/(1+t)"}, "gain: '50/(1+t)' differs from the certified gain '1/(1+t)'"),
    ],
)
def test_an_option_that_differs_from_the_proof_is_refused(kwargs, needle):
    with pytest.raises(InputError) as err:
        load_source(CERTS / "g1_digital.json", ExportOptions(**kwargs))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(needle) and "g1_digital.json" in msg, msg


@pytest.mark.hostile
@pytest.mark.parametrize("path", ["g1_digital.json", "g1.json", "deadline"])
@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"f": float("inf")}, "f: expected a finite number, got inf"),
        ({"f": float("nan")}, "f: expected a finite number, got nan"),
        ({"sigma": float("nan")}, "sigma: expected a finite number >= 0, got nan"),
        ({"sigma": float("-inf")}, "sigma: expected a finite number >= 0, got -inf"),
    ],
)
def test_a_non_finite_noise_option_is_one_line_on_every_route(path, kwargs, needle):
    # --f inf was an internal error (formatting a missing minimum), exit 1, on all three
    # routes; a NaN σ on a certificate was "nan differs from the certified value"
    src = DEADLINE if path == "deadline" else CERTS / path
    with pytest.raises(InputError) as err:
        load_source(src, ExportOptions(period=0.1, **kwargs))
    msg = str(err.value)
    assert msg == needle, msg


@pytest.mark.hostile
def test_a_differing_f_names_plain_numbers_and_a_certified_matrix(tmp_path):
    with pytest.raises(InputError) as err:
        load_source(CERTS / "g1_digital.json", ExportOptions(f=0.30000000000000004))
    assert str(err.value).startswith(
        "f: 0.30000000000000004 differs from the certified value 0.3 ("
    ), str(err.value)  # not np.float64(0.3)
    # a certified matrix F against a scalar --f: refused naming the matrix (was a ValueError
    # converting the text "a matrix F" to a number, an internal error)
    doc = json.loads((CERTS / "g1_digital.json").read_text())
    f_mat = [[0.3, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.3]]
    doc["subject"]["digital"]["noise"]["f"] = f_mat
    p = _sealed_doc(tmp_path, doc)
    assert verify(json.loads(p.read_text()), "m.json").valid
    with pytest.raises(InputError) as err:
        load_source(p, ExportOptions(f=0.3))
    msg = str(err.value)
    assert msg.startswith(f"f: 0.3 differs from the certified value {f_mat!r} ("), msg


def _sealed_doc(tmp_path, doc):
    from ntc_design.certify.format import finish

    doc = json.loads(json.dumps(doc))
    for key in ("digest", "subject_digest", "versions"):
        doc.pop(key, None)
    p = tmp_path / "m.json"
    p.write_text(json.dumps(finish(doc)))
    return p


def test_a_continuous_certificate_is_certified_sampled_first(g1_json_d0):
    # g1.json proves the continuous protocol only: the sampled one is certified here
    # (load_source reads a certificate with from_certificate: test_load_source_tells_the_two_apart)
    src = g1_json_d0
    assert "the sampled protocol certified here" in src.notes[0]
    # at D = 0 (without the delay line, whose k₀ = 24 the scenario's test asserts)
    assert "for the sampled one (contracting from step k₀ = 4)" in src.notes[1]
    # at h = 0.5 the h = 0.1 proof does not hold; certified anew at h = 0.5, it does
    assert (
        "(contracting from step k₀ = 7)"
        in load_source(CERTS / "g1.json", ExportOptions(period=0.5)).notes[1]
    )


@pytest.mark.hostile
def test_a_continuous_certificate_whose_sampled_protocol_is_unproven_is_refused(monkeypatch):
    # a sampled protocol whose theorems are not guaranteed (here: every sampled verdict
    # turned undetermined) exports nothing, whatever the continuous certificate proves
    import dataclasses
    import types

    import ntc_design.export.source as source

    real = source.certify

    def unproven(*args, **kwargs):
        res = real(*args, **kwargs)
        theorems = tuple(
            types.SimpleNamespace(theorem=t.theorem, sampled=True, guaranteed=None)
            if t.sampled
            else t
            for t in res.theorems
        )
        return dataclasses.replace(res, theorems=theorems)

    monkeypatch.setattr(source, "certify", unproven)
    with pytest.raises(InputError) as err:
        load_source(CERTS / "g1.json", ExportOptions(period=0.5))
    msg = str(err.value)
    assert "\n" not in msg and "no theorem is guaranteed for the sampled protocol" in msg, msg
    assert "h = 0.5" in msg and "nothing exported" in msg


@pytest.mark.hostile
@pytest.mark.parametrize("value", [5e-324, 1e-300])
def test_a_subnormal_sigma_is_refused_up_front(value):
    for call in (
        lambda: from_scenario(DEADLINE, ExportOptions(period=0.1, sigma=value)),
        lambda: load_source(CERTS / "g1.json", ExportOptions(period=0.1, sigma=value)),
    ):
        with pytest.raises(InputError) as err:
            call()
        msg = str(err.value)
        assert msg.startswith("sigma: ") and repr(value) in msg and "\n" not in msg, msg


@pytest.mark.hostile
def test_an_unknown_digital_key_is_refused_as_simulate_does(tmp_path):
    p = _scenario(tmp_path, "digital: {period: 0.1, delya: 1}\n")
    with pytest.raises(InputError) as err:
        from_scenario(p)
    assert str(err.value).startswith(f"{p}: digital.delya: unknown field"), str(err.value)
    with pytest.raises(InputError, match=r"digital.delya: unknown field"):
        from_scenario(p, ExportOptions(period=0.1, delay=1))  # the options do not hide it


@pytest.mark.hostile
def test_a_time_varying_scenario_is_refused():
    with pytest.raises(InputError, match=r"only a fixed topology or a switching set"):
        from_scenario(EXAMPLES / "scenarios" / "g1_tv.yaml", ExportOptions(period=0.1))


def test_the_option_replaces_a_file_period_that_would_be_refused(tmp_path):
    p = _small(tmp_path, "digital: {period: 20, delay: 1}\n")  # longer than T = 5
    with pytest.raises(InputError, match=r"s.yaml: digital.period: h = 20 is longer"):
        from_scenario(p)
    assert from_scenario(p, ExportOptions(period=0.1)).law.digital == Digital(0.1, 1)


def _order(law, m=0):
    ml = law.modes[m]
    return [(law.labels[j], law.labels[i]) for i, j in zip(ml.dst, ml.src, strict=True)]


def test_a_certificate_and_its_scenario_list_the_edges_in_the_file_order(
    tmp_path, g1_scenario_d1, g1_digital_d1, switching_json
):
    top = nd.load(EXAMPLES / "g1.yaml")
    file_order = [(top.labels[j], top.labels[i]) for i, j in top.weights]
    assert file_order[:3] == [(2, 1), (1, 2), (5, 6)]  # not the sorted (2,1), (1,2), (6,2)
    scenario = g1_scenario_d1.law
    shipped = load_source(CERTS / "g1_digital.json").law
    # a certificate issued by this checkout: certify(G1, θ, "1/(1+t)", Digital(0.1, 1)), the
    # session's (tests/support/certificates.py)
    fresh = g1_digital_d1.certificate
    p = tmp_path / "fresh.json"
    p.write_text(json.dumps(fresh))
    issued = load_source(p).law
    assert _order(scenario) == _order(shipped) == _order(issued) == file_order
    assert (scenario.modes[0].weight == issued.modes[0].weight).all()
    # the switching set: each mode in its own file's order
    sw = switching_json.law
    for m, name in enumerate(sw.mode_names):
        t = nd.load(EXAMPLES / f"{name.lower()}.yaml")
        assert _order(sw, m) == [(t.labels[j], t.labels[i]) for i, j in t.weights]


@pytest.mark.slow
def test_a_lossy_scenario_and_its_certificate_export_the_certified_losses(tmp_path):
    import ntc_design.certify as cz
    from ntc_design.io.documents import read_document

    src = from_scenario(_scenario(tmp_path, "digital: {period: 0.1, loss: 0.2, policy: rescale}\n"))
    assert src.law.policy == "rescale" and "digital_loss certificate valid" in src.notes[0]
    assert np.array_equal(src.law.modes[0].keep, np.full(src.law.modes[0].n_edges, 1.0 - 0.2))
    # the certificate's own reading: p_e and the policy; a flag that differs is refused
    res = cz.certify(
        nd.load(EXAMPLES / "g1.yaml"), [1, 2, -1], 0.1, "1/(1+t)", None, noise_sigma=0.4,
        noise_f=0.3, digital=Digital(0.1, 0, 0.2, "skip"),
    )  # fmt: skip
    cert = tmp_path / "loss.json"
    cert.write_text(json.dumps(res.certificate))
    assert read_document(cert)["kind"] == "digital_loss"
    law = from_certificate(cert).law
    assert law.policy == "skip" and np.all(law.modes[0].keep == 1.0 - 0.2)
    assert from_certificate(cert, ExportOptions(loss=0.2, policy="skip")).law.policy == "skip"
    for kw, needle in (
        ({"loss": 0.1}, "loss: 0.1 differs from the certified 0.2"),
        (
            {"policy": "rescale"},
            "policy: 'rescale' differs from the certified policy 'skip'",
        ),
    ):
        with pytest.raises(InputError, match=needle):
            from_certificate(cert, ExportOptions(**kw))
    with pytest.raises(InputError, match="loss: 0.3 differs from the certified protocol"):
        from_certificate(CERTS / "g1_digital.json", ExportOptions(loss=0.3))


def test_the_export_options_are_written_once(g1_scenario_d1):
    """(period, delay, gain, σ, f, loss, policy) is one frozen ExportOptions that every
    reader takes (issue 48: the tuple was written four times)."""
    import dataclasses
    import inspect

    from ntc_design.export.run import export

    assert [f.name for f in dataclasses.fields(ExportOptions)] == [
        "period", "delay", "gain", "sigma", "f", "loss", "policy",
    ]  # fmt: skip
    for fn in (from_scenario, from_certificate, load_source, export):
        names = set(inspect.signature(fn).parameters)
        assert "options" in names and not names & {"period", "delay", "sigma", "f"}, fn
    # the options set over the file's values: the same law as the file's own block
    given = g1_scenario_d1.law
    assert given.digital == Digital(0.1, 1)
