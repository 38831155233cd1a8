"""Sweeps and Monte Carlo on a real Dask cluster: a scheduler and two worker processes on
127.0.0.1 (LocalCluster with processes), one worker killed mid-sweep, resumption after an
interrupted run, and bit-identical Monte Carlo through the scheduler."""

import os
import signal
import socket
import time
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from ntc_design import distributed as dist
from ntc_design.distributed import DaskEngine, LocalEngine
from ntc_design.errors import InputError
from ntc_design.rows import fmt
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import load_scenario
from ntc_design.sweep import MAX_POINTS, load_sweep, run_sweep

from .cli_helpers import assert_input_error, run_cli

TOPOLOGY = """name: tiny
dim: 1
agents: 3
edges:
  - {from: 1, to: 2, weight: [[1]]}
  - {from: 2, to: 3, weight: [[-1]]}
  - {from: 3, to: 1, weight: [[2]]}
"""
SCENARIO = """topology: tiny.yaml
theta: [1]
margin: 0.5
noise: {sigma: 0.3, f: 0.2}
initial: {uniform: [-1, 1], seed: 1}
T: 1
dt: 0.01
paths: 200
block_size: 50
"""
SWEEP = """base: sc.yaml
grid:
  noise.sigma: [0.1, 0.3]
  seed: [0, 1, 2, 3]
"""
# columns that legitimately differ between runs: who ran a point and how long it took
VOLATILE = ["wall_seconds", "worker"]


@pytest.fixture(scope="module")
def sweep_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("sweep")
    (d / "tiny.yaml").write_text(TOPOLOGY)
    (d / "sc.yaml").write_text(SCENARIO)
    (d / "sw.yaml").write_text(SWEEP)
    return d


@pytest.fixture(scope="module")
def sweep_reference(sweep_files):
    """The sweep run here, undisturbed, with no cluster."""
    out = sweep_files / "ref"
    res = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (res.points, res.computed, res.failed) == (8, 8, 0)
    return out


@pytest.fixture(scope="module")
def cluster():
    """A scheduler and two single-threaded worker processes on the loopback interface."""
    from distributed import Client, LocalCluster

    cl = LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    )
    client = Client(cl)
    try:
        yield client
    finally:
        client.close()
        cl.close()


def _stable(path) -> pd.DataFrame:
    return pd.read_csv(path).drop(columns=VOLATILE)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.slow
def test_sweep_on_cluster_survives_a_killed_worker(sweep_files, sweep_reference, cluster):
    addr = cluster.scheduler.address
    assert addr.startswith("tcp://127.0.0.1:")
    pids = cluster.run(os.getpid)
    assert len(pids) == 2
    killed: list[int] = []

    def kill_a_busy_worker(state) -> None:
        if killed or state.path_steps_done == 0:
            return
        busy = [w for w, keys in cluster.processing().items() if keys and w in pids]
        if busy:
            killed.append(pids[busy[0]])
            os.kill(pids[busy[0]], signal.SIGKILL)

    out = sweep_files / "cluster"
    with DaskEngine(cluster) as eng:
        res = run_sweep(sweep_files / "sw.yaml", out, engine=eng, progress=kill_a_busy_worker)
    assert killed, "no worker was busy to kill"
    assert not _alive(killed[0])
    assert (res.points, res.computed, res.failed) == (8, 8, 0)
    # the same numbers as the undisturbed local run: every row and every curve
    pd.testing.assert_frame_equal(
        _stable(out / "results.csv"), _stable(sweep_reference / "results.csv")
    )
    pd.testing.assert_frame_equal(
        pd.read_parquet(out / "curves.parquet"), pd.read_parquet(sweep_reference / "curves.parquet")
    )
    table = pd.read_csv(out / "results.csv")
    assert table["worker"].str.startswith("tcp://127.0.0.1:").all()
    assert table["error"].isna().all() and table["certified"].all()
    # the mean-square error grows with the noise intensity (exact moments)
    ex = table.groupby("noise.sigma")["ms_final_exact"].first()
    assert ex[0.3] > ex[0.1]


def test_monte_carlo_bit_identical_through_the_scheduler(sweep_files, cluster):
    top, spec, _ = load_scenario(sweep_files / "sc.yaml")
    # 6 blocks, the last one short
    spec = spec.replace(mc=replace(spec.mc, paths=230, block_size=40), method="mc")
    local1 = simulate(top, spec.replace(mc=replace(spec.mc, workers=1)))
    local2 = simulate(top, spec.replace(mc=replace(spec.mc, workers=2)))
    for chunk in (1, 4):
        with DaskEngine(cluster, blocks_per_chunk=chunk) as eng:
            remote = simulate(top, spec, engine=eng)
        assert remote.stats.engine["engine"] == "dask"
        for key in ("mean", "lo", "hi", "mean_state", "paths"):
            got = getattr(remote.mc, key)
            assert np.array_equal(got, getattr(local1.mc, key)), (chunk, key)
            assert np.array_equal(got, getattr(local2.mc, key)), (chunk, key)


def test_cli_simulate_with_scheduler_matches_local(
    sweep_files, cluster, tmp_path, capsys, monkeypatch
):
    sc = sweep_files / "sc.yaml"
    code, _, err = run_cli(["simulate", sc, "--out", tmp_path / "local"], capsys, monkeypatch)
    assert code == 0, err
    args = ["simulate", sc, "--out", tmp_path / "dask", "--scheduler", cluster.scheduler.address]
    code, out, err = run_cli(args, capsys, monkeypatch)
    assert code == 0, err
    local = (tmp_path / "local" / "ms_error.csv").read_text()
    assert (tmp_path / "dask" / "ms_error.csv").read_text() == local


def test_interrupted_sweep_resumes_to_the_same_results(sweep_files, sweep_reference, tmp_path):
    out = tmp_path / "resumed"

    def stop_after_three(state) -> None:
        if state.points_done >= 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep_files / "sw.yaml", out, workers=1, progress=stop_after_three)
    assert len(list((out / "points").glob("*.json"))) == 3
    assert not (out / "results.csv").exists()
    assert not list(out.rglob("*.tmp*"))  # nothing half-written
    res = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (res.computed, res.reused) == (5, 3)
    assert _stable(out / "results.csv").equals(_stable(sweep_reference / "results.csv"))
    # a third run computes nothing
    again = run_sweep(sweep_files / "sw.yaml", out, workers=1)
    assert (again.computed, again.reused) == (0, 8)


def test_a_failing_point_is_a_row_and_the_others_go_on(sweep_files, tmp_path, capsys, monkeypatch):
    sw = tmp_path / "bad.yaml"
    sw.write_text(
        f"base: {sweep_files / 'sc.yaml'}\n"
        "points:\n"
        "  - {noise.sigma: 0.2}\n"
        "  - {noise.sigma: -1}\n"  # a bad parameter
        "  - {margin: 50, dt: 0.1}\n"  # Euler–Maruyama unstable at this step
        "  - {noise.sigma: 0.3, seed: 5}\n"
    )
    code, out, err = run_cli(["sweep", sw, "--out", tmp_path / "o"], capsys, monkeypatch)
    assert code == 1, err
    assert "2 failed" in out
    table = pd.read_csv(tmp_path / "o" / "results.csv")
    assert list(table.columns[:4]) == ["noise.sigma", "margin", "dt", "seed"]
    assert table["margin"].tolist() == [0.5, 0.5, 50, 0.5]  # the base's value where unset
    assert table["error"].notna().tolist() == [False, True, True, False]
    assert "noise.sigma: must be >= 0" in table["error"][1]
    assert "unstable" in table["error"][2]
    assert np.isfinite(table["ms_final_mc"][[0, 3]]).all()
    # plain progress lines on a non-terminal stderr (a batch job)
    assert "sweep: 4/4 points (2 failed" in err


def test_report_of_a_sweep_directory(sweep_reference, capsys, monkeypatch):
    code, out, err = run_cli(["report", sweep_reference], capsys, monkeypatch)
    assert code == 0, err
    html = (sweep_reference / "report.html").read_text()
    for needle in ('href="results.csv"', 'href="results.parquet"', 'href="curves.parquet"'):
        assert needle in html
    assert html.count("data:image/png;base64,") == 3  # noise.sigma, seed, the overlay
    assert html.count("<tr>") == 1 + 8  # header + one row per point
    assert (sweep_reference / "figures" / "sweep_ms_vs_noise_sigma.png").is_file()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.hostile
def test_unreachable_scheduler_is_one_line(sweep_files, tmp_path, capsys, monkeypatch):
    import distributed

    monkeypatch.setattr(dist, "CONNECT_TIMEOUT", 1.0)
    timeouts = []
    real = distributed.Client

    def client(*a, **kw):  # the bound on the wait: every connection carries the timeout
        timeouts.append(kw.get("timeout"))
        return real(*a, **kw)

    monkeypatch.setattr(distributed, "Client", client)
    addr = f"tcp://127.0.0.1:{_free_port()}"
    for cmd in (
        ["simulate", sweep_files / "sc.yaml", "--out", tmp_path / "a"],
        ["sweep", sweep_files / "sw.yaml", "--out", tmp_path / "b"],
    ):
        assert_input_error([*cmd, "--scheduler", addr], capsys, monkeypatch, "--scheduler", addr)
    assert timeouts == [1.0, 1.0]  # one attempt per command, each bounded
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.mark.hostile
def test_a_service_that_is_not_dask_is_one_line(sweep_files, tmp_path, capsys, monkeypatch):
    """A non-Dask service at the address: its reply was read as a frame length of
    exabytes (MemoryError, reported as 'out of memory')."""
    import threading

    monkeypatch.setattr(dist, "CONNECT_TIMEOUT", 2.0)
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    stop = threading.Event()

    def answer():
        srv.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except OSError:
                continue
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n" * 4)
            time.sleep(0.5)
            conn.close()

    th = threading.Thread(target=answer, daemon=True)
    th.start()
    addr = f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    try:
        line = assert_input_error(
            ["sweep", sweep_files / "sw.yaml", "--out", tmp_path / "b", "--scheduler", addr],
            capsys,
            monkeypatch,
            "--scheduler",
            addr,
        )
    finally:
        stop.set()
        th.join()
        srv.close()
    assert "out of memory" not in line
    assert not (tmp_path / "b").exists()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "body, needles",
    [
        ("base: sc.yaml\ngrid: {seed: [0]}\nextra: 1\n", ["extra", "unknown field"]),
        ("base: sc.yaml\ngrid: {noise.sgima: [0.1]}\n", ["grid.noise.sgima", "no such field"]),
        ("base: sc.yaml\ngrid: {sigma: [0.1]}\n", ["grid.sigma", "not a scenario field"]),
        ("base: sc.yaml\ngrid: {workers: [1, 2]}\n", ["grid.workers", "not a scenario field"]),
        ("base: sc.yaml\ngrid: {seed: []}\n", ["grid.seed", "non-empty list"]),
        ("base: sc.yaml\ngrid: {seed: 3}\n", ["grid.seed", "non-empty list"]),
        ("base: sc.yaml\ngrid: {}\n", ["grid", "non-empty mapping"]),
        ("base: sc.yaml\n", ["grid", "exactly one"]),
        ("base: sc.yaml\ngrid: {seed: [0]}\npoints: [{seed: 1}]\n", ["exactly one"]),
        ("base: nope.yaml\ngrid: {seed: [0]}\n", ["base", "no such file"]),
        ("grid: {seed: [0]}\n", ["base", "expected the path"]),
        ("base: sc.yaml\npoints: []\n", ["points", "non-empty list"]),
        ("base: sc.yaml\npoints: [{seed: 1}, 3]\n", ["points[1]", "mapping"]),
        ("base: sc.yaml\npoints: [{seed: 1}, {seed: 1}]\n", ["points", "repeats point 0"]),
        (
            "base: sc.yaml\ngrid: {noise: [{sigma: 1}], noise.sigma: [0.1]}\n",
            ["noise.sigma", "conflicts"],
        ),
        ("base: sc.yaml\ngrid: {seed: [1, 2]\n", ["not valid YAML"]),
        # a trailing dot used to set all of noise to each value: every point failed
        ('base: sc.yaml\ngrid: {"noise.": [0.1, 0.2]}\n', ["grid.noise.", "no such field"]),
        ('base: sc.yaml\npoints: [{"noise.": 0.1}]\n', ["points[0].noise.", "no such field"]),
        ('base: sc.yaml\ngrid: {"initial.": [1]}\n', ["grid.initial.", "no such field"]),
        # a name that is not text used to be used as its repr
        ("name: [1]\nbase: sc.yaml\ngrid: {seed: [0]}\n", ["name", "expected text, got list"]),
        ("description: {a: 1}\nbase: sc.yaml\ngrid: {seed: [0]}\n", ["description", "text"]),
    ],
)
def test_bad_sweep_files(sweep_files, tmp_path, capsys, monkeypatch, body, needles):
    (tmp_path / "sc.yaml").write_text((sweep_files / "sc.yaml").read_text())
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    sw = tmp_path / "sw.yaml"
    sw.write_text(body)
    assert_input_error(["sweep", sw, "--out", tmp_path / "o"], capsys, monkeypatch, *needles)
    assert not (tmp_path / "o").exists()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "opts, needles",
    [
        (["--workers", "0"], ["--workers", "must be a positive integer, got 0"]),
        (["--workers", "-1"], ["--workers", "must be a positive integer, got -1"]),
        (["--workers", "1000000"], ["--workers", "at most 4096"]),
        (["--scheduler", ""], ["--scheduler", "expected an address"]),
        (["--scheduler", "  "], ["--scheduler", "expected an address"]),
        (["--scheduler", "tcp://127.0.0.1:1", "--workers", "0"], ["--workers", "positive"]),
    ],
    ids=["workers-0", "workers--1", "workers-1e6", "scheduler-empty", "scheduler-blank", "both"],
)
def test_bad_sweep_options_are_refused_before_any_point(
    sweep_files, tmp_path, capsys, monkeypatch, opts, needles
):
    """Every point used to fail with the same error (workers), or the empty address was
    taken as 'no scheduler', and out/ was written either way."""

    def no_point(*args, **kw):
        raise AssertionError("a point ran")

    monkeypatch.setattr("ntc_design.sweep.run.run_point", no_point)
    out = tmp_path / "o"
    assert_input_error(
        ["sweep", sweep_files / "sw.yaml", "--out", out, *opts], capsys, monkeypatch, *needles
    )
    assert not out.exists()


@pytest.mark.hostile
def test_bad_workers_and_scheduler_in_the_api(sweep_files, tmp_path):
    with pytest.raises(InputError, match="--workers: must be a positive integer"):
        dist.LocalEngine(0)  # used to run on 2 processes
    with pytest.raises(InputError, match="--scheduler: expected an address"):
        dist.engine_for("")
    with pytest.raises(InputError, match="--workers: must be at most 4096"):
        run_sweep(sweep_files / "sw.yaml", tmp_path / "o", workers=10**6)
    assert not (tmp_path / "o").exists()


@pytest.mark.hostile
def test_too_many_points_is_refused_before_anything_runs(sweep_files, tmp_path):
    sw = tmp_path / "big.yaml"
    n = int(MAX_POINTS**0.5) + 1
    sw.write_text(
        f"base: {sweep_files / 'sc.yaml'}\ngrid:\n  seed: {list(range(n))}\n  margin: {[0.1 * (k + 1) for k in range(n)]}\n"
    )
    with pytest.raises(Exception, match=f"{n * n} points; at most {MAX_POINTS}"):
        load_sweep(sw)


@pytest.mark.hostile
def test_initial_seed_needs_a_mapping_initial(sweep_files, tmp_path):
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO.replace("{uniform: [-1, 1], seed: 1}", "[0, 1, 2]"))
    (tmp_path / "sw.yaml").write_text("base: sc.yaml\ngrid: {initial.seed: [1, 2]}\n")
    with pytest.raises(Exception, match="initial.seed: the base scenario's initial"):
        load_sweep(tmp_path / "sw.yaml")


def test_point_hash_depends_on_resolved_parameters_only(tmp_path):
    """The same resolved parameters are the same point whichever sweep lists them (so a
    point computed by one sweep is reused by another); an edited topology file is not."""
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY)
    (tmp_path / "sc.yaml").write_text(SCENARIO)
    (tmp_path / "a.yaml").write_text("base: sc.yaml\npoints: [{margin: 0.5}, {margin: 0.7}]\n")
    (tmp_path / "b.yaml").write_text("base: sc.yaml\ngrid: {margin: [0.7], T: [1]}\n")
    a = [t.point for t in load_sweep(tmp_path / "a.yaml").tasks()]
    b = [t.point for t in load_sweep(tmp_path / "b.yaml").tasks()]
    assert len(set(a)) == 2 and b == a[1:]  # T: 1 is the base's own value
    (tmp_path / "tiny.yaml").write_text(TOPOLOGY.replace("[[2]]", "[[3]]"))
    assert [t.point for t in load_sweep(tmp_path / "b.yaml").tasks()] != b


def test_local_engine_runs_in_process():
    eng = LocalEngine(1)
    got = list(eng.map_unordered(lambda x, progress, remote: (x, remote), [("a", (1,))]))
    assert got == [("a", (1, False), None)]


def test_sweep_report_shows_every_point(sweep_files, sweep_reference, tmp_path):
    """``ntc report`` on a sweep folder: one table row per point (its hash and its final
    error as in results.csv), a figure per swept key with two or more values plus the
    overlay, each also written to figures/."""
    import shutil

    import pandas as pd

    from ntc_design.reports.sweep import write_sweep_report

    d = tmp_path / "sw"
    shutil.copytree(sweep_reference, d)
    out = write_sweep_report(d)
    page = out.read_text(encoding="utf-8")
    table = pd.read_csv(d / "results.csv")
    body = page.split('id="points-table"')[1]
    assert body.count("<tr>") == len(table) + 1  # the header and one row per point
    for point, ms in zip(table["point"], table["ms_final_mc"], strict=True):
        assert point in body and fmt(float(ms), 5) in body
    swept = [
        k for k in ("noise.sigma", "margin", "seed", "T") if k in table and table[k].nunique() > 1
    ]
    assert page.count("<img") == len(swept) + 1
    assert len(list((d / "figures").glob("sweep_*.png"))) == len(swept) + 1


def test_worker_tasks_take_large_allocations_from_the_heap():
    """Dask's nanny pins glibc's mmap threshold at 128 KiB (MALLOC_TRIM_THRESHOLD_); a
    task raises it once per process: mallopt accepts it on glibc, and the call is cached."""
    import ctypes
    import platform

    from ntc_design import distributed as dist

    dist._heap_set = None
    got = dist.heap_allocations()
    if platform.system() == "Linux" and platform.libc_ver()[0] == "glibc":
        assert got is True
        assert ctypes.CDLL(None).mallopt(-3, dist.MMAP_THRESHOLD) == 1  # a value glibc takes
    assert dist.heap_allocations() is got and dist._heap_set is got


def test_heap_allocations_without_glibc_is_a_no_op(monkeypatch):
    """Windows: ctypes.CDLL(None) raises TypeError; elsewhere no mallopt: AttributeError.
    Either way a task goes on (False), never fails."""
    import ctypes

    from ntc_design import distributed as dist

    for exc in (TypeError, AttributeError, OSError):

        def cdll(_name, exc=exc):
            raise exc("no libc here")

        monkeypatch.setattr(ctypes, "CDLL", cdll)
        dist._heap_set = None
        assert dist.heap_allocations() is False
    dist._heap_set = None
