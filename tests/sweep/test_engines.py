"""Tests of :mod:`ntc_design.sweep.engines`."""

import os
import signal
import socket
import time
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from ntc_design.errors import InputError
from ntc_design.simulate import simulate
from ntc_design.simulate.scenario import load_scenario
from ntc_design.sweep import engines as dist
from ntc_design.sweep import run_sweep
from ntc_design.sweep.engines import DaskEngine, LocalEngine
from tests.cli_helpers import assert_input_error, run_cli
from tests.support.distributed import _stable


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
    # 6 blocks, the last one short (small blocks: the split, not the statistics, is checked)
    spec = spec.replace(mc=replace(spec.mc, paths=55, block_size=10), method="mc")
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


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.hostile
def test_unreachable_scheduler_is_one_line(sweep_files, tmp_path, capsys, monkeypatch):
    import distributed

    monkeypatch.setattr(dist, "CONNECT_TIMEOUT", 0.5)
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
    assert timeouts == [0.5, 0.5]  # one attempt per command, each bounded
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
    # the Python caller's names (ntc sweep names the flags: tests/cli)
    with pytest.raises(InputError, match="^workers: must be a positive integer"):
        dist.LocalEngine(0)  # used to run on 2 processes
    with pytest.raises(InputError, match="^scheduler: expected an address"):
        dist.engine_for("")
    with pytest.raises(InputError, match="^workers: must be at most 4096"):
        run_sweep(sweep_files / "sw.yaml", tmp_path / "o", workers=10**6)
    assert not (tmp_path / "o").exists()


def test_local_engine_runs_in_process():
    eng = LocalEngine(1)
    got = list(eng.map_unordered(lambda x, progress, remote: (x, remote), [("a", (1,))]))
    assert got == [("a", (1, False), None)]


def test_worker_tasks_take_large_allocations_from_the_heap():
    """Dask's nanny pins glibc's mmap threshold at 128 KiB (MALLOC_TRIM_THRESHOLD_); a
    task raises it once per process: mallopt accepts it on glibc, and the call is cached."""
    import ctypes
    import platform

    from ntc_design.sweep import engines as dist

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

    from ntc_design.sweep import engines as dist

    for exc in (TypeError, AttributeError, OSError):

        def cdll(_name, exc=exc):
            raise exc("no libc here")

        monkeypatch.setattr(ctypes, "CDLL", cdll)
        dist._heap_set = None
        assert dist.heap_allocations() is False
    dist._heap_set = None
