"""``qsplan plan`` / ``qsplan demo``: outputs, re-simulation, refusing to overwrite, failure reports (exit 2)."""

import json

import pytest

from qsplan.planner.cli.main import main
from qsplan.planner.export.plan_files import read_plan_csv

from tests.planner.conftest import SMALL_TASK


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.ompl
def test_plan_writes_the_trajectory_and_its_resimulation(tmp_path, capsys):
    task = tmp_path / "small.toml"
    task.write_text(SMALL_TASK)
    out = tmp_path / "out"
    code, stdout, err = run(["plan", str(task), "--out", str(out), "--no-plots", "--verify", "2", "--quiet"], capsys)
    assert code == 0 and err == ""
    assert "planned 3 in-contact segments and 1 regrasps" in stdout  # two slides and the hold before the release
    assert stdout.count("re-simulated at mu = ") == 2 and "followed SSSS RRRR SSSS" in stdout
    d = read_plan_csv(out / "plan.csv")
    assert set(d["mode"]) == {"SSSS", "RRRR", "free"}
    replays = json.loads((out / "replay.json").read_text())
    assert [r["mu"] for r in replays] == [[0.0] * 4, [0.2] * 4] and all(r["followed"] for r in replays)
    assert {s["planned_mode"] for r in replays for s in r["segments"]} == {"SSSS", "RRRR"}
    # a second run refuses to overwrite a file qsplan did not write (here: edited), in one line, before planning
    (out / "plan.csv").write_bytes((out / "plan.csv").read_bytes() + b"\n")
    before = (out / "plan.csv").read_bytes()
    code, stdout, err = run(["plan", str(task), "--out", str(out), "--no-plots", "--quiet"], capsys)
    assert code == 2 and err.count("\n") == 1 and "--force" in err and "exists" in err
    assert (out / "plan.csv").read_bytes() == before


@pytest.mark.ompl
def test_infeasible_task_fails_with_a_named_report(tmp_path, capsys):
    task = tmp_path / "wide.toml"
    task.write_text(SMALL_TASK.replace("range = [0.0, 0.2]", "range = [0.0, 0.5]").replace("[-0.02, 0.0]", "[-0.04]")
                    .replace("torque_resolution = 0.02", "torque_resolution = 0.05"))  # fmt: skip
    code, stdout, err = run(["plan", str(task), "--out", str(tmp_path / "o"), "--quiet"], capsys)
    assert code == 2 and err.startswith("qsplan: error: ") and err.count("\n") == 1
    assert "band closes at x in" in err and "failure.json" in err
    report = json.loads((tmp_path / "o" / "failure.json").read_text())
    assert report["message"] in err and report["mu_closes"] is not None


@pytest.mark.parametrize("args, match", [
    (["plan", "missing.toml"], "task: cannot read"),
    (["plan", "TASK", "--verify", "-1"], "--verify"),
    (["plan", "TASK", "--time-limit", "0"], "--time-limit"),
])  # fmt: skip
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, args, match):
    task = tmp_path / "t.toml"
    task.write_text(SMALL_TASK)
    args = [str(task) if a == "TASK" else a for a in args]
    code, stdout, err = run(args + ["--out", str(tmp_path / "o")], capsys)
    assert code == 2 and match in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.ompl
def test_ctrl_c_during_planning_exits_130_and_leaves_nothing(tmp_path):
    """SIGINT while a segment is being planned (its dense sweep runs Python): one line, exit 130, no output."""
    import signal
    import subprocess
    import sys
    import time

    from qsplan.planner.task.task import task_paths

    out = tmp_path / "plan"
    # a described hand's regrasp and slide: its band tables take about a second after they are announced (the paper
    # hand's tasks plan in well under a second, so a signal after their first segment landed in the export)
    task = str(task_paths()["two_link_regrasp_task"])
    proc = subprocess.Popen([sys.executable, "-m", "qsplan.planner.cli", "plan", task, "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    t0, seen = time.perf_counter(), ""
    while time.perf_counter() - t0 < 60 and "band tables:" not in seen:  # the tables being built
        seen = proc.stderr.readline()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err[-500:]
    assert err.splitlines()[-1] == "qsplan: interrupted" and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())


def test_the_demo_plans_what_its_description_says():
    """``qsplan demo --help`` and the README say what the demo plans (DEMO_PLAN); the plan is held to it."""
    from pathlib import Path

    from qsplan.planner.cli.demo import DEMO_PLAN
    from qsplan.planner.plan.results import ContactSegmentPlan, RegraspPlan
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.task import demo_task_path, load_task

    plan = plan_task(load_task(demo_task_path()))
    slides = [p for p in plan.phases if isinstance(p, ContactSegmentPlan)]
    assert "one slide" in DEMO_PLAN and "no regrasp" in DEMO_PLAN and "4 cm to the left" in DEMO_PLAN
    assert len(slides) == 1 and not any(isinstance(p, RegraspPlan) for p in plan.phases)
    assert slides[0].x[-1] - slides[0].x[0] == pytest.approx(-0.04, abs=1e-12)
    assert slides[0].mode == "SSSS"
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    assert "one slide 4 cm to the left, no regrasp" in readme and "bundled regrasp" not in readme


def test_the_readmes_first_task_plans(tmp_path):
    """The task file of the README's "A first task of your own" loads and plans, as the README says."""
    from pathlib import Path

    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.task import load_task

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = readme[readme.index("## A first task of your own"):]
    text = section[section.index("```toml") + len("```toml"):section.index("```", section.index("```toml") + 7)]
    path = tmp_path / "my_task.toml"
    path.write_text(text)
    plan = plan_task(load_task(path))
    assert plan.phases[-1].x[-1] == pytest.approx(-0.03, abs=1e-12)
    assert plan.narrowest()[2] >= 0.02
