"""Goals that say orientation (issue 23, item 4): ``[goal] theta`` and ``palm``, their validation, the record round
trip, the refusal of a palm-edge goal without x, and the reorientation route's refusal by name of the turning goals
it cannot serve (``qsplan plan`` exit 2 in one line; ``qsplan check`` says a turn is planned by ``qsplan plan``)."""

from __future__ import annotations

import copy
import json
import math
import tomllib

import pytest

from qsplan.mechanics.errors import NoAnswerError, QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.task.goal import THETA_TOL, Goal, GoalNotServedError, check_goal_served, goal_refusal
from qsplan.planner.task.record import task_record
from qsplan.planner.task.task import demo_task_path, load_task, task_from_record, task_paths

#: The demo's workpiece written from its vertex 1 on: the edge it rests on is then edge 3 as written.
ROTATED = [[0.080, 0.0], [0.085, 0.080], [0.008, 0.100], [0.0, 0.0]]


def demo_doc(goal, workpiece=None) -> dict:
    """The demo task's tables with ``goal`` as its ``[goal]`` (and another ``workpiece``, written otherwise)."""
    doc = tomllib.loads(demo_task_path().read_text())
    doc["goal"] = goal
    if workpiece is not None:
        doc["hand"]["workpiece"] = workpiece
    return doc


def demo_with(goal, workpiece=None):
    return task_from_record(demo_doc(goal, workpiece), base_dir=demo_task_path().parent)


def tilt_file(tmp_path):
    """The issue's example: the demo's hand and start, ``[goal] theta = -0.5`` and no x."""
    text = demo_task_path().read_text()
    assert "\n[goal]\nx = -0.04\nleft = \"vertex:3\"\n" in text  # the lines replaced below
    path = tmp_path / "tilt.toml"
    path.write_text(text.replace("\n[goal]\nx = -0.04\nleft = \"vertex:3\"\n", "\n[goal]\ntheta = -0.5\n"))
    return path


def test_theta_and_palm_parse_and_x_becomes_optional():
    assert demo_with({"theta": -0.5}).goal == Goal(None, theta=-0.5)
    assert demo_with({"palm": "vertex:1"}).goal == Goal(None, palm=("vertex", 1))
    goal = demo_with({"x": -0.04, "theta": -0.5, "palm": " edge:2 ", "left": "vertex:3"}).goal
    assert goal == Goal(-0.04, ("vertex", 3), None, -0.5, ("edge", 2))
    assert goal.describe() == "x = -0.04 m, theta = -0.5 rad, edge 2 on the palm, left finger on vertex 3"
    assert demo_with({"theta": math.pi}).goal.theta == math.pi and demo_with({"theta": -3}).goal.theta == -3.0


@pytest.mark.parametrize("goal, match", [
    ({"x": -0.04, "yaw": 0.1}, r"^goal\.yaw: unknown field; expected some of left, palm, right, theta, x$"),
    ({"left": "vertex:3"}, r"^goal\.x: missing: give x \(m: the workpiece's x\), or theta .* or palm"),
    ({"theta": "-0.5"}, r"^goal\.theta: expected a number \(rad\); got '-0\.5'"),
    ({"theta": float("nan")}, r"^goal\.theta: expected a finite number \(rad\)"),
    ({"theta": -3.2}, r"^goal\.theta: expected an angle within \[-pi, pi\] rad .*; got -3\.2$"),
    ({"palm": "corner:1"}, r'^goal\.palm: expected "edge:K" or "vertex:K"'),
    ({"palm": "vertex:4"}, r"^goal\.palm: the workpiece has 4 vertices and edges \(0 to 3\); got 'vertex:4'$"),
])  # fmt: skip
def test_bad_goal_is_refused_naming_the_field(goal, match):
    with pytest.raises(QsplanError, match=match):
        demo_with(goal)


@pytest.mark.parametrize("goal", [{"theta": -0.5}, {"palm": "vertex:1"}, {"x": -0.03, "theta": 0.25, "palm": "edge:2"},
                                  {"palm": "edge:0", "right": "vertex:2"}])  # fmt: skip
def test_record_round_trip_keeps_theta_and_palm(goal):
    task = demo_with(goal)
    record = json.loads(json.dumps(task_record(task)))  # plain JSON, as plan.json stores it
    assert set(record["goal"]) == set(goal)  # only the keys the goal gives: no x invented
    again = task_from_record(copy.deepcopy(record))
    assert again.goal == task.goal and task_record(again)["goal"] == record["goal"]


@pytest.mark.parametrize("goal, field", [({"palm": "edge:0"}, "goal.x"), ({"theta": 0.0}, "goal.x")])
def test_goals_of_the_palm_edge_formation_without_x_are_refused(goal, field):
    task = demo_with(goal)
    refusal = goal_refusal(task)
    assert isinstance(refusal, GoalNotServedError) and isinstance(refusal, NoAnswerError)
    assert not isinstance(refusal, ValueError)  # a valid task without an answer, not bad input
    assert refusal.field == field and str(refusal).startswith(f"{field}: ")
    assert "palm_edge formation: edge 0 on the palm, theta = 0" in str(refusal)
    with pytest.raises(GoalNotServedError, match=f"^{field}: "):
        check_goal_served(task)


@pytest.mark.parametrize("goal, field, why", [
    ({"x": -0.04, "theta": -0.5}, "goal.x", "the pivot decides x"),
    ({"theta": 2 * THETA_TOL, "x": -0.04}, "goal.x", "the pivot decides x"),
    ({"palm": "vertex:1"}, "goal.theta", "give the angle too"),
    ({"palm": "vertex:1", "x": -0.04}, "goal.x", "the pivot decides x"),
    ({"palm": "edge:1", "x": -0.04}, "goal.x", "the pivot decides x"),
])  # fmt: skip
def test_turning_goals_no_formation_can_mean_are_refused_by_name(goal, field, why, monkeypatch):
    from qsplan.planner.plan import autoplan
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.goal import reorients

    def never(*args, **kwargs):
        raise AssertionError("the planner ran on a goal it refuses")

    monkeypatch.setattr(autoplan, "plan_automatic", never)
    task = demo_with(goal)
    assert reorients(task) and goal_refusal(task) is None  # the formation search decides
    with pytest.raises(GoalNotServedError, match=f"^{field}: .*{why}") as info:
        plan_task(task)
    assert info.value.field == field and not isinstance(info.value, ValueError)


@pytest.mark.parametrize("goal, why", [
    ({"theta": 0.3, "palm": "vertex:1"}, ["it turns the workpiece clockwise", "it pivots on vertex 0"]),
    ({"theta": -0.3, "palm": "vertex:2"}, ["it pivots on vertex 1", "it turns the workpiece counter-clockwise"]),
    ({"palm": "edge:2"}, ["turning clockwise on vertex 1 lands edge 1", "turning counter-clockwise on vertex 0 lands edge 3"]),
])  # fmt: skip
def test_turning_goals_no_formation_reaches_report_every_formation(goal, why, monkeypatch):
    """The demo's hand and workpiece offer two pivots (clockwise on vertex 1 with the left finger flush, its mirror);
    a goal neither can serve is refused with each formation and why, before any slide is planned."""
    from qsplan.planner.plan import autoplan
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task

    def never(*args, **kwargs):
        raise AssertionError("the planner ran a slide for a goal no formation reaches")

    monkeypatch.setattr(autoplan, "plan_automatic", never)
    with pytest.raises(PlanFailure) as info:
        plan_task(demo_with(goal))
    report = info.value.report.as_dict()
    assert report["kind"] == "no turn" and [f["status"] for f in report["formations"]] == ["not this goal"] * 2
    assert [f["why"] for f in report["formations"]] == why
    assert report["formations"][0]["formation"] == "pivot:v1:left:e3:vertex2"


@pytest.mark.parametrize("goal", [{"x": -0.04, "theta": 0.0}, {"x": -0.04, "theta": -THETA_TOL / 2},
                                  {"x": -0.04, "palm": "edge:0"},
                                  {"x": -0.04, "palm": "edge:0", "theta": 0.0}])  # fmt: skip
def test_the_palm_edge_formation_at_an_x_is_served(goal):
    assert goal_refusal(demo_with(goal)) is None


def test_palm_names_the_resting_edge_as_the_polygon_is_written():
    from qsplan.planner.task.goal import reorients

    assert goal_refusal(demo_with({"x": -0.04, "palm": "edge:3"}, ROTATED)) is None
    assert not reorients(demo_with({"x": -0.04, "palm": "edge:3"}, ROTATED))
    assert reorients(demo_with({"x": -0.04, "palm": "edge:0"}, ROTATED))  # edge 0 as written: the bottom-right one


@pytest.mark.parametrize("name", sorted(n for n, p in task_paths().items()
                                         if "x" in tomllib.loads(p.read_text()).get("goal", {})))
def test_existing_goals_are_unchanged(name):
    table = tomllib.loads(task_paths()[name].read_text())["goal"]
    goal = load_task(task_paths()[name]).goal

    def feature(key):
        if key not in table:
            return None
        kind, k = table[key].split(":")
        return (kind, int(k))

    assert goal == Goal(float(table["x"]), feature("left"), feature("right"))  # the fields as before, nothing new
    assert goal.theta is None and goal.palm is None and goal_refusal(load_task(task_paths()[name])) is None


def test_plan_refuses_a_turn_no_formation_reaches_in_one_line(tmp_path, capsys):
    """The demo's counter-clockwise pivot (the right finger flush on edge 1) has no band at its transition: the one
    formation that could serve theta = +0.5 rad is named with where it closes, in one line and ``failure.json``."""
    path = tilt_file(tmp_path)
    path.write_text(path.read_text().replace("theta = -0.5", "theta = 0.5"))
    out = tmp_path / "out"
    code = main(["plan", str(path), "--out", str(out), "--no-plots", "--verify", "0", "--quiet"])
    stdout, err = capsys.readouterr()
    assert code == 2 and stdout == "" and len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.startswith("qsplan: error: no plan: no guaranteed band at least the torque resolution") and \
        "pivot on vertex 0 from theta = 0" in err  # fmt: skip
    assert json.loads((out / "failure.json").read_text())["planner_status"].startswith("ran: ")
    assert not (out / "plan.csv").exists() and not (out / "plan.json").exists()


def test_check_previews_a_turning_goal_as_the_formation_search_sees_it(tmp_path, capsys):
    """Issue 31 called a turning goal "goal (x = 0 m): not a valid configuration"; issue 32: the check shows every
    formation the search sees (where each ends, or its band) and previews the slide to the flush instant of the one
    that reaches the goal, as ``qsplan plan`` plans it."""
    from qsplan.hands.formations.pivots import pivot_formations

    path = tilt_file(tmp_path)
    task = load_task(path)
    assert goal_refusal(task) is None
    code = main(["check", str(path), "--json", "--out", str(tmp_path / "check")])
    stdout, err = capsys.readouterr()
    doc = json.loads(stdout)
    assert code == 0 and err == "" and doc["ok"]
    goal, end = doc["goal"], doc["slide_end"]
    assert [f["status"] for f in doc["formations"]] == ["reaches the goal", "not this goal"]
    assert goal["message"].startswith("goal: a turn (theta = -0.5 rad): the formations searched: pivot on vertex 1")
    assert doc["verdict"].startswith("goal: a turn (theta = -0.5 rad): pivot on vertex 1 (clockwise), the left finger "
                                     "flush on edge 3, the right finger on vertex 2 reaches it")  # fmt: skip
    x = float(pivot_formations(task.hand)[0][1][0])  # the slide's end: the flush instant, 5 um short
    assert end["ok"] and end["previewed"] and abs(end["x_m"] - x) < 0.5e-3 and doc["start"]["ok"]
    assert doc["route"] and doc["route"][0].startswith("slide left from x = 0 to ")


@pytest.mark.parametrize("edit, why", [
    (("theta = -0.5", "theta = 0.5"), "no formation reaches it (pivot on vertex 1 (clockwise), the left finger flush "
                                      "on edge 3, the right finger on vertex 2: not this goal: it turns the workpiece "
                                      "clockwise; pivot on vertex 0 (counter-clockwise), the right finger flush on edge "
                                      "1, the left finger on vertex 3: no band at theta = 0 deg: no guaranteed band"),
    (("theta = -0.5", 'palm = "edge:2"'), "no formation reaches it (pivot on vertex 1 (clockwise), the left finger "
                                          "flush on edge 3, the right finger on vertex 2: not this goal: turning "
                                          "clockwise on vertex 1 lands edge 1"),
])  # fmt: skip
def test_check_names_every_formation_of_a_turn_none_reaches(tmp_path, capsys, edit, why):
    path = tilt_file(tmp_path)
    path.write_text(path.read_text().replace(*edit))
    code = main(["check", str(path), "--json", "--out", str(tmp_path / "check")])
    stdout, err = capsys.readouterr()
    doc = json.loads(stdout)
    assert code == 0 and err == "" and not doc["ok"] and doc["slide_end"] is None and doc["route"] == []
    assert doc["goal"]["refused"] and not doc["goal"]["previewed"] and why in doc["goal"]["message"]
    assert doc["goal"]["message"].startswith("goal: a turn (") and doc["start"]["ok"] and why in doc["verdict"]
    assert (tmp_path / "check" / "check.png").is_file()


def test_check_previews_a_chain_hands_turn_as_the_planner_plans_its_slide(capsys):
    """A hand with free joints (``full_turn_task``'s turning hand): the preview judges the slide to the flush instant
    as ``plan_automatic`` plans it, ending at rows that hold the flush instant's free joints, by a slide in that grasp
    (:func:`qsplan.planner.plan.autoplan.ending_in_place`).  Before, it previewed a regrasp into another grasp at the
    end, a route the planner does not take; now its route is the plan's: one slide, the same torque-controlled joint."""
    from tests.planner.bundled import planned

    code = main(["check", "full_turn_task", "--json"])
    doc = json.loads(capsys.readouterr()[0])
    assert code == 0 and doc["ok"]
    assert len(doc["route"]) == 1 and doc["route"][0].startswith("slide left from x = ")
    slide = planned("full_turn_task").phases[0]
    assert slide.kind == "slide" and f"(joint {slide.effort_joint} torque-controlled)" in doc["route"][0]
    assert all("regrasp" not in step for step in doc["route"])
