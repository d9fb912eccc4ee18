"""Settings of the whole suite."""

import os

import pytest

#: The BLAS thread limit this process applies (kept: a limit lasts while its object does).
_BLAS_LIMIT = []


def pytest_configure(config):
    """Under pytest-xdist (the README's ``-n auto``), each worker's BLAS gets its share of the cores.

    Every worker already keeps a core busy: OpenBLAS's own threads (one per core by default) then fight the other
    workers for the cores (the mechanics and hands tests took ~15 % more CPU time with them on two workers).  The
    limit also reaches the processes a test starts (``OPENBLAS_NUM_THREADS``, unless already set).  Results do not
    change: the tests compare to stated tolerances, and the plans' byte-identity is between runs of one process."""
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
