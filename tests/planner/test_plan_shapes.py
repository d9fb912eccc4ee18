"""Workpiece shapes planned with no two bodies overlapping in any exported row, or refused with a report.

The overlap check is independent of the planner's (:mod:`tests.planner.overlaps`: the bodies rebuilt
from the exported ``plan.csv`` and the hand's dimensions, measured with shapely).
"""

import pytest

from qsplan.planner.task.task import make_task

from tests.planner.overlaps import plan_or_refuse, plan_overlaps

pytestmark = pytest.mark.ompl

#: name: (workpiece polygon (m), finger length (m), start x, waypoints, expected outcome: "plan" or a
#: substring of the refusal).  Short moves keep each plan to a few seconds.
SHAPES = {
    "triangle": ([[0, 0], [0.08, 0], [0.04, 0.07]], 0.16, -0.025, [-0.03], "left finger and right finger overlap"),
    "pentagon": ([[0, 0], [0.07, 0], [0.08, 0.04], [0.035, 0.07], [-0.01, 0.04]], 0.11, 0.0, [-0.005, 0.0], "plan"),
    "thin rectangle": ([[0, 0], [0.03, 0], [0.03, 0.10], [0, 0.10]], 0.16, -0.025, [-0.03], "plan"),
    "flat rectangle": ([[0, 0], [0.10, 0], [0.10, 0.025], [0, 0.025]], 0.16, -0.025, [-0.03], "palm and right finger overlap"),
    "hexagon": ([[0.02, 0], [0.06, 0], [0.08, 0.035], [0.06, 0.07], [0.02, 0.07], [0, 0.035]], 0.11, 0.0, [-0.005], "plan"),
    "trapezoid": ([[0, 0], [0.09, 0], [0.07, 0.06], [0.02, 0.06]], 0.16, -0.025, [-0.03], "left finger and right finger overlap"),
}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SHAPES))
def test_shape_is_planned_without_overlaps_or_refused_with_the_reason(name, tmp_path):
    polygon, length, x0, waypoints, expected = SHAPES[name]
    task = make_task({"workpiece": polygon, "finger_length": length}, x0, waypoints, name=name)
    outcome, result = plan_or_refuse(task, tmp_path / "out")
    if expected == "plan":
        assert outcome == "plan", result
        assert plan_overlaps(task.hand, result) == []
        assert len(result["t"]) > 5
    else:
        assert outcome == "refused" and expected in result["reason"]
        assert result["kind"] == "invalid configuration" and len(result["bodies"]) == 2
