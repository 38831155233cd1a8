"""SimulationSpec: one self-checking spec built by the keyword API and the scenario
parser; size before allocation; all-or-nothing outputs; the executor's ordering."""

import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.errors import InputError, one_line, quote
from ntc_design.outputs import atomic_path, output_folder, write_atomic
from ntc_design.paper import THETA  # the paper's θ, defined once
from ntc_design.simulate import (
    MonteCarlo,
    NoiseModel,
    SaveAt,
    SimulationSpec,
    Stepping,
    UniformInitial,
    simulate,
)
from ntc_design.simulate.budget import MAX_PATH_STEPS, check_budget, estimate
from ntc_design.simulate.scenario import load_scenario, write_outputs
from ntc_design.simulate.spec import OPTION_KEYS, SCENARIO_KEYS

from .conftest import ROOT


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


def test_spec_and_keywords_give_identical_runs(g1):
    kw = dict(T=0.2, dt=1e-3, paths=20, seed=2, save_every=0.1, workers=1)
    a = simulate(g1, THETA, **kw)
    b = simulate(g1, SimulationSpec.build(THETA, **kw))
    assert np.array_equal(a.mc.mean, b.mc.mean)
    assert np.array_equal(a.exact.ms_error, b.exact.ms_error)


def test_spec_is_frozen_and_rechecked_on_replace():
    s = SimulationSpec.build(THETA, paths=10)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.T = 3.0  # type: ignore[misc]
    with pytest.raises(InputError, match=r"^T: must be a positive number"):
        s.replace(T=-1.0)
    assert not s.theta.flags.writeable


@pytest.mark.parametrize(
    "topology, gain, t_end, every",
    [
        ("g1.yaml", "1/(1+t)", 100.0, 1.0),
        ("g1.yaml", "2/(1+t)^0.5", 10.0, 1.0),
        ("g1.yaml", "1", 20.0, 0.5),
        ("switching.yaml", "1/(1+t)", 10.0, 0.1),  # the largest ρ of the modes, and switches
    ],
)
def test_exact_step_estimate_matches_the_run(monkeypatch, topology, gain, t_end, every):
    """The estimate that refuses long exact runs counts the RK4 steps the run takes (within
    a factor of 2, never below by more than 10 %)."""
    import ntc_design.simulate.driver as drv

    seen = []
    orig = drv.estimate_exact_steps
    monkeypatch.setattr(drv, "estimate_exact_steps", lambda *a: seen.append(orig(*a)) or seen[-1])
    top = nd.load(ROOT / "examples" / topology)
    res = simulate(top, THETA, T=t_end, gain=gain, method="exact", save_every=every)
    steps = res.stats.exact_rk4_steps
    assert len(seen) == 1 and 0.9 * steps <= seen[0] <= 2 * steps, (seen, steps)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: SaveAt(), "save_every"),
        (lambda: SaveAt(every=0.1, times=[1.0]), "save_every"),
        (lambda: SaveAt(every=0.0), "save_every"),
        (lambda: SaveAt(every=float("nan")), "save_every"),
        (lambda: SaveAt(times=[]), "save_times"),
        (lambda: SaveAt(times=[-1.0]), "save_times"),
        (lambda: SaveAt(times=[[1.0]]), "save_times[0]"),
        (lambda: SaveAt(times=[float("inf")]), "save_times[0]"),
        (lambda: Stepping(kind="rk4"), "stepping"),
        (lambda: Stepping(dt=0), "dt"),
        (lambda: Stepping(kind="intrinsic", ds=0), "ds"),
        (lambda: Stepping(kind="intrinsic", ds=-1e-3), "ds"),
        (lambda: Stepping(kind="intrinsic", ds=float("nan")), "ds"),
        (lambda: MonteCarlo(paths=0), "paths"),
        (lambda: MonteCarlo(paths=2.0), "paths"),
        (lambda: MonteCarlo(paths=True), "paths"),
        (lambda: MonteCarlo(seed=1.5), "seed"),
        (lambda: MonteCarlo(seed=-1), "seed"),
        (lambda: MonteCarlo(seed=2**200), "seed"),
        (lambda: MonteCarlo(store_paths=-1), "store_paths"),
        (lambda: MonteCarlo(block_size=0), "block_size"),
        (lambda: MonteCarlo(workers=0), "workers"),
        (lambda: MonteCarlo(workers=10**9), "workers"),
        (lambda: UniformInitial(1, -1, 0), "initial.uniform"),
        (lambda: UniformInitial(0, float("nan"), 0), "initial.uniform[1]"),
        (lambda: UniformInitial(0, 1, 0.5), "initial.seed"),
        (lambda: SimulationSpec.build([[1, 2], [3]]), "theta[0]"),
        (lambda: SimulationSpec.build([1, float("nan"), 2]), "theta[1]"),
        (lambda: SimulationSpec.build([0, 0, 0]), "theta"),
        (lambda: SimulationSpec.build(THETA, T=float("inf")), "T"),
        (lambda: SimulationSpec.build(THETA, margin=-1), "margin"),
        (lambda: SimulationSpec.build(THETA, gain=3.0), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="t" * 20000), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="__import__('os')"), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="1/(1+"), "gain"),
        (lambda: SimulationSpec.build(THETA, gain="x + t"), "gain"),
        (lambda: SimulationSpec.build(THETA, method="magic"), "method"),
        (lambda: SimulationSpec.build(THETA, resample=0), "resample"),
        (lambda: SimulationSpec.build(THETA, colour=1), "colour"),
        (lambda: SimulationSpec.build(THETA, initial=[1, float("inf")]), "initial[1]"),
        (lambda: SimulationSpec.build(THETA, T=1.0, save_times=[2.0]), "save_times"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(-0.1)), "noise.sigma"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(float("nan"))), "noise.sigma"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, True)), "noise.f"),
        (lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, np.ones(3))), "noise.f"),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, np.full((3, 3), np.nan))),
            "noise.f",
        ),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3, {(1, 2): -1.0})),
            "noise.sigma_edges 1->2",
        ),
        (
            lambda: SimulationSpec.build(THETA, noise=NoiseModel(0.4, 0.3, {(1, 2): np.nan})),
            "noise.sigma_edges 1->2",
        ),
    ],
)
def test_option_objects_check_themselves(make, needle):
    with pytest.raises(InputError) as exc:
        make()
    msg = str(exc.value)
    assert msg.startswith(needle), msg
    assert "\n" not in msg


@pytest.mark.hostile
def test_resample_on_a_fixed_topology_is_refused(g1):
    with pytest.raises(InputError, match=r"^resample: applies only"):
        simulate(g1, THETA, T=0.1, paths=2, resample=0.05)


@pytest.mark.hostile
def test_theta_length_checked_against_the_topology(g1):
    with pytest.raises(InputError, match=r"^theta: expected 3 numbers"):
        simulate(g1, [1, 2], T=0.1, paths=2)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "durations, needle",
    [
        ([1e308, 1e308], "overflows to infinity"),
        ([1.0, 1e-300], "schedule[1].duration"),
        ([1e-6, 1e-6], "switching segments"),
    ],
)
def test_switching_schedule_limits(durations, needle):
    g1 = nd.load(ROOT / "examples" / "g1.yaml")
    # a degenerate schedule is refused by the model itself, a too fine one by the budget
    with pytest.raises(InputError) as exc:
        sw = nd.SwitchingTopology({"a": g1, "b": g1}, tuple(zip("ab", durations, strict=True)))
        simulate(sw, THETA, T=100.0, paths=2, method="exact")
    assert needle in str(exc.value)


def test_budget_refuses_before_allocating():
    kw = dict(
        n=7,
        d=3,
        edges=12,
        modes=1,
        segments=1,
        steps=1e4,
        paths=1000,
        block_size=500,
        workers=2,
        mc=True,
        exact=True,
    )
    small = estimate(saves=101, store_paths=10, **kw)
    check_budget(small, available=2**30)
    assert small.total < 50 * 2**20  # the paper's run needs tens of MB, not GB
    big = estimate(saves=1e9, store_paths=10, **kw)
    with pytest.raises(InputError, match=r"^save_every: the run would need about .* GiB"):
        check_budget(big, available=2**30)
    stored = estimate(saves=1e5, store_paths=10**6, **{**kw, "paths": 10**6})
    with pytest.raises(InputError, match=r"^store_paths: .*stored paths"):
        check_budget(stored, available=2**30)
    work = estimate(saves=10, store_paths=1, **{**kw, "paths": 10**12})
    assert work.path_steps > MAX_PATH_STEPS
    with pytest.raises(InputError, match=r"^paths: .* path-steps"):
        check_budget(work, available=2**40)
    # memory grows linearly with the save count (statistics and tables)
    s2 = estimate(saves=2e6, store_paths=10, **kw).total
    s1 = estimate(saves=1e6, store_paths=10, **kw).total
    assert 1.8 < s2 / s1 < 2.1


@pytest.mark.hostile
@pytest.mark.parametrize(
    "over, needle",
    [
        ({"save_every": 1e-12, "T": 10.0}, "save_every"),
        ({"dt": 1e-13}, "dt"),
        ({"T": 1e300, "method": "exact"}, "dt"),
        ({"paths": 10**15}, "paths"),
        ({"store_paths": 10**9, "paths": 10**9, "T": 10.0, "dt": 0.01}, "store_paths"),
        ({"stepping": "intrinsic", "ds": 1e-300}, "dt"),
    ],
)
def test_huge_requests_refused_by_field(g1, over, needle):
    with pytest.raises(InputError) as exc:
        simulate(g1, THETA, **{"T": 1.0, "paths": 10, **over})
    assert str(exc.value).startswith(needle + ":"), str(exc.value)


def test_one_path_has_no_band(g1):
    res = simulate(g1, THETA, T=0.1, paths=1, save_every=0.05, workers=1, method="mc")
    assert np.all(np.isnan(res.mc.lo)) and np.all(np.isnan(res.mc.hi))
    summ = json.loads(json.dumps(nd.files.jsonable(res.summary())))
    assert all(v == [None, None] for v in summ["final_ms_error_mc_band"].values())
    assert summ["sample_paths"]["final_error_norm_spread"] is None
    two = simulate(g1, THETA, T=0.1, paths=2, save_every=0.05, workers=1, method="mc")
    assert np.all(two.mc.hi[1:] > two.mc.lo[1:])


def test_workers_capped_at_the_machine(g1):
    res = simulate(g1, THETA, T=0.05, paths=4, block_size=2, save_every=0.05, workers=4096)
    assert res.parameters["workers"] == (os.cpu_count() or 1)
    assert any("workers: 4096 asked" in n for n in res.notes)
    one = simulate(g1, THETA, T=0.05, paths=4, block_size=2, save_every=0.05, workers=1)
    assert np.array_equal(res.mc.mean, one.mc.mean)


def test_quote_and_one_line():
    assert quote(3) == "3" and quote("a") == "'a'"
    assert "\n" not in quote("a\nerror: forged")
    assert one_line("a\nb\rc\x1b") == "a\\nb\\rc\\x1b"


# ------------------------------------------------------------------- atomic outputs


def test_write_atomic_replaces_whole_file(tmp_path):
    p = tmp_path / "f.txt"
    write_atomic(p, "old")
    write_atomic(p, "new")
    assert p.read_text() == "new" and os.listdir(tmp_path) == ["f.txt"]
    with pytest.raises(InputError, match=r"^--out: .* is a folder"):
        write_atomic(tmp_path, "x")


@pytest.mark.hostile
def test_atomic_writer_removes_its_temporary_file(tmp_path, monkeypatch):
    """The rename fails (a folder took the target's name after the check), the writer
    raises, Ctrl-C: each leaves only what was there, never a temporary file."""
    import ntc_design.outputs as outputs

    target = tmp_path / "report.html"
    target.mkdir()
    monkeypatch.setattr(outputs, "check_output_file", lambda p, option="--out": Path(p))
    with pytest.raises(InputError, match=r"^report: cannot write .*report.html"):
        write_atomic(target, "x", option="report")
    assert os.listdir(tmp_path) == ["report.html"] and os.listdir(target) == []
    monkeypatch.undo()
    for exc in (RuntimeError, KeyboardInterrupt):
        with pytest.raises(exc), atomic_path(tmp_path / "a.npz") as tmp:
            np.savez_compressed(tmp, x=np.ones(3))
            raise exc
    assert os.listdir(tmp_path) == ["report.html"]
    with atomic_path(tmp_path / "a.npz") as tmp:  # NumPy adds no second .npz to the name
        np.savez_compressed(tmp, x=np.ones(3))
    assert sorted(os.listdir(tmp_path)) == ["a.npz", "report.html"]
    assert np.load(tmp_path / "a.npz")["x"].tolist() == [1.0, 1.0, 1.0]


def test_output_folder_is_all_or_nothing(tmp_path):
    target = tmp_path / "run"
    with output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("1")
        (tmp / "b.txt").write_text("1")
    with pytest.raises(KeyboardInterrupt), output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("2")
        raise KeyboardInterrupt
    assert (target / "a.txt").read_text() == "1" and (target / "b.txt").read_text() == "1"
    assert os.listdir(tmp_path) == ["run"]  # no temporary folder left
    with output_folder(target, ["a.txt", "b.txt"]) as tmp:
        (tmp / "a.txt").write_text("3")
    assert os.listdir(target) == ["a.txt"] and os.listdir(tmp_path) == ["run"]


@pytest.mark.hostile
def test_output_folder_refuses_a_folder_with_other_files(tmp_path):
    (tmp_path / "precious.txt").write_text("keep")
    with pytest.raises(InputError, match=r"^--out: .* holds other files \('precious.txt'"):
        with output_folder(tmp_path, ["summary.json"]):
            pass
    assert (tmp_path / "precious.txt").read_text() == "keep"


def test_interrupted_write_outputs_leaves_the_old_run(g1, tmp_path, monkeypatch):
    res = simulate(g1, THETA, T=0.1, paths=4, save_every=0.05, workers=1)
    out = tmp_path / "o"
    write_outputs(res, out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    import ntc_design.simulate.scenario as sc

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(sc.np, "savez_compressed", boom)
    with pytest.raises(KeyboardInterrupt):
        write_outputs(res, out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert os.listdir(tmp_path) == ["o"]


def test_permission_error_while_writing_is_one_line(g1, tmp_path, monkeypatch):
    res = simulate(g1, THETA, T=0.1, paths=4, save_every=0.05, workers=1)
    import ntc_design.outputs as outputs

    def denied(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(outputs.tempfile, "mkdtemp", denied)
    with pytest.raises(InputError, match=r"^--out: cannot write .* \(Permission denied\)$"):
        write_outputs(res, tmp_path / "o")
    assert not (tmp_path / "o").exists()


@pytest.mark.hostile
def test_large_topology_refused_before_the_design(monkeypatch):
    monkeypatch.setattr("ntc_design.simulate.budget.available_memory", lambda: 2.0**30)
    top = nd.Topology.from_edges(20000, 1, [(1, 2, np.eye(1))])
    with pytest.raises(InputError, match=r"^method: .* GiB .*use method: mc"):
        simulate(top, [1.0], T=1.0, paths=10)
    with pytest.raises(InputError, match=r"^topology: .* GiB .*too large"):
        simulate(top, [1.0], T=1.0, paths=10, method="mc")


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


def test_json_text_is_indented_json_with_long_values_on_one_line(monkeypatch):
    """summary.json at 10⁵ agents: long values go through json's C encoder on one line;
    short documents are byte for byte json.dumps(indent=1)."""
    import json

    from ntc_design import outputs

    small = {"a": [1, 2.5], "b": {"c": None, "d": []}, "e": {}, "f": "ü", "g": [{"x": 1}]}
    assert outputs.json_text(small) == json.dumps(small, indent=1, ensure_ascii=False) + "\n"
    assert outputs.json_text({}) == "{}\n"
    monkeypatch.setattr(outputs, "JSON_INDENT_MAX_CHARS", 12)
    text = outputs.json_text(small)
    assert json.loads(text) == small
    lines = text.splitlines()
    assert ' "b": {"c": null, "d": []},' in lines and ' "a": [' in lines  # 22 chars vs 8
