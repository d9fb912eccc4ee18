"""Chunked work (qsplan.mechanics.parallel): a local process pool and a Dask LocalCluster started here
give exactly the single-process results for modes, mu-space maps and torque-band sweeps."""

import math
import operator
import socket
import sys
from functools import partial

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq42_scene
from qsplan.hands.paper_hand.segments import first_segment, sample_segment
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import QsplanError, scene_from_dict, solve
from qsplan.mechanics import parallel
from qsplan.mechanics.muspace import maps as muspace
from qsplan.mechanics.solver import chunks as mode_chunks
from qsplan.mechanics.muspace.maps import feasibility_map, grid_points
from qsplan.mechanics.muspace.slices import mu_slice
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES
from qsplan.mechanics.parallel import chunk_count, first_difference, map_chunks, split_range
from qsplan.mechanics.modes.planted import planted_scene
from qsplan.planner.torque import sweep as bands_sweep
from qsplan.planner.torque.sweep import segment_bands
from qsplan.planner.cli.main import main

#: Seconds to wait for the test's own cluster, and for the unreachable one.
CLUSTER_TIMEOUT = 30


@pytest.fixture(scope="module")
def client():
    """A Dask client on a two-process LocalCluster, started once for the module."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           timeout=CLUSTER_TIMEOUT)  # fmt: skip
    c = Client(cluster, timeout=CLUSTER_TIMEOUT, set_as_default=False)
    yield c
    c.close()
    cluster.close()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def same(a, b):
    assert first_difference(a, b) is None, first_difference(a, b)


# --- map_chunks and the chunking rule -------------------------------------------------------


@pytest.mark.parametrize("workers", [1, 2, None])
def test_map_chunks_keeps_input_order(workers):
    items = list(range(-7, 13))
    assert map_chunks(operator.neg, items, workers=workers) == [-i for i in items]


def test_map_chunks_on_cluster_keeps_input_order(client):
    items = [float(i) for i in range(20)]
    assert map_chunks(math.sqrt, items, scheduler=client) == [math.sqrt(x) for x in items]
    assert map_chunks(math.sqrt, items, scheduler=client.scheduler.address) == [math.sqrt(x) for x in items]


def test_pool_inside_a_cluster_worker_runs_in_process(client):
    # a Dask worker is a daemon process, which may not start a pool of its own
    nested = partial(map_chunks, workers=2)
    assert client.submit(nested, operator.neg, [1, 2, 3], pure=False).result(timeout=CLUSTER_TIMEOUT) == [-1, -2, -3]


def test_errors_in_chunks_propagate():
    with pytest.raises(ValueError, match="math domain error"):
        map_chunks(math.sqrt, [1.0, -1.0], workers=2)


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_bad_workers(workers):
    with pytest.raises(QsplanError, match="workers: expected a positive integer"):
        map_chunks(abs, [1, 2], workers=workers)


def test_bad_scheduler_object():
    with pytest.raises(QsplanError, match="scheduler: expected an address"):
        map_chunks(abs, [1], scheduler=42)


def test_unreachable_scheduler_is_a_clean_error(monkeypatch):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 0.5)
    address = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(QsplanError, match=f"^scheduler: cannot reach a Dask scheduler at {address}"):
        map_chunks(abs, [1], scheduler=address)


def test_missing_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    with pytest.raises(QsplanError, match=r"needs Dask distributed; install it with: pip install 'qsplan\[cluster\]'"):
        map_chunks(abs, [1], scheduler="tcp://127.0.0.1:8786")


def test_unreachable_scheduler_exits_2(monkeypatch, capsys):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 0.5)
    address = f"tcp://127.0.0.1:{_free_port()}"
    assert main(["modes", "examples/scenes/eq42.json", "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--scheduler: cannot reach a Dask scheduler at {address}" in err and "Traceback" not in err


@pytest.mark.parametrize("command", [["modes", "examples/scenes/eq42.json"], ["sweep", "--no-plots"],
                                     ["muspace", "examples/scenes/eq42.json", "--x", "mu1", "--y", "mu2",
                                      "--range", "0", "1", "--n", "5"]])  # fmt: skip
def test_cli_bad_workers_exits_2(command, capsys, tmp_path):
    assert main(command + ["--workers", "0"]) == 2
    assert "--workers: expected " in capsys.readouterr().err


def test_first_difference_finds_the_first_mismatch():
    a = {"x": (np.array([1.0, np.nan]), 3), "y": "z"}
    assert first_difference(a, {"x": (np.array([1.0, np.nan]), 3), "y": "z"}) is None
    assert first_difference(a, {"x": (np.array([1.0, 2.0]), 3), "y": "z"}) == "result['x'][0]"
    assert first_difference(a, {"x": (np.array([1, 0]), 3), "y": "z"}) == "result['x'][0]"  # dtype
    assert first_difference(a, {"x": (np.array([1.0, np.nan]), 4), "y": "z"}) == "result['x'][1]"
    assert first_difference(a, {"y": "z", "x": (np.array([1.0, np.nan]), 3)}) == "result"


@pytest.mark.parametrize("n, parts", [(0, 3), (1, 4), (7, 3), (10, 10), (5, 1), (100, 7)])
def test_split_range_covers_in_order(n, parts):
    pieces = split_range(n, parts)
    assert [i for lo, hi in pieces for i in range(lo, hi)] == list(range(n))
    assert all(hi > lo for lo, hi in pieces) and len(pieces) <= max(parts, 1)
    sizes = [hi - lo for lo, hi in pieces]
    assert not sizes or max(sizes) - min(sizes) <= 1


def test_chunk_count_rule():
    assert chunk_count(99, 100, workers=8) == 1  # too little work: in-process
    assert chunk_count(199, 100, workers=8) == 1
    assert chunk_count(200, 100, workers=8) == 2
    assert chunk_count(10**6, 100, workers=3) == 3  # one per worker
    assert chunk_count(10**6, 100, workers=1) == 1
    assert chunk_count(10**6, 100, scheduler="tcp://x:1") == parallel.MAX_CLUSTER_CHUNKS
    assert chunk_count(10**6, 100, workers=5, scheduler="tcp://x:1") == 5


def test_small_scene_solves_in_process():
    scene = scene_from_dict(eq42_scene(0.5))
    assert mode_chunks.solve_in_chunks(scene, DEFAULT_TOLERANCES, 8192, True, False, workers=2) is None


# --- identical results: modes, mu-space maps, sweeps ------------------------------------------


@pytest.fixture
def chunks_sent(monkeypatch):
    """Number of chunks each map_chunks call of the chunked modules got: the work was really split."""
    sent = []

    def spy(fn, items, **kw):
        items = list(items)
        sent.append(len(items))
        return map_chunks(fn, items, **kw)

    for module in (mode_chunks, muspace, bands_sweep):
        monkeypatch.setattr(module, "map_chunks", spy)
    return sent


@pytest.fixture(scope="module")
def mode_scene():
    """A seeded scene with 73789 modes (n_c = 12, 3 + |tau_I| = 12) and a planted feasible mode.

    With this seed, arrays as Dask delivers them (unaligned views of its frames) changed
    the last bits of a residual of eq. (2): the test caught that before map_chunks unpickled
    the items itself."""
    scene, planted = planted_scene(np.random.default_rng(1995), 12, 9, 11)
    return scene, planted


@pytest.fixture(scope="module")
def mode_reference(mode_scene):
    return solve(mode_scene[0], batch=4096, keep_statuses=True, workers=1)


def _chunked_solve(monkeypatch, scene, **kw):
    monkeypatch.setattr(mode_chunks, "MIN_CHUNK_MODES", 1)  # split even this small scene
    return solve(scene, batch=4096, keep_statuses=True, **kw)


def test_modes_identical_on_pool(monkeypatch, chunks_sent, mode_scene, mode_reference):
    scene, planted = mode_scene
    assert planted.letters in mode_reference.feasible_modes  # the independent check: the planted mode is found
    same(_chunked_solve(monkeypatch, scene, workers=2), mode_reference)
    assert chunks_sent == [2]


def test_modes_identical_on_cluster(monkeypatch, chunks_sent, client, mode_scene, mode_reference):
    same(_chunked_solve(monkeypatch, mode_scene[0], scheduler=client), mode_reference)
    assert chunks_sent and chunks_sent[0] > 2


@pytest.fixture(scope="module")
def mu_grid():
    scene = scene_from_dict(eq42_scene(0.5))
    xs = np.linspace(0.0, 1.5, 61)
    return scene, xs, feasibility_map(scene, grid_points(scene.mu, 0, 1, xs, xs), workers=1)


@pytest.mark.parametrize("where", ["pool", "cluster"])
def test_feasibility_map_identical(where, monkeypatch, chunks_sent, request, mu_grid):
    scene, xs, ref = mu_grid
    kw = {"workers": 2} if where == "pool" else {"scheduler": request.getfixturevalue("client"), "workers": 3}
    monkeypatch.setattr(muspace, "MIN_CHUNK_ROWS", 1000)
    assert ref.feasible.any() and ref.ambiguous.any()  # a map worth comparing: several regions
    same(feasibility_map(scene, ref.mu, **kw), ref)
    assert chunks_sent == [kw["workers"]]


@pytest.mark.parametrize("where", ["pool", "cluster"])
def test_polynomial_slice_identical(where, monkeypatch, chunks_sent, request, mu_grid):
    scene, xs, ref = mu_grid
    one = mu_slice(scene, 0, 1, xs, xs, workers=1)
    kw = {"workers": 2} if where == "pool" else {"scheduler": request.getfixturevalue("client")}
    monkeypatch.setattr(muspace, "MIN_CHUNK_POLYNOMIAL_ROWS", 1000)
    split = mu_slice(scene, 0, 1, xs, xs, **kw)
    same(split.mumap, one.mumap)
    assert chunks_sent and chunks_sent[0] >= 2
    for a, b in zip(one.regions, split.regions):
        np.testing.assert_array_equal(a.contains(ref.mu), b.contains(ref.mu))


@pytest.fixture(scope="module")
def segment_samples():
    return sample_segment(first_segment(default_hand()), 24)


@pytest.fixture(scope="module")
def bands_reference(segment_samples):
    return segment_bands(segment_samples, workers=1)


@pytest.mark.parametrize("where", ["pool", "cluster"])
def test_sweep_identical(where, monkeypatch, chunks_sent, request, segment_samples, bands_reference):
    monkeypatch.setattr(bands_sweep, "MIN_CHUNK_SAMPLES", 5)
    monkeypatch.setattr(bands_sweep, "MIN_CHUNK_KINEMATIC_SAMPLES", 5)
    kw = {"workers": 2} if where == "pool" else {"scheduler": request.getfixturevalue("client"), "workers": 4}
    sb = segment_bands(segment_samples, **kw)
    assert bands_reference.guaranteed.band.feasible.any()
    same(sb, bands_reference)
    assert chunks_sent == [min(kw["workers"], 4)] * 2  # competing modes, then the bands
