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

__all__ = ["failure_figure", "failed_configuration"]

#: Characters per line of the wrapped message (the figure is 8 inches wide at 7.5 pt), and the most lines shown.
WRAP, MAX_LINES = 120, 8


def _row_q(task, segment: str, x: float):
    """The joints (n_j,) at ``x`` of the grasp a report's segment names (``"... grasp <label> ..."``, the longest label
    found), else of the scripted grasp (the start's free joints held); None where it has none there."""
    from qsplan.mechanics.errors import QsplanError

    hand = task.hand
    if task.goal is not None:
        from qsplan.planner.plan.autoplan import grasp_rows

        rows = [r for r in grasp_rows(task, task.start_x, task.goal.x) if f"grasp {r.label}" in segment]
        if rows:
            row = max(rows, key=lambda r: len(r.label))
            q = hand.grasp_states(task.formation, row.grasp, np.array([x]), row.free_at([x])).q[0]
            return q if np.all(np.isfinite(q)) else None
    free = None
    if hand.free_joints and task.start_joints is not None:
        free = np.asarray(task.start_joints)[list(hand.free_joints)]
    try:
        return hand.closed_configuration(task.formation, None, x, free)
    except QsplanError:
        return None


def _band_report(report):
    """The segment report (``FailureReport``) a report carries, or None."""
    if report.as_dict().get("kind") == "band closes":
        return report
    return getattr(report, "band", None)


def failed_configuration(task, report) -> tuple:
    """``(x, q, collisions, highlight)``: the configuration ``report`` names (m; rad or m, None where no grasp
    closes), its overlapping bodies (:class:`qsplan.hands.collision.Collision`) and other bodies to outline (a joint
    beyond its limit, the palm an edge passes)."""
    d = report.as_dict()
    band = _band_report(report)
    kind = d.get("kind")  # a report of another kind (a refused certificate): the start is drawn
    if kind == "invalid configuration":
        x, q = float(report.x), None if report.q is None else np.asarray(report.q, float)
    elif kind == "beyond the palm":
        return float(report.x), None, (), ()
    elif band is not None:
        x = float(band.narrowest.x if band.narrowest is not None else band.x_start)
        q = _row_q(task, band.segment, x)
    else:  # no route for the geometry, or a certificate refused: the start
        x = float(task.start_x)
        q = _row_q(task, "", x)
    if q is None:
        return x, None, (), ()
    lim = task.joint_limits
    over = tuple(n for k, n in enumerate(task.hand.joint_names) if not lim[k, 0] <= q[k] <= lim[k, 1])
    hits = tuple(task.hand.collisions(task.pose(x), q))
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
    goal = task.goal.x if task.goal is not None else float(task.waypoints[-1])
    ax.axvspan(lo, hi, color="#eeeeee", zorder=0)
    handles = [Patch(fc="#eeeeee", label="the workpiece rests on the palm")]
    pts = [lo, hi, task.start_x, goal, x_failed]
    ax.axvline(task.start_x, color="k", lw=1.0)
    ax.axvline(goal, color="k", lw=1.0, ls="--")
    handles += [Line2D([], [], color="k", lw=1.0, label="start"), Line2D([], [], color="k", ls="--", label="goal")]
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

    x, q, hits, over = failed_configuration(task, report)
    fig = Figure(figsize=(8.0, 6.6), layout="constrained")
    ax, strip = fig.subplots(2, 1, height_ratios=[3.6, 0.6])
    plot_configuration(task, x, q, ax=ax, collisions=hits, highlight=over)
    if report.as_dict().get("kind") == "beyond the palm":  # the stretch of the resting edge beyond the palm's end
        end, edge = report.palm_end, report.edge
        far = edge[0] if report.side == "left" else edge[1]
        ax.plot([end, far], [0.0, 0.0], color=COLLISION, lw=4, solid_capstyle="butt", zorder=8)
    from qsplan.hands.interface import joint_units

    units = joint_units(task.hand)
    what = ("fingers drawn open at mid-range: no grasp closes here" if q is None else
            "q = (" + ", ".join(f"{v:.4g} {u}" for v, u in zip(q, units)) + ")")  # fmt: skip
    red = "; red: overlapping bodies, joints beyond their limits" if hits or over else ""
    if report.as_dict().get("kind") == "beyond the palm":
        red = "; red: the resting edge beyond the palm's end"
    ax.set_title(f"workpiece x = {x:.4g} m, {what}{red}", fontsize=FONT["note"])
    _x_strip(strip, task, report, x)
    lines = textwrap.wrap(report.message, WRAP)
    fig.suptitle("\n".join(lines[:MAX_LINES] + (["..."] if len(lines) > MAX_LINES else [])), fontsize=FONT["note"])
    if path is not None:
        save_figure(fig, path, option="out_dir")
    return fig
