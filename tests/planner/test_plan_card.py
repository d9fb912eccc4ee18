"""The plan card for the operator (issue 25): snapshot labels checked against the plan's rows on every bundled task that
plans, start and end grasps always drawn, slack and command range in words and on the plot, edges beyond the plot
drawn by kind, narrowest arrows never cut, phase numbers as in plan.csv, a legend of what is drawn only, and the
layout checks of every figure (no overlapping text, no legend over data, units on every axis)."""

import re

import numpy as np
import pytest

from qsplan.hands.interface import contacts_at, joint_axes, joint_kinds, joint_names
from qsplan.mechanics import SceneError
from qsplan.planner.plan.results import ContactSegmentPlan, RegraspPlan
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.plotting.card import card_snapshots, phase_rows, plan_card
from qsplan.planner.plotting.hands import STATES, effort_direction, plan_snapshots
from qsplan.planner.plotting.style import torque_text
from qsplan.planner.task.task import load_task, task_paths
from tests.planner.figure_checks import all_text, labels_without_units, legends_over_axes, overlapping_texts

pytestmark = pytest.mark.ompl

#: Bundled tasks that plan (``friction_closes_task`` is the bundled example of a task with no plan).
TASKS = sorted(n for n in task_paths() if n != "friction_closes_task")

#: Tasks whose cards are drawn in the default run (one paper-hand slide, one chain-hand regrasp); the rest are slow.
QUICK_CARDS = ("demo_task", "two_link_regrasp_task")

_PLANS = {}


def planned(name):
    """``plan_task`` of a bundled task, once per test session."""
    if name not in _PLANS:
        _PLANS[name] = plan_task(load_task(task_paths()[name]))
    return _PLANS[name]


def every_finger_touches(plan, pose, q) -> bool:
    """The contact search finds the grasp's contact set (palm, palm, a left-finger link, a right-finger link); a
    paper-form hand's in any formation: the palm and both fingers touch (qsplan.hands.found_contacts)."""
    from qsplan.hands.contact_sets import finger_link
    from qsplan.hands.found_contacts import ordered_contacts

    hand = plan.task.hand
    if getattr(hand, "paper", None) is not None:
        bodies = {c.body for c in ordered_contacts(hand, pose, q)}
        return {-1, finger_link(hand, "left"), finger_link(hand, "right")} <= bodies
    try:
        return len(contacts_at(hand, pose, q)) == 4
    except SceneError:
        return False


def row_config(plan, i, k):
    ph = plan.phases[i]
    return ph.poses(plan.task.hand.rest_height)[min(k, ph.t.size - 1)], ph.q[k]


@pytest.mark.parametrize("name", TASKS)
def test_snapshot_labels_match_the_rows(name):
    plan = planned(name)
    last = (len(plan.phases) - 1, plan.phases[-1].t.size - 1)
    for shots in (card_snapshots(plan), plan_snapshots(plan), card_snapshots(plan, limit=3)):
        assert [(s.phase, s.row, s.role) for s in (shots[0], shots[-1])] == [(0, 0, "start"), (*last, "end")]
        assert np.all(np.diff([s.t for s in shots]) > 0)
        for s in shots:
            ph = plan.phases[s.phase]
            pose, q = row_config(plan, s.phase, s.row)
            assert s.t == ph.t[s.row] and np.array_equal(s.pose, pose) and np.array_equal(s.q, q)
            assert s.state in STATES
            touching = every_finger_touches(plan, pose, q)
            assert s.touching == touching, (name, s.t)
            if isinstance(ph, ContactSegmentPlan) and ph.kind == "hold":  # nothing moves, the torque ramps
                assert s.state == "holding" and np.ptp(ph.x) == 0 and s.effort == ph.command[s.row]
            elif isinstance(ph, ContactSegmentPlan):
                assert s.state == "sliding" and np.ptp(ph.x) > 0 and s.effort == ph.command[s.row]
            elif touching:
                assert s.state == "holding" and s.row in (0, ph.t.size - 1)  # released from, or closed onto, a grasp
            else:  # off the workpiece: closing when the next row touches again after an off row, else open
                closing = every_finger_touches(plan, *row_config(plan, s.phase, s.row + 1)) and not every_finger_touches(
                    plan, *row_config(plan, s.phase, s.row - 1))  # fmt: skip
                assert s.state == ("closing" if closing else "open"), (name, s.t)


@pytest.mark.parametrize("name", [n for n in TASKS if n in ("pentagon_task", "scripted_regrasp_task",
                                                            "two_link_regrasp_task")])  # fmt: skip
def test_every_regrasp_is_drawn_open_and_closed_again(name):
    plan = planned(name)
    shots = card_snapshots(plan)
    times = {s.t: s for s in shots}
    for i, ph in enumerate(plan.phases):
        if isinstance(ph, RegraspPlan):
            assert any(s.phase == i and s.state in ("open", "closing") for s in shots)
            closed = times[float(ph.t[-1])]  # the new grasp: this regrasp's last row or the next phase's first
            assert closed.touching and closed.state in ("holding", "sliding")


def test_two_link_regrasp_ends_on_its_closed_goal_grasp():
    """Issue 25: the card called the final, closed goal grasp "open" and drew it without contacts."""
    plan = planned("two_link_regrasp_task")
    end = card_snapshots(plan)[-1]
    assert isinstance(plan.phases[end.phase], RegraspPlan) and end.role == "end"
    assert end.state == "holding" and end.touching and every_finger_touches(plan, end.pose, end.q)
    fig = plan_card(plan)
    ax = next(a for a in fig.axes if a.get_title().startswith(f"{chr(ord('A') + len(card_snapshots(plan)) - 1)}: "))
    assert "end" in ax.get_title() and "holding" in ax.get_title()
    assert any(line.get_marker() == "o" and len(line.get_xdata()) for line in ax.get_lines())  # its contacts


def legend_of(fig):
    """The card's one legend (under its body)."""
    from matplotlib.legend import Legend

    (legend,) = fig.findobj(Legend)
    return legend


def snapshot_axes(fig):
    return [a for a in fig.axes if re.match(r"[A-Z]: t = ", a.get_title())]


def torque_axes(fig):
    return [a for a in fig.axes if "command inside its guaranteed band" in a.get_title(loc="left")]


def check_card(plan, fig):
    """What every card shows, read back from the drawn figure and checked against the plan."""
    assert overlapping_texts(fig) == []
    assert legends_over_axes(fig) == []
    assert labels_without_units(fig, (r"^$",)) == []
    text = all_text(fig)
    hand = plan.task.hand
    rows = phase_rows(plan)
    assert [r[0] for r in rows] == [str(i) for i in range(len(plan.phases))] and "segment 1" not in text
    for i, ph in enumerate(plan.phases):  # the command's range and the slack, in the joint's unit
        if isinstance(ph, ContactSegmentPlan):
            unit = "N" if dict(zip(joint_names(hand), joint_kinds(hand)))[ph.effort_joint] == "prismatic" else "N m"
            slack = float(np.min(np.minimum(ph.command - ph.lower, ph.upper - ph.command)))
            assert torque_text(slack, unit) in rows[i][5] and ph.effort_joint in rows[i][3]
            assert f"{np.min(ph.command):.3g}" in rows[i][4] and f"{np.max(ph.command):.3g}" in rows[i][4]
            assert ("clockwise" in rows[i][4]) == (unit == "N m")
    shots = card_snapshots(plan)
    axes = snapshot_axes(fig)
    assert len(axes) == len(shots)
    for ax, s in zip(axes, shots):  # each panel titled with its state; contacts drawn exactly where the fingers touch
        assert s.state in ax.get_title() and f"phase {s.phase}" in ax.get_title()
        dots = [ln for ln in ax.get_lines() if ln.get_marker() == "o" and len(ln.get_xdata())]
        assert bool(dots) == s.touching
    legend = {t.get_text() for t in legend_of(fig).get_texts()}
    marks = {(m, filled) for ax in torque_axes(fig) for ln in ax.get_lines() if len(ln.get_xdata())
             for m, filled in [(ln.get_marker(), ln.get_markerfacecolor() != "white")]}  # fmt: skip
    for (m, filled), label in {("^", True): "upper edge unbounded", ("^", False): "upper edge above the plot (finite)",
                               ("v", True): "lower edge unbounded", ("v", False): "lower edge below the plot (finite)"}.items():  # fmt: skip
        assert ((m, filled) in marks) == (label in legend), label
    notes = [t for ax in torque_axes(fig) for t in ax.texts]
    assert any(t.get_text().startswith("narrowest ") for t in notes) == ("narrowest band, with its width" in legend)
    assert any(t.get_text().startswith("slack ") for t in notes) == ("slack: command to the nearer edge" in legend)
    assert ("contact" in legend) == any(s.touching for s in shots)
    for ax in torque_axes(fig):  # a narrowest arrow is whole or not drawn
        y0, y1 = ax.get_ylim()
        for a in ax.texts:
            if getattr(a, "arrow_patch", None) is not None and a.arrowprops.get("arrowstyle") == "<->":
                assert y0 <= min(a.xy[1], a.xyann[1]) and max(a.xy[1], a.xyann[1]) <= y1
    bar = next(a for a in fig.axes if a.get_title(loc="left").startswith("phases as numbered in plan.csv"))
    assert bar.get_position().height < 0.35 * torque_axes(fig)[0].get_position().height  # a compact mode bar


@pytest.mark.parametrize("name", QUICK_CARDS)
def test_card(name):
    check_card(planned(name), plan_card(planned(name)))


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in TASKS if n not in QUICK_CARDS])
def test_card_of_every_bundled_task(name):
    check_card(planned(name), plan_card(planned(name)))


def test_demo_card_tells_a_finite_upper_edge_from_an_unbounded_one():
    """Issue 25: the demo's upper edge is a finite 1.82 N m above the plot, not infinite; its slack is 0.04 N m."""
    plan = planned("demo_task")
    (seg,) = plan.segments
    assert np.all(np.isfinite(seg.upper)) and np.max(seg.upper) > 1.0
    fig = plan_card(plan)
    legend = {t.get_text() for t in legend_of(fig).get_texts()}
    assert "upper edge above the plot (finite)" in legend and "upper edge unbounded" not in legend
    assert "slack 0.04 N m" in all_text(fig) and "0.04 N m" in phase_rows(plan)[0][5]


def test_torque_direction_is_shown():
    """A positive torque turns the link counter-clockwise about its joint; the snapshots draw it, the table says it."""
    plan = planned("demo_task")
    hand, (seg,) = plan.task.hand, plan.segments
    pose, q = plan.task.pose(seg.x[0]), seg.q[0]
    axis = joint_axes(hand, q)[joint_names(hand).index(seg.effort_joint)]
    for sign in (1.0, -1.0):
        p, d = effort_direction(hand, pose, q, seg.effort_joint, sign)
        r = p - axis
        assert np.sign(r[0] * d[1] - r[1] * d[0]) == sign and np.hypot(*d) == pytest.approx(1.0)
    assert np.all(seg.command > 0) and "counter-clockwise" in phase_rows(plan)[0][4]
    fig = plan_card(plan)
    for ax in snapshot_axes(fig):
        assert any(getattr(a, "arrowprops", None) and a.arrowprops.get("arrowstyle") == "-|>" for a in ax.texts)
