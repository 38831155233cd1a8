"""Tests of :mod:`ntc_design.reports.parts`."""

import copy
import dataclasses
import json

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.reports import parts
from ntc_design.reports.rundata import load_run
from ntc_design.simulate import NoiseModel, simulate
from ntc_design.simulate.scenario import write_outputs

# pair_topology (tests/support/tune.py): two agents, d = 1, both edges antagonistic (−1),
# both informed with B_i = 1: L_B = [[1 + δ, 1], [1, 1 + δ]], eigenvalues 2 + δ and δ.
T_RUN = 0.5
X_INIT = [3.0, -1.0]


@pytest.fixture(scope="module")
def run(pair_topology, tmp_path_factory):
    """A small run written and read back as ``ntc report`` does (margin 0.3, gain 2/(1+t))."""
    res = simulate(
        pair_topology, [1.0], noise=NoiseModel(0.5, 0.2), initial=X_INIT, T=T_RUN, dt=0.01, paths=8,
        seed=3, save_every=0.05, workers=1, margin=0.3, gain="2/(1+t)",
    )  # fmt: skip
    out = tmp_path_factory.mktemp("run") / "run"
    write_outputs(res, out)
    return load_run(out)


@pytest.fixture(scope="module")
def cert(run):
    return parts.certify_run(run)


# -- certify_run, certificate_tables ---------------------------------------------------------


def test_certify_run_uses_the_runs_margin_theta_and_gain(cert):
    assert cert.verification.valid
    delta = cert.design.delta
    assert delta == pytest.approx(0.3)  # C = 0 here: δ = ΔC, the run's margin (not 0.1)
    lb = np.array([[1 + delta, 1.0], [1.0, 1 + delta]])
    bound = np.linalg.eigvalsh(lb).min()  # the decay-rate bound min Re λ(L_B) = δ
    assert cert.certificate["results"]["eig_bound"] == pytest.approx(bound, rel=1e-9)
    mode = cert.certificate["subject"]["modes"]["pair"]
    assert mode["theta"] == [1.0] and mode["margin"] == 0.3
    assert cert.gain.expression == "2/(1+t)"


def test_certificate_tables_write_and_reverify_the_file(cert, tmp_path):
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "c.json"
    summary, checks, info = parts.certificate_tables(cert, path, tmp_path)
    on_disk = json.loads(path.read_text(encoding="utf-8"))
    assert on_disk["digest"] == cert.certificate["digest"]
    (label, first), (label2, second), *results = summary.rows
    # typed cells, rendered: a link and a verdict (never a dict printed as Python)
    assert label == "certificate"
    assert first == f'<a href="sub/c.json">c.json (hurwitz, {on_disk["digest"][:23]}…)</a>'
    assert label2.startswith("re-verified from the file")
    n = len(checks.rows)
    assert second == f'<span class="ok">yes</span> — exact-rational, {n}/{n} checks'
    assert len(results) == len(cert.rows) and "decay rate" in str(results[0][0])
    assert info == {"valid": True, "results": cert.certificate["results"]}


def test_certificate_tables_judge_the_file_not_the_result(cert, tmp_path):
    """A reported number changed before writing: the re-verification from the file fails."""
    bad = copy.deepcopy(cert.certificate)
    bad["results"]["eig_bound"] = 5.0
    summary, checks, info = parts.certificate_tables(
        dataclasses.replace(cert, certificate=bad), tmp_path / "c.json", tmp_path
    )
    assert info["valid"] is False and summary.rows[1][1].startswith('<span class="bad">no</span>')
    failing = [str(r[0]) for r in checks.rows if "FAILS" in str(r[1])]
    assert "digest" in failing and any("reported results" in f for f in failing)
    ok = len(checks.rows) - len(failing)
    assert summary.rows[1][1].endswith(f", {ok}/{len(checks.rows)} checks")


def test_certificate_tables_refuse_a_missing_folder(cert, tmp_path):
    with pytest.raises(InputError, match=r"^report: the folder .*nowhere.* does not exist"):
        parts.certificate_tables(cert, tmp_path / "nowhere" / "c.json", tmp_path)


# -- window_warning, fitted_exponent --------------------------------------------------------


@pytest.mark.parametrize(
    "t_from, t_end, decades",
    [
        (0.0, 9.0, None),
        (3.0, 39.0, None),
        (0.0, 99.0, None),
        (0.0, 7.0, "0.90"),
        (1.0, 2.0, "0.18"),
        (0.0, 8.9, "0.99"),  # 0.9956 decades: rounded down, never "only 1.00"
    ],
)
def test_window_warning_below_one_decade_of_one_plus_t(t_from, t_end, decades):
    got = parts.window_warning(t_from, t_end)
    if decades is None:  # log10((1 + t_end)/(1 + t_from)) >= 1
        assert got == ""
    else:
        assert got.startswith(f" The window spans only {decades} decades of 1 + t")
        assert got.endswith("take it as indicative.")


def test_fitted_exponent_recovers_an_exact_power_law():
    t = np.linspace(0.0, 50.0, 101)
    y = 3.0 * (1 + t) ** -0.75
    assert parts.fitted_exponent(t, y, 0.0) == pytest.approx(0.75, abs=1e-12)


def test_fitted_exponent_fits_only_the_window_and_skips_bad_values():
    t = np.linspace(0.0, 40.0, 81)
    y = np.where(t < 10, 5.0 * (1 + t) ** -2.0, 0.2 * (1 + t) ** -0.5)  # a regime change
    y[[30, 41, 60]] = [0.0, np.nan, -1.0]  # not positive or not finite: left out
    assert parts.fitted_exponent(t, y, 10.0) == pytest.approx(0.5, abs=1e-12)
    assert parts.fitted_exponent(t, y, 0.0) > 0.6  # the transient pulls the fit


def test_fitted_exponent_needs_five_usable_points():
    t = np.arange(6.0)
    y = (1 + t) ** -1.0
    y[0] = np.nan
    assert parts.fitted_exponent(t, y, 0.0) == pytest.approx(1.0, abs=1e-12)  # 5 points
    y[1] = 0.0
    assert parts.fitted_exponent(t, y, 0.0) is None  # 4 points
    assert parts.fitted_exponent(t, (1 + t) ** -1.0, 1.5) is None  # 4 in the window


# -- parameter_table ------------------------------------------------------------------------


def rows(table):
    return [tuple(str(c) for c in r) for r in table.rows]


def test_parameter_table_rows():
    p = {
        "theta": [1.0, 2.0],
        "gain": {"t": [0, 0.5, 1], "c": [2, 1, 0.5], "interpolation": "linear", "tail": "1/(1+t)"},
        "schedule": [{"mode": "A", "duration": 0.5}, {"mode": "B", "duration": 2}],
        "noise": {"sigma": 0.4, "f": 0.3, "sigma_edges": {}, "extra": {"deep": 1.5}},
        "delta": None,
        "T": 2.5,
    }
    run_info = {"steps": 50, "exact_rk4_steps": 3, "mc_seconds": 0.25}
    got = rows(parts.parameter_table(p, 2, 1, run_info))
    assert got == [
        ("theta", "[1.0000, 2.0000]"),
        ("gain", "schedule (3 points on [0, 1], linear) then 1/(1+t)"),
        ("schedule (one period)", "A 0.5, B 2"),
        ("noise.sigma", "0.4000"),
        ("noise.f", "0.3000"),
        ("noise.sigma_edges", "—"),  # an empty mapping
        ("noise.extra.deep", "1.5000"),
        ("delta", "—"),
        ("T", "2.5000"),
        ("run.steps", "50"),  # only the listed run statistics, in their order
        ("run.mc_seconds", "0.2500"),
    ]


def test_parameter_table_initial_state_as_matrix_or_range():
    few = rows(parts.parameter_table({"initial": [1.0, 2.0, 3.0, 4.0]}, 2, 2, {}))
    ((label, cell),) = few
    assert label == "initial x(0) (agents × d)"
    # agents down, d across: [[1, 2], [3, 4]]
    assert cell.count("<tr>") == 2 and "<td>1</td><td>2</td></tr><tr><td>3</td><td>4</td>" in cell
    many = rows(parts.parameter_table({"initial": list(np.linspace(-3, 2.5, 21))}, 21, 1, {}))
    assert many == [("initial x(0)", "21 × 1 values in summary.json, in [-3.0000, 2.5000]")]
    odd = rows(parts.parameter_table({"initial": [1.0, 2.0, 3.0]}, 2, 2, {}))  # not N·d
    assert odd == [("initial", "[1.0000, 2.0000, 3.0000]")]


def test_parameter_table_refuses_a_malformed_schedule_gain():
    with pytest.raises(InputError, match=r"^parameters\.gain"):
        parts.parameter_table({"gain": {"t": [0, 1], "c": [1.0]}}, 2, 1, {})


# -- mc_band, data_links --------------------------------------------------------------------


def test_mc_band_reads_the_curves_back(run):
    band = parts.mc_band(run)
    assert band.mean.shape == band.lo.shape == band.hi.shape == (run.t.size, 2)
    for k, a in enumerate(run.labels):
        np.testing.assert_array_equal(band.mean[:, k], run.table[f"mc_{a}"])
        np.testing.assert_array_equal(band.hi[:, k], run.table[f"mc_{a}_hi"])
    assert np.all(band.lo <= band.mean) and np.all(band.mean <= band.hi)
    assert np.any(band.lo < band.hi)  # 8 noisy paths: a band of some width


def test_mc_band_is_none_without_monte_carlo(run):
    exact_only = {k: v for k, v in run.table.items() if not k.startswith("mc_")}
    assert parts.mc_band(dataclasses.replace(run, table=exact_only)) is None


def test_data_links_list_data_files_then_the_sections_figures(run, tmp_path):
    d = tmp_path / "run"
    d.mkdir()
    for name in ("summary.json", "ms_error.csv", "paths.npz", ".hidden.json", "notes.txt"):
        (d / name).write_text("x")
    (d / "sub.csv").mkdir()  # a folder, not a file
    figs = tmp_path / "figs"
    figs.mkdir()
    for name in ("k_ms.png", "k_ms.svg", "k_ms.pdf", "k_ms.txt", "other_ms.png", "k.png"):
        (figs / name).write_text("x")
    got = parts.data_links(dataclasses.replace(run, path=d), figs, "k", tmp_path)
    assert got == [
        ("ms_error.csv", "run/ms_error.csv"),
        ("paths.npz", "run/paths.npz"),
        ("summary.json", "run/summary.json"),
        ("k_ms.pdf", "figs/k_ms.pdf"),
        ("k_ms.png", "figs/k_ms.png"),
        ("k_ms.svg", "figs/k_ms.svg"),
    ]


# -- companion_paths ------------------------------------------------------------------------


def test_companion_paths_repeat_the_runs_scenario_finely(run, pair_topology):
    got = parts.companion_paths(run, pair_topology)
    t, paths = got["t"], got["paths"]
    assert t.size == parts.FINE_POINTS + 1 and t[0] == 0.0 and t[-1] == pytest.approx(T_RUN)
    np.testing.assert_allclose(np.diff(t), T_RUN / parts.FINE_POINTS, rtol=1e-9)
    assert paths.shape == (2, t.size, 2)
    np.testing.assert_array_equal(paths[:, 0, :], [X_INIT, X_INIT])  # the run's x(0)
    assert not np.allclose(paths[0], paths[1])  # two independent noise realisations
    again = parts.companion_paths(run, pair_topology)  # the run's seed: the same paths
    np.testing.assert_array_equal(again["paths"], paths)


def with_spec(run, **changes):
    record = dataclasses.replace(run.record, spec=run.spec.replace(**changes))
    return dataclasses.replace(run, record=record)


def test_companion_paths_none_when_too_costly_or_not_repeatable(run, pair_topology):
    # 2 paths × T/dt steps over the budget
    steps = parts.COMPANION_MAX_STEPS / 2 + 100
    assert parts.companion_paths(with_spec(run, T=steps * 0.01), pair_topology) is None
    # a callable f is recorded as "callable": the run cannot be repeated from its summary
    noise = NoiseModel(0.5, lambda x: 0.2 * x)
    assert parts.companion_paths(with_spec(run, noise=noise), pair_topology) is None
