"""Tests of :mod:`ntc_design.certify.theorems`."""

import json

import pytest

import ntc_design as nd
from ntc_design.certify import certify
from ntc_design.model.paper import THETA
from tests.cli_helpers import run_cli
from tests.conftest import EXAMPLES, ROOT
from tests.support.rows import _text


def test_theorem_verdict_g1_and_switching(examples):
    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="1/(1+t)")
    assert [(t.theorem, t.guaranteed) for t in r.theorems] == [(1, True), (2, True)]
    assert r.proven
    r = certify(nd.load(examples / "switching.yaml"), THETA, gain="1/(1+t)")
    assert [(t.theorem, t.guaranteed) for t in r.theorems] == [(3, True), (4, True)]
    a2 = [p for p in r.theorems[0].premises if p.name.startswith("Assumption 2")][0]
    assert (
        "G3" in a2.detail
    )  # G3 breaks Assumption 2 as stated; the proof needs only L_B + L_Bᵀ ≻ 0
    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="(1+t)^(-1/3)")
    assert r.theorems[0].guaranteed is True and r.theorems[1].guaranteed is False
    assert [p.name for p in r.theorems[1].failing] == ["∫₀^∞ c² dt < ∞"]
    # the JSON form keeps the keys the README shows
    doc = r.to_dict()["theorems"][1]
    assert doc["guaranteed"] is False and doc["failing"][0]["premise"] == "∫₀^∞ c² dt < ∞"


def test_verdict_names_failing_symmetric_premise_and_by_how_much(examples):
    sw = nd.load(examples / "switching.yaml")
    r = certify(sw, THETA, gain="1/(1+t)", delta=0.5)
    th3 = r.theorems[0]
    assert th3.guaranteed is False and not r.proven and not r.verification.valid
    failing = {p.name: p.detail for p in th3.failing}
    assert "L_B(G1) + L_B(G1)ᵀ ≻ 0" in failing
    assert "δ_S = 3.11769" in failing["L_B(G1) + L_B(G1)ᵀ ≻ 0"]
    assert "fails by" in failing["L_B(G1) + L_B(G1)ᵀ ≻ 0"]


def test_verdicts_read_typed_claims_not_names(examples):
    """Renaming every check leaves the verdict unchanged: theorems.py keys on the claim's
    property, not on its text."""
    import dataclasses

    from ntc_design.certify.theorems import fixed_verdicts

    r = certify(nd.load(examples / "g1.yaml"), THETA, gain="1/(1+t)")
    renamed = dataclasses.replace(
        r.verification,
        checks=tuple(
            dataclasses.replace(c, name=f"check {k}") for k, c in enumerate(r.verification.checks)
        ),
    )
    th = fixed_verdicts(r.design, renamed, r.gain)
    assert [t.guaranteed for t in th] == [True, True]
    # and a failing Hurwitz claim is seen whatever it is called
    broken = dataclasses.replace(
        renamed,
        checks=tuple(
            dataclasses.replace(c, ok=False)
            if c.claim is not None
            and c.claim.kind.value == "lyapunov"
            and c.claim.prop.value == "hurwitz"
            else c
            for c in renamed.checks
        ),
    )
    assert [t.guaranteed for t in fixed_verdicts(r.design, broken, r.gain)] == [False, False]


@pytest.mark.parametrize(
    "file, theorems",
    [("switching.yaml", ("Theorem 3", "Theorem 4")), ("g3.yaml", ("Theorem 1", "Theorem 2"))],
)
def test_terminal_verdict_names_a_replaced_assumption_2(file, theorems, capsys, monkeypatch):
    """G3 fails Assumption 2; the certified −L_B Hurwitz (or L_B + L_Bᵀ ≻ 0) replaces it, and
    the terminal says so under each theorem, as --json does."""
    from tests.cli_helpers import run_cli

    args = ["certify", ROOT / "examples" / file, "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    for th in theorems:
        block = out.split(th)[1].split("Theorem")[0]
        assert "guaranteed" in block and "replaced: Assumption 2" in block
        assert "in its place:" in block
    code, out, _ = run_cli([*args, "--json"], capsys, monkeypatch)
    doc = json.loads(out)
    for th in doc["theorems"]:
        (rep,) = th["replaced"]
        assert rep["premise"].startswith("Assumption 2") and rep["holds"] is True
        assert rep["replaced_by"] and "fails" in rep["detail"]


def test_the_terminal_verdict_names_a_failing_assumption(capsys, monkeypatch):
    args = ["certify", EXAMPLES / "switching.yaml", "--theta", "1,2,-1", "--gain", "1/(1+t)"]
    code, out, _ = run_cli(args, capsys, monkeypatch)
    assert code == 0
    for th in ("Theorem 3 (mean square): guaranteed", "Theorem 4 (almost sure): guaranteed"):
        block = out.split(th)[1].split("Theorem")[0]
        assert "replaced: Assumption 2" in block and "fails in mode(s) G3" in block
    res = certify(nd.load(EXAMPLES / "switching.yaml"), [1, 2, -1], gain="1/(1+t)")
    page = _text(res._repr_html_())
    assert "replaced: Assumption 2" in page  # the notebook and the report say it too


def test_each_violation_is_said_once_with_its_fix(tmp_path):
    """With the sampled analogues there are four verdicts that name Assumption 2; each
    violation (and each fix) is said once, under them, not in every verdict."""
    import warnings

    from ntc_design.protocol.digital import Digital

    p = tmp_path / "coop.yaml"
    p.write_text(
        "dim: 2\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: {diag: [1, 1]}}\n"
        "  - {from: 2, to: 3, weight: {diag: [1, 2]}}\n"
        "  - {from: 3, to: 1, weight: {diag: [2, 1]}}\n",
        encoding="utf-8",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = certify(nd.load(p), [1, 2], gain="1/(1+t)", digital=Digital(0.1, 0))
    assert len(r.theorems) == 4
    text = "\n".join(t.text() for t in r.tables())
    for v in r.design.base.decomposition.violations:
        said = f"agent {v.agent + 1}: {v.reason}"
        assert text.count(said) == 1, said
    assert text.count("not in-degree-dominated and has no antagonistic in-edge") == 2  # 2, 3
    fixes = [ln for ln in r.theorems_table().notes if ln.startswith("fix (")]
    assert len(fixes) == 2 and fixes[1].startswith("fix (agents 2, 3): give the agent")
    for th in r.theorems:
        (a2,) = [q for q in th.failing if q.name.startswith("Assumption 2")]
        assert a2.detail.startswith("fails for agents 1, 2, 3")
