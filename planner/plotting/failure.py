"""``failure.png``: the configuration a failure report names, drawn (issue 25).

:func:`failure_figure` draws what :mod:`qsplan.planner.plan.failure` and :mod:`qsplan.planner.plan.obstacles` report
when a task has no plan: the hand and the workpiece at the failed configuration, the overlapping bodies in red
(outlined, their overlap filled) and a joint beyond its limit outlined in red
(:func:`qsplan.planner.plotting.preview.plot_configuration`); below, the workpiece x along the palm: where the
workpiece rests on it, the task's start and goal, the failed slide with the configurations where its band closes
and the narrowest one marked.  The report's message is the title.  Units SI (m).
"""

from __future__ import annotations

import textwrap

import numpy as np

from qsplan.planner.plotting.preview import COLLISION, plot_configuration
from qsplan.planner.plotting.style import FONT, legend_below

__all__ = ["drawn_report", "failed_configuration", "failed_pose", "failure_figure"]

#: Characters per line of the wrapped message (the figure is 8 inches wide at 7.5 pt), and the most lines shown.
WRAP, MAX_LINES = 120, 8


def _row_q(task, segment: str, x: float):
    """The joints (n_j,) at ``x`` of the grasp a report's segment names (``"... grasp <label> ..."``, the longest label
    found), else of the scripted grasp (the start's free joints held); None where it has none there."""
    from qsplan.mechanics.errors import QsplanError

    hand = task.hand
    if task.goal is not None and task.goal.x is not None:
        from qsplan.planner.plan.autoplan import grasp_rows

        rows = [r for r in grasp_rows(task, task.start_x, task.goal.x) if f"grasp {r.label}" in segment]
        if rows:
            row = max(rows, key=lambda r: len(r.label))
            q = hand.grasp_states(task.formation, row.grasp, np.array([x]), row.free_at([x])).q[0]
            return q if np.all(np.isfinite(q)) else None
    try:
        return hand.closed_configuration(task.formation, None, x, task.start_free)
    except QsplanError:
        return None


def _band_report(report):
    """The segment report (``FailureReport``) a report carries, or None."""
    if report.as_dict().get("kind") == "band closes":
        return report
    return getattr(report, "band", None)


def drawn_report(task, report) -> tuple:
    """``(task, report)`` to draw: a route step's failure (:class:`qsplan.planner.plan.failure.StepReport`) is drawn
    as its own report, with the task that step was planned as (its goal the step's end)."""
    from qsplan.planner.plan.failure import StepReport

    while isinstance(report, StepReport):
        task, report = report.task, report.report
    return task, report


def failed_pose(task, report, x: float) -> np.ndarray:
    """The workpiece's pose ``(x, y, theta)`` (m, m, rad) at the configuration ``report`` names: its own (a pivot's
    row), else resting on its bottom edge at ``x``."""
    pose = getattr(report, "pose", None)
    return task.pose(x) if pose is None else np.asarray(pose, dtype=float)


def failed_configuration(task, report) -> tuple:
    """``(x, q, collisions, highlight)``: the configuration ``report`` names (m; rad or m, None where no grasp
    closes; its pose :func:`failed_pose`), its overlapping bodies (:class:`qsplan.hands.geometry.collision.Collision`)
    and other bodies to outline (a joint beyond its limit, the palm an edge passes)."""
    task, report = drawn_report(task, report)
    d = report.as_dict()
    band = _band_report(report)
    kind = d.get("kind")  # a report of another kind (a refused certificate): the start is drawn
    if kind == "invalid configuration" or (kind == "no turn" and report.pose is not None):
        x, q = float(report.x), None if report.q is None else np.asarray(report.q, float)
    elif kind == "beyond the palm":
        return float(report.x), None, (), ()
    elif band is not None:
        x = float(band.narrowest.x if band.narrowest is not None else band.x_start)
        q = _row_q(task, band.segment, x)
    else:  # no route for the geometry, a goal not served, or a certificate refused: the start
        x = float(task.start_x)
        q = _row_q(task, "", x)
    if q is None:
        return x, None, (), ()
    lim = task.joint_limits
    over = tuple(n for k, n in enumerate(task.hand.joint_names) if not lim[k, 0] <= q[k] <= lim[k, 1])
    hits = tuple(task.hand.collisions(failed_pose(task, report, x), q))
    bodies = set(d.get("bodies") or ())
    if bodies:  # the pair the report names (a finger drawn fully open may fold onto itself: not the obstacle)
        hits = tuple(c for c in hits if set(c.bodies) == bodies)
    return x, q, hits, over


def _x_strip(ax, task, report, x_failed):
    """The workpiece x along the palm: where it rests on it, the start and the goal, the failed slide."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from qsplan.planner.task.goal import palm_x_range

    lo, hi = palm_x_range(task.hand)
    goal = float(task.waypoints[-1]) if task.goal is None else task.goal.x  # None: a goal placed otherwise (a turn)
    ax.axvspan(lo, hi, color="#eeeeee", zorder=0)
    handles = [Patch(fc="#eeeeee", label="the workpiece rests on the palm")]
    pts = [lo, hi, task.start_x, x_failed]
    ax.axvline(task.start_x, color="k", lw=1.0)
    handles.append(Line2D([], [], color="k", lw=1.0, label="start"))
    if goal is not None:
        pts.append(goal)
        ax.axvline(goal, color="k", lw=1.0, ls="--")
        handles.append(Line2D([], [], color="k", ls="--", label="goal"))
    band = _band_report(report)
    if band is not None:
        ax.annotate("", (band.x_goal, 0.5), (band.x_start, 0.5), arrowprops={"arrowstyle": "->", "color": "0.3"})
        handles.append(Line2D([], [], color="0.3", marker=">", ms=4, label="the failed slide"))
        xs = [p.x for p in band.closed]
        if xs:
            ax.plot(xs, np.full(len(xs), 0.5), "o", ms=4, color=COLLISION, zorder=4)
            handles.append(Line2D([], [], ls="none", marker="o", ms=4, color=COLLISION, label="band closed"))
        pts += [band.x_start, band.x_goal]
    ax.plot([x_failed], [0.5], "*", ms=12, color=COLLISION, mec="k", zorder=5)
    handles.append(Line2D([], [], ls="none", marker="*", ms=10, color=COLLISION, mec="k", label="drawn above"))
    span = max(pts) - min(pts)
    ax.set_xlim(min(pts) - 0.05 * span, max(pts) + 0.05 * span)
    ax.set_ylim(0.0, 1.0)
    ax.set_yticks([])
    ax.set_xlabel("workpiece x (m)", fontsize=FONT["label"])
    legend_below(ax, handles, ncol=3)


def _goal_theta(task, report):
    """The angle (rad) a turning goal asks: its ``theta``, or where a formation the search tried lands its palm edge
    (the report's ``goal_theta``); None where nothing places it."""
    if task.goal is not None and task.goal.theta is not None:
        return float(task.goal.theta)
    return getattr(report, "goal_theta", None)


def _theta_strip(ax, task, report, theta_failed):
    """The workpiece's angle (deg) for a goal that turns it: the start (0), the goal's angle, the failed row."""
    from matplotlib.lines import Line2D

    goal = _goal_theta(task, report)
    pts = [0.0, np.degrees(theta_failed)]
    ax.axvline(0.0, color="k", lw=1.0)
    handles = [Line2D([], [], color="k", lw=1.0, label="start (theta = 0)")]
    if goal is not None:
        pts.append(np.degrees(goal))
        ax.axvline(np.degrees(goal), color="k", lw=1.0, ls="--")
        handles.append(Line2D([], [], color="k", ls="--", label=f"goal (theta = {np.degrees(goal):.4g} deg)"))
    ax.plot([np.degrees(theta_failed)], [0.5], "*", ms=12, color=COLLISION, mec="k", zorder=5)
    handles.append(Line2D([], [], ls="none", marker="*", ms=10, color=COLLISION, mec="k", label="drawn above"))
    span = max(max(pts) - min(pts), 1.0)
    ax.set_xlim(min(pts) - 0.05 * span, max(pts) + 0.05 * span)
    ax.set_ylim(0.0, 1.0)
    ax.set_yticks([])
    ax.set_xlabel("workpiece angle theta (deg, counter-clockwise)", fontsize=FONT["label"])
    legend_below(ax, handles, ncol=3)


def failure_figure(task, report, path=None):
    """``failure.png``: the failed configuration ``report`` names (see the module docstring).

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    report : FailureReport, ConfigurationReport, PalmReport or NoRouteReport
        (:mod:`qsplan.planner.plan.failure`, :mod:`qsplan.planner.plan.obstacles`); any other report with
        ``as_dict()`` and ``message`` is drawn at the start.
    path : str or Path, optional
        Written there (atomically, replacing a file: the caller checked its outputs).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from qsplan.planner.plotting.style import save_figure

    from qsplan.planner.task.goal import reorients

    message = report.message
    x, q, hits, over = failed_configuration(task, report)
    task, report = drawn_report(task, report)
    pose = failed_pose(task, report, x)
    fig = Figure(figsize=(8.0, 6.6), layout="constrained")
    ax, strip = fig.subplots(2, 1, height_ratios=[3.6, 0.6])
    plot_configuration(task, x, q, ax=ax, collisions=hits, highlight=over, pose=pose)
    if report.as_dict().get("kind") == "beyond the palm":  # the stretch of the resting edge beyond the palm's end
        end, edge = report.palm_end, report.edge
        far = edge[0] if report.side == "left" else edge[1]
        ax.plot([end, far], [0.0, 0.0], color=COLLISION, lw=4, solid_capstyle="butt", zorder=8)
    units = task.hand.joint_units()
    what = ("fingers drawn open at mid-range: no grasp closes here" if q is None else
            "q = (" + ", ".join(f"{v:.4g} {u}" for v, u in zip(q, units)) + ")")  # fmt: skip
    red = "; red: overlapping bodies, joints beyond their limits" if hits or over else ""
    if report.as_dict().get("kind") == "beyond the palm":
        red = "; red: the resting edge beyond the palm's end"
    turned = f", theta = {np.degrees(pose[2]):.4g} deg" if pose[2] != 0.0 else ""
    ax.set_title(f"workpiece x = {x:.4g} m{turned}, {what}{red}", fontsize=FONT["note"])
    if reorients(task):  # a goal that turns the workpiece: its angle, not its x, says how far the route came
        _theta_strip(strip, task, report, float(pose[2]))
    else:
        _x_strip(strip, task, report, x)
    lines = textwrap.wrap(message, WRAP)
    fig.suptitle("\n".join(lines[:MAX_LINES] + (["..."] if len(lines) > MAX_LINES else [])), fontsize=FONT["note"])
    if path is not None:
        save_figure(fig, path, option="out_dir")
    return fig
