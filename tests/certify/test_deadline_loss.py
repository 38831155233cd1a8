"""Tests of :mod:`ntc_design.certify.deadline_loss`: the proven figures at the deadline on
lossy links against an exact enumeration of every arrival pattern (tests/simulate/
test_loss.py, x coordinates, the weights read from the topology) and against the float
recursion of simulate/loss.py with a partial last step; verify re-derives them and rejects
forged fields; bad input is refused in one line."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from ntc_design.certify import certify, verify
from ntc_design.certify.deadline_loss import (
    check_loss_work,
    loss_section,
    loss_width,
    read_loss_section,
)
from ntc_design.certify.deadline_subject import add_deadline, section_bound
from ntc_design.certify.format import finish
from ntc_design.errors import InputError
from ntc_design.protocol import design
from ntc_design.protocol.digital import Digital
from ntc_design.rigorous.exact import Dyadic
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.digital import digital_grid
from ntc_design.simulate.loss import loss_moments
from ntc_design.simulate.system import mode_system
from tests.cli_helpers import assert_input_error, run_cli
from tests.simulate.test_loss import enumerate_moments, tiny  # noqa: F401 (a fixture)

POLICIES = ("skip", "rescale", "hold")
X0_G1 = np.linspace(-3.0, 3.0, 21)


def _modes(top, des):
    lap = des.grounded_laplacian()
    return {"m": (top, lap, np.zeros_like(lap), Dyadic.of(lap))}


def _section(t_end, h, delay, x0, sigma, f, loss):
    return {
        "T": t_end,
        "period": h,
        "delay": delay,
        "gain": "1/(1+t)",
        "noise": {"sigma": sigma, "f": f, "sigma_edges": []},
        "initial": {"x0": [float(v) for v in x0]},
        "loss": loss,
    }


def _tiny_loss(top, losses, policy):
    lab = [str(x) for x in top.labels]
    return {
        "policy": policy,
        "edges": [
            {"from": lab[j], "to": lab[i], "p": p}
            for (i, j), p in zip(top.edges, losses, strict=True)
        ],
    }


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("delay", [0, 1])
def test_bound_encloses_the_enumeration_of_every_arrival_pattern(tiny, policy, delay):  # noqa: F811
    top, des, _, theta, noise = tiny
    x0 = np.array([0.5, -1.0, 2.0, 0.3, -1.5, 1.0])
    loss, h, k_steps = [0.3, 0.5, 0.1], 0.2, 3
    th = np.tile(theta, 3)
    values = [float(np.sum((x0 - th) ** 2))]
    for k in range(1, k_steps + 1):
        m, zz = enumerate_moments(top, des, noise, x0, h, delay, k, loss, policy)
        values.append(float(np.trace(zz) - 2 * th @ m + th @ th))
    sec = _section(h * k_steps, h, delay, x0, noise[0], noise[1], _tiny_loss(top, loss, policy))
    b = section_bound(_modes(top, des), None, sec, theta)
    assert b.loss == {"policy": policy, "p_max": 0.5}
    # a bound, and the exact figure to the balls' radius (the enumeration's rounding)
    assert values[-1] * (1 - 1e-12) <= b.ms_error_bound <= values[-1] * (1 + 1e-9)
    # between samples E‖e‖² is a convex quadratic: the peak is a sample's
    assert max(values) * (1 - 1e-12) <= b.peak_bound <= max(values) * (1 + 1e-9)
    assert b.steps == k_steps and b.ms_error == pytest.approx(values[-1], rel=1e-10)


@pytest.fixture(scope="module")
def g1_parts(g1, theta):
    des = design(g1, theta, 0.1)
    return g1, des, mode_system(des, NoiseModel(sigma=0.4, f=0.3))


@pytest.mark.parametrize("policy", POLICIES)
def test_partial_step_bound_against_the_float_recursion(g1_parts, theta, policy):
    top, des, s = g1_parts
    t_end, h, delay, p = 0.45, 0.1, 1, 0.3
    grid, _ = digital_grid(Digital(h, delay), t_end, np.array([t_end]))
    eps0 = X0_G1 - np.tile(theta, 7)
    lm = loss_moments(s, grid, lambda t: 1 / (1 + t), eps0, theta, delay, np.full(8, p), policy)
    exact_t = float(lm.moments.ms_error[-1].sum())
    exact_peak = max(lm.peak, exact_t)
    sec = _section(t_end, h, delay, X0_G1, 0.4, 0.3, loss_section(top, p, policy))
    b = section_bound(_modes(top, des), None, sec, theta)
    # the float figure carries its own rounding: at or below the bound to 1e-12, and the
    # bound within the 5 % a stated figure may exceed the proven one (far within, in fact)
    assert exact_t * (1 - 1e-12) <= b.ms_error_bound <= 1.05 * exact_t
    assert b.ms_error_bound == pytest.approx(exact_t, rel=1e-9)
    assert exact_peak * (1 - 1e-12) <= b.peak_bound <= exact_peak * (1 + 1e-9)
    assert b.steps == 4 and 0 <= b.peak_time <= t_end


def test_no_loss_is_no_loss_section_and_the_same_figures(g1_parts, theta):
    top, des, _ = g1_parts
    assert loss_section(top, 0.0, "hold") is None
    # every p = 0 under hold: the lossless figures (the lossless recursion of deadline.py)
    zero = {"policy": "hold", "edges": [{"from": "1", "to": "2", "p": 0.0}]}
    sec = _section(0.45, 0.1, 1, X0_G1, 0.4, 0.3, zero)
    plain = {k: v for k, v in sec.items() if k != "loss"}
    lossy = section_bound(_modes(top, des), None, sec, theta)
    lossless = section_bound(_modes(top, des), None, plain, theta)
    assert lossy.ms_error == pytest.approx(lossless.ms_error, rel=1e-12)
    assert lossy.peak == pytest.approx(lossless.peak, rel=1e-12)


def test_width_and_the_section_of_a_uniform_loss(g1):
    assert loss_width(21, 1, 8, 3, "hold") == 2 * 21 + 1 + 24
    assert loss_width(21, 0, 8, 3, "skip") == 22
    sec = loss_section(g1, 0.1, "rescale")
    assert sec["policy"] == "rescale" and len(sec["edges"]) == 8
    assert {e["p"] for e in sec["edges"]} == {0.1}
    read = read_loss_section(sec, g1, "loss")
    assert read.p_max == 0.1 and set(read.losses) == set(g1.edges)


# -- the certificate --------------------------------------------------------------------


@pytest.fixture(scope="module")
def loss_cert(g1, theta):
    res = certify(g1, theta, 0.1, "1/(1+t)", digital=Digital(0.1, 0, 0.1, "skip"))
    doc = copy.deepcopy(res.certificate)
    section = _section(0.45, 0.1, 0, X0_G1, 0.4, 0.3, loss_section(g1, 0.1, "skip"))
    bound = add_deadline(doc, section)
    return json.loads(json.dumps(doc)), bound


def _resealed(doc):
    doc.pop("digest", None)
    return finish(doc, doc.get("verification_method"))


def test_the_honest_lossy_certificate_verifies(loss_cert):
    doc, bound = loss_cert
    assert doc["kind"] == "digital_loss"
    assert doc["results"]["deadline"]["loss"] == {"policy": "skip", "p_max": 0.1}
    ver = verify(copy.deepcopy(doc))
    assert ver.valid
    names = [c.name for c in ver.checks if c.ok]
    assert any(n.startswith("deadline T = 0.45") for n in names)
    assert any(n.startswith("deadline: the lossy links of subject.digital") for n in names)
    assert doc["results"]["deadline"]["ms_error_bound"] == bound.ms_error_bound


def _set_p(doc, p):
    for e in doc["subject"]["deadline"]["loss"]["edges"]:
        e["p"] = p


def _both_p(doc, p):
    _set_p(doc, p)
    for e in doc["subject"]["digital"]["loss"]["edges"]:
        e["p"] = p


@pytest.mark.hostile
@pytest.mark.parametrize(
    "forge",
    [
        lambda d: d["results"]["deadline"].update(
            ms_error_bound=0.99 * d["results"]["deadline"]["ms_error_bound"]
        ),
        lambda d: d["results"]["deadline"].update(
            peak_bound=0.99 * d["results"]["deadline"]["peak_bound"]
        ),
        lambda d: _set_p(d, 0.05),  # the deadline's p, not the subject's
        lambda d: _both_p(d, 0.3),  # both: the bound is not this loss's
        lambda d: d["subject"]["deadline"]["loss"].update(policy="rescale"),
        lambda d: d["subject"]["deadline"].pop("loss"),
        lambda d: d["results"]["deadline"]["loss"].update(p_max=0.05),
        lambda d: d["results"]["deadline"]["loss"].update(policy="hold"),
        lambda d: d["subject"]["deadline"].update(T=0.55),
    ],
    ids=["bound", "peak", "deadline-p", "both-p", "policy", "no-loss", "p_max", "r-policy", "T"],
)
def test_forged_lossy_deadline_fields_are_rejected(loss_cert, forge):
    doc = copy.deepcopy(loss_cert[0])
    forge(doc)
    assert not verify(_resealed(doc)).valid


# -- bad input --------------------------------------------------------------------------


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("edit", "needle"),
    [
        (lambda s: s["loss"]["edges"][0].update(p=1.0), "loss.edges[0].p"),
        (lambda s: s["loss"]["edges"][0].update(p=float("nan")), "loss.edges[0].p"),
        (lambda s: s["loss"].update(policy="drop"), "loss.policy: unknown policy"),
        (lambda s: s["loss"]["edges"][0].update(to="7"), "loss.edges[0]: no edge"),
        (lambda s: s["loss"]["edges"].append(dict(s["loss"]["edges"][0])), "listed twice"),
        (lambda s: s.update(loss=[0.1]), "loss: expected {policy, edges}"),
        (lambda s: s.update(period=None), "loss: lossy links need a period"),
    ],
)
def test_a_malformed_loss_section_is_refused_naming_it(g1_parts, theta, edit, needle):
    top, des, _ = g1_parts
    sec = _section(0.45, 0.1, 0, X0_G1, 0.4, 0.3, loss_section(top, 0.1, "skip"))
    edit(sec)
    with pytest.raises(InputError, match="deadline") as err:
        section_bound(_modes(top, des), None, sec, theta)
    assert needle in str(err.value) and "\n" not in str(err.value)


@pytest.mark.hostile
def test_the_size_guard_refuses_before_the_recursion(monkeypatch):
    monkeypatch.setenv("NTC_AVAILABLE_MEMORY", "64M")
    with pytest.raises(InputError, match=r"^deadline: the proven moments with lossy links hold"):
        check_loss_work(2000, 8000, 3, 10.0, 0.1, 1, "hold")
    with pytest.raises(InputError, match=r"^deadline: the proven moments on lossy links take"):
        check_loss_work(21, 8, 3, 10.0, 1e-5, 1, "hold")
    check_loss_work(21, 8, 3, 10.0, 0.1, 1, "hold")  # G1: accepted


SCEN = "scenarios/g1_deadline.yaml"


@pytest.mark.hostile
@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--period", "0.1", "--loss", "1.5"], "--loss: "),
        (["--period", "0.1", "--loss", "-0.1"], "--loss: "),
        (["--period", "0.1", "--loss", "nan"], "--loss"),
        (["--period", "0.1", "--loss", "0.1", "--loss-policy", "drop"], "--loss-policy"),
        (["--loss", "0.1"], "--loss: needs --period"),
        (["--period", "1e-5", "--loss", "0.1", "--loss-policy", "hold"], "--deadline:"),
    ],
)
def test_certify_deadline_refuses_bad_loss_flags(
    examples, tmp_path, capsys, monkeypatch, extra, needle
):
    out = tmp_path / "c.json"
    args = ["certify", examples / SCEN, "--deadline", *extra, "--out", out]
    assert_input_error(args, capsys, monkeypatch, needle)
    assert not out.exists()


@pytest.mark.hostile
def test_certify_deadline_refuses_loss_on_a_switching_set(examples, capsys, monkeypatch):
    args = ["certify", examples / "scenarios" / "switching.yaml", "--period", "0.01"]
    args += ["--loss", "0.1", "--deadline", "2"]
    assert_input_error(args, capsys, monkeypatch, "--loss: lossy links are modelled on one")


def test_certify_deadline_on_lossy_links_states_the_loss(examples, tmp_path, capsys, monkeypatch):
    out = tmp_path / "c.json"
    args = ["certify", examples / SCEN, "--period", "0.1", "--loss", "0.3"]
    args += ["--loss-policy", "rescale", "--deadline", "0.45", "--out", out, "--json"]
    code, text, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    figures = json.loads(text)["deadline"]
    assert figures["loss"] == {"policy": "rescale", "p_max": 0.3}
    assert figures["T"] == 0.45 and figures["peak_bound"] >= figures["ms_error_bound"] > 0
    cert = json.loads(out.read_text())
    assert cert["subject"]["deadline"]["loss"]["policy"] == "rescale"
    assert verify(cert).valid
    code, text, _ = run_cli(args[:-1], capsys, monkeypatch)  # the terminal's rows
    line = next(ln for ln in text.splitlines() if ln.startswith("proven at the deadline"))
    assert line.endswith("on lossy links (p_e <= 0.3, rescale)")
    beside = next(ln for ln in text.splitlines() if ln.startswith("proven at T = 0.45"))
    assert "sampled on lossy links (p_e <= 0.3, rescale)" in beside
