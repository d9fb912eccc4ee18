"""Planning two-finger tasks: task files, the band guarantee of an exported plan (re-swept independently), failure reports."""

import numpy as np
import pytest

from hands.two_finger import default_hand, finger_angles, hand_scene
from mechanics import QsplanError
from mechanics.bands import guaranteed_band_box
from mechanics.modes import ContactMode
from planner.plan_export import export_plan, read_plan_csv
from planner.task import load_task, make_task, task_paths


def test_bundled_tasks_load():
    tasks = {k: load_task(p) for k, p in task_paths().items()}
    assert {"demo_task", "pentagon_task"} <= set(tasks)
    assert len(tasks["demo_task"].waypoints) == 3
    assert tasks["demo_task"].hand.workpiece.shape != tasks["pentagon_task"].hand.workpiece.shape


@pytest.mark.parametrize("text, match", [
    ("[motion]\nstart_x = 0.0\nwaypoints = [0.01]\n[controller]\ntorque_resolution = 0.02\n", "hand.workpiece"),
    ("[hand]\nworkpiece = [[0,0],[0.08,0],[0.085,0.08],[0.008,0.1]]\n[motion]\nstart_x = 0.0\nwaypoints = [0.01]\n",
     "controller.torque_resolution"),
    ("bogus = 1\n", "bogus"),
    ("[hand]\nworkpiece = [[0,0],[0.08,0],[0.085,0.08],[0.008,0.1]]\n[motion]\nstart_x = 0.0\nwaypoints = [0.0]\n"
     "[controller]\ntorque_resolution = 0.02\n", "motion.waypoints"),
    ("[hand]\nworkpiece = [[0,0],[0.08,0],[0.085,0.08],[0.008,0.1]]\n[motion]\nstart_x = 0.0\nwaypoints = [0.01]\n"
     "[controller]\ntorque_resolution = -1\n", "controller.torque_resolution"),
    ("[hand]\nworkpiece = [[0,0],[0.08,0],[0.085,0.08],[0.008,0.1]]\n[motion]\nstart_x = 0.0\nwaypoints = [0.01]\n"
     "[controller]\ntorque_resolution = 0.02\n[friction]\nrange = [0.3, 0.1]\n", "friction.range"),
])  # fmt: skip
def test_task_validation_names_the_field(tmp_path, text, match):
    p = tmp_path / "t.toml"
    p.write_text(text)
    with pytest.raises(QsplanError, match=match):
        load_task(p)


@pytest.fixture(scope="module")
def small_plan():
    from planner.plan import plan_task

    task = make_task(default_hand(), 0.0, [-0.02, 0.0], torque_resolution=0.02, name="small")
    return plan_task(task)


@pytest.mark.ompl
def test_exported_plan_keeps_every_command_in_an_independently_reswept_band(small_plan, tmp_path):
    export_plan(small_plan, tmp_path)
    with pytest.raises(QsplanError, match="exists"):
        export_plan(small_plan, tmp_path)
    d = read_plan_csv(tmp_path / "plan.csv")
    hand = small_plan.task.hand
    lo, hi = small_plan.task.mu_range
    rows = np.flatnonzero(d["mode"] == "SSSS")
    assert rows.size > 50 and set(d["mode"]) == {"SSSS", "free"}
    for k in rows:
        pose = np.array([d["x_workpiece"][k], d["y_workpiece"][k], d["theta_workpiece"][k]])
        q = np.array([d["q_left"][k], d["q_right"][k]])
        assert np.allclose(q, finger_angles(hand, pose)[0], atol=1e-9)  # the grasp is the tangency
        e = str(d["effort_joint"][k])
        v = "left" if e == "right" else "right"
        scene = hand_scene(hand, pose, q, e, velocity=d[f"qd_{v}"][k])
        band = guaranteed_band_box(scene, ContactMode("SSSS"), lo, hi)  # the desired mode, recomputed from the file
        tau = d[f"tau_{e}"][k]
        assert band.feasible and band.lower - 1e-9 <= d[f"tau_{e}_min"][k] and d[f"tau_{e}_max"][k] <= band.upper + 1e-9
        assert d[f"tau_{e}_min"][k] < tau < d[f"tau_{e}_max"][k]
        assert d[f"tau_{e}_max"][k] - d[f"tau_{e}_min"][k] >= small_plan.task.torque_resolution
    t = d["t"]
    assert np.all(np.diff(t) >= 0)
    qd = np.nan_to_num(np.vstack([d["qd_left"], d["qd_right"]]))
    assert np.abs(qd).max() <= small_plan.task.joint_speed * (1 + 1e-9)


@pytest.mark.ompl
def test_plan_counts_and_checks(small_plan):
    small_plan.check()
    assert len(small_plan.segments) == 2 and len(small_plan.phases) == 3
    assert small_plan.validity_checks > 0 and small_plan.checks_per_second > 0
    assert small_plan.segments[0].effort_joint == "right"  # the trailing (pushing) finger when sliding left


@pytest.mark.ompl
def test_too_wide_friction_fails_with_a_report():
    from planner.plan import PlanFailure, plan_task

    task = make_task(default_hand(), 0.0, [-0.04], mu_range=(0.0, 0.5), torque_resolution=0.05)
    with pytest.raises(PlanFailure, match="band closes at x in") as info:
        plan_task(task)
    r = info.value.report
    assert r.closed and r.narrowest is not None
    assert r.mu_closes is not None and 0.0 < r.mu_closes < 0.5
    assert r.narrowest.mu_lower_edge is not None
    assert r.as_dict()["message"] == str(info.value)
