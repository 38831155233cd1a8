"""Tests of :mod:`ntc_design.tune.evidence`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.gain.schedule import ScheduleGain
from ntc_design.model import TimeVaryingTopology, Topology
from ntc_design.simulate import NoiseModel, SimulationSpec
from ntc_design.tune import evidence
from ntc_design.tune.evidence import IMPLICIT, certify_tuned, checked_spec, stable_stepping
from ntc_design.tune.family import PowerGain
from tests.conftest import EXAMPLES

# pair_topology (tests/support/tune.py): two agents, d = 1, both edges antagonistic (−1),
# both informed with B_i = 1: L_B = [[1 + δ, 1], [1, 1 + δ]], eigenvalues 2 + δ and δ.
DT = 0.1


@pytest.fixture(scope="module")
def spec():
    # additive noise only (f = 0): the explicit guard is the drift's 2·Re λ/|λ|²
    return SimulationSpec.build(
        [1.0], noise=NoiseModel(1.0, 0.0), initial=[3.0, -1.0], T=1.0, dt=DT, paths=4, workers=1
    )


def l_b(delta: float) -> np.ndarray:
    return np.array([[1.0 + delta, 1.0], [1.0, 1.0 + delta]])


def explicit_limit(delta: float) -> float:
    """The largest stable c·h of explicit Euler–Maruyama for a real spectrum: 2/λ_max."""
    return 2.0 / np.linalg.eigvalsh(l_b(delta)).max()


@pytest.fixture(scope="module")
def delta0(pair_topology):
    return nd.design(pair_topology, [1.0]).delta  # Lemma 1's δ for the spec's margin


# -- checked_spec ---------------------------------------------------------------------------


def test_checked_spec_keeps_a_spec_below_the_explicit_limit(pair_topology, spec, delta0):
    a = float(0.9 * explicit_limit(delta0) / DT)  # c(0)·h at 90 % of the limit
    s = spec.replace(gain=f"{a!r}/(1+t)")
    with pytest.warns(UserWarning, match="within a factor 1.11 of instability"):
        got, why = checked_spec(pair_topology, s)
    assert got is s and why is None


def test_checked_spec_switches_to_drift_implicit_past_the_explicit_limit(
    pair_topology, spec, delta0
):
    limit = explicit_limit(delta0)
    a = float(1.1 * limit / DT)
    s = spec.replace(gain=f"{a!r}/(1+t)")
    got, why = checked_spec(pair_topology, s)
    assert (got.stepping.kind, got.stepping.scheme) == ("intrinsic", "implicit")
    assert got.stepping.dt == DT
    # only the stepping changed
    assert (got.T, got.gain, got.mc, got.method) == (s.T, s.gain, s.mc, s.method)
    assert why.startswith("dt: ") and "unstable" in why
    assert f"{limit:.4g}" in why  # the refusal quotes the independent limit 2/λ_max


def test_checked_spec_on_a_gpu_falls_back_to_the_cpu_for_the_implicit_scheme(
    pair_topology, spec, delta0
):
    a = float(1.1 * explicit_limit(delta0) / DT)
    s = spec.replace(gain=f"{a!r}/(1+t)").replace(mc=spec.mc.__class__(paths=4, device="gpu"))
    got, why = checked_spec(pair_topology, s)  # the explicit probe runs on the CPU: no GPU
    assert got.stepping.scheme == "implicit" and got.mc.device == "cpu"
    assert got.mc.paths == 4 and "unstable" in why


def test_checked_spec_reraises_an_error_that_is_not_the_step_guard(pair_topology):
    bad = SimulationSpec.build([1.0, 2.0], T=1.0, dt=DT, paths=2, workers=1)  # d = 2 ≠ 1
    with pytest.raises(InputError, match=r"^theta: expected 1 numbers"):
        checked_spec(pair_topology, bad)


# -- stable_stepping ------------------------------------------------------------------------


def test_stable_stepping_needs_nothing_for_a_stable_tuned_gain(pair_topology, spec, delta0):
    notes = []
    tuned = PowerGain(0.5 * explicit_limit(delta0) / DT, 1.0, 1.0)
    assert stable_stepping(pair_topology, spec, tuned, None, 1.0, notes) == {}
    assert notes == []


def test_stable_stepping_asks_for_the_implicit_scheme_with_a_note(pair_topology, spec, delta0):
    notes = []
    tuned = PowerGain(1.5 * explicit_limit(delta0) / DT, 1.0, 1.0)
    got = stable_stepping(pair_topology, spec, tuned, None, 1.0, notes)
    assert got == {"stepping": "intrinsic", "scheme": "implicit"}
    got["scheme"] = "changed"
    assert IMPLICIT["scheme"] == "implicit"  # a copy: the module's constant is untouched
    assert len(notes) == 1
    note = notes[0]
    assert note.startswith("the scenario's explicit Euler–Maruyama step is unstable")
    assert note.endswith("tuned.yaml uses the drift-implicit scheme")
    # the refusal's first clause only, without its "dt: " field prefix
    assert "(Euler–Maruyama is unstable" in note and "use dt <" not in note


def test_stable_stepping_uses_the_tuned_delta(pair_topology, spec, delta0):
    """A gain stable at Lemma 1's δ is unstable at a larger tuned δ (λ_max = 2 + δ)."""
    big = 5.0
    assert explicit_limit(big) < explicit_limit(delta0)
    # c(0)·h at 45 % of the limit at Lemma 1's δ (no warning), past it at δ = 5
    a = 0.45 * explicit_limit(delta0) / DT
    assert a * DT > explicit_limit(big)
    tuned = PowerGain(a, 1.0, 1.0)
    assert stable_stepping(pair_topology, spec, tuned, None, 1.0, []) == {}
    assert stable_stepping(pair_topology, spec, tuned, big, 1.0, []) == IMPLICIT


def test_stable_stepping_checks_the_written_scenario(pair_topology, spec, monkeypatch):
    """The probe runs T = horizon, the tuned gain and δ, Monte Carlo only."""
    seen = []

    def record(top, s):
        seen.append(s)
        return s, None

    monkeypatch.setattr(evidence, "checked_spec", record)
    tuned = PowerGain(2.0, 3.0, 0.75)
    stable_stepping(pair_topology, spec.replace(delta=0.4), tuned, None, 7.5, [])
    stable_stepping(pair_topology, spec, tuned, 1.25, 7.5, [])
    assert [(s.T, s.gain, s.delta, s.method) for s in seen] == [
        (7.5, tuned, 0.4, "mc"),  # δ None: the scenario's
        (7.5, tuned, 1.25, "mc"),
    ]


def test_stable_stepping_notes_a_scenario_that_cannot_run(pair_topology):
    notes = []
    bad = SimulationSpec.build([1.0, 2.0], T=1.0, dt=DT, paths=2, workers=1)
    assert stable_stepping(pair_topology, bad, PowerGain(1.0, 1.0, 1.0), None, 1.0, notes) == {}
    assert notes == ["the tuned scenario cannot be simulated as written: theta: expected 1 "
                     "numbers (the state dimension d), got 2"]  # fmt: skip


# -- certify_tuned --------------------------------------------------------------------------


def test_certify_tuned_certifies_the_power_gain_at_the_tuned_delta(pair_topology, spec):
    notes = []
    res = certify_tuned(pair_topology, spec, PowerGain(2.0, 1.0, 1.0), 0.7, notes)
    assert notes == [] and res.verification.valid
    assert res.design.delta == 0.7
    # the decay-rate bound is min Re λ(L_B) = δ for this network
    bound = np.linalg.eigvalsh(l_b(0.7)).min()
    assert res.certificate["results"]["eig_bound"] == pytest.approx(bound, rel=1e-9)
    assert res.gain.expression == "2/(1 + t)"  # the tuned gain's text


def test_certify_tuned_stores_a_schedule_in_the_certificate(pair_topology, spec, delta0):
    sched = ScheduleGain([0.0, 0.5, 1.0], [2.0, 1.0, 0.5], tail="1/(1+t)")
    res = certify_tuned(pair_topology, spec, sched, None, [])
    assert res.design.delta == pytest.approx(delta0)  # δ None: the scenario's
    assert res.certificate["gain"] == {
        "t": [0.0, 0.5, 1.0], "c": [2.0, 1.0, 0.5], "interpolation": "linear", "tail": "1/(1+t)"
    }  # fmt: skip


def test_certify_tuned_has_no_certificate_for_functions_of_t(spec):
    tv = TimeVaryingTopology((1, 2), 1, {(1, 2): lambda t: np.array([[1.0]])})
    notes = []
    assert certify_tuned(tv, spec, PowerGain(1.0, 1.0, 1.0), None, notes) is None
    assert notes == ["no certificate: a topology given as Python functions of t has none"]


def test_certify_tuned_needs_a_linear_f_for_expressions_of_t():
    tv = nd.load(EXAMPLES / "g1_tv.yaml")
    sp = SimulationSpec.build([1.0, 2.0, -1.0], noise=NoiseModel(0.4, lambda x: 0.3 * x))
    notes = []
    assert certify_tuned(tv, sp, PowerGain(1.0, 1.0, 1.0), None, notes) is None
    assert notes == ["no certificate: a time-varying certificate needs a linear f's bound"]


@pytest.mark.parametrize(
    "f, bound",
    [
        (0.3, 0.3),
        (-0.3, 0.3),
        # ‖F‖₂ of [[1, 2], [0, 2]]: sqrt of the largest eigenvalue of FᵀF = [[1, 2], [2, 8]]
        (np.array([[1.0, 2.0], [0.0, 2.0]]), np.sqrt((9 + np.sqrt(65)) / 2)),
        (lambda x: 0.3 * x, 0.0),  # a fixed topology's certificate does not use f
    ],
)
def test_certify_tuned_passes_the_noise_bound_sigma_and_delta(f, bound, monkeypatch):
    calls = []
    top2 = Topology.from_edges(2, 2, [(2, 1, -np.eye(2)), (1, 2, -np.eye(2))])  # d = 2, as F

    def record(top, theta, margin, **kw):
        calls.append((top, tuple(theta), margin, kw))
        return "certified"

    monkeypatch.setattr(evidence, "certify", record)
    sp = SimulationSpec.build([1.0, 2.0], noise=NoiseModel(0.25, f), margin=0.2, delta=0.9)
    assert certify_tuned(top2, sp, PowerGain(1.5, 2.0, 0.6), None, []) == "certified"
    ((top, theta, margin, kw),) = calls
    assert top is top2 and theta == (1.0, 2.0) and margin == 0.2
    assert kw["gain"] == "1.5*(2 + t)^(-0.6)" and kw["delta"] == 0.9
    assert kw["noise_sigma"] == 0.25
    assert kw["noise_f"] == pytest.approx(bound, rel=1e-12)


def test_certify_tuned_turns_a_refusal_into_a_note(pair_topology):
    notes = []
    sp = SimulationSpec.build([1.0, 2.0])  # θ of dimension 2 for a d = 1 network
    assert certify_tuned(pair_topology, sp, PowerGain(1.0, 1.0, 1.0), None, notes) is None
    assert notes == ["no certificate: theta: expected 1 numbers (the state dimension d), got 2"]


def test_the_step_search_evaluates_the_guard_at_most_twice_and_runs_no_path(
    pair_topology, spec, delta0, monkeypatch
):
    # the step for the tuned gain is derived from the spectra (one guard per scheme), not
    # from a Monte Carlo probe: counted by spying on the guard and the simulator
    from ntc_design.simulate import driver, steps

    guards, runs = [], []
    real_guard = driver.check_step_size
    monkeypatch.setattr(
        driver, "check_step_size", lambda *a, **k: guards.append(a[3]) or real_guard(*a, **k)
    )
    monkeypatch.setattr(evidence, "simulate", lambda *a, **k: runs.append(a) or None)
    monkeypatch.setattr(steps, "run_monte_carlo", lambda *a, **k: runs.append(a) or None)
    stable = PowerGain(0.5 * explicit_limit(delta0) / DT, 1.0, 1.0)
    assert stable_stepping(pair_topology, spec, stable, None, 1.0, []) == {}
    assert guards == ["explicit"] and runs == []
    unstable = PowerGain(1.5 * explicit_limit(delta0) / DT, 1.0, 1.0)
    assert stable_stepping(pair_topology, spec, unstable, None, 1.0, []) == IMPLICIT
    assert guards == ["explicit", "explicit", "implicit"] and runs == []


def test_proven_text_rounds_the_bound_up():
    from types import SimpleNamespace

    from ntc_design.tune.evidence import proven_text

    def cert(bound, valid=True):
        doc = {"results": {"deadline": {"ms_error_bound": bound}}}
        return SimpleNamespace(verification=SimpleNamespace(valid=valid), certificate=doc)

    assert proven_text(cert(0.83251234)) == ", proven ≤ 0.832513"
    assert proven_text(cert(15.816133)) == ", proven ≤ 15.8162"
    assert proven_text(cert(1.0, valid=False)) == "" and proven_text(None) == ""


def test_certify_tuned_proves_the_deadline_on_the_scenarios_lossy_links():
    from ntc_design.certify import verify
    from ntc_design.protocol.digital import Digital
    from ntc_design.simulate.scenario import load_scenario

    top, spec, _ = load_scenario(EXAMPLES / "scenarios" / "g1_deadline.yaml")
    lossy = spec.replace(digital=Digital(0.1, 0, 0.3, "rescale"))
    notes: list[str] = []
    res = certify_tuned(top, lossy, PowerGain(1.0, 1.0, 1.0), None, notes, deadline=0.45)
    assert notes == [] and res.certificate["kind"] == "digital_loss"
    figures = res.certificate["results"]["deadline"]
    assert figures["loss"] == {"policy": "rescale", "p_max": 0.3}
    assert verify(res.certificate).valid  # the figures are those of the lossy subject
