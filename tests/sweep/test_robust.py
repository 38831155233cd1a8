"""Tests of :mod:`ntc_design.sweep.robust`."""

import dataclasses
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.generate import random_network
from ntc_design.model.paper import THETA
from ntc_design.protocol import design_topology
from ntc_design.simulate import SimulationSpec
from ntc_design.simulate.robust_sampling import RobustSampling
from ntc_design.sweep.robust import (
    ROW_KEYS,
    RobustStudy,
    draw_realisation,
    robust_study,
    study_sentence,
    within_brackets,
)
from tests.support.robust import _scenario, features, in_set


@pytest.mark.slow  # the full suite runs it; the fast lane stays under 3 min
def test_the_study_draws_in_the_set_and_respects_the_brackets(tmp_path):
    from ntc_design.simulate.scenario import load_scenario
    from ntc_design.sweep.robust import draw_realisation, robust_study, within_brackets

    sc = _scenario(tmp_path, "robust: {realizations: 4, radius: 0.1, seed: 3}")
    top, spec, _ = load_scenario(sc)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        st = robust_study(top, spec)
    assert len(st.rows) == 4 and within_brackets(st) == {"decay": True, "offset": True}
    des = nd.design(top, THETA, thresholds=False)
    for r in st.rows:
        real = draw_realisation(top, np.full(8, 0.1), 3, r["realization"])
        assert in_set(des, dict(real.weights), 0.1)
        a, o = features(des, dict(real.weights))  # the independent rebuild
        assert r["decay_rate"] == pytest.approx(a, rel=1e-9)
        assert r["offset"] == pytest.approx(o, rel=1e-9)
    # the draws depend on (seed, index) only: the same realisation 2 on its own
    again = draw_realisation(top, np.full(8, 0.1), 3, 2)
    assert all(
        np.array_equal(again.weights[k], draw_realisation(top, np.full(8, 0.1), 3, 2).weights[k])
        for k in again.weights
    )
    assert st.csv().count("\n") == 5 and st.csv().startswith("realization,decay_rate,offset")


THETA2 = [1.0, -0.5]


@pytest.fixture(scope="module")
def small():
    top = random_network(4, 2, seed=5)
    spec = SimulationSpec.build(
        THETA2, T=0.2, dt=0.01, paths=4, seed=1, method="mc", workers=1, save_every=0.1,
        robust=RobustSampling(realizations=3, radius=0.05, seed=7),
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return top, spec, robust_study(top, spec)


def test_a_small_study_matches_an_independent_rebuild(small):
    top, spec, st = small
    nominal = design_topology(top, spec.theta, spec.margin, None, thresholds=False)
    radii = np.array(st.radii)
    assert st.radius == pytest.approx(0.05) and np.allclose(radii, 0.05)
    assert [r["realization"] for r in st.rows] == [0, 1, 2]
    for r in st.rows:
        real = draw_realisation(top, radii, 7, r["realization"])
        assert in_set(nominal, dict(real.weights), 0.05)  # (1∓ρ)|A| ⪯ |A'| in the Loewner order
        a, o = features(nominal, dict(real.weights))  # L_B(A') rebuilt independently
        assert r["decay_rate"] == pytest.approx(a, rel=1e-9)
        assert r["offset"] == pytest.approx(o, rel=1e-9)
        assert r["final_ms_error"] > 0 and r["mc_offset_T"] > 0
    assert within_brackets(st) == {"decay": True, "offset": True}
    lines = st.csv().splitlines()
    assert lines[0] == ",".join(ROW_KEYS) and len(lines) == 4
    doc = st.to_dict()
    assert doc["realizations"] == 3 and doc["spread"]["offset"]["max"] == max(
        r["offset"] for r in st.rows
    )
    assert study_sentence(doc).endswith("both proven bounds hold")


def test_a_broken_bracket_is_reported(small):
    _, _, st = small
    lower = max(r["decay_rate"] for r in st.rows) + 1.0  # a "proven" bound the rows break
    bad = RobustStudy(st.radius, st.radii, {"decay": {"lower": lower}}, st.rows)
    assert within_brackets(bad) == {"decay": False, "offset": True}
    assert "VIOLATED" in study_sentence(bad.to_dict())


def test_a_study_needs_robust_and_one_fixed_topology(small):
    top, spec, _ = small
    with pytest.raises(InputError, match="robust: the scenario has no robust"):
        robust_study(top, dataclasses.replace(spec, robust=None))
    with pytest.raises(InputError, match="one fixed topology"):
        robust_study("not a topology", spec)


@pytest.mark.parametrize(
    "radii, radius, said, title",
    [
        ([0.05, 0.05], 0.05, "3 weight realisations within ρ = 0.05,", "ρ = 0.05"),
        (
            [0.02, 0.5, 0.02],
            0.5,
            "3 weight realisations within the per-edge radii (max 0.5; ρ_e = 0.02, 0.5, 0.02),",
            "the per-edge radii (max 0.5)",
        ),
    ],
)
def test_a_study_names_its_set(small, radii, radius, said, title):
    # summary.json keeps the brackets' radius: one number, or the per-edge list
    from ntc_design.sweep.robust import study_radius_text

    _, _, st = small
    brackets = {**st.brackets, "radius": radius if len(set(radii)) == 1 else radii}
    doc = RobustStudy(radius, tuple(radii), brackets, st.rows).to_dict()
    assert study_sentence(doc).startswith(said)
    assert study_radius_text(doc, short=True) == title
