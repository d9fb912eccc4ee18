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
    """``run_plan`` of :data:`SMALL_TASK` with the plots and one re-simulation (a PlanRun; files in ``out_dir``), once
    per test run (pytest-xdist's workers share it: ``tests/planner/bundled.py``).  Read it; never change it."""
    import pickle
    import tempfile
    from pathlib import Path

    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.task.task import load_task
    from tests.planner.bundled import held, shared_root

    root = shared_root(tmp_path_factory) / "small"
    root.mkdir(exist_ok=True)
    done = root / "run.pickle"
    with held(root / "lock"):
        if done.is_file():
            return pickle.loads(done.read_bytes())
        mine = Path(tempfile.mkdtemp(dir=root))  # this process's: another plans again if it cannot share this one
        path = mine / "small.toml"
        path.write_text(SMALL_TASK)
        run = run_plan(load_task(path), mine / "out", verify=1)
        try:
            done.write_bytes(pickle.dumps(run, protocol=pickle.HIGHEST_PROTOCOL))
        except (pickle.PicklingError, TypeError, AttributeError):  # not shared: each process plans it
            pass
        return run


@pytest.fixture(scope="session")
def bundled_plan(tmp_path_factory):
    """``bundled_plan(name)``: the directory of the bundled task ``name`` planned once per test run through
    ``qsplan plan`` (``--no-plots --verify 0``): ``plan.csv``, ``plan.json``, ``certificate.json``, ``scene.xml``
    (pytest-xdist's workers share it: ``tests/planner/bundled.py``).  Read it, or copy it before changing anything."""
    from qsplan.planner.cli import main
    from tests.planner.bundled import held, shared_root

    root, done = shared_root(tmp_path_factory) / "bundled_outputs", {}
    root.mkdir(exist_ok=True)

    def plan(name: str):
        if name not in done:
            out = root / name
            with held(root / f"{name}.lock"):  # another worker may be writing it: its outputs are whole after
                if not (out / "certificate.json").is_file():
                    code = main(["plan", name, "--out", str(out), "--no-plots", "--verify", "0", "--quiet"])
                    assert code == 0, f"the bundled task {name} did not plan"
            done[name] = out
        return done[name]

    return plan
