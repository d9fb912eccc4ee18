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
import os
import pickle
import threading
from contextlib import contextmanager
from functools import partial

from qsplan.mechanics.errors import ParallelError, QsplanError

# multiprocessing, concurrent.futures and the Dask helpers (asyncio, ssl) are imported where a pool
# or a cluster is used: ~45 ms that a command solving in-process (`qsplan modes` up to n_c ~ 16) skips.

__all__ = [
    "map_chunks",
    "chunk_count",
    "resolve_workers",
    "split_range",
    "first_difference",
    "no_progress_timeout",
    "CONNECT_TIMEOUT",
    "NO_PROGRESS_TIMEOUT",
    "MAX_CLUSTER_CHUNKS",
]

#: Seconds to wait for a Dask scheduler to answer: long enough for a cluster on a
#: local network, short enough that a mistyped ``--scheduler`` fails promptly.
CONNECT_TIMEOUT = 5.0

#: Seconds a Dask cluster may go with no chunk finished and none running before the wait is an
#: error (:func:`qsplan.mechanics.cluster.gather_with_progress`): a nanny restarts a lost worker
#: in a few seconds and the scheduler reassigns its chunk at once, so a minute without any chunk
#: running means no worker is coming; a chunk still running (however long) keeps the wait alive.
#: Set ``QSPLAN_NO_PROGRESS_TIMEOUT`` for clusters whose workers take longer to join.
NO_PROGRESS_TIMEOUT = 60.0

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


_MISSING = object()


def _worker_start(parent: int | None = None):
    """Pool initializer: Ctrl-C ignored, one BLAS thread per worker process, ended with ``parent`` (its pid).

    Ctrl-C at a terminal signals the whole foreground process group, the workers too: each would
    print a ``KeyboardInterrupt`` traceback (37 lines for ``qsplan sweep`` on two workers).  The parent
    alone answers it (:func:`_stop_pool`, then ``qsplan: interrupted``); a worker is started with
    SIGINT blocked (:func:`_sigint_held`), ignores it here, then unblocks it (a pending one is dropped).

    The workers already fill the cores; a forked worker would otherwise keep the
    parent's BLAS thread pool, and two workers with two BLAS threads each ran the
    n_c = 12..14 mode solves 0.75-0.86x as fast as one process instead of 1.5-1.9x
    (benchmarks/bench_parallel.py).  Dask's workers do the same by default.
    """
    import signal

    from threadpoolctl import threadpool_limits

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    _die_with_parent(parent)
    threadpool_limits(limits=1)


#: ``prctl`` option asking the kernel to signal this process when its parent dies (Linux, ``<sys/prctl.h>``).
_PR_SET_PDEATHSIG = 1


def _die_with_parent(parent: int | None = None) -> None:
    """Linux: this worker gets SIGTERM when the process that started it dies.

    A parent killed (SIGTERM, SIGKILL: not a Ctrl-C, which :func:`_stop_pool` answers) never shuts its pool down, and
    its workers, blocked reading their next task, would live on forever.  A parent that died between the fork and
    this request sends no signal (the worker has already been handed to another parent): with ``parent``, the pid
    that forked this worker, that is seen and the worker ends here.  Elsewhere nothing is done (the workers end when
    their pipe to the parent breaks at their next task)."""
    import sys

    if not sys.platform.startswith("linux"):
        return
    import ctypes
    import signal

    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):  # no libc prctl: the old behaviour
        return
    if parent is not None and os.getppid() != parent:  # the parent died before the request: as if signalled
        os.kill(os.getpid(), signal.SIGTERM)


@contextmanager
def _sigint_held():
    """SIGINT blocked in this thread meanwhile, and delivered when the block ends (never lost).

    Worker processes and the executor's thread started meanwhile inherit the block (fork, and the
    exec of spawn and of the forkserver keep a signal mask), so no Ctrl-C reaches a worker before
    :func:`_worker_start` ignores it.
    """
    import signal

    if not hasattr(signal, "pthread_sigmask"):  # not POSIX: workers get no process-group Ctrl-C
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


#: Seconds a worker process is given to end after SIGTERM before it is killed (a worker computing
#: ends at once: nothing of ours handles SIGTERM).
STOP_SECONDS = 5.0


def _stop_pool(ex) -> None:
    """Cancel the chunks not started and end the worker processes now.

    For a Ctrl-C or a chunk that raised: the remaining results are moot, and the executor's own
    shutdown (its ``with`` block's end) would run every queued chunk first.  The workers are the
    executor's ``_processes`` (Python has no public handle on them before 3.14's ``terminate_workers``).
    """
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        p.terminate()
    for p in procs:
        p.join(STOP_SECONDS)
        if p.is_alive():
            p.kill()
            p.join()


def _pool_context():
    # fork starts a worker in ~10 ms instead of ~0.5 s (spawn re-imports numpy and
    # scipy), but forking a process that runs other threads (a Dask client's event
    # loop, say) can deadlock the child, so only fork a single-threaded process.
    import multiprocessing

    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def _in_daemon() -> bool:
    import multiprocessing

    return multiprocessing.current_process().daemon


def _check_client(scheduler):
    """``scheduler`` when it is a Dask client (a caller's, not ours to close); else a named error."""
    if not (hasattr(scheduler, "map") and hasattr(scheduler, "gather")):
        raise QsplanError(
            f"scheduler: expected an address such as 'tcp://host:8786' or a dask.distributed Client; "
            f"got {type(scheduler).__name__}"
        )
    return scheduler


def no_progress_timeout() -> float:
    """:data:`NO_PROGRESS_TIMEOUT`, or the environment's ``QSPLAN_NO_PROGRESS_TIMEOUT`` (seconds) when set."""
    raw = os.environ.get("QSPLAN_NO_PROGRESS_TIMEOUT")
    if raw is None:
        return NO_PROGRESS_TIMEOUT
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise QsplanError(f"QSPLAN_NO_PROGRESS_TIMEOUT: expected a positive number of seconds; got {raw!r}")
    return value


def _in_pool(fn, items: list, n: int, progress=None) -> list:
    """``[fn(item) ...]`` on ``n`` local processes; a pool that breaks is replaced once for the missing items.

    A Ctrl-C (``KeyboardInterrupt`` here; the workers ignore it) or an exception of ``fn`` ends the
    workers at once (:func:`_stop_pool`) and propagates.
    """
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    results: list = [_MISSING] * len(items)
    todo = list(range(len(items)))
    for attempt in (1, 2):
        ex, futures = None, []
        try:
            with _sigint_held():  # the workers start inside: none sees a Ctrl-C before it ignores them
                context = _pool_context()
                # the pid that starts each worker: this process, but the forkserver's own under forkserver
                parent = None if context.get_start_method() == "forkserver" else os.getpid()
                ex = ProcessPoolExecutor(max_workers=min(n, len(todo)), mp_context=context,
                                         initializer=_worker_start, initargs=(parent,))  # fmt: skip
                futures = [(i, ex.submit(fn, items[i])) for i in todo]
            for i, f in futures:  # in order: the first exception of fn propagates, as in a loop
                results[i] = f.result()
                if progress:
                    progress(sum(r is not _MISSING for r in results), len(items), "chunks")
        except BrokenProcessPool:
            for i, f in futures:
                if f.done() and not f.cancelled() and f.exception() is None:
                    results[i] = f.result()
            todo = [i for i in todo if results[i] is _MISSING]
            ex.shutdown(wait=True)
            continue
        except BaseException:  # KeyboardInterrupt, fn's exception
            if ex is not None:
                _stop_pool(ex)
            raise
        ex.shutdown(wait=True)
        return results
    raise ParallelError(
        f"workers: a local worker process died (killed, or out of memory) while running {len(todo)} of "
        f"{len(items)} chunks, and again in a new pool; rerun with workers=1 to compute in this process"
    )


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


def _on_cluster(client, fn, items: list, address: str, timeout: float, progress) -> list:
    from qsplan.mechanics.cluster import gather_with_progress

    payloads = [pickle.dumps(item, protocol=_PROTOCOL) for item in items]
    futures = client.map(partial(_call_unpickled, fn), payloads, pure=False)
    return gather_with_progress(client, futures, address, timeout, progress)


def map_chunks(fn, items, *, workers=None, scheduler=None, progress=None) -> list:
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
    progress : callable, optional
        ``progress(done, total, "chunks")`` each time another chunk is done.
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
        Bad ``workers``; a malformed scheduler address, or one where no scheduler answers
        within :data:`CONNECT_TIMEOUT`; Dask not installed.
    ParallelError
        A local worker process died, and again when its chunks were rerun in a new pool;
        a cluster on which, for :func:`no_progress_timeout` seconds, no chunk finished or
        ran (no workers, workers lost, a scheduler that stopped answering), or whose
        scheduler gave up after workers died.  Exceptions raised by ``fn`` propagate unchanged.
    """
    items = list(items)
    if scheduler is not None:
        timeout = no_progress_timeout()
        if not isinstance(scheduler, str):
            client = _check_client(scheduler)
            address = getattr(getattr(client, "scheduler", None), "address", "the client's")
            return _on_cluster(client, fn, items, address, timeout, progress)
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise QsplanError(
                f"scheduler: {scheduler} needs Dask distributed; install it with: pip install 'qsplan[cluster]'"
            ) from None
        from qsplan.mechanics.cluster import connect, quiet_dask_logs

        with quiet_dask_logs():
            client = connect(scheduler, CONNECT_TIMEOUT)
            try:
                return _on_cluster(client, fn, items, scheduler, timeout, progress)
            finally:
                try:
                    client.close(timeout=CONNECT_TIMEOUT)
                except Exception:  # noqa: BLE001 - a dead scheduler: the error raised above says so
                    pass
    n = min(resolve_workers(workers), len(items))
    if n <= 1 or _in_daemon():  # a daemon (a Dask worker) may not start processes
        out = []
        for item in items:
            out.append(fn(item))
            if progress:
                progress(len(out), len(items), "chunks")
        return out
    return _in_pool(fn, items, n, progress)


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
