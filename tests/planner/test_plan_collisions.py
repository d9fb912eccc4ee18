"""The planner's own checks: every pair of bodies in every state, invalid starts refused with a report."""

import json

import numpy as np
import pytest

from qsplan.hands.paper_hand.two_finger import default_hand, finger_angles
from qsplan.planner.cli.main import main
from qsplan.planner.plan import scripted
from qsplan.planner.plan.scripted import PlanFailure, check_configurations, plan_task
from qsplan.hands.geometry.collision import LINK_DEPTH_TOL, find_collisions, overlap_depth
from qsplan.planner.states.contact import check_contact_state, check_free_state, configuration_problem
from qsplan.planner.task.task import load_task, make_task, task_paths

from tests.planner.overlaps import row_overlaps

#: A pentagon whose grasp at x = 0 crosses the 16 cm fingers above it (the bundled pentagon task's
#: workpiece; the bundled task uses 11 cm fingers for that reason).
PENTAGON = [[0.0, 0.0], [0.070, 0.0], [0.070, 0.060], [0.035, 0.090], [0.0, 0.060]]


def crossing_pentagon_file(tmp_path):
    """The bundled pentagon task with the demo hand's 16 cm fingers, which cross above it."""
    text = task_paths()["pentagon_task"].read_text()
    assert "finger_length = 0.11" in text
    path = tmp_path / "pentagon16.toml"
    path.write_text(text.replace("finger_length = 0.11", "finger_length = 0.16"))
    return path


def _grasp(task, x):
    return task.pose(x), finger_angles(task.hand.paper, task.pose(x))[0]


def test_crossing_fingers_are_found_and_named():
    task = make_task({"workpiece": PENTAGON, "finger_length": 0.16}, 0.0, [0.02])
    pose, q = _grasp(task, 0.0)
    hits = find_collisions(task.hand, pose, q)
    assert [c.bodies for c in hits] == [("left finger", "right finger")]
    assert hits[0].area == pytest.approx(1.48e-4, rel=0.01) and hits[0].depth == pytest.approx(0.012, rel=1e-6)
    assert configuration_problem(task, pose, q).startswith("left finger and right finger overlap by 148 mm^2")
    # the in-contact validity checker refuses it (it tested finger against workpiece and palm only)
    c = check_contact_state(task, 0.0, "right", -1.0)
    assert not c.ok and "left finger and right finger overlap" in c.reason
    # the independent check agrees
    assert [(a, b) for a, b, *_ in row_overlaps(task.hand, pose, q)] == [("left finger", "right finger")]


def test_touching_contacts_pass_and_every_pair_is_tested():
    hand = default_hand()
    task = make_task(hand, 0.0, [-0.04])
    pose, q = _grasp(task, 0.0)
    assert find_collisions(hand, pose, q) == [] and configuration_problem(task, pose, q) is None
    # both fingers pushed 0.05 rad into the workpiece, and below the palm's surface: every pair is reported
    pairs = {c.bodies for c in find_collisions(hand, pose, q + [-0.05, 0.05])}
    assert pairs == {("workpiece", "left finger"), ("workpiece", "right finger")}
    pairs = {frozenset(c.bodies) for c in find_collisions(hand, pose, [0.02, 3.12])}
    assert {frozenset(p) for p in (("palm", "left finger"), ("palm", "right finger"))} <= pairs
    assert frozenset(("left finger", "right finger")) in pairs


def test_free_state_rejects_fingers_through_each_other():
    task = make_task({"workpiece": PENTAGON, "finger_length": 0.16}, 0.0, [0.02])
    _, q = _grasp(task, 0.0)
    opened = q + [0.05, -0.05]  # off the workpiece, still crossed above it
    assert not check_free_state(task, 0.0, opened)
    assert configuration_problem(task, task.pose(0.0), opened).startswith("left finger and right finger overlap")
    _, q = _grasp(task, 0.03)
    assert check_free_state(task, 0.03, q) and check_free_state(task, 0.03, q + [0.05, -0.05])


@pytest.mark.parametrize("shape", ["square", "sliver", "triangle"])
def test_overlap_depth_is_the_narrowest_width(shape):
    from shapely.geometry import Polygon, box

    region = {"square": box(0, 0, 2, 2), "sliver": box(0, 0, 10, 1e-7),
              "triangle": Polygon([(0, 0), (4, 0), (0, 3)])}[shape]  # fmt: skip
    expected = {"square": 2.0, "sliver": 1e-7, "triangle": 12.0 / 5.0}[shape]
    assert overlap_depth(region) == pytest.approx(expected, rel=1e-9)
    assert overlap_depth(box(0, 0, 1, 1).intersection(box(1, 0, 2, 1))) == 0.0  # touching only
    assert LINK_DEPTH_TOL <= 1e-6


def _no_planning(monkeypatch):
    """Make any planning step of a scripted task (a segment's effort joint, its in-contact checks, its sweep)
    fail the test: a refusal "at once" is one that comes before them."""

    def planned(*args, **kwargs):
        raise AssertionError("planning started")

    for name in ("_effort_joint", "_segment", "check_contact_state", "contact_samples", "slide_phase", "regrasp_phase"):
        monkeypatch.setattr(scripted, name, planned)


def test_invalid_start_is_refused_at_once_naming_the_bodies(monkeypatch):
    task = make_task({"workpiece": PENTAGON, "finger_length": 0.16}, 0.0, [0.02, -0.02])
    _no_planning(monkeypatch)
    with pytest.raises(PlanFailure, match=r"left finger and right finger overlap by 148 mm\^2 .* at the start") as info:
        plan_task(task)
    d = info.value.report.as_dict()
    assert d["kind"] == "invalid configuration" and d["where"] == "the start"
    assert d["bodies"] == ["left finger", "right finger"] and d["overlap_area_m2"] == pytest.approx(1.48e-4, rel=0.01)
    assert d["message"] == str(info.value)


@pytest.mark.parametrize("kwargs, match", [
    (dict(waypoints=[0.02], joint_limits=((0.05, 0.8), (0.05, 3.09))), r"the left finger's angle 0\.9026 rad is outside its limits \[0\.05, 0\.8\] rad .*at the start"),
    (dict(start_x=0.025, waypoints=[0.03, 0.0]), r"left finger and right finger overlap .* at the goal"),
    (dict(start_x=0.025, waypoints=[0.03, 0.025], joint_limits=((0.05, 3.09), (1.8, 3.09))), r"right finger's angle 1\.773 rad .* at the opened fingers of regrasp 1"),
])  # fmt: skip
def test_invalid_goal_limits_and_regrasps_are_named(kwargs, match):
    args = {"start_x": 0.0, "waypoints": [0.02], **kwargs}
    task = make_task({"workpiece": PENTAGON, "finger_length": 0.16}, args.pop("start_x"), args.pop("waypoints"), **args)
    with pytest.raises(PlanFailure, match=match):
        check_configurations(task)


def test_cli_refuses_an_invalid_start_with_failure_json(tmp_path, capsys, monkeypatch):
    """Before: 20 s of planning, then ``qsplan: error: start: the state is not valid: [...]`` and no report."""
    _no_planning(monkeypatch)
    code = main(["plan", str(crossing_pentagon_file(tmp_path)), "--out", str(tmp_path / "o"), "--quiet", "--no-plots"])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and err.startswith("qsplan: error: no plan: left finger and right finger")
    report = json.loads((tmp_path / "o" / "failure.json").read_text())
    assert report["bodies"] == ["left finger", "right finger"] and report["message"] in err
    assert not (tmp_path / "o" / "plan.csv").exists()


def test_pentagon_with_long_fingers_is_refused_where_its_fingers_cross(tmp_path):
    task = load_task(crossing_pentagon_file(tmp_path))
    xs = np.arange(-0.04, 0.0401, 0.005)
    crossed = [x for x in xs if configuration_problem(task, *_grasp(task, x))]
    assert np.allclose([min(crossed), max(crossed)], [-0.015, 0.015])
