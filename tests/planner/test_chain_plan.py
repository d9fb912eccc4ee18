"""Plans of hands with free joints (the one pipeline, qsplan.planner.plan.autoplan): grasp rows, band tables, slides.

Each plan is checked independently of the planner: shapely measures every body pair and each finger's
contact at every row, the joint and speed limits are checked by finite differences of the rows, and
each row's contact velocities (eq. 6) are rebuilt by moving the bodies along the commanded rates."""

import numpy as np
import pytest
from shapely.geometry import Polygon

from qsplan.hands.chains.hand import chain_polygons
from qsplan.planner import load_task, plan_task, task_paths
from qsplan.planner.task.task import make_task
from qsplan.planner.plan.timing import quasistatic_rows

#: Overlap (m^2) and gap (m) tolerated by the checks: the contact finder's micron, squared for areas.
GAP = 1e-6


@pytest.fixture(scope="module")
def two_link_plan():
    from tests.planner.bundled import planned

    return planned("two_link_task")


def _check_rows(plan):
    for seg in plan.segments:
        if seg.kind == "slide":  # a release hold keeps the slide's last row (qsplan.planner.plan.release)
            _check_segment(plan.task, seg)


def _check_segment(task, seg):
    hand = task.hand
    man = hand.manipulator
    carriers = {frozenset((j.name, "palm" if j.parent < 0 else man.joints[j.parent].name))
                for j in man.joints if j.kind == "revolute"}  # fmt: skip
    assert np.all(np.diff(seg.x) < 0) or np.all(np.diff(seg.x) > 0)
    for k in range(len(seg.t)):
        polys = {n: Polygon(p) for n, p in chain_polygons(hand, task.pose(seg.x[k]), seg.q[k]).items()}
        W = polys["workpiece"]
        for f in range(2):
            link = hand.joint_names[hand.finger_joints[f][-1]]
            assert polys[link].distance(W) < GAP, (k, link)
        names = list(polys)
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                if frozenset((a, b)) not in carriers:  # a link may turn inside its carrier (its joint housing)
                    assert polys[a].intersection(polys[b]).area < GAP**2, (k, a, b)
        assert np.all(seg.q[k] >= task.joint_limits[:, 0]) and np.all(seg.q[k] <= task.joint_limits[:, 1])
    dt = np.diff(seg.t)
    rates = np.abs(np.diff(seg.q, axis=0)) / dt[:, None]
    assert np.all(rates <= task.joint_speeds[None, :] * (1 + 1e-6))
    assert np.all(np.abs(np.diff(seg.x)) / dt <= task.workpiece_speed * (1 + 1e-9))
    assert np.all(seg.width >= task.torque_resolution)
    assert np.all((seg.command > seg.lower) & (seg.command < seg.upper))


def test_two_link_hand_slides_in_4s(two_link_plan):
    (seg,) = two_link_plan.segments
    assert seg.mode == "SSSS"
    assert seg.x[0] == 0.0 and seg.x[-1] == pytest.approx(-0.03)
    assert seg.effort_joint in two_link_plan.task.hand.joint_names
    _check_rows(two_link_plan)


def test_velocity_commands_keep_the_finger_contacts_closed(two_link_plan):
    """Moving the bodies along the commands for a short time keeps each finger on the workpiece to second order."""
    task = two_link_plan.task
    hand = task.hand
    (seg,) = two_link_plan.segments
    e = hand.joint_names.index(seg.effort_joint)
    s, _ = quasistatic_rows(seg.t, seg.speed_scale, seg.q, seg.qd)  # the path parameter: x and q smooth in it
    u = seg.speed_scale
    xdot = np.gradient(seg.x, s) * u
    for k in range(1, len(seg.t) - 1, 7):
        qd = seg.qd[k].copy()
        qd[e] = (seg.q[k + 1, e] - seg.q[k - 1, e]) / (s[k + 1] - s[k - 1]) * u[k]  # the effort joint follows
        for dt in (1e-3,):
            polys = chain_polygons(hand, task.pose(seg.x[k] + xdot[k] * dt), seg.q[k] + qd * dt)
            W = Polygon(polys["workpiece"])
            for f in range(2):
                link = Polygon(polys[hand.joint_names[hand.finger_joints[f][-1]]])
                gap = link.distance(W) - link.intersection(W).area ** 0.5
                assert abs(gap) < 1e-7, (k, f, gap)


def test_inclined_parallel_jaws_slide_in_4s():
    """Prismatic jaws inclined 15 degrees toward the palm: each jaw slides down along a hexagon corner."""
    hexagon = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]
    task = make_task({"file": "parallel_jaw", "workpiece": hexagon, "workpiece_mass": 0.2}, 0.0, goal={"x": -0.02})
    plan = plan_task(task)
    (seg,) = plan.segments
    assert seg.mode == "SSSS"
    _check_rows(plan)


def test_a_regrasp_onto_another_feature_is_planned():
    """The two-link fingers choose where they touch: the left one regrasps from a corner onto the left side."""
    from qsplan.hands.chains.hand import close_grasp
    from qsplan.hands.paper_hand.grasps import internal_edge
    from qsplan.planner.plan.results import ContactSegmentPlan, RegraspPlan
    from tests.planner.bundled import bundled_task, planned

    task = bundled_task("two_link_regrasp_task")
    plan = planned("two_link_regrasp_task")
    assert any(isinstance(p, RegraspPlan) for p in plan.phases)
    assert any(isinstance(p, ContactSegmentPlan) for p in plan.phases)
    _check_rows(plan)
    hand = task.hand.chain
    first = close_grasp(hand, task.start_x, plan.phases[0].q[0])[1][0]
    last = close_grasp(hand, task.goal.x, plan.phases[-1].q[-1])[1][0]
    assert first.key == (1, "vertex", 3)  # the start: the distal link's inner edge on the top-left corner
    assert last.key == (1, "edge", internal_edge(hand, 3))  # the goal: the fingertip on the left side
    for rg in (p for p in plan.phases if isinstance(p, RegraspPlan)):  # free motion: nothing overlaps, the workpiece still
        for a, b in zip(rg.q[:-1], rg.q[1:]):
            for s in np.linspace(0.0, 1.0, 21):
                polys = {n: Polygon(p) for n, p in chain_polygons(hand, task.pose(rg.x), a + s * (b - a)).items()}
                for name in hand.joint_names:
                    assert polys[name].intersection(polys["workpiece"]).area < GAP**2
                assert polys["left_distal"].intersection(polys["right_distal"]).area < GAP**2
        assert np.all(np.abs(np.diff(rg.q, axis=0)) / np.diff(rg.t)[:, None] <= task.joint_speeds * (1 + 1e-9))


def test_a_goal_feature_no_finger_can_touch_is_reported():
    from dataclasses import replace

    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.task.goal import Goal

    task = load_task(task_paths()["two_link_task"])
    with pytest.raises(PlanFailure, match="the goal is unreachable on this palm: no grasp meeting it") as info:
        plan_task(replace(task, goal=Goal(-0.03, None, ("vertex", 0))))  # the right finger on the far bottom corner
    report = info.value.report.as_dict()  # the paper hand's report, fields and all: what is valid there instead
    assert report["kind"] == "invalid configuration" and "is valid there with the left finger's" in report["reason"]


def test_the_paper_hand_file_plans_the_demo_byte_for_byte(tmp_path):
    """demo_task.toml names file = "paper_hand": the same hand, and the same plan, as the parameter form."""
    from qsplan.hands.paper_hand.two_finger import TwoFingerHand
    from qsplan.planner.export.plan_files import export_plan

    path = task_paths()["demo_task"]
    text = path.read_text()
    assert 'file = "paper_hand"' in text
    by_file = load_task(path)
    assert by_file.hand.accelerated and isinstance(by_file.hand.paper, TwoFingerHand)
    params = tmp_path / "demo_params.toml"
    params.write_text(text.replace('file = "paper_hand"', "finger_base = 0.09\nfinger_length = 0.16\nfinger_width = 0.012"))
    by_params = load_task(params)
    for name in ("finger_base", "finger_length", "finger_width", "finger_mass", "palm_halfwidth", "palm_thickness",
                 "gravity", "mu", "workpiece_mass"):
        assert getattr(by_file.hand, name) == getattr(by_params.hand, name), name
    np.testing.assert_array_equal(by_file.joint_limits, by_params.joint_limits)
    assert by_file.joint_speed == by_params.joint_speed
    for key, task in (("a", by_file), ("b", by_params)):
        export_plan(plan_task(task), tmp_path / key)
    assert (tmp_path / "a" / "plan.csv").read_bytes() == (tmp_path / "b" / "plan.csv").read_bytes()


def test_any_chain_a_two_link_finger_beside_a_leaning_jaw():
    """Fingers of different kinds in one hand: a two-link revolute finger and a prismatic jaw, described inline."""
    rect = [[0.0, -0.006], [0.07, -0.006], [0.07, 0.006], [0.0, 0.006]]
    left = {"name": "left", "joints": [
        {"name": "left_1", "type": "revolute", "origin": [-0.09, 0.0, 0.0], "limits": [0.05, 3.09], "speed": 0.5,
         "link": {"polygon": rect}},
        {"name": "left_2", "type": "revolute", "origin": [0.07, 0.0, 0.0], "limits": [-2.6, 2.6], "speed": 0.5,
         "link": {"polygon": rect}}]}
    jaw = load_task(task_paths()["parallel_jaw_task"]).hand.description
    k = jaw.joint_names.index("right_jaw")
    right = {"name": "right", "joints": [{"name": "right_jaw", "type": "prismatic",
                                          "origin": jaw.manipulator.joints[k].origin.tolist(), "limits": [0.0, 0.1],
                                          "speed": 0.05, "link": {"polygon": [list(p) for p in jaw.manipulator.joints[k].link_shape]}}]}
    hexagon = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]
    table = {"name": "mixed", "palm": {"polygon": [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]]},
             "fingers": [left, right], "workpiece": hexagon}
    plan = plan_task(make_task(table, 0.0, goal={"x": -0.02}))
    assert plan.task.hand.joint_names == ("left_1", "left_2", "right_jaw")
    assert [s.mode for s in plan.segments] == ["SSSS"]
    _check_rows(plan)


@pytest.mark.slow
def test_the_two_link_hands_exported_commands_drive_the_simulator_through_the_plan(two_link_plan, tmp_path):
    """The exported file alone (plan.csv), driven through the finite-motion simulator (every mode checked at every
    instant, eqs. 13-28): the workpiece follows the planned x and all four contacts slide, at the friction interval's
    extremes and seeded random points."""
    from qsplan.planner.export.plan_files import export_plan, read_plan_csv
    from qsplan.planner.replay.replay import friction_samples, replay_plan

    export_plan(two_link_plan, tmp_path)
    columns = read_plan_csv(tmp_path / "plan.csv")
    task = two_link_plan.task
    for mu in friction_samples(task.mu_range, 4, seed=3):
        replay = replay_plan(columns, task.hand, mu)
        (seg,) = replay.segments
        assert seg.stop is None and seg.labels == ("SSSS",), (mu, seg.stop, seg.labels)
        assert seg.x_error < 1e-5  # m, against the planned x at every row
        states = seg.motion.states
        assert states[-1, 0] == pytest.approx(-0.03, abs=1e-5)  # the workpiece reached the goal
        assert np.all(np.diff(states[:, 0]) <= 1e-12)  # and slid left all along
