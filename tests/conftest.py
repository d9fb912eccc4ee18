"""Settings of the whole suite."""

import os

import pytest

#: The BLAS thread limit this process applies (kept: a limit lasts while its object does).
_BLAS_LIMIT = []


def _sigint_as_at_a_terminal():
    """SIGINT at its default action here, so that the processes the Ctrl-C tests start see it as at a terminal.

    A command started in the background of a non-interactive shell (``cmd &`` in a script, as some CI runners start
    jobs) begins with SIGINT ignored (POSIX), and every process it starts inherits that: Python then installs no
    handler, and a ``qsplan`` the tests interrupt runs to its end (exit 0) instead of exiting 130.  An ignored SIGINT
    is given Python's own handler back (``signal.default_int_handler``, which a child's ``exec`` resets to the
    default); a handler set otherwise is left alone."""
    import signal

    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        try:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        except ValueError:  # not the main thread of its process: nothing this process can set
            pass


def pytest_configure(config):
    """Under pytest-xdist (the README's ``-n auto``), each worker's BLAS gets its share of the cores.

    Every worker already keeps a core busy: OpenBLAS's own threads (one per core by default) then fight the other
    workers for the cores (the mechanics and hands tests took ~15 % more CPU time with them on two workers).  The
    limit also reaches the processes a test starts (``OPENBLAS_NUM_THREADS``, unless already set).  Results do not
    change: the tests compare to stated tolerances, and the plans' byte-identity is between runs of one process."""
    _sigint_as_at_a_terminal()  # every process of the run: the controller and each worker
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT") or 1)
    if workers <= 1:
        return
    threads = max(1, (os.cpu_count() or 1) // workers)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", str(threads))  # read when a BLAS library loads
    import numpy  # noqa: F401 - loaded here, so that the limit below reaches it
    from threadpoolctl import threadpool_limits

    _BLAS_LIMIT.append(threadpool_limits(limits=threads, user_api="blas"))


@pytest.fixture(scope="session", autouse=True)
def _plans_shared_by_the_workers(tmp_path_factory):
    """The bundled tasks' plans shared by the processes of one run (``tests/planner/bundled.py``)."""
    from tests.planner import bundled

    bundled.SHARED = bundled.shared_root(tmp_path_factory) / "bundled_plans"
