"""The public API of qsplan.planner, errors by kind, the one-scene robust band and the planning pipeline."""

import ast
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import qsplan.mechanics as mechanics
import qsplan.planner as planner
from qsplan.hands import default_hand, first_segment, sample_segment
from qsplan.mechanics import NoAnswerError, QsplanError, RobustBand, robust_band
from qsplan.planner.cli.main import main
from qsplan.planner.cli.options import cli_message

ROOT = Path(__file__).resolve().parents[2]

SMALL_TASK = """
name = "small"
[hand]
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
[motion]
start_x = 0.0
waypoints = [-0.02]
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""


# --- the public API ---------------------------------------------------------------------------------------


def test_every_public_name_resolves_once():
    assert len(planner.__all__) == len(set(planner.__all__))
    for name in planner.__all__:
        assert getattr(planner, name) is not None, name
    for name in ("load_task", "make_task", "Task", "demo_task_path", "plan_task", "Plan", "ContactSegmentPlan",
                 "RegraspPlan", "PlanFailure", "run_plan", "PlanRun", "export_plan", "read_plan_csv", "replay_plan",
                 "friction_samples", "plan_figures", "choose_command", "robust_band", "RobustBand",
                 "QsplanError", "NoAnswerError"):  # fmt: skip
        assert name in planner.__all__, name


def test_importing_the_planner_stays_light():
    code = "import sys, qsplan.planner; print(sorted(m for m in ('numpy', 'matplotlib', 'shapely', 'ompl') if m in sys.modules))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_both_packages_export_the_same_error_types():
    assert planner.QsplanError is mechanics.QsplanError is QsplanError
    assert planner.NoAnswerError is mechanics.NoAnswerError is NoAnswerError
    assert mechanics.robust_band is planner.robust_band is robust_band


# --- errors by kind ---------------------------------------------------------------------------------------


def test_no_answer_is_not_bad_input():
    assert issubclass(QsplanError, ValueError)
    assert not issubclass(NoAnswerError, ValueError)
    assert issubclass(NoAnswerError, RuntimeError)
    assert issubclass(planner.PlanFailure, NoAnswerError) and not issubclass(planner.PlanFailure, ValueError)
    assert issubclass(planner.OutputExistsError, QsplanError)


def test_the_cli_translates_library_fields_into_its_options():
    assert cli_message("out_dir: 'x' exists; pass force=True to overwrite it") == "--out: 'x' exists; pass --force to overwrite it"
    assert cli_message("mu: expected 1 or 3 values", {"mu": "--mu"}) == "--mu: expected 1 or 3 values"
    assert cli_message("task: cannot read 'x'") == "task: cannot read 'x'"


def _raised_strings(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and node.exc is not None:
            for sub in ast.walk(node.exc):
                if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                    yield sub.value


@pytest.mark.parametrize("path", sorted(p for p in (ROOT / "planner").rglob("*.py") if "cli" not in p.parts),
                         ids=lambda p: str(p.relative_to(ROOT)))  # fmt: skip
def test_library_messages_name_no_command_line_flag(path):
    flagged = [s for s in _raised_strings(path) if "--" in s]
    assert flagged == []


def test_cli_exit_codes_are_unchanged(capsys):
    assert main(["count", "--contacts", "3", "--dof", "2"]) == 0
    assert main(["count", "--contacts", "-1", "--dof", "2"]) == 2
    assert main(["count", "--contacts", "3"]) == 2
    err = capsys.readouterr().err
    assert "--contacts: expected a nonnegative integer" in err


# --- the guaranteed band of one scene with every competitor precluded ----------------------------------------


@pytest.fixture(scope="module")
def samples():
    return sample_segment(first_segment(default_hand(), duration=10.0), 9)


@pytest.mark.parametrize("shared", [False, True])
def test_robust_band_is_what_the_sweep_computes_at_each_sample(samples, shared):
    g = planner.guaranteed_sweep(samples, (0.0, 0.2), shared)
    comps = planner.competing_modes(samples)
    for k in (0, 4, 8):
        rb = robust_band(samples.scenes[k], "SSSS", (0.0, 0.2), shared=shared, competitors=comps)
        assert isinstance(rb, RobustBand) and rb.mode == "SSSS" and rb.shared == shared
        assert rb.feasible == g.band.feasible[k] and rb.exact == g.band.exact[k] and rb.split == g.split[k]
        np.testing.assert_array_equal([rb.lower, rb.upper], [g.band.lower[k], g.band.upper[k]])
        assert rb.desired.lower == g.desired.lower[k] and rb.desired.upper == g.desired.upper[k]
        for c, (lo, hi) in g.competitors.items():
            if c in rb.precluded:
                assert (rb.precluded[c].lower, rb.precluded[c].upper) == (lo[k], hi[k])
            else:
                assert np.isnan(lo[k]) and np.isnan(hi[k])
        # inside the desired band, never wider
        assert rb.desired.lower <= rb.lower <= rb.upper <= rb.desired.upper


def test_robust_band_finds_its_own_competitors(samples):
    scene = samples.scenes[0]
    rb = robust_band(scene, "SSSS", (0.0, 0.2))
    assert rb.competitors and "SSSS" not in rb.competitors
    assert rb == rb and rb.width == pytest.approx(rb.upper - rb.lower)
    with pytest.raises(QsplanError, match="mu range"):
        robust_band(scene, "SSSS", (0.3, 0.1))


# --- the planning pipeline --------------------------------------------------------------------------------


def test_run_plan_refuses_to_overwrite_before_planning(tmp_path):
    task = planner.load_task(planner.demo_task_path())
    (tmp_path / "plan.csv").write_text("mine")
    with pytest.raises(planner.OutputExistsError, match="exists; pass force=True") as info:
        planner.run_plan(task, tmp_path)
    assert info.value.path.endswith("plan.csv") and info.value.count == 1
    assert (tmp_path / "plan.csv").read_text() == "mine"
    with pytest.raises(QsplanError, match="verify"):
        planner.run_plan(task, tmp_path / "o", verify=-1)
    with pytest.raises(QsplanError, match="time_limit"):
        planner.run_plan(task, tmp_path / "o", time_limit=0.0)
    assert not (tmp_path / "o").exists()


@pytest.mark.ompl
def test_run_plan_plans_exports_and_replays(tmp_path):
    task_file = tmp_path / "small.toml"
    task_file.write_text(SMALL_TASK)
    run = planner.run_plan(planner.load_task(task_file), tmp_path / "out", verify=1, plots=False)
    assert isinstance(run, planner.PlanRun) and run.followed and len(run.replays) == 1
    assert [Path(f).name for f in run.files] == ["plan.csv", "plan.json", "certificate.json", "replay.json", "scene.xml"]
    assert run.certificate.ok
    cols = planner.read_plan_csv(tmp_path / "out" / "plan.csv")
    assert set(cols["mode"]) == {"SSSS"} and len(run.plan.segments) == 1


@pytest.mark.ompl
def test_run_plan_without_a_plan_writes_the_report_and_raises_no_answer(tmp_path):
    task_file = tmp_path / "wide.toml"
    task_file.write_text(SMALL_TASK.replace("range = [0.0, 0.2]", "range = [0.0, 0.5]").replace("[-0.02]", "[-0.04]")
                         .replace("torque_resolution = 0.02", "torque_resolution = 0.05"))  # fmt: skip
    with pytest.raises(NoAnswerError, match="band closes at x in") as info:
        planner.run_plan(planner.load_task(task_file), tmp_path / "o", plots=False)
    assert not isinstance(info.value, ValueError)
    assert Path(info.value.report_path) == tmp_path / "o" / "failure.json" and info.value.report_path.exists()
