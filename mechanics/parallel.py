"""Independent chunks of work on all local cores or on a Dask distributed cluster.

Mode testing, mu-space maps and trajectory sweeps split into chunks that share
nothing: each chunk is one call of a top-level function on one picklable item.
:func:`map_chunks` runs such calls in-process, on a local process pool, or on a
Dask cluster, and returns the results in input order, so the merged result is
the same as the single-process one whatever runs it (callers split their work
along the same batches the single-process code uses, so even floating-point
results are bit-identical).

Why Dask ``distributed`` rather than Ray: a pure-Python wheel of a few MB (Ray is
a large binary wheel per platform), a ``LocalCluster`` the tests can start in a
second, and ``Client.map`` takes plain functions and numpy arguments as they are.
It is an optional dependency (``pip install qsplan[cluster]``), imported only
when a scheduler is given.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import pickle
import threading
from concurrent.futures import ProcessPoolExecutor
from functools import partial

from qsplan.mechanics.errors import QsplanError

__all__ = [
    "map_chunks",
    "chunk_count",
    "resolve_workers",
    "split_range",
    "first_difference",
    "CONNECT_TIMEOUT",
    "MAX_CLUSTER_CHUNKS",
]

#: Seconds to wait for a Dask scheduler to answer: long enough for a cluster on a
#: local network, short enough that a mistyped ``--scheduler`` fails promptly.
CONNECT_TIMEOUT = 5.0

#: Chunks sent to a cluster when ``workers`` does not say: enough to keep a few dozen
#: workers busy and balanced, few enough that per-task overhead (~ms) stays negligible.
MAX_CLUSTER_CHUNKS = 64


def resolve_workers(workers) -> int:
    """Number of local processes: ``None`` means all cores (``os.cpu_count()``).

    Raises
    ------
    QsplanError
        ``workers`` is not a positive integer.
    """
    if workers is None:
        return os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise QsplanError(f"workers: expected a positive integer (1 runs in-process); got {workers!r}")
    return workers


def split_range(n: int, parts: int) -> list[tuple[int, int]]:
    """``range(n)`` as at most ``parts`` contiguous, nonempty ``(lo, hi)`` pieces of near-equal size."""
    parts = max(1, min(parts, n))
    edges = [n * i // parts for i in range(parts + 1)]
    return [(lo, hi) for lo, hi in zip(edges[:-1], edges[1:]) if hi > lo]


def chunk_count(n_units: int, min_units: int, *, workers=None, scheduler=None) -> int:
    """Into how many chunks to split ``n_units`` of work: one per worker, none under ``min_units``.

    The rule that keeps small jobs in-process: a chunk must hold at least ``min_units``
    (each caller sizes it at ~0.1 s of work, several times the start-up of a local
    pool), so work under ``2 min_units`` gives 1, and one chunk runs in-process.

    Parameters
    ----------
    n_units : int
        Size of the work (points, samples, batches: whatever the caller splits).
    min_units : int
        Smallest chunk worth sending to another process.
    workers : int or None
        Local processes (``None``: all cores); with a scheduler, the number of chunks
        to send (``None``: up to :data:`MAX_CLUSTER_CHUNKS`).
    scheduler : str or Client or None
    """
    if scheduler is None:
        cap = resolve_workers(workers)
    else:
        cap = MAX_CLUSTER_CHUNKS if workers is None else resolve_workers(workers)
    return max(1, min(cap, n_units // max(1, min_units)))


def _one_blas_thread():
    """Pool initializer: one BLAS thread per worker process.

    The workers already fill the cores; a forked worker would otherwise keep the
    parent's BLAS thread pool, and two workers with two BLAS threads each ran the
    n_c = 12..14 mode solves 0.75-0.86x as fast as one process instead of 1.5-1.9x
    (benchmarks/bench_parallel.py).  Dask's workers do the same by default.
    """
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)


def _pool_context():
    # fork starts a worker in ~10 ms instead of ~0.5 s (spawn re-imports numpy and
    # scipy), but forking a process that runs other threads (a Dask client's event
    # loop, say) can deadlock the child, so only fork a single-threaded process.
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def _client(scheduler):
    """A connected Dask client for ``scheduler`` and whether we own (must close) it."""
    if not isinstance(scheduler, str):
        if not (hasattr(scheduler, "map") and hasattr(scheduler, "gather")):
            raise QsplanError(
                f"scheduler: expected an address such as 'tcp://host:8786' or a dask.distributed Client; "
                f"got {type(scheduler).__name__}"
            )
        return scheduler, False
    try:
        from distributed import Client
    except ImportError:
        raise QsplanError(
            f"--scheduler {scheduler}: needs Dask distributed; install it with: pip install 'qsplan[cluster]'"
        ) from None
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False), True
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise QsplanError(
            f"--scheduler {scheduler}: cannot reach a Dask scheduler within {CONNECT_TIMEOUT:g} s ({exc})"
        ) from None


#: Protocol 4 rebuilds numpy arrays by copying into memory numpy allocates, as a local
#: pool (multiprocessing's default protocol) does.
_PROTOCOL = 4


def _call_unpickled(fn, payload: bytes):
    """``fn(item)`` for a pickled item, on a Dask worker.

    Dask's own serialisation hands numpy arrays over as views of its network frames,
    whose alignment differs from numpy's allocations; BLAS kernels then sum in another
    order and the last bits change (seen in the residuals of eq. 2).  Unpickling here
    gives the arrays a local pool's worker would get, so the results are identical.
    """
    return fn(pickle.loads(payload))


def map_chunks(fn, items, *, workers=None, scheduler=None) -> list:
    """``[fn(item) for item in items]``, computed in parallel, in input order.

    Parameters
    ----------
    fn : callable
        A top-level (importable, picklable) function of one argument.
    items : iterable
        Picklable arguments, one per chunk of work.
    workers : int or None
        Local processes; ``None`` means all cores, 1 means in-process (no pool).
        A single item, or a call from a daemon process, runs in-process.  Ignored
        when ``scheduler`` is given (callers then use it as the number of chunks:
        :func:`chunk_count`).
    scheduler : str or dask.distributed.Client or None
        Address of a Dask scheduler (``"tcp://host:8786"``) or a connected client:
        the chunks run on that cluster.  A client passed in is left open.

    Returns
    -------
    list
        ``fn(item)`` for every item, in the order of ``items``.

    Raises
    ------
    QsplanError
        Bad ``workers``; a scheduler that cannot be reached within
        :data:`CONNECT_TIMEOUT`; Dask not installed.  Exceptions raised by ``fn``
        propagate unchanged.
    """
    items = list(items)
    if scheduler is not None:
        client, owned = _client(scheduler)
        payloads = [pickle.dumps(item, protocol=_PROTOCOL) for item in items]
        try:
            return client.gather(client.map(partial(_call_unpickled, fn), payloads, pure=False))
        finally:
            if owned:
                client.close()
    n = min(resolve_workers(workers), len(items))
    if n <= 1 or multiprocessing.current_process().daemon:  # a daemon (a Dask worker) may not start processes
        return [fn(item) for item in items]
    with ProcessPoolExecutor(max_workers=n, mp_context=_pool_context(), initializer=_one_blas_thread) as ex:
        return list(ex.map(fn, items))


def first_difference(a, b, path: str = "result", skip=("scene", "samples")) -> str | None:
    """Where two results first differ, or None when they are exactly equal.

    For checking a chunked result against the single-process one: dataclasses field
    by field (``skip`` names inputs passed through, compared by the caller if at all),
    dicts in key order, sequences, numpy arrays by dtype, shape and every element
    (NaN equal to NaN), anything else by ``==``.
    """
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return path
        for f in dataclasses.fields(a):
            if f.name not in skip:
                d = first_difference(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}", skip)
                if d:
                    return d
        return None
    if isinstance(a, dict):
        if not isinstance(b, dict) or list(a) != list(b):
            return path
        return next((d for k in a if (d := first_difference(a[k], b[k], f"{path}[{k!r}]", skip))), None)
    if isinstance(a, (tuple, list)):
        if not isinstance(b, (tuple, list)) or len(a) != len(b):
            return path
        return next((d for i, (x, y) in enumerate(zip(a, b)) if (d := first_difference(x, y, f"{path}[{i}]", skip))), None)
    if hasattr(a, "dtype") and hasattr(a, "shape"):
        import numpy as np

        ok = (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
              and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))  # fmt: skip
        return None if ok else path
    return None if (a == b or (a != a and b != b)) else path  # NaN equals NaN here
