"""Planning two-finger tasks: task files, the band guarantee of an exported plan (re-swept independently), failure reports."""

from dataclasses import replace

import numpy as np
import pytest

from qsplan.hands.paper_hand.two_finger import default_hand, finger_angles
from qsplan.hands.paper_hand.scene import hand_scene
from qsplan.mechanics import QsplanError
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.solver.all_modes import solve
from qsplan.planner.export.plan_files import export_plan, read_plan_csv
from qsplan.planner.plan.scripted import check_free_state
from qsplan.planner.replay.replay import friction_samples, replay_plan
from qsplan.planner.task.task import load_task, make_task, task_paths
from tests.planner.rest_rows import moving_velocity


def test_bundled_tasks_load():
    tasks = {k: load_task(p) for k, p in task_paths().items()}
    assert {"demo_task", "pentagon_task", "scripted_regrasp_task"} <= set(tasks)
    assert len(tasks["scripted_regrasp_task"].waypoints) == 3 and tasks["demo_task"].goal is not None
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
def demo_files(tmp_path_factory):
    """The bundled scripted task (the demo before automatic planning: three segments, two regrasps, each release
    after a hold: qsplan.planner.plan.release) planned once, exported, and read back from the file."""
    from tests.planner.bundled import planned

    plan = planned("scripted_regrasp_task")
    out = tmp_path_factory.mktemp("demo")
    export_plan(plan, out)
    return plan, out, read_plan_csv(out / "plan.csv")


def _rows(d):
    """Slide rows of an exported plan: index, pose (3,), q (2,), effort joint, velocity joint."""
    for k in np.flatnonzero(d["mode"] == "SSSS"):
        e = str(d["effort_joint"][k])
        pose = np.array([d["x_workpiece"][k], d["y_workpiece"][k], d["theta_workpiece"][k]])
        yield k, pose, np.array([d["q_left"][k], d["q_right"][k]]), e, ("left" if e == "right" else "right")


@pytest.mark.ompl
def test_demo_export_keeps_every_command_inside_the_desired_modes_exact_band(demo_files, tmp_path):
    plan, out, d = demo_files
    with pytest.raises(QsplanError, match="exists"):
        export_plan(plan, out)  # nothing a user has is overwritten
    hand, task = plan.task.hand, plan.task
    lo, hi = task.mu_range
    assert set(d["mode"]) == {"SSSS", "RRRR", "free"} and np.sum(d["mode"] == "SSSS") > 200
    for k, pose, q, e, v in _rows(d):
        assert np.allclose(q, finger_angles(hand, pose)[0], atol=1e-9)  # the grasp is the tangency
        scene = hand_scene(hand, pose, q, e, velocity=moving_velocity(d, k, v))
        band = guaranteed_band_box(scene, ContactMode("SSSS"), lo, hi)  # exact, over the corners of the mu box
        assert band.feasible and band.lower - 1e-9 <= d[f"tau_{e}_min"][k] and d[f"tau_{e}_max"][k] <= band.upper + 1e-9
        assert d[f"tau_{e}_min"][k] < d[f"tau_{e}"][k] < d[f"tau_{e}_max"][k]
        assert d[f"tau_{e}_max"][k] - d[f"tau_{e}_min"][k] >= task.torque_resolution
    assert np.all(np.diff(d["t"]) >= 0)
    qd = np.nan_to_num(np.vstack([d["qd_left"], d["qd_right"]]))
    assert np.abs(qd).max() <= task.joint_speed * (1 + 1e-9)


@pytest.mark.ompl
def test_demo_commands_leave_4s_the_only_feasible_mode_at_sampled_friction(demo_files):
    """A second method: the full all-modes solver with the exported command as the effort, at the corners of the
    friction box and seeded random points inside it, must find 4S alone, sliding the planned way."""
    plan, _, d = demo_files
    lo, hi = plan.task.mu_range
    rng = np.random.default_rng(7)
    corners = np.array(np.meshgrid(*[[lo, hi]] * 4)).reshape(4, -1).T
    mus = np.vstack([corners, rng.uniform(lo, hi, (4, 4))])
    checked = 0
    for k, pose, q, e, v in list(_rows(d))[::3]:
        scene = hand_scene(plan.task.hand, pose, q, e, velocity=moving_velocity(d, k, v), effort=d[f"tau_{e}"][k])
        nxt = min(k + 1, d["t"].size - 1)
        direction = np.sign(d["x_workpiece"][nxt] - d["x_workpiece"][k - 1 if nxt == k else k])
        for mu in mus:
            res = solve(replace(scene, mu=mu))
            assert res.feasible_modes == ["SSSS"], (k, mu, res.feasible_modes)
            sol = res.solutions[0]
            assert sol.max_residual < 1e-9
            xdot = sol.qdot[0] - sol.qdot[2] * pose[1]  # the centre of mass's velocity (the world origin is the palm's)
            assert np.sign(xdot) == direction
            checked += 1
    assert checked > 1500


@pytest.mark.ompl
def test_demo_export_resimulated_follows_the_planned_modes(demo_files):
    plan, _, d = demo_files
    for mu in friction_samples(plan.task.mu_range, 3, seed=3):
        r = replay_plan(d, plan.task.hand, mu)
        assert r.followed, r.summary()
        assert [s.labels for s in r.segments] == [("SSSS",), ("RRRR",)] * 2 + [("SSSS",)]  # a hold before each release
        assert r.x_error < 1e-6  # the 4S motion is fixed by the kinematics: the planned path, to integration error


@pytest.mark.ompl
def test_resimulation_catches_commands_outside_the_band(demo_files):
    plan, _, d = demo_files
    e = str(d["effort_joint"][0])
    bad = dict(d)
    bad[f"tau_{e}"] = np.where(d["mode"] != "free", d[f"tau_{e}_min"] - 0.5, np.nan)
    r = replay_plan(bad, plan.task.hand, plan.task.mu_range[1])
    assert not r.followed and r.segments[0].phase == 0
    assert "feasible modes" in r.segments[0].stop


@pytest.mark.ompl
def test_plan_counts_and_checks(demo_files):
    plan = demo_files[0]
    plan.check()
    slides = [p for p in plan.segments if p.kind == "slide"]
    assert len(slides) == 3 and len(plan.phases) == 7  # and a release hold before each of the two regrasps
    assert [p.kind for p in plan.segments if p.kind != "slide"] == ["hold", "hold"]
    assert plan.validity_checks > 0 and plan.checks_per_second > 0
    assert slides[0].effort_joint == "right"  # the trailing (pushing) finger when sliding left
    from qsplan.planner.torque.command import MAX_MARGIN_RESOLUTIONS

    cap = MAX_MARGIN_RESOLUTIONS * plan.task.torque_resolution
    for seg in slides:  # each command keeps half the narrowest band, at most the cap, from both edges
        keep = min(0.5 * np.min(seg.width), cap)
        assert np.all(seg.margin >= keep * (1 - 1e-12)) and np.all(seg.command - seg.lower >= keep * (1 - 1e-12))
        assert np.all(seg.upper - seg.command >= keep * (1 - 1e-12))
    for ph in [p for p in plan.phases if not p.in_contact]:  # regrasps: collision-free, back where they started
        assert all(check_free_state(plan.task, ph.x, q) for q in ph.q[1:-1])
        assert np.allclose(ph.q[0], ph.q[-1])


@pytest.mark.ompl
def test_too_wide_friction_fails_with_a_report():
    from qsplan.planner.plan.scripted import PlanFailure, plan_task

    task = make_task(default_hand(), 0.0, [-0.04], mu_range=(0.0, 0.5), torque_resolution=0.05)
    with pytest.raises(PlanFailure, match="band closes at x in") as info:
        plan_task(task)
    r = info.value.report
    assert r.closed and r.narrowest is not None
    assert r.mu_closes is not None and 0.0 < r.mu_closes < 0.5
    assert r.narrowest.mu_lower_edge is not None
    assert r.as_dict()["message"] == str(info.value)


@pytest.mark.ompl
def test_degenerate_closure_is_named_without_meaningless_edge_corners():
    from qsplan.planner.plan.scripted import PlanFailure, plan_task

    task = load_task(task_paths()["pentagon_task"])
    task = make_task(replace(task.hand.paper, finger_length=0.16), 0.0, [0.02])  # the demo hand's fingers: they cross
    with pytest.raises(PlanFailure) as info:
        # from x = 0.025 (the fingers cross above the pentagon below 0.0175) to 0.035, the same contacts throughout
        plan_task(make_task(task.hand, 0.025, [0.035], mu_range=(0.0, 0.6), torque_resolution=0.01))
    r = info.value.report
    assert "degenerate" in r.narrowest.reason and "edges attained" not in r.message
    assert r.narrowest.mu_lower_edge is None and 0.0 < r.mu_closes < 0.6


@pytest.mark.ompl
@pytest.mark.parametrize("stem", sorted(task_paths()))
def test_bundled_tasks_are_planned_without_overlaps_or_refused_with_a_reason(stem, demo_files, bundled_plan, tmp_path):
    """Checked independently of the planner, from the exported rows (tests/planner/overlaps.py)."""
    from qsplan.planner.plan.results import PlanFailure
    from tests.planner.bundled import planned
    from tests.planner.overlaps import plan_or_refuse, plan_overlaps

    task = load_task(task_paths()[stem])
    if stem == "scripted_regrasp_task":  # planned once for the whole module
        plan, _, cols = demo_files
        assert plan_overlaps(plan.task.hand, cols) == []
        return
    try:
        planned(stem)  # once per test run: a task without a plan says so here
    except PlanFailure:
        outcome, result = plan_or_refuse(task, tmp_path / "out")  # its refusal through the pipeline
    else:  # the pipeline's files (qsplan plan), once per test run
        outcome, result = "plan", read_plan_csv(bundled_plan(stem) / "plan.csv")
    if outcome == "plan":
        assert plan_overlaps(task.hand, result) == []
    else:
        assert result.get("reason") or result.get("narrowest") or result.get("summary")
