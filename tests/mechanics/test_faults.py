"""Faults while computing in parallel (issue 12): a local worker killed mid-run, a Dask worker
killed, a cluster without workers, a scheduler that accepts and never answers, malformed
addresses.  Each ends in a result or a one-line error within a stated time, never a wait.
All sockets are on 127.0.0.1; every cluster and server is started here."""

import multiprocessing
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from qsplan.mechanics import QsplanError, planted_scene, solve
from qsplan.mechanics import parallel
from qsplan.mechanics.errors import ParallelError
from qsplan.mechanics.parallel import first_difference, map_chunks
from qsplan.mechanics.solver import chunks as mode_chunks
from qsplan.planner.cli.main import main

#: Seconds the tests wait for their own cluster to start.
START_TIMEOUT = 30


def _exit_in_worker(x):
    """Kill the process running it, unless that is the test process itself."""
    if multiprocessing.parent_process() is not None:
        os._exit(3)
    return x


def _exit_once(item):
    """Kill the worker the first time (a marker file says it happened), then compute."""
    marker, x = item
    if multiprocessing.parent_process() is not None and not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(3)
    return -x


def _slow_double(x):
    time.sleep(0.5)
    return 2 * x


# --- local process pool ---------------------------------------------------------------------


def test_lost_local_worker_is_rerun_in_a_new_pool(tmp_path):
    marker = str(tmp_path / "died")
    assert map_chunks(_exit_once, [(marker, i) for i in range(6)], workers=2) == [-i for i in range(6)]
    assert os.path.exists(marker)  # a worker did die


def test_local_worker_lost_twice_is_one_error():
    t = time.perf_counter()
    with pytest.raises(ParallelError, match="workers: a local worker process died .* and again in a new pool"):
        map_chunks(_exit_in_worker, [1, 2, 3], workers=2)
    assert time.perf_counter() - t < 30


def test_lost_worker_exits_2_in_one_line(monkeypatch, capsys):
    monkeypatch.setattr(mode_chunks, "MIN_CHUNK_MODES", 1)
    monkeypatch.setattr(mode_chunks, "map_chunks", lambda fn, items, **kw: map_chunks(_exit_in_worker, items, **kw))
    assert main(["modes", "examples/scenes/eq42.json", "--search", "all", "--workers", "2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--workers: a local worker process died" in err and "Traceback" not in err


# --- Dask: addresses and a scheduler that never answers -------------------------------------


@pytest.mark.parametrize("address, why", [
    ("foo", "missing port"), ("http://127.0.0.1:8786", "unknown scheme 'http'"),
    ("tcp://127.0.0.1:99999", "port in 1..65535"), ("localhost:abc", "invalid literal"),
])  # fmt: skip
def test_malformed_scheduler_address_is_refused_at_once(address, why):
    t = time.perf_counter()
    with pytest.raises(QsplanError, match=f"^scheduler: {re.escape(address)} is not a Dask scheduler address .*{why}"):
        map_chunks(abs, [1], scheduler=address)
    assert time.perf_counter() - t < 2


@pytest.fixture
def silent_server():
    """A TCP server on 127.0.0.1 that accepts connections and never sends a byte."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    held = []

    def accept():
        while True:
            try:
                held.append(srv.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    srv.close()
    for c in held:
        c.close()


def test_scheduler_that_never_answers_is_an_error_after_the_timeout(monkeypatch, silent_server, capsys):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1.0)
    t = time.perf_counter()
    assert main(["modes", "examples/scenes/eq42.json", "--scheduler", silent_server]) == 2
    assert time.perf_counter() - t < 10
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--scheduler: cannot reach a Dask scheduler at {silent_server} within 1 s" in err and "Traceback" not in err


# --- Dask: workers lost, no workers ---------------------------------------------------------


def test_cluster_without_workers_is_an_error_after_the_timeout(monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(parallel, "NO_PROGRESS_TIMEOUT", 2.0)
    with LocalCluster(n_workers=0, processes=True, dashboard_address=None, timeout=START_TIMEOUT) as cluster:
        t = time.perf_counter()
        with pytest.raises(ParallelError, match=r"no progress on the Dask cluster .* for 2 s \(no workers; 0 of 3"):
            map_chunks(abs, [1, 2, 3], scheduler=cluster.scheduler_address)
        assert time.perf_counter() - t < 15


def test_timeout_from_the_environment(monkeypatch):
    monkeypatch.setenv("QSPLAN_NO_PROGRESS_TIMEOUT", "7.5")
    assert parallel.no_progress_timeout() == 7.5
    monkeypatch.setenv("QSPLAN_NO_PROGRESS_TIMEOUT", "forever")
    with pytest.raises(QsplanError, match="QSPLAN_NO_PROGRESS_TIMEOUT: expected a positive number"):
        parallel.no_progress_timeout()


@pytest.mark.slow
def test_killed_dask_worker_is_restarted_and_results_are_identical():
    """A LocalCluster's nanny restarts a killed worker and the scheduler reruns its chunk: same bits."""
    from distributed import Client, LocalCluster

    scene, _ = planted_scene(np.random.default_rng(1995), 9, 6, 8)
    ref = solve(scene, batch=512, workers=1, search="all", keep_statuses=True)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                      timeout=START_TIMEOUT) as cluster, Client(cluster, set_as_default=False) as client:  # fmt: skip
        pid = next(iter(client.run(os.getpid).values()))
        assert map_chunks(_slow_double, [0, 1], scheduler=client) == [0, 2]  # warm
        killer = threading.Timer(0.7, os.kill, (pid, signal.SIGKILL))
        killer.start()
        assert map_chunks(_slow_double, list(range(4)), scheduler=client) == [0, 2, 4, 6]
        killer.join()
        got = solve(scene, batch=512, keep_statuses=True, search="all", scheduler=client)
    assert first_difference(got, ref) is None


def test_only_worker_killed_is_an_error_after_the_timeout(monkeypatch):
    """A worker without a nanny (``dask worker --no-nanny``) killed mid-run leaves no worker."""
    from distributed import LocalCluster

    monkeypatch.setattr(parallel, "NO_PROGRESS_TIMEOUT", 2.0)
    with LocalCluster(n_workers=0, processes=True, dashboard_address=None, timeout=START_TIMEOUT) as cluster:
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", cluster.scheduler_address,
                                   "--no-nanny", "--nthreads", "1"], stderr=subprocess.DEVNULL)  # fmt: skip
        try:
            deadline = time.monotonic() + START_TIMEOUT
            while not cluster.scheduler.workers and time.monotonic() < deadline:
                time.sleep(0.1)
            killer = threading.Timer(0.8, worker.kill)
            killer.start()
            t = time.perf_counter()
            with pytest.raises(ParallelError, match=r"no progress on the Dask cluster .* \(no workers"):
                map_chunks(_slow_double, list(range(6)), scheduler=cluster.scheduler_address)
            assert time.perf_counter() - t < 20
        finally:
            worker.kill()
            worker.wait()
