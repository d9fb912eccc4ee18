"""``qsplan check``: a task's feasibility preview (issue 25, item 3), and ``failure.png``.

The CLI contract (exit 0 with a table or one JSON document, exit 2 with one line), the preview's banded ranges against
an independent band (:func:`qsplan.mechanics.robust_band` on the scene of the slide at that x), the start's collision
named and measured, a joint beyond its limit named with its excess, the figures drawn and laid out as a reader needs,
and the chain-hand goal report naming the bodies in the way.
"""

import json

import numpy as np
import pytest

from qsplan.planner.cli.main import COMMANDS, main
from qsplan.planner.task.task import load_task, task_paths
from tests.planner.figure_checks import all_text, labels_without_units, legends_over_axes, overlapping_texts

#: The pentagon of pentagon_task.toml with the demo hand's 16 cm fingers: they cross above its apex for x near 0.
CROSSED_FINGERS = """
name = "pentagon, 16 cm fingers"
[hand]
workpiece = [[0.0, 0.0], [0.070, 0.0], [0.070, 0.060], [0.035, 0.090], [0.0, 0.060]]
workpiece_mass = 0.15
finger_length = 0.16
[motion]
start_x = 0.0
[goal]
x = 0.03
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""

#: The two-link hand asked to hold the demo's workpiece over its own left pivot: every grasp's proximal link is in it.
FAR_GOAL = """
name = "two-link hand, goal over the left pivot"
[hand]
file = "two_link_hand"
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
workpiece_mass = 0.2
[motion]
start_x = 0.0
[start]
left_proximal = 1.4
right_proximal = 1.74
[goal]
x = -0.09
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def write(tmp_path, text, name="task.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def demo():
    from qsplan.planner.reports.preview import preview_task

    task = load_task(task_paths()["demo_task"])
    return task, preview_task(task)


def test_check_is_registered():
    assert "check" in COMMANDS


def test_table_names_start_goal_grasps_and_a_route(capsys):
    code, out, err = run(["check", "demo_task"], capsys)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[2].startswith("start (x = 0 m): ok, grasp G1") and lines[3].startswith("goal (x = -0.04 m): ok")
    assert any(line.strip().startswith("banded, sliding left:  [-0.042, 0.0455]") for line in lines)
    assert lines[-1].startswith("verdict: start ok / goal ok / a banded route exists from the start to the goal: "
                                "slide left from x = 0 to -0.04 m along G1")  # fmt: skip


def test_json_is_one_document(capsys, tmp_path):
    code, out, err = run(["check", "demo_task", "--json", "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)  # nothing else on stdout, not even the "wrote" lines
    assert doc["kind"] == "feasibility preview" and doc["ok"] is True
    assert doc["start"]["ok"] and doc["goal"]["ok"] and doc["route"]
    assert doc["grasps"][0]["valid_x_m"] == [[-0.042, pytest.approx(0.0455)]]
    assert json.loads((tmp_path / "o" / "check.json").read_text()) == doc


def test_missing_task_is_one_line(capsys, tmp_path):
    code, out, err = run(["check", str(tmp_path / "nowhere.toml")], capsys)
    assert code == 2 and out == "" and len(err.splitlines()) == 1 and err.startswith("qsplan: error: task:")


def test_bad_field_is_one_line(capsys, tmp_path):
    path = write(tmp_path, CROSSED_FINGERS.replace("x = 0.03", 'x = "left"'))
    code, out, err = run(["check", str(path)], capsys)
    assert code == 2 and out == "" and len(err.splitlines()) == 1 and "goal.x" in err


def test_out_is_a_file_is_one_line(capsys, tmp_path):
    (tmp_path / "file").write_text("")
    code, out, err = run(["check", "demo_task", "--out", str(tmp_path / "file")], capsys)
    assert code == 2 and out == "" and len(err.splitlines()) == 1 and "--out:" in err and "is a file" in err


def test_outputs_replaced_only_with_force(capsys, tmp_path):
    out_dir = tmp_path / "o"
    code, out, _ = run(["check", "demo_task", "--out", str(out_dir)], capsys)
    png = out_dir / "check.png"
    assert code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"wrote {png}" in out
    before = png.stat().st_mtime_ns
    code, out, err = run(["check", "demo_task", "--out", str(out_dir)], capsys)
    assert code == 2 and out == "" and "--force" in err and len(err.splitlines()) == 1
    assert png.stat().st_mtime_ns == before  # refused before any work
    code, _, err = run(["check", "demo_task", "--out", str(out_dir), "--force"], capsys)
    assert code == 0 and err == ""


def _independent_banded(task, grasp, x, direction):
    """Whether some torque-controlled joint has a guaranteed band at least the resolution wide at ``x``: the slide's
    scene (:meth:`qsplan.hands.protocol.Hand.slide_motion`) and :func:`qsplan.mechanics.robust_band`, one state, no
    tables."""
    from qsplan.mechanics import robust_band
    from qsplan.mechanics.errors import QsplanError

    hand = task.hand
    for e in range(len(hand.joint_names)):
        try:
            motion = hand.slide_motion(task.formation, grasp, [x], direction * task.workpiece_speed, e)
        except QsplanError:
            return False  # no configuration there
        band = robust_band(motion.scenes[0], task.formation.mode, task.mu_range, shared=task.shared_mu,
                           force_margin=task.force_margin)  # fmt: skip
        if band.feasible and band.upper - band.lower >= task.torque_resolution:
            return True
    return False


@pytest.mark.parametrize("stem, xs", [("demo_task", (-0.03, 0.0, 0.04)), ("friction_closes_task", (-0.01, 0.0, 0.02))])
def test_banded_ranges_agree_with_an_independent_band(stem, xs):
    from qsplan.planner.reports.preview import preview_task

    task = load_task(task_paths()[stem])
    preview = preview_task(task)
    bar = preview.grasps[0]
    grasp = task.hand.grasp_candidates(task.formation)[bar.row]
    seen = set()
    for x in xs:
        i = int(np.argmin(np.abs(preview.x - x)))
        for d, direction in ((0, -1.0), (1, 1.0)):
            expected = _independent_banded(task, grasp, float(preview.x[i]), direction)
            assert bool(bar.banded[d, i]) == expected, (stem, x, direction)
            seen.add(expected)
    if stem == "friction_closes_task":
        assert seen == {True, False}  # both answers occur: the comparison can fail


def test_a_collision_at_the_start_names_the_bodies(capsys, tmp_path):
    path = write(tmp_path, CROSSED_FINGERS)
    code, out, err = run(["check", str(path), "--json"], capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)
    start = doc["start"]
    assert not start["ok"] and not doc["ok"]
    hit = start["collisions"][0]
    assert sorted(hit["bodies"]) == ["left finger", "right finger"] and hit["area_m2"] > 1e-5 and hit["depth_m"] > 1e-3
    assert doc["verdict"].startswith("start not ok / goal ok: the start: left finger and right finger overlap by")
    assert "banded nearest: G" in doc["verdict"]  # where to put the start instead


def test_a_joint_beyond_its_limit_is_named_with_its_excess(tmp_path):
    from qsplan.planner.reports.preview import preview_task

    text = CROSSED_FINGERS.replace("start_x = 0.0", "start_x = 0.03").replace("x = 0.03", "x = 0.035")
    free = preview_task(load_task(write(tmp_path, text)))
    q_left = free.start.q[0]
    limited = preview_task(load_task(write(tmp_path, text + f"[limits]\nleft = [{q_left + 0.1}, 3.0]\n", "lim.toml")))
    assert not limited.start.ok and [lim.joint for lim in limited.start.limits] == ["left"]
    assert limited.start.limits[0].excess == pytest.approx(0.1)
    assert "beyond its lower limit" in limited.start.message


def test_a_scripted_task_is_judged_segment_by_segment():
    from qsplan.planner.reports.preview import preview_task

    preview = preview_task(load_task(task_paths()["scripted_regrasp_task"]))
    assert preview.ok and len(preview.route) == 3 and preview.waypoints == (-0.04, 0.03, 0.0)
    assert preview.verdict.startswith("start ok / goal ok / every segment slides banded in the start's grasp")


def test_a_position_beyond_the_palm_is_the_verdict(tmp_path):
    from qsplan.planner.reports.preview import preview_task

    preview = preview_task(load_task(write(tmp_path, CROSSED_FINGERS.replace("x = 0.03", "x = 0.14"))))
    assert not preview.ok and not preview.goal.ok and "beyond the palm's right end" in preview.goal.beyond_palm
    assert "beyond the palm's right end" in preview.verdict


@pytest.mark.slow
def test_preview_figure_is_laid_out(demo, tmp_path):
    from qsplan.planner.plotting.preview import preview_figure
    from qsplan.planner.reports.preview import preview_task

    for task, preview in (demo, (t := load_task(write(tmp_path, CROSSED_FINGERS)), preview_task(t))):
        fig = preview_figure(task, preview)
        assert overlapping_texts(fig) == [] and legends_over_axes(fig) == []
        assert labels_without_units(fig, (r"^$",)) == []
        text = all_text(fig)
        assert "start" in text and "goal" in text and "G1" in text and "valid and banded" in text
    assert "left finger and right finger overlap" in text


@pytest.mark.slow
@pytest.mark.ompl
def test_failure_figure_of_each_report(tmp_path):
    pytest.importorskip("ompl")  # the friction_closes task's no-route report comes out of the OMPL search
    from qsplan.planner.plan.failure import configuration_report, palm_report
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.plotting.failure import failed_configuration, failure_figure

    crossed = load_task(write(tmp_path, CROSSED_FINGERS))
    q = crossed.hand.closed_configuration(crossed.formation, None, 0.0)
    overlap = configuration_report(crossed, "segment 1", "the start", 0.0, q)
    beyond = palm_report(load_task(write(tmp_path, CROSSED_FINGERS.replace("x = 0.03", "x = 0.14"), "b.toml")))
    closes = load_task(task_paths()["friction_closes_task"])
    with pytest.raises(PlanFailure) as info:
        plan_task(closes)
    for task, report in ((crossed, overlap), (crossed, beyond), (closes, info.value.report)):
        fig = failure_figure(task, report, tmp_path / "failure.png")
        assert (tmp_path / "failure.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert overlapping_texts(fig) == [] and legends_over_axes(fig) == []
        assert labels_without_units(fig, (r"^$",)) == []
    x, q_drawn, hits, _ = failed_configuration(crossed, overlap)
    assert x == 0.0 and np.allclose(q_drawn, q) and {h.bodies for h in hits} == {overlap.bodies}
    x, _, _, _ = failed_configuration(closes, info.value.report)
    assert x == info.value.report.band.narrowest.x  # the band-closing configuration


def test_chain_goal_without_features_names_the_bodies_in_the_way(tmp_path):
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task

    task = load_task(write(tmp_path, FAR_GOAL))
    with pytest.raises(PlanFailure) as info:
        plan_task(task)
    report = info.value.report.as_dict()
    assert report["kind"] == "invalid configuration"
    assert "names no features" in report["reason"] and "meeting it" not in report["reason"]
    assert sorted(report["bodies"]) == ["left_proximal link", "workpiece"] and report["overlap_area_m2"] > 1e-4
    assert len(report["q_rad"]) == 4


def test_paper_hand_start_with_crossed_fingers_names_them(tmp_path):
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task

    with pytest.raises(PlanFailure) as info:
        plan_task(load_task(write(tmp_path, CROSSED_FINGERS)))
    report = info.value.report.as_dict()
    assert report["where"] == "the start" and "no grasp meeting it (start features" in report["reason"]
    assert report["bodies"] == ["left finger", "right finger"] and report["overlap_area_m2"] > 1e-5
    assert len(report["q_rad"]) == 2


def test_turning_goal_preview_figure_is_laid_out():
    """Issues 31-32: a turning goal's check.png draws the start and the end of the slide to the flush instant of the
    formation the search prefers (the route's first step), says under it which formations the search sees, and marks
    no goal x on the bars (the turn has none)."""
    from qsplan.planner.plotting.preview import preview_figure
    from qsplan.planner.reports.preview import preview_task

    task = load_task(task_paths()["reorient_edge_task"])
    preview = preview_task(task)
    assert preview.slide_end is not None and preview.slide_end.ok and preview.route and preview.ok
    assert not preview.goal.previewed and "the formations searched: " in preview.goal.message
    fig = preview_figure(task, preview)
    assert overlapping_texts(fig) == [] and legends_over_axes(fig) == []
    text = all_text(fig)
    assert "slide's end: x = " in text and "the formations searched" in text and "not valid" not in text
    marks = [t.get_text() for ax in fig.axes for top in ax.child_axes for t in top.get_xticklabels()]  # the bars' marks
    assert "slide's end" in marks and "goal" not in marks
