"""Tests of :mod:`ntc_design.sweep.store`."""

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from ntc_design.sweep import store
from ntc_design.sweep.point import ROW_FIELDS, PointResult, PointRow
from ntc_design.sweep.spec import FORMAT, Sweep, load_sweep
from ntc_design.sweep.store import load_point, save_point, write_manifest, write_tables
from tests.support.distributed import SCENARIO, TOPOLOGY

LABELS = ["1", "2", "3"]


def _sweep(tmp_path, grid: str = "  noise.sigma: [0.1, 0.3]\n  seed: [0, 1]\n") -> Sweep:
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO)
    (tmp_path / "sw.yaml").write_text(f"name: small\nbase: sc.yaml\ngrid:\n{grid}")
    return load_sweep(tmp_path / "sw.yaml")


def _result(point: str, params: dict | None = None, seed: int = 0, s: int = 4, **kw):
    """A point's result with distinct curves (every entry tells its time and agent)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    t = np.cumsum(rng.uniform(0.1, 1.0, size=s))
    curves = {k: rng.uniform(0.0, 2.0, size=(s, len(LABELS))) for k in ("mc", "lo", "hi")}
    row = PointRow(point, delta=1.5 + seed, certified=True, ms_guaranteed=True, T=1.0, paths=200)
    args = {"t": t, "labels": list(LABELS), **curves, "exact": None, **kw}
    return PointResult(point, params if params is not None else {"seed": seed}, row, **args)


# -- one point -----------------------------------------------------------------------------


def test_save_writes_the_row_and_the_curves(tmp_path):
    res = _result("abc123", {"noise.sigma": 0.1, "seed": 0})
    path = save_point(tmp_path, res)
    assert path == tmp_path / "points" / "abc123.json"
    # exactly the two files: no temporary file is left behind
    assert sorted(p.name for p in (tmp_path / "points").iterdir()) == [
        "abc123.json",
        "abc123.npz",
    ]
    doc = json.loads(path.read_text())
    assert doc["format"] == FORMAT and doc["point"] == "abc123"
    assert doc["params"] == {"noise.sigma": 0.1, "seed": 0}
    assert list(doc["row"]) == list(ROW_FIELDS)
    assert doc["row"]["delta"] == 1.5 and doc["row"]["error"] is None
    with np.load(tmp_path / "points" / "abc123.npz") as z:
        assert set(z.files) == {"t", "labels", "mc", "lo", "hi"}  # exact is None: left out
        np.testing.assert_array_equal(z["mc"], res.mc)


def test_save_then_load_round_trips(tmp_path):
    res = _result("p1", seed=3, exact=np.full((4, 3), 0.25))
    save_point(tmp_path, res)
    got = load_point(tmp_path, "p1")
    assert got is not None
    assert (got.point, got.params, got.row) == ("p1", {"seed": 3}, res.row)
    assert got.labels == LABELS and all(type(a) is str for a in got.labels)
    for k in ("t", "mc", "lo", "hi", "exact"):
        np.testing.assert_array_equal(getattr(got, k), getattr(res, k))


def test_a_missing_curve_loads_as_none(tmp_path):
    save_point(tmp_path, _result("p1", lo=None, hi=None))
    got = load_point(tmp_path, "p1")
    assert got.lo is None and got.hi is None and got.exact is None and got.mc is not None


def test_non_finite_row_values_are_stored_as_null(tmp_path):
    res = _result("p1")
    res = replace(res, row=replace(res.row, ms_final_mc=float("nan"), delta=float("inf")))
    path = save_point(tmp_path, res)
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text  # strict JSON
    got = load_point(tmp_path, "p1")
    assert got.row.ms_final_mc is None and got.row.delta is None


def test_saving_again_replaces_the_point(tmp_path):
    save_point(tmp_path, _result("p1", seed=0))
    second = _result("p1", seed=1)
    save_point(tmp_path, second)
    got = load_point(tmp_path, "p1")
    np.testing.assert_array_equal(got.mc, second.mc)
    assert got.row.delta == 2.5


def test_missing_points_load_as_none(tmp_path):
    assert load_point(tmp_path, "nope") is None
    save_point(tmp_path, _result("p1"))
    (tmp_path / "points" / "p1.npz").unlink()  # a row without its curves is not done
    assert load_point(tmp_path, "p1") is None


def _damage_json(tmp_path, change):
    save_point(tmp_path, _result("p1"))
    js = tmp_path / "points" / "p1.json"
    doc = json.loads(js.read_text())
    js.write_text(json.dumps(change(doc)))
    return load_point(tmp_path, "p1")


@pytest.mark.parametrize(
    "change",
    [
        lambda d: {**d, "format": FORMAT - 1},  # an older format hashes differently
        lambda d: {k: v for k, v in d.items() if k != "format"},
        lambda d: {**d, "point": "p2"},  # a file renamed to another point
        lambda d: {**d, "row": [1, 2]},
        lambda d: {k: v for k, v in d.items() if k != "row"},
        lambda d: {**d, "params": [0]},
        lambda d: [d],
    ],
    ids=["old-format", "no-format", "other-point", "row-list", "no-row", "params-list", "list"],
)
def test_a_foreign_row_file_is_computed_again(tmp_path, change):
    assert _damage_json(tmp_path, change) is None


def test_params_default_to_empty(tmp_path):
    got = _damage_json(tmp_path, lambda d: {k: v for k, v in d.items() if k != "params"})
    assert got is not None and got.params == {}


def test_a_row_file_that_is_not_json_is_computed_again(tmp_path):
    save_point(tmp_path, _result("p1"))
    (tmp_path / "points" / "p1.json").write_text("{not json")
    assert load_point(tmp_path, "p1") is None
    (tmp_path / "points" / "p1.json").write_bytes(b"\xff\xfe\x00")
    assert load_point(tmp_path, "p1") is None


def _with_arrays(tmp_path, **arrays):
    save_point(tmp_path, _result("p1"))
    np.savez(tmp_path / "points" / "p1.npz", **arrays)
    return load_point(tmp_path, "p1")


T3 = np.array([0.0, 0.5, 1.0])
L3 = np.array(LABELS)
C3 = np.ones((3, 3))


def test_valid_arrays_load(tmp_path):
    got = _with_arrays(tmp_path, t=T3, labels=L3, mc=C3)
    assert got is not None and got.lo is None


@pytest.mark.parametrize(
    "arrays",
    [
        {"t": T3, "labels": L3, "mc": C3, "extra": C3},  # an unknown array
        {"t": T3, "mc": C3},  # no labels
        {"t": T3[::-1], "labels": L3},  # time not increasing
        {"t": np.array([0.0, 0.5, 0.5]), "labels": L3},  # a repeated time
        {"t": np.array([0.0, np.nan, 1.0]), "labels": L3},
        {"t": np.array([0, 1, 2]), "labels": L3},  # integer times
        {"t": T3.reshape(3, 1), "labels": L3},
        {"t": T3, "labels": np.array([1, 2, 3])},  # labels not text
        {"t": T3, "labels": L3.reshape(1, 3)},
        {"t": T3, "labels": L3, "mc": np.ones((3, 2))},  # a curve of the wrong shape
        {"t": T3, "labels": L3, "hi": np.ones((3, 3), dtype=complex)},
        {"t": T3, "labels": L3, "lo": np.ones((3, 3), dtype=int)},
    ],
    ids=[
        "extra",
        "no-labels",
        "decreasing",
        "repeat",
        "nan",
        "int-t",
        "2d-t",
        "int-labels",
        "2d-labels",
        "shape",
        "complex",
        "int-curve",
    ],
)
def test_inconsistent_arrays_are_computed_again(tmp_path, arrays):
    assert _with_arrays(tmp_path, **arrays) is None


def test_oversized_point_files_are_not_read(tmp_path, monkeypatch):
    save_point(tmp_path, _result("p1"))
    js = tmp_path / "points" / "p1.json"
    npz = tmp_path / "points" / "p1.npz"
    # the limit is checked on either file's size, before reading it: each file alone over it
    assert npz.stat().st_size > js.stat().st_size  # the arrays are the bigger file
    monkeypatch.setattr(store, "MAX_POINT_BYTES", npz.stat().st_size - 1)
    assert load_point(tmp_path, "p1") is None  # the npz alone is over the limit
    js.write_text(js.read_text() + " " * 2 * npz.stat().st_size)  # still valid JSON
    monkeypatch.setattr(store, "MAX_POINT_BYTES", js.stat().st_size - 1)
    assert npz.stat().st_size <= store.MAX_POINT_BYTES
    assert load_point(tmp_path, "p1") is None  # the JSON alone is over the limit
    monkeypatch.setattr(store, "MAX_POINT_BYTES", 2**30)
    assert load_point(tmp_path, "p1") is not None


def test_a_zip_bomb_member_is_refused_by_its_declared_size(tmp_path, monkeypatch):
    save_point(tmp_path, _result("p1"))
    npz = tmp_path / "points" / "p1.npz"
    # one highly compressible array: a small file that inflates past the limit
    np.savez_compressed(npz, t=np.arange(1, 20001, dtype=float), labels=np.array(LABELS))
    limit = 2 * max(npz.stat().st_size, (tmp_path / "points" / "p1.json").stat().st_size)
    assert 20000 * 8 > limit
    monkeypatch.setattr(store, "MAX_POINT_BYTES", limit)
    assert load_point(tmp_path, "p1") is None


# -- the manifest and the tables -----------------------------------------------------------


def test_manifest_lists_every_point_in_order(tmp_path):
    sweep = _sweep(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    path = write_manifest(sweep, out)
    assert path == out / "sweep.json"
    doc = json.loads(path.read_text())
    assert (doc["format"], doc["kind"], doc["name"]) == (FORMAT, "sweep", "small")
    assert doc["source"] == str(tmp_path / "sw.yaml") and doc["base"] == str(tmp_path / "sc.yaml")
    assert doc["keys"] == ["noise.sigma", "seed"]
    params = [p["params"] for p in doc["points"]]
    assert params == [
        {"noise.sigma": s, "seed": k} for s in (0.1, 0.3) for k in (0, 1)
    ]  # the grid's product, last key fastest
    assert [p["point"] for p in doc["points"]] == [t.point for t in sweep.tasks()]
    assert len({p["point"] for p in doc["points"]}) == 4


def test_tables_hold_one_row_per_point_in_sweep_order(tmp_path):
    sweep = _sweep(tmp_path)
    tasks = sweep.tasks()
    results = {t.point: _result(t.point, t.params, seed=k) for k, t in enumerate(tasks) if k != 2}
    out = tmp_path / "out"
    out.mkdir()
    written = write_tables(sweep, out, results)
    assert written == [out / "results.csv", out / "results.parquet", out / "curves.parquet"]
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written)

    table = pd.read_parquet(out / "results.parquet")
    assert list(table.columns) == ["noise.sigma", "seed", *ROW_FIELDS]
    assert table["point"].tolist() == [t.point for t in tasks]
    assert table["noise.sigma"].tolist() == [0.1, 0.1, 0.3, 0.3]
    assert table["seed"].tolist() == [0, 1, 0, 1]
    # the point that is missing gets an error row, the others their own values
    assert table["error"].isna().tolist() == [True, True, False, True]
    assert table["error"][2] == "not computed"
    np.testing.assert_array_equal(table["delta"], [1.5, 2.5, np.nan, 4.5])
    assert str(table["certified"].dtype) == "boolean"
    assert table["certified"].isna().tolist() == [False, False, True, False]
    assert str(table["paths"].dtype) == "Int64" and table["paths"][0] == 200
    assert table["delta"].dtype == float and table["wall_seconds"].dtype == float

    csv = pd.read_csv(out / "results.csv")
    assert list(csv.columns) == list(table.columns)
    assert csv["point"].tolist() == table["point"].tolist()


def test_curves_are_long_form_with_one_row_per_time_and_agent(tmp_path):
    sweep = _sweep(tmp_path)
    tasks = sweep.tasks()
    results = {t.point: _result(t.point, t.params, seed=k, s=3 + k) for k, t in enumerate(tasks)}
    out = tmp_path / "out"
    out.mkdir()
    write_tables(sweep, out, results)
    long = pd.read_parquet(out / "curves.parquet")
    assert list(long.columns) == ["point", "t", "agent", "mc", "lo", "hi", "exact"]
    assert len(long) == sum((3 + k) * 3 for k in range(4))
    for t in tasks:
        res = results[t.point]
        part = long[long["point"] == t.point]
        for _, r in part.sample(5, random_state=0).iterrows():
            k = int(np.flatnonzero(res.t == r["t"])[0])
            j = LABELS.index(r["agent"])
            assert (r["mc"], r["lo"], r["hi"]) == (res.mc[k, j], res.lo[k, j], res.hi[k, j])
            assert np.isnan(r["exact"])  # not computed: NaN, not a missing column
        assert part["t"].is_monotonic_increasing
        assert part["agent"].tolist()[:3] == LABELS


def test_no_results_give_error_rows_and_empty_curves(tmp_path):
    sweep = _sweep(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    write_tables(sweep, out, {})
    table = pd.read_csv(out / "results.csv")
    assert (table["error"] == "not computed").all() and len(table) == 4
    long = pd.read_parquet(out / "curves.parquet")
    assert len(long) == 0 and list(long.columns) == [
        "point",
        "t",
        "agent",
        "mc",
        "lo",
        "hi",
        "exact",
    ]
    assert long["t"].dtype == float and long["mc"].dtype == float


def test_a_point_without_curves_adds_no_curve_rows(tmp_path):
    sweep = _sweep(tmp_path)
    tasks = sweep.tasks()
    results = {tasks[0].point: _result(tasks[0].point, s=0)}  # no save times
    out = tmp_path / "out"
    out.mkdir()
    write_tables(sweep, out, results)
    assert len(pd.read_parquet(out / "curves.parquet")) == 0
    assert pd.read_csv(out / "results.csv")["error"].isna().tolist() == [True, False, False, False]


def test_a_swept_row_field_is_one_column(tmp_path):
    # "paths" is both a scenario key and a row field: shown once, with the swept value
    sweep = _sweep(tmp_path, grid="  paths: [10, 20]\n")
    tasks = sweep.tasks()
    results = {t.point: _result(t.point, t.params) for t in tasks}
    out = tmp_path / "out"
    out.mkdir()
    write_tables(sweep, out, results)
    table = pd.read_parquet(out / "results.parquet")
    assert list(table.columns).count("paths") == 1
    assert list(table.columns) == ["paths", *(f for f in ROW_FIELDS if f != "paths")]
    assert table["paths"].tolist() == [10, 20]


def _direct_sweep(tmp_path, values) -> Sweep:
    """A sweep over margin with the given values (built directly: the values are the
    table's business here, not the sweep file's)."""
    base = {"topology": "tiny.yaml", "theta": [1], "margin": 0.5}
    top = {"dim": 1, "agents": 2, "edges": [{"from": 1, "to": 2, "weight": [[1]]}]}
    points = tuple({"margin": v} for v in values)
    return Sweep(tmp_path / "sw.yaml", tmp_path / "sc.yaml", base, top, ("margin",), points, "d")


@pytest.mark.parametrize(
    "values, expected",
    [
        ([0.5, 1], [0.5, 1.0]),  # int and float stay numbers
        ([1, "a"], ["1", "a"]),  # mixed kinds become text (one type per Parquet column)
        ([True, 2], ["True", "2"]),
        ([[1, 2], {"a": 1}], ["[1, 2]", '{"a": 1}']),  # structured values as JSON text
        ([None, 0.5], [None, 0.5]),
    ],
)
def test_swept_values_become_one_typed_column(tmp_path, values, expected):
    sweep = _direct_sweep(tmp_path, values)
    out = tmp_path / "out"
    out.mkdir()
    write_tables(sweep, out, {})
    got = pd.read_parquet(out / "results.parquet")["margin"].tolist()
    assert [None if isinstance(v, float) and np.isnan(v) else v for v in got] == expected
