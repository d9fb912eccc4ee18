"""A route that a turn continues ends holding the flush instant's free joints, sliding (issue 34, item 3).

The formation search holds a chain hand's free joints at the task's start through a pivot, so the slide that reaches
the pivot's flush instant must end in that grasp: not in another grasp touching the goal's features (its last row
would jump to the flush instant), and not by a regrasp into it (the turn continues the slide's last row).
``plan_automatic(goal_free=...)`` asks for that; checked here on the bundled two-link task against the tables' own
joint values.
"""

from __future__ import annotations

import numpy as np
import pytest

from qsplan.planner.plan.autoplan import GOAL_FREE_TOL, goal_nodes, grasp_rows, plan_automatic
from qsplan.planner.search.tables import band_tables, table_grid
from qsplan.planner.task.goal import palm_x_range
from tests.planner.bundled import bundled_task


@pytest.fixture(scope="module")
def tables_of_task():
    from qsplan.planner.plan.autoplan import FREE_SEARCH_MARGIN

    task = bundled_task("two_link_task")
    grid = table_grid(task.start_x, task.goal.x, palm_x_range(task.hand), margin=FREE_SEARCH_MARGIN)
    return task, band_tables(task, grasp_rows(task, task.start_x, task.goal.x), grid)


def test_goal_free_keeps_only_the_goal_rows_holding_those_joints(tables_of_task):
    task, tables = tables_of_task
    free = list(task.hand.free_joints)
    want = np.asarray(task.start_joints, float)[free]
    every = goal_nodes(tables, task)
    kept = goal_nodes(tables, task, want)
    assert kept and set(kept) < set(every)  # the start's grasp held is a goal row; other goal grasps are not kept
    for g, i in every:
        holds = bool(np.all(np.abs(tables.q[g, i, free] - want) <= GOAL_FREE_TOL))
        assert holds == ((g, i) in kept)
    assert np.min([np.max(np.abs(tables.q[g, i, free] - want)) for g, i in set(every) - set(kept)]) > 1e-3


def test_the_route_ends_sliding_in_that_grasp_or_is_refused(tables_of_task):
    from qsplan.planner.plan.results import PlanFailure

    task, tables = tables_of_task
    free = list(task.hand.free_joints)
    free_plan = plan_automatic(task, tables=tables, timed=False)  # any goal grasp
    ends = np.asarray(free_plan.phases[-1].q[-1], float)[free]
    plan = plan_automatic(task, tables=tables, timed=False, goal_free=ends)
    last = plan.phases[-1]
    assert last.in_contact  # a slide, not a regrasp into the grasp
    assert float(last.x[-1]) == pytest.approx(task.goal.x, abs=1e-12)
    np.testing.assert_allclose(last.q[-1][free], ends, atol=GOAL_FREE_TOL)
    # the start's grasp held to the goal has no band at x = -0.007 m (the tables say so): refused, not jumped to
    start = np.asarray(task.start_joints, float)[free]
    assert np.max(np.abs(ends - start)) > 1e-3
    with pytest.raises(PlanFailure, match="no guaranteed band"):
        plan_automatic(task, tables=tables, timed=False, goal_free=start)


def test_a_goal_met_only_with_other_free_joints_says_so(tables_of_task):
    """The goal's features are met, but by no row holding the asked free joints: the refusal says so, naming each
    free joint with the value asked and the values the goal's rows hold, not "unreachable on this palm"."""
    from qsplan.planner.plan.results import PlanFailure

    task, tables = tables_of_task
    free = list(task.hand.free_joints)
    asked = np.asarray(task.start_joints, float)[free] + 0.123  # off the grid of held values
    with pytest.raises(PlanFailure) as err:
        plan_automatic(task, tables=tables, timed=False, goal_free=asked)
    msg = err.value.report.message
    assert "only by grasps holding the free joints elsewhere" in msg and "unreachable" not in msg
    for j, v in zip(free, asked):
        assert f"{task.hand.joint_names[j]} = {v:.6g} rad" in msg
