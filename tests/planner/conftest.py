"""Shared fixtures of the planner tests: one small task planned once through the whole pipeline."""

import pytest

#: Two 4S segments and one regrasp of the default hand: the smallest task with every kind of phase.
SMALL_TASK = """
name = "small"
[hand]
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
[motion]
start_x = 0.0
waypoints = [-0.02, 0.0]
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""


@pytest.fixture(scope="session")
def small_run(tmp_path_factory):
    """``run_plan`` of :data:`SMALL_TASK` with the plots and one re-simulation (a PlanRun; files in ``out_dir``)."""
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.task.task import load_task

    root = tmp_path_factory.mktemp("small")
    path = root / "small.toml"
    path.write_text(SMALL_TASK)
    return run_plan(load_task(path), root / "out", verify=1)
