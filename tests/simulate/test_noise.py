"""Tests of :mod:`ntc_design.simulate.noise`: the three forms of f against written-out
products, the probe of a callable f, the defaults, the reading of a ``noise`` mapping
field by field, and the three forms giving the same Monte Carlo paths for the same f."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.model.paper import F_SCALE, SIGMA, THETA
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.noise import (
    MAX_MAGNITUDE,
    CallableNoise,
    MatrixNoise,
    ScalarNoise,
    StateNoise,
    noise_from_document,
    state_noise,
)
from tests.conftest import X0

hostile = pytest.mark.hostile


def test_noise_callable_shape_is_checked(g1):
    with pytest.raises(nd.InputError, match=r"noise.f: returned shape"):
        simulate(g1, THETA, T=0.1, paths=4, noise=NoiseModel(0.4, lambda x: x[..., :1]))


# -- the three forms of f ------------------------------------------------------------------


@pytest.mark.parametrize("s", [0.3, -2.5, 0.0, np.float64(1.5), np.array(0.7)])
def test_a_number_is_a_scalar_noise_whose_matrix_scales_every_difference(s):
    term = state_noise(s)
    assert isinstance(term, ScalarNoise) and term.linear and term.function is None
    x = np.random.default_rng(np.random.SeedSequence(5)).normal(size=(4, 3))
    # f(x) = s·x, written out entry by entry
    want = np.array([[float(s) * v for v in row] for row in x])
    np.testing.assert_allclose(x @ term.matrix(3).T, want, rtol=1e-14, atol=0)
    assert term.matrix(1).shape == (1, 1) and term.matrix(5).shape == (5, 5)
    term.check(3, 10)  # a number fits every dimension


def test_a_matrix_is_a_matrix_noise_applied_as_f_x():
    f = [[0.3, 0.1], [-0.2, 0.5]]
    term = state_noise(f)
    assert isinstance(term, MatrixNoise) and term.linear and term.function is None
    x = np.array([1.5, -2.0])
    fx = term.matrix(2) @ x
    # F x by the definition of a matrix-vector product (to the rounding of a fused add)
    want = [0.3 * 1.5 + 0.1 * -2.0, -0.2 * 1.5 + 0.5 * -2.0]
    np.testing.assert_allclose(fx, want, rtol=1e-14, atol=0)
    term.check(2, 4)


@hostile
@pytest.mark.parametrize("d", [1, 3])
def test_a_matrix_of_the_wrong_shape_names_noise_f_and_both_shapes(d):
    term = state_noise(np.eye(2))
    with pytest.raises(nd.InputError, match=rf"noise.f: expected a scalar or a {d}x{d} matrix"):
        term.matrix(d)
    with pytest.raises(nd.InputError, match=r"got shape \(2, 2\)"):
        term.check(d, 5)


def test_a_callable_is_applied_as_a_function_after_the_identity():
    def fn(x):
        return np.tanh(x)

    term = state_noise(fn)
    assert isinstance(term, CallableNoise) and not term.linear
    assert term.function is fn
    # the kernels multiply by the identity, then apply f
    assert np.array_equal(term.matrix(4), np.eye(4))


def test_the_probe_of_a_callable_has_the_kernels_shape_and_ones():
    seen = []

    def fn(x):
        seen.append(x.copy())
        return 0.3 * x

    state_noise(fn).check(3, 7)
    (probe,) = seen
    assert probe.shape == (2, 7, 3) and np.all(probe == 1.0)


@hostile
def test_a_callable_that_raises_is_refused_naming_the_exception_not_its_text():
    def fn(x):
        raise KeyError("secret detail")

    with pytest.raises(nd.InputError) as err:
        state_noise(fn).check(2, 3)
    msg = str(err.value)
    assert "noise.f" in msg and "(2, 3, 2)" in msg and "KeyError" in msg
    assert "secret detail" not in msg and "\n" not in msg


@hostile
@pytest.mark.parametrize(
    "fn, shape",
    [
        (lambda x: x.sum(axis=-1), "(2, 3)"),
        (lambda x: x[..., None], "(2, 3, 2, 1)"),
        (lambda x: 1.0, "()"),
    ],
    ids=["summed", "extra axis", "a number"],
)
def test_a_callable_of_another_shape_is_refused_with_both_shapes(fn, shape):
    with pytest.raises(nd.InputError, match=r"noise.f: returned shape") as err:
        state_noise(fn).check(2, 3)
    assert f"returned shape {shape} for input shape (2, 3, 2)" in str(err.value)


def test_the_base_form_is_the_identity_and_linear():
    base = StateNoise()
    assert base.linear and base.function is None
    assert np.array_equal(base.matrix(2), np.eye(2))


# -- the model -----------------------------------------------------------------------------


def test_the_defaults_are_the_papers_sigma_and_f():
    m = NoiseModel()
    assert (m.sigma, m.f, dict(m.sigma_edges)) == (SIGMA, F_SCALE, {}) == (0.4, 0.3, {})
    assert m.linear
    np.testing.assert_array_equal(m.f_matrix(3), 0.3 * np.eye(3))


def test_f_matrix_of_a_matrix_model_and_refusal_for_a_callable():
    f = np.array([[0.1, 0.0], [0.2, 0.3]])
    assert np.array_equal(NoiseModel(0.4, f).f_matrix(2), f)
    m = NoiseModel(0.4, np.sin)
    assert not m.linear and isinstance(m.term, CallableNoise)
    with pytest.raises(ValueError, match="f is a callable"):
        m.f_matrix(2)


def test_the_three_forms_of_one_linear_f_give_the_same_paths(g1):
    """f(x) = 0.3x as a number, as 0.3·I and as a function: the kernels' matrix path and
    their function path draw the same noise, so the Monte Carlo curves agree to rounding;
    the exact moments exist for the two linear forms only, and agree."""
    kw = dict(T=0.2, paths=8, initial=X0, save_every=0.1, workers=1, seed=3)
    runs = [
        simulate(g1, THETA, noise=NoiseModel(0.4, f), **kw)
        for f in (0.3, 0.3 * np.eye(3), lambda x: 0.3 * x)
    ]
    ref = runs[0].mc.mean
    assert ref.shape == (3, 7) and np.all(ref[-1] > 0)
    for r in runs[1:]:
        np.testing.assert_allclose(r.mc.mean, ref, rtol=1e-12, atol=1e-14 * ref.max())
    assert runs[2].exact is None
    np.testing.assert_allclose(runs[1].exact.ms_error, runs[0].exact.ms_error, rtol=1e-12)


# -- a noise mapping -----------------------------------------------------------------------


def test_no_mapping_is_the_papers_noise():
    m = noise_from_document(None)
    assert (m.sigma, m.f, dict(m.sigma_edges)) == (SIGMA, F_SCALE, {})
    assert noise_from_document({}).sigma == SIGMA


def test_a_full_mapping_is_read_value_by_value():
    doc = {
        "sigma": 0.25,
        "f": [[0.1, 0.0], [0.0, 0.2]],
        "sigma_edges": [{"from": 1, "to": 2, "sigma": 0.5}, {"from": "a", "to": "b", "sigma": 0}],
    }
    m = noise_from_document(doc)
    assert m.sigma == 0.25
    assert isinstance(m.f, np.ndarray) and m.f.tolist() == [[0.1, 0.0], [0.0, 0.2]]
    assert dict(m.sigma_edges) == {(1, 2): 0.5, ("a", "b"): 0.0}
    assert noise_from_document({"f": -2}).f == -2
    assert noise_from_document({"sigma_edges": None}).sigma_edges == {}


@hostile
@pytest.mark.parametrize(
    "doc, needle",
    [
        ([0.4], "noise: expected {sigma, f, sigma_edges}"),
        ("0.4", "noise: expected {sigma, f, sigma_edges}"),
        ({"sigma": 0.4, "g": 1, "a": 2}, "noise.a: unknown field"),
        ({"sigma": -0.1}, "noise.sigma: must be >= 0"),
        ({"sigma": True}, "noise.sigma: expected a number"),
        ({"sigma": float("nan")}, "noise.sigma: must be finite"),
        ({"sigma": 10 * MAX_MAGNITUDE}, "noise.sigma: must be at most 1e+100"),
        ({"f": True}, "noise.f: expected a number or a d×d matrix"),
        ({"f": "0.3*x"}, "noise.f: expected a number or a d×d matrix, got '0.3*x'"),
        ({"f": {"a": 1}}, "noise.f: expected a number or a d×d matrix"),
        ({"f": -1e101}, "noise.f: must be at most 1e+100"),
        ({"f": [1.0, 2.0]}, "noise.f[0]: expected a row"),
        ({"f": [[1.0, 2.0], [3.0]]}, "noise.f: expected a square matrix, row 1 has 1 of 2"),
        ({"f": [[1.0, "x"], [3.0, 4.0]]}, "noise.f[0][1]: expected a number"),
        ({"f": [[1.0, 0.0], [0.0, float("inf")]]}, "noise.f[1][1]: must be finite"),
        ({"sigma_edges": {"1->2": 0.1}}, "noise.sigma_edges: expected a list"),
        ({"sigma_edges": [{"from": 1, "to": 2}]}, "noise.sigma_edges[0]: expected {from, to"),
        ({"sigma_edges": [[1, 2, 0.1]]}, "noise.sigma_edges[0]: expected {from, to"),
        (
            {"sigma_edges": [{"from": True, "to": 2, "sigma": 0.1}]},
            "noise.sigma_edges[0].from: expected an agent label",
        ),
        (
            {"sigma_edges": [{"from": 1, "to": 2.5, "sigma": 0.1}]},
            "noise.sigma_edges[0].to: expected an agent label",
        ),
        (
            {"sigma_edges": [{"from": 1, "to": 2, "sigma": -1}]},
            "noise.sigma_edges[0].sigma: must be >= 0",
        ),
        (
            {
                "sigma_edges": [
                    {"from": 1, "to": 2, "sigma": 0.1},
                    {"from": 1, "to": 2, "sigma": 0.2},
                ]
            },
            "noise.sigma_edges[1]: edge 1->2 listed twice",
        ),
    ],
)
def test_a_bad_noise_mapping_is_refused_in_one_line_naming_its_field(doc, needle):
    with pytest.raises(nd.InputError) as err:
        noise_from_document(doc)
    msg = str(err.value)
    assert needle in msg and "\n" not in msg, msg


@hostile
def test_a_huge_sigma_edge_is_refused_at_the_bound_and_accepted_below_it():
    edge = {"from": 1, "to": 2, "sigma": MAX_MAGNITUDE}
    assert noise_from_document({"sigma_edges": [edge]}).sigma_edges[(1, 2)] == 1e100
    with pytest.raises(nd.InputError, match=r"noise.sigma_edges\[0\].sigma: must be at most"):
        noise_from_document({"sigma_edges": [{**edge, "sigma": 2e100}]})
