"""A Dask cluster that fails in one line: connecting with a bounded handshake, gathering with a progress watch.

:func:`qsplan.mechanics.parallel.map_chunks` sends chunks to a Dask scheduler through
these two functions.  Dask itself waits forever in three situations seen in practice:
a scheduler that accepts a connection and never answers (``Client(timeout=...)`` does not
bound the handshake), a cluster with no worker left (tasks queue indefinitely), and
a scheduler that dies mid-run (the client keeps reconnecting).  Here each becomes a
:class:`qsplan.mechanics.errors.ParallelError` (or a ``QsplanError`` for an address that
cannot be one) after a stated time.  A worker that dies is Dask's to retry (its nanny
restarts it and the scheduler reruns the task, up to ``allowed-failures`` times): only
when it gives up (``KilledWorker``) or no worker remains is it an error.
"""

from __future__ import annotations

import asyncio
import logging
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

from qsplan.mechanics.errors import ParallelError, QsplanError

__all__ = ["POLL_SECONDS", "check_address", "connect", "gather_with_progress", "quiet_dask_logs"]

#: Seconds between two looks at the futures: short against any chunk worth sending (~0.1 s).
POLL_SECONDS = 0.05


@contextmanager
def quiet_dask_logs():
    """Only critical records from Dask's loggers meanwhile: a failure is reported once, as our error.

    Used around a client this package opened itself (a ``--scheduler`` address): Dask logs a lost
    scheduler or worker on stderr, which would add lines to the command's one-line error.
    """
    import distributed  # noqa: F401 - creates its loggers, so that they are all quieted

    names = ["distributed", *(n for n in logging.root.manager.loggerDict if n.startswith("distributed."))]
    saved = {n: logging.getLogger(n).level for n in names}
    for n in names:
        logging.getLogger(n).setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for n, level in saved.items():
            logging.getLogger(n).setLevel(level)


def check_address(address: str) -> None:
    """Raise a one-line :class:`QsplanError` when ``address`` cannot be a Dask scheduler's address.

    Accepts ``[scheme://]host:port`` with a scheme Dask knows (tcp, tls, ws, wss, ucx, inproc),
    for tcp and tls a port in 1..65535, and for inproc ``inproc://host/pid/n`` (a scheduler in
    this very process: ``LocalCluster(processes=False).scheduler_address``).
    """
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.registry import backends

    try:
        scheme, loc = parse_address(address)
        if scheme not in backends:
            raise ValueError(f"unknown scheme {scheme!r}; expected one of {', '.join(sorted(backends))}")
        if scheme in ("tcp", "tls"):
            host, port = parse_host_port(loc)
            if not host or not 0 < int(port) < 65536:
                raise ValueError(f"expected host:port with a port in 1..65535; got {loc!r}")
        if scheme == "inproc":
            parts = loc.split("/")
            if len(parts) != 3 or not (parts[0] and parts[1].isdigit() and parts[2].isdigit()):
                raise ValueError(f"expected inproc://host/pid/n, a scheduler in this process; got {loc!r}")
    except (ValueError, TypeError) as exc:
        raise QsplanError(
            f"scheduler: {address} is not a Dask scheduler address such as tcp://host:8786 ({exc})"
        ) from None


def _probe(address: str, timeout: float):
    """Ask the scheduler at ``address`` who it is, the whole exchange bounded by ``timeout`` s."""

    async def ask():
        from distributed.comm import connect as comm_connect
        from distributed.security import Security

        # the connection arguments a Client would use (TLS from Dask's configuration)
        comm = await comm_connect(address, timeout=timeout, **Security().get_connection_args("client"))
        try:
            await comm.write({"op": "identity"})
            return await comm.read()
        finally:
            comm.abort()

    async def bounded():
        return await asyncio.wait_for(ask(), timeout)

    # a thread of its own: the caller may already run an event loop (a notebook)
    with ThreadPoolExecutor(max_workers=1) as ex:
        return ex.submit(asyncio.run, bounded()).result()


def _client(address: str, timeout: float):
    """``Client(address)``, closed here when its constructor raises.

    A ``Client`` whose start failed is closed by its ``__del__`` at the next garbage collection, which
    waits out twice the timeout for a loop that has stopped and then prints a ``TimeoutError``
    traceback (10 s after ``qsplan: error: ...``).  Allocating it first keeps a handle to close it now.
    """
    from distributed import Client

    client = Client.__new__(Client)
    try:
        client.__init__(address, timeout=timeout, set_as_default=False)
    except BaseException:
        try:
            client.close(timeout=timeout)
        except Exception:  # noqa: BLE001 - the constructor's error is the one reported
            pass
        raise
    return client


def connect(address: str, timeout: float):
    """A Dask ``Client`` for the scheduler at ``address``, or a one-line error within about ``timeout`` s.

    The scheduler is asked who it is first (every scheme), so that no ``Client`` is built where none
    answers: ``Client(timeout=...)`` does not bound the handshake.

    Raises
    ------
    QsplanError
        A malformed address, or no scheduler answering there within ``timeout`` s.
    """
    check_address(address)
    try:
        _probe(address, timeout)
    except (OSError, asyncio.TimeoutError, TimeoutError, ValueError, TypeError) as exc:
        why = str(exc) or type(exc).__name__
        if isinstance(exc, (asyncio.TimeoutError, TimeoutError)):
            why = "connected or tried to, but no answer"
        raise QsplanError(
            f"scheduler: cannot reach a Dask scheduler at {address} within {timeout:g} s ({why})"
        ) from None
    try:
        return _client(address, timeout)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise QsplanError(
            f"scheduler: cannot reach a Dask scheduler at {address} within {timeout:g} s ({exc})"
        ) from None


def _running(client, keys, timeout: float):
    """``(workers, ours)``: workers the scheduler knows and how many of ``keys`` run on one; None if it does not answer."""
    try:
        processing = client.sync(client.scheduler.processing, callback_timeout=timeout)
    except Exception:  # noqa: BLE001 - any failure to answer is "does not answer"
        return None
    return len(processing), sum(1 for ks in processing.values() for k in ks if k in keys)


def gather_with_progress(client, futures, address: str, timeout: float, progress=None) -> list:
    """The results of ``futures`` in order, or :class:`ParallelError` once the cluster stalls.

    The cluster stalls when for ``timeout`` seconds no chunk finished and none was running
    on a worker: no workers, workers lost and not replaced, or a scheduler that stopped
    answering.  A long chunk that is running keeps the wait alive.  Exceptions raised by
    the chunk function propagate unchanged.  ``progress(done, total, "chunks")`` is called
    as chunks finish.
    """
    from distributed import KilledWorker

    keys = {f.key for f in futures}
    done, since = 0, time.monotonic()
    while True:
        states = [f.status for f in futures]
        if "error" in states or states.count("finished") == len(states):
            break
        if "cancelled" in states:  # ("lost": a result died with its worker; the scheduler recomputes it)
            raise ParallelError(f"scheduler: the connection to the Dask scheduler at {address} was lost "
                                f"({states.count('finished')} of {len(futures)} chunks done); rerun when the cluster "
                                f"is up, or without a scheduler")  # fmt: skip
        now = time.monotonic()
        if states.count("finished") > done:
            done, since = states.count("finished"), now
            if progress:
                progress(done, len(futures), "chunks")
        elif now - since > timeout:
            seen = _running(client, keys, timeout)
            if seen is None:
                raise ParallelError(f"scheduler: the Dask scheduler at {address} stopped answering; {done} of "
                                    f"{len(futures)} chunks done after {timeout:g} s without progress")  # fmt: skip
            if seen[1] == 0:
                who = "no workers" if seen[0] == 0 else f"{seen[0]} workers, none running a chunk of this job"
                raise ParallelError(f"scheduler: no progress on the Dask cluster at {address} for {timeout:g} s "
                                    f"({who}; {done} of {len(futures)} chunks done)")  # fmt: skip
            since = now  # a long chunk under way
        time.sleep(POLL_SECONDS)
    try:
        return client.gather(futures)
    except KilledWorker as exc:
        raise ParallelError(f"scheduler: Dask workers at {address} died running a chunk and the scheduler gave up "
                            f"({exc})") from None  # fmt: skip
