"""Every planner ``qsplan plan --planner`` offers returns (PRM used to hang forever), and the ones that search in a
second thread are stopped by OMPL's own timer, never by a Python callable.  How long each takes against its
``--time-limit`` is measured by ``benchmarks/bench_time_limits.py`` (a table, not a test: wall times depend on the
machine and its load)."""

import subprocess
import sys

import pytest

from qsplan.planner.search.ompl_bridge import PLANNERS, TIMED_PLANNERS, PlannerOptions, plan_path

pytestmark = pytest.mark.ompl

#: One 5 mm segment of the default workpiece: one OMPL query, no regrasp.
TASK = """
name = "one short segment"
[hand]
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
[motion]
start_x = 0.0
waypoints = [-0.005]
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""

#: Seconds per OMPL query.
LIMIT = 0.5

#: Seconds after which the subprocess counts as hung: a guard against "forever" (PRM's old hang), far above any
#: run of this one-segment task on a loaded machine; not a speed claim.
HANG_GUARD = 300


@pytest.mark.slow
@pytest.mark.parametrize("planner", PLANNERS)
def test_plan_returns_with_any_planner(planner, tmp_path):
    task = tmp_path / "t.toml"
    task.write_text(TASK)
    cmd = [sys.executable, "-m", "qsplan.planner.cli", "plan", str(task), "--planner", planner, "--time-limit",
           str(LIMIT), "--out", str(tmp_path / "o"), "--no-plots", "--verify", "0"]  # fmt: skip
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=HANG_GUARD)
    # planned, or refused in one line with a report (a slow planner may find no path in half a second)
    assert p.returncode in (0, 2), p.stderr
    if p.returncode == 2:
        assert "no plan: " in p.stderr and (tmp_path / "o" / "failure.json").exists()


@pytest.mark.parametrize("planner", TIMED_PLANNERS)
def test_timed_planners_stop_by_time_and_refuse_a_python_objective(planner, monkeypatch):
    """A query with no path (an obstacle across the only dimension) ends by OMPL's timer at the time limit: the
    timer is the only termination condition given, no Python callable is, and the result says it ran out
    (approximate at best, never exact)."""
    from ompl import base as ob

    timers, callables = [], []
    timed, python = ob.timedPlannerTerminationCondition, ob.PlannerTerminationCondition
    monkeypatch.setattr(ob, "timedPlannerTerminationCondition", lambda s: timers.append(s) or timed(s))
    monkeypatch.setattr(ob, "PlannerTerminationCondition", lambda f: callables.append(f) or python(f))
    blocked = plan_path([0.0], [1.0], [0.1], [0.9], lambda x: not 0.4 < x[0] < 0.6, PlannerOptions(planner, time_limit=0.3))
    assert timers == [0.3] and callables == []
    assert not blocked.exact and len(blocked.path) == 0
    assert blocked.status in ("Approximate solution", "Timeout"), blocked.status  # OMPL's: ran to its termination
    with pytest.raises(Exception, match="cannot take a Python objective"):
        plan_path([0.0], [1.0], [0.1], [0.9], lambda x: True, PlannerOptions(planner), state_cost=lambda x: 1.0)
