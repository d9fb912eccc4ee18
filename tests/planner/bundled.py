"""The bundled tasks planned once per test run (test helper).

``plan_task`` of a bundled task is deterministic (the same plan every run in one environment), so the tests that read a
bundled task's plan share one: :func:`planned` plans it the first time a test asks and returns the same
:class:`~qsplan.planner.plan.results.Plan` afterwards, or raises the same
:class:`~qsplan.planner.plan.results.PlanFailure` for a task without a plan.  Under pytest-xdist the workers of one
run share the plans too (:data:`SHARED`: the first to ask plans it, the others read its pickle).  Read them; never
change them (copy first).  The plan's task is :func:`bundled_task`'s object.  A test that plans under a monkeypatch,
or with options of its own, plans for itself.  ``tests/planner/conftest.py``'s ``bundled_plan`` fixture gives the
exported files of a bundled task (``qsplan plan``) instead, shared the same way.
"""

from __future__ import annotations

import pickle
from contextlib import contextmanager
from functools import cache
from pathlib import Path

try:
    import fcntl
except ImportError:  # not POSIX: each process plans for itself
    fcntl = None

__all__ = ["SHARED", "bundled_task", "held", "planned", "shared_root"]

#: The directory where the processes of one test run share their plans (set by ``tests/conftest.py`` in a
#: pytest-xdist worker); None: this process alone.
SHARED: Path | None = None


def shared_root(tmp_path_factory) -> Path:
    """The directory the processes of this test run share: beside each pytest-xdist worker's own temporary
    directory (their parent, made anew for each run), else this process's."""
    import os

    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") and fcntl is not None else base


@contextmanager
def held(lock: Path):
    """Inside, no other process of the run holds ``lock`` (an exclusive ``flock``; released when a process dies)."""
    if fcntl is None:
        yield
        return
    with open(lock, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _plan(name: str) -> tuple:
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.task import load_task, task_paths

    task = load_task(task_paths()[name])
    try:
        return task, plan_task(task), None
    except PlanFailure as exc:
        return task, None, exc


@cache
def _outcome(name: str) -> tuple:
    if SHARED is None or fcntl is None:
        return _plan(name)
    SHARED.mkdir(parents=True, exist_ok=True)
    path = SHARED / f"{name}.pickle"
    with held(SHARED / f"{name}.lock"):
        if path.is_file():
            plan = pickle.loads(path.read_bytes())
            return plan.task, plan, None
        task, plan, failure = _plan(name)
        if plan is not None:  # a refusal is not shared (a PlanFailure does not unpickle), and costs little
            try:
                path.write_bytes(pickle.dumps(plan, protocol=pickle.HIGHEST_PROTOCOL))
            except (pickle.PicklingError, TypeError, AttributeError):  # not shared: each process plans it
                pass
        return task, plan, failure


def bundled_task(name: str):
    """The bundled task ``name`` as :func:`planned` planned it (its plan's task)."""
    return _outcome(name)[0]


def planned(name: str):
    """``plan_task`` of the bundled task ``name`` (default options), once per test run; a refusal re-raised."""
    _, plan, failure = _outcome(name)
    if failure is not None:
        raise failure
    return plan
