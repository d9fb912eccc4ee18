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


@pytest.fixture(scope="session")
def bundled_plan(tmp_path_factory):
    """``bundled_plan(name)``: the directory of the bundled task ``name`` planned once per test session through
    ``qsplan plan`` (``--no-plots --verify 0``): ``plan.csv``, ``plan.json``, ``certificate.json``, ``scene.xml``.
    Read it, or copy it before changing anything."""
    from qsplan.planner.cli import main

    root, done = tmp_path_factory.mktemp("bundled"), {}

    def plan(name: str):
        if name not in done:
            out = root / name
            code = main(["plan", name, "--out", str(out), "--no-plots", "--verify", "0", "--quiet"])
            assert code == 0, f"the bundled task {name} did not plan"
            done[name] = out
        return done[name]

    return plan
