"""The plan card for the operator (issue 25): snapshot labels checked against the plan's rows on every bundled task that
plans, start and end grasps always drawn, slack and command range in words and on the plot, edges beyond the plot
drawn by kind, narrowest arrows never cut, phase numbers as in plan.csv, a legend of what is drawn only, and the
layout checks of every figure (no overlapping text, no legend over data, units on every axis)."""

import re
from dataclasses import fields
from functools import cache

import numpy as np
import pytest

from qsplan.hands.described.records import contacts_at, joint_axes, joint_kinds, joint_names
from qsplan.mechanics import SceneError
from qsplan.planner.plan.results import ContactSegmentPlan, RegraspPlan, SlidePhase
from qsplan.planner.plotting.card import card_snapshots, phase_rows, plan_card
from qsplan.planner.plotting.hands import STATES, effort_direction, plan_snapshots
from qsplan.planner.plotting.style import torque_text
from qsplan.planner.task.task import task_paths
from tests.planner.figure_checks import all_text, labels_without_units, legends_over_axes, overlapping_texts

pytestmark = pytest.mark.ompl

#: Bundled tasks that plan (``friction_closes_task`` is the bundled example of a task with no plan).
TASKS = sorted(n for n in task_paths() if n != "friction_closes_task")

#: Tasks whose cards are drawn in the default run (one paper-hand slide, one chain-hand regrasp); the rest are slow.
QUICK_CARDS = ("demo_task", "two_link_regrasp_task")

def planned(name):
    """``plan_task`` of a bundled task, once per test run (tests/planner/bundled.py)."""
    from tests.planner.bundled import planned as shared

    return shared(name)


@cache
def card(name):
    """The plan card of a bundled task's plan, drawn once per process: the tests below only read it (1-3 s each)."""
    return plan_card(planned(name))


def every_finger_touches(plan, pose, q) -> bool:
    """The contact search finds the grasp's contact set (palm, palm, a left-finger link, a right-finger link); a
    paper-form hand's in any formation, and a chain hand's in a turning one: the palm and both fingers' last links
    touch (qsplan.hands.contacts.found)."""
    from qsplan.hands.contacts.found import ordered_contacts
    from qsplan.hands.contacts.sets import finger_link

    hand = plan.task.hand
    if getattr(hand, "paper", None) is not None:
        bodies = {c.body for c in ordered_contacts(hand, pose, q)}
        return {-1, finger_link(hand, "left"), finger_link(hand, "right")} <= bodies
    try:
        if len(contacts_at(hand, pose, q)) == 4:
            return True
    except SceneError:
        pass
    try:  # a chain hand in a turning formation (a hold, a pivot: five contacts, or the workpiece turned): as above
        bodies = {c.body for c in ordered_contacts(hand, pose, q)}
    except SceneError:
        return False
    return {-1, finger_link(hand, "left"), finger_link(hand, "right")} <= bodies


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
            # contacts drawn: every finger on the workpiece, or the one holding it while the other is replaced
            touching = every_finger_touches(plan, pose, q) or ph.kind == "replace"
            assert s.touching == touching, (name, s.t)
            if isinstance(ph, ContactSegmentPlan) and ph.kind == "hold":  # nothing moves, the torque ramps
                assert s.state == "holding" and np.ptp(ph.x) == 0 and s.effort == ph.command[s.row]
            elif isinstance(ph, ContactSegmentPlan) and ph.kind == "pivot":  # the workpiece turns on a palm vertex
                assert s.state == "pivoting" and np.ptp(ph.pose[:, 2]) > 0 and s.effort == ph.command[s.row]
            elif isinstance(ph, ContactSegmentPlan):
                assert s.state == "sliding" and np.ptp(ph.x) > 0 and s.effort == ph.command[s.row]
            elif every_finger_touches(plan, pose, q):
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
    check_card(planned(name), card(name))


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in TASKS if n not in QUICK_CARDS])
def test_card_of_every_bundled_task(name):
    check_card(planned(name), card(name))


def test_demo_card_tells_a_finite_upper_edge_from_an_unbounded_one():
    """Issue 25: the demo's upper edge is a finite 1.82 N m above the plot, not infinite; its slack is 0.04 N m."""
    plan = planned("demo_task")
    (seg,) = plan.segments
    assert np.all(np.isfinite(seg.upper)) and np.max(seg.upper) > 1.0
    fig = card("demo_task")
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
    fig = card("demo_task")
    for ax in snapshot_axes(fig):
        assert any(getattr(a, "arrowprops", None) and a.arrowprops.get("arrowstyle") == "-|>" for a in ax.texts)


# --- issue 31, item 7: what the operator sees of a turning plan ----------------------------------------------------

#: The bundled tasks that turn the workpiece: slide, hold, pivot; both pivot on vertex 1 as their files write it.
TURNING = ("reorient_task", "reorient_edge_task")

#: Least share of its panel's height the smallest slack of a phase is drawn at: 3 % (about 7 pixels of a torque panel
#: on the 150 dpi page), the bracket and both lines apart.  Phase 0 of reorient_task on the one 0-8.6 N m axis it had:
#: 0.5 %.
MIN_SLACK_SHARE = 0.03


def vertex_heights(plan, phase):
    """Each workpiece vertex's height above the palm (m) at ``phase``'s rows, shape (n, n_v), columns as the task
    writes the vertices."""
    hand = plan.task.hand
    V = np.asarray(hand.workpiece, float)
    pose = phase.poses(hand.rest_height)
    y = pose[:, 1:2] + np.sin(pose[:, 2:3]) * V[None, :, 0] + np.cos(pose[:, 2:3]) * V[None, :, 1]
    out = np.empty_like(y)
    out[:, np.asarray(hand.user_vertices, int)] = y
    return out


def as_slide(phase) -> SlidePhase:
    """``phase``'s rows as a slide (the fields every in-contact phase has)."""
    return SlidePhase(**{f.name: getattr(phase, f.name) for f in fields(ContactSegmentPlan)})


@pytest.mark.parametrize("name", TURNING)
def test_a_turning_plan_names_and_colours_each_step_kind(name):
    from matplotlib.colors import to_rgb
    from qsplan.planner.plotting.plan_panels import phase_colour, timeline_handles

    plan = planned(name)
    kinds = [ph.kind for ph in plan.phases]
    assert kinds == ["slide", "hold", "pivot"]
    pivot = plan.phases[2]
    y = vertex_heights(plan, pivot)  # the workpiece turns on vertex 1, the one on the palm: what the title says
    assert np.abs(y[:, 1]).max() < 1e-6 and np.ptp(pivot.pose[:, 2]) > 0.3
    assert np.all(np.delete(y[1:-1], 1, axis=1) > 1e-4)  # every other vertex lifted (the last row may land an edge)
    fig = card(name)
    for ax, s in zip(snapshot_axes(fig), card_snapshots(plan)):
        title = ax.get_title()
        expected = {"slide": "sliding", "hold": "holding", "pivot": "pivoting on vertex 1"}[kinds[s.phase]]
        assert expected in title and (kinds[s.phase] != "pivot" or "sliding" not in title), title
    assert "pivots on vertex 1, 0 to" in phase_rows(plan)[2][2]
    # one colour per step kind: in the bars, the card's mode bar and the legend's patches
    colours = [to_rgb(phase_colour(ph, plan.task.hand)) for ph in plan.phases]
    for i in range(3):
        for j in range(i):
            assert np.linalg.norm(np.subtract(colours[i], colours[j])) > 0.2, (i, j)
    luminance = [np.dot(c, [0.299, 0.587, 0.114]) for c in colours[1:]]  # the right finger's hold and pivot
    assert luminance[0] > np.dot(to_rgb(phase_colour(as_slide(pivot), plan.task.hand)),
                                 [0.299, 0.587, 0.114]) > luminance[1]  # fmt: skip
    patches = {h.get_label(): to_rgb(h.get_facecolor()) for h in timeline_handles(plan)}
    assert len(patches) == 3 and len(set(patches.values())) == 3
    legend = {t.get_text(): to_rgb(h.get_facecolor()) for t, h in zip(legend_of(fig).get_texts(),
                                                                       legend_of(fig).legend_handles)
              if t.get_text() in patches}  # fmt: skip
    assert legend == {k: pytest.approx(v, abs=0.02) for k, v in patches.items()}
    bar = next(a for a in fig.axes if a.get_title(loc="left").startswith("phases as numbered in plan.csv"))
    drawn = [to_rgb(p.get_facecolor()) for p in bar.patches]
    assert len(drawn) == 3 and all(np.allclose(d, c, atol=0.02) for d, c in zip(drawn, colours))


def command_panel(fig, ph):
    """The card's axes drawing ``ph``'s command (a line through its rows)."""
    for ax in torque_axes(fig):
        for ln in ax.get_lines():
            x, y = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
            if x.shape == ph.t.shape and np.array_equal(x, ph.t) and np.array_equal(y, ph.command):
                return ax
    raise AssertionError(f"no panel draws {ph.name}'s command")


#: Least share of its panel's height a phase's command and finite band edges span: a quarter.  Phase 0 of
#: reorient_task on the one 0-8.6 N m axis it had: 4 %.
MIN_PHASE_SHARE = 0.25


@pytest.mark.parametrize("name", TURNING + ("demo_task", "two_link_regrasp_task"))
def test_every_phase_is_drawn_on_a_readable_scale(name):
    """Issue 31: the reorientation card drew phase 0's 0.1-0.35 N m band on the pivot's 8 N m axis.  Each phase's
    command and band span a quarter of its panel at least, and each slack bracket 3 % of it."""
    plan = planned(name)
    fig = card(name)
    for ph in plan.segments:
        ax = command_panel(fig, ph)
        to_axes = ax.transData + ax.transAxes.inverted()
        y0, y1 = ax.get_ylim()
        assert y0 <= ph.command.min() and ph.command.max() <= y1  # the whole command in view
        values = np.concatenate([ph.command, ph.lower, ph.upper])
        values = np.clip(values[np.isfinite(values)], y0, y1)
        frac = to_axes.transform(np.column_stack([np.full(values.size, ph.t[0]), values]))[:, 1]
        assert np.ptp(frac) >= MIN_PHASE_SHARE, (ph.name, float(np.ptp(frac)))
    brackets = [(ax, a) for ax in torque_axes(fig) for a in ax.texts
                if getattr(a, "arrowprops", None) and str(a.arrowprops.get("arrowstyle", "")).startswith("|-|")]
    assert brackets
    for ax, a in brackets:
        to_axes = ax.transData + ax.transAxes.inverted()
        ends = to_axes.transform([a.xy, a.xyann])[:, 1]
        assert abs(ends[1] - ends[0]) >= MIN_SLACK_SHARE, (ax.get_title(loc="left"), float(abs(ends[1] - ends[0])))


def data_points(ax, renderer_dpi):
    """Every point of ``ax``'s data lines (not reference lines), densely resampled in display pixels (1 px)."""
    out = []
    for ln in ax.get_lines():
        if not ln.get_visible() or ln.get_transform() != ax.transData:
            continue
        xy = ax.transData.transform(np.asarray(ln.get_xydata(), float))
        for a, b in zip(xy[:-1], xy[1:]):
            if np.all(np.isfinite([a, b])) and ln.get_linestyle() not in ("None", "none", ""):
                n = int(np.ceil(np.hypot(*(b - a)))) + 1
                out.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
        out += [p[None, :] for p in xy if np.all(np.isfinite(p))]
    return np.vstack(out) if out else np.zeros((0, 2))


def labels_over_data(fig) -> list:
    """The narrowest-band and slack labels of ``fig`` whose box holds a point of a data line of their axes."""
    from matplotlib.text import Text

    from tests.planner.figure_checks import render

    renderer = render(fig)
    out = []
    for ax in fig.axes:
        pts = None
        for t in ax.texts:
            if not re.match(r"(narrowest|slack) ", t.get_text()):
                continue
            pts = data_points(ax, fig.dpi) if pts is None else pts
            box = Text.get_window_extent(t, renderer).padded(-1.0)
            inside = (pts[:, 0] > box.x0) & (pts[:, 0] < box.x1) & (pts[:, 1] > box.y0) & (pts[:, 1] < box.y1)
            if inside.any():
                out.append((ax.get_title(loc="left") or ax.get_title(), t.get_text()))
    return out


@pytest.mark.parametrize("name", TURNING + ("demo_task", "two_link_regrasp_task"))
def test_band_labels_cover_no_data(name):
    """Issue 31: on reorient_edge_task's card the "narrowest 0.0439 N m" label covered the command and the band where the
    band is narrowest (3.9-5.4 s)."""
    from qsplan.planner.plotting.plan import plot_plan_bands

    plan = planned(name)
    drawn = card(name)
    assert labels_over_data(drawn) == []
    assert any(t.get_text().startswith("narrowest ") for ax in drawn.axes for t in ax.texts) == np.isfinite(
        min(np.min(s.width) for s in plan.segments))  # fmt: skip
    bands = plot_plan_bands(plan)[0].get_figure(root=True)
    assert labels_over_data(bands) == [] and overlapping_texts(bands) == []


@pytest.mark.parametrize("name", TURNING + ("two_link_regrasp_task",))
def test_mode_timeline_labels_fit_their_bars(name):
    """Issue 31: the mode timeline's pivot label ran past its bar."""
    from matplotlib.patches import Rectangle
    from matplotlib.text import Text
    from qsplan.planner.plotting.plan import plot_mode_timeline

    from tests.planner.figure_checks import render

    plan = planned(name)
    for ax in (plot_mode_timeline(plan), next(a for a in card(name).axes
                                              if a.get_title(loc="left").startswith("phases as numbered"))):  # fmt: skip
        fig = ax.get_figure(root=True)
        renderer = render(fig)
        bars = [p.get_window_extent(renderer) for p in ax.patches if isinstance(p, Rectangle)]
        assert len(bars) == len(plan.phases)
        inside = [t for t in ax.texts if type(t) is Text and t.get_position()[1] == 0 and t.get_text().strip()]
        assert inside  # some labels sit in their bars
        for t in inside:
            box = Text.get_window_extent(t, renderer)
            bar = next(b for b in bars if b.x0 <= 0.5 * (box.x0 + box.x1) <= b.x1)
            assert bar.x0 <= box.x0 and box.x1 <= bar.x1, t.get_text()
        assert overlapping_texts(fig) == []


def test_velocity_panels_draw_what_the_controller_is_sent(tmp_path):
    """Issue 31: the card drew a regrasp's velocities as steps where plan.csv and ``qsplan sample`` ramp them from rest
    to rest.  Each drawn velocity is ``qsplan sample``'s at its ticks (read from the exported plan.csv), it changes no
    faster than the task's joint acceleration on the regrasp, and integrated it follows the plan's joints."""
    from qsplan.hands.described.records import joint_names
    from qsplan.planner.export.plan_files import export_plan
    from qsplan.planner.export.sample import sample_plan

    plan = planned("two_link_regrasp_task")
    export_plan(plan, tmp_path)
    fig = card("two_link_regrasp_task")
    names = joint_names(plan.task.hand)
    regrasp = next(i for i, ph in enumerate(plan.phases) if isinstance(ph, RegraspPlan))
    ph = plan.phases[regrasp]
    a_max = float(np.max(plan.task.dynamics.joint_accelerations))
    for joint in names:
        ax = next(a for a in fig.axes if a.get_title(loc="left") == f"{joint} joint: velocity command")
        (line,) = [ln for ln in ax.get_lines() if ln.get_transform() == ax.transData and len(ln.get_xdata()) > 10]
        assert line.get_drawstyle() == "steps-post"  # each tick's command held until the next
        t, qd = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        ticks = sample_plan(tmp_path, t)  # what `qsplan sample` writes for these ticks
        want = ticks.qd[:, names.index(joint)]
        assert np.array_equal(np.isnan(qd), np.isnan(want)) and np.nanmax(np.abs(qd - want)) < 1e-9
        on = (t >= ph.t[0]) & (t < ph.t[-1])
        dt = float(np.max(np.diff(t)))
        assert np.max(np.abs(np.diff(qd[on]))) <= 1.05 * a_max * dt + 1e-12  # ramps: no step
        k = int(np.searchsorted(t, ph.t[0]))  # integrated over the regrasp: the joint's path at its rows
        q = ph.q[:, names.index(joint)]
        for tr, qr in zip(ph.t[1:], q[1:]):
            m = int(np.searchsorted(t, tr))
            moved = float(np.sum(qd[k:m] * np.diff(t[k:m + 1]))) if m > k else 0.0
            assert abs(q[0] + moved - qr) <= np.nanmax(np.abs(qd)) * dt + 1e-9
