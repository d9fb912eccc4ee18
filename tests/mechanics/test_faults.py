"""Faults while computing in parallel (issue 12): a local worker killed mid-run, a Dask worker
killed, a cluster without workers, a scheduler that accepts and never answers, malformed
addresses; and Ctrl-C while workers compute (issue 31).  Each ends in a result or a one-line
error after the timeout its message names, never a wait forever; how long each takes is not
asserted (wall times depend on the machine).  All sockets are on 127.0.0.1; every cluster and
server is started here."""

import json
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
    with pytest.raises(ParallelError, match="workers: a local worker process died .* and again in a new pool"):
        map_chunks(_exit_in_worker, [1, 2, 3], workers=2)


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
def test_malformed_scheduler_address_is_refused_at_once(address, why, monkeypatch):
    """Refused from the address alone: nothing is contacted (a probe or a client would fail this test)."""
    import distributed

    from qsplan.mechanics import cluster

    def contacted(*args, **kwargs):
        raise AssertionError("a scheduler was contacted")

    monkeypatch.setattr(cluster, "_probe", contacted)
    monkeypatch.setattr(distributed, "Client", contacted)
    with pytest.raises(QsplanError, match=f"^scheduler: {re.escape(address)} is not a Dask scheduler address .*{why}"):
        map_chunks(abs, [1], scheduler=address)


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
    assert main(["modes", "examples/scenes/eq42.json", "--scheduler", silent_server]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--scheduler: cannot reach a Dask scheduler at {silent_server} within 1 s" in err and "Traceback" not in err


# --- Dask: workers lost, no workers ---------------------------------------------------------


def test_cluster_without_workers_is_an_error_after_the_timeout(monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(parallel, "NO_PROGRESS_TIMEOUT", 2.0)
    with LocalCluster(n_workers=0, processes=True, dashboard_address=None, timeout=START_TIMEOUT) as cluster:
        with pytest.raises(ParallelError, match=r"no progress on the Dask cluster .* for 2 s \(no workers; 0 of 3"):
            map_chunks(abs, [1, 2, 3], scheduler=cluster.scheduler_address)


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
            with pytest.raises(ParallelError, match=r"no progress on the Dask cluster .* \(no workers"):
                map_chunks(_slow_double, list(range(6)), scheduler=cluster.scheduler_address)
        finally:
            worker.kill()
            worker.wait()


# --- Dask: an address where no scheduler can answer is one line, and nothing after it (issue 31) ----------


def _qsplan(*argv, **kwargs):
    """``qsplan ARGV`` in a subprocess (its finalisers run before it exits, so late output is caught)."""
    return subprocess.run([sys.executable, "-m", "qsplan.planner.cli", *argv], capture_output=True, text=True,
                          timeout=HANG_GUARD, **kwargs)  # fmt: skip


#: Seconds after which a subprocess counts as hung: a guard against a wait forever, not a speed claim.
HANG_GUARD = 300


@pytest.mark.parametrize("address, why", [
    ("inproc://x", "is not a Dask scheduler address such as tcp://host:8786 (expected inproc://host/pid/n"),
    ("inproc://127.0.0.1/1/1", "cannot reach a Dask scheduler at inproc://127.0.0.1/1/1 within 5 s"),
])  # fmt: skip
def test_unreachable_scheduler_is_one_line_and_nothing_after(tmp_path, address, why):
    """Before: the line, then 10 s later a ``Client.__del__`` ``TimeoutError`` traceback."""
    p = _qsplan("sweep", "--samples", "200", "--no-plots", "--out", str(tmp_path / "o"), "--scheduler", address)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and p.stderr.startswith(f"qsplan: error: --scheduler: ") and why in p.stderr


#: ``qsplan modes`` with the scheduler probe skipped, so that a Dask ``Client`` is built for an address where no
#: scheduler answers and its constructor fails (argv: the address).
_CLIENT_FAILS = """
import sys
from qsplan.mechanics import cluster
cluster._probe = lambda address, timeout: None
from qsplan.planner.cli.main import main
sys.exit(main(["modes", "examples/scenes/eq42.json", "--scheduler", sys.argv[1]]))
"""


def test_a_client_that_fails_to_start_is_closed_at_once():
    """The half-built client is closed by :func:`qsplan.mechanics.cluster.connect` itself, not left to its
    ``__del__`` (which waited 10 s for a stopped loop and printed a traceback)."""
    p = subprocess.run([sys.executable, "-c", _CLIENT_FAILS, "inproc://127.0.0.1/1/1"], capture_output=True, text=True,
                       timeout=HANG_GUARD)  # fmt: skip
    assert p.returncode == 2, p.stderr[-2000:]
    assert p.stderr.count("\n") == 1 and p.stderr.startswith("qsplan: error: --scheduler: cannot reach a Dask scheduler")


# --- Ctrl-C while local workers compute (issue 31) ------------------------------------------------------


def _pool_workers(pid: int) -> list:
    """The worker processes of ``pid``'s pool: its children running its own command line (forked)."""
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            children = f.read().split()
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            own = f.read()
        found = []
        for child in children:
            with open(f"/proc/{child}/cmdline", "rb") as f:
                if f.read() == own:
                    found.append(int(child))
        return found
    except OSError:  # the process or a child ended meanwhile
        return []


def _wait_for_workers(proc) -> list:
    deadline = time.monotonic() + HANG_GUARD
    while proc.poll() is None and time.monotonic() < deadline:
        workers = _pool_workers(proc.pid)
        if workers:
            return workers
        time.sleep(0.05)
    proc.kill()
    raise AssertionError(f"no worker pool appeared: {proc.communicate()[1][-1000:]}")


def _gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (reaped, or a zombie waiting for its parent)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def _interrupt(proc, workers, how):
    """Ctrl-C: at a terminal it reaches the whole foreground process group (the workers too); ``kill -INT`` reaches
    the command alone.  Returns the rest of stderr once the command has ended."""
    if how == "terminal":
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=HANG_GUARD)
    deadline = time.monotonic() + HANG_GUARD
    while not all(_gone(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(_gone(w) for w in workers), "a worker outlived the interrupted command"
    return err


pytestmark_linux = pytest.mark.skipif(not os.path.exists(f"/proc/{os.getpid()}/task/{os.getpid()}/children"),
                                      reason="finds the pool's workers through Linux's /proc")  # fmt: skip


@pytestmark_linux
@pytest.mark.parametrize("how", ["terminal", "kill"])
def test_ctrl_c_while_workers_compute_is_one_line(tmp_path, how):
    """Before: each worker printed its ``KeyboardInterrupt`` traceback (37 lines for two) above ``qsplan:
    interrupted``.  Now the workers ignore SIGINT, the command ends them and prints one line, exit 130."""
    from qsplan.mechanics.model.scene_io_write import scene_to_dict

    scene, _ = planted_scene(np.random.default_rng([1995, 16, 13]), 16, 13, 15)  # 5,196,627 modes: ~15 s on 2 workers
    path = tmp_path / "n16.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    argv = [sys.executable, "-m", "qsplan.planner.cli", "modes", str(path), "--search", "all", "--workers", "2"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, process_group=0)
    line = proc.stderr.readline()  # the long work announces itself, then the pool starts
    assert "this takes about" in line, line
    workers = _wait_for_workers(proc)
    err = _interrupt(proc, workers, how)
    assert proc.returncode == 130 and err == "qsplan: interrupted\n", err[-2000:]


@pytestmark_linux
@pytest.mark.slow
def test_ctrl_c_in_a_sweep_is_one_line(tmp_path):
    """The issue's command: ``qsplan sweep --samples 20000`` (no progress lines; its pools start after ~7 s)."""
    argv = [sys.executable, "-m", "qsplan.planner.cli", "sweep", "--samples", "20000", "--no-plots", "--out",
            str(tmp_path / "o")]  # fmt: skip
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, process_group=0)
    workers = _wait_for_workers(proc)
    err = _interrupt(proc, workers, "terminal")
    assert proc.returncode == 130 and err == "qsplan: interrupted\n", err[-2000:]


@pytestmark_linux
def test_workers_end_when_their_command_is_killed(tmp_path):
    """A command killed outright (SIGKILL: it cannot shut its pool down) takes its workers with it: each asked the
    kernel for SIGTERM at its parent's death (``mechanics.parallel``).  Before, they waited for a task forever."""
    from qsplan.mechanics.model.scene_io_write import scene_to_dict

    scene, _ = planted_scene(np.random.default_rng([1995, 16, 13]), 16, 13, 15)  # ~15 s of work on 2 workers
    path = tmp_path / "n16.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    argv = [sys.executable, "-m", "qsplan.planner.cli", "modes", str(path), "--search", "all", "--workers", "2"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, process_group=0)
    assert "this takes about" in proc.stderr.readline()
    workers = _wait_for_workers(proc)
    proc.kill()
    proc.communicate(timeout=HANG_GUARD)
    deadline = time.monotonic() + HANG_GUARD
    while not all(_gone(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(_gone(w) for w in workers), "a worker outlived its killed command"
