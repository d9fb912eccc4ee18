"""The feasibility preview drawn (``check.png``): the start and the goal, collisions in red, each grasp along the palm.

:func:`preview_figure` takes the values of a :class:`qsplan.planner.reports.preview.Preview` (this layer does not
import the reports): two hand panels, the start and the goal closed (:func:`plot_configuration`: the overlapping
bodies outlined in red and their overlap filled; a finger that closes onto nothing drawn faded at mid-range), and
one horizontal bar per grasp over the workpiece x: grey where it is not a valid configuration, light where it is,
dark where a guaranteed band at least the torque resolution wide exists; the upper half of a bar for slides toward
+x, the lower half toward -x; the start, the goal and a scripted task's waypoints marked.  matplotlib is imported
inside the functions.  Units SI (m).
"""

from __future__ import annotations

import textwrap

import numpy as np

from qsplan.planner.plotting.style import FONT, axes_or_new, legend_below

__all__ = ["BANDED", "COLLISION", "INVALID", "VALID", "plot_configuration", "plot_grasp_bars", "preview_figure"]

#: Bar colours: not a valid configuration, valid without a band at least the resolution wide, valid and banded.
INVALID, VALID, BANDED = "#d9d9d9", "#9ecae1", "#08519c"
#: Overlapping bodies and joints beyond their limits.
COLLISION = "#d62728"

#: Characters per line of wrapped titles and notes (a panel about 4 inches wide at 7.5 pt).
WRAP = 62
#: Two marks on the bar axis closer than this fraction of its span share one label (their texts would overlap).
MARK_MERGE = 0.06
#: Height (inches) of one bar of the grasp axis, the hand panels' usual height (their drawings keep their aspect, within
#: 0.6 to 1.6 times it), and the width of ``check.png``.
BAR_HEIGHT, HAND_HEIGHT, FIGURE_WIDTH = 0.36, 2.6, 10.0
#: The bar axis shows the valid grasps and the marks, padded by this fraction of their span, at least
#: :data:`VIEW_MIN_PAD` (m).
VIEW_PAD, VIEW_MIN_PAD = 0.08, 0.005


def _drawable(task, q):
    """``(q, closed)``: ``q`` (n_j,) with every NaN joint (a finger that closes onto nothing) at mid-range, and
    whether nothing was replaced."""
    lim = task.joint_limits
    if q is None:
        return 0.5 * (lim[:, 0] + lim[:, 1]), False
    q = np.array(q, dtype=float)
    bad = ~np.isfinite(q)
    q[bad] = 0.5 * (lim[bad, 0] + lim[bad, 1])
    return q, not bad.any()


def plot_configuration(task, x, q, ax=None, collisions=(), limits=None, highlight=(), pose=None):
    """The hand with the workpiece at ``x`` (m) and joints ``q`` (n_j,; None or NaN joints: drawn faded at mid-range),
    every overlap of ``collisions`` (:class:`qsplan.hands.geometry.collision.Collision`) in red: both bodies outlined,
    their intersection filled; ``highlight``: more body names (``"palm"``, ``"workpiece"``, a joint) to outline in red;
    ``pose`` ``(x, y, theta)`` (m, m, rad) where the workpiece does not rest on its bottom edge at ``x``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Polygon as Patch
    from shapely.geometry import Polygon

    from qsplan.hands.geometry.collision import body_label
    from qsplan.planner.plotting.hands import hand_limits, plot_hand

    ax = axes_or_new(ax, size=(3.6, HAND_HEIGHT))
    hand = task.hand
    pose = task.pose(x) if pose is None else np.asarray(pose, dtype=float)
    q_draw, closed = _drawable(task, q)
    limits = limits or hand_limits(hand, [(pose, q_draw)])
    valid = closed and not collisions and not highlight
    plot_hand(hand, pose, q_draw, ax=ax, contacts=valid, limits=limits, alpha=1.0 if closed else 0.35)
    polys = hand.body_polygons(pose, q_draw)
    of_label = {body_label(name): name for name in polys}
    names = set(highlight)
    for c in collisions:
        a, b = (of_label.get(n, n) for n in c.bodies)
        names |= {a, b}
        if a in polys and b in polys:
            region = Polygon(polys[a]).intersection(Polygon(polys[b]))
            for part in getattr(region, "geoms", [region]):
                if part.geom_type == "Polygon" and part.area > 0:
                    ax.add_patch(Patch(np.asarray(part.exterior.coords), closed=True, fc=COLLISION, ec=COLLISION,
                                       alpha=0.8, zorder=7))  # fmt: skip
    for name in names & set(polys):
        ax.add_patch(Patch(polys[name], closed=True, fill=False, ec=COLLISION, lw=2.0, zorder=6))
    return ax


def _check_title(check) -> tuple:
    """A configuration check's panel title and its colour."""
    head = f"{check['where']}: x = {check['x_m']:.4g} m"
    if check["ok"]:
        return f"{head}: ok\n" + textwrap.fill(str(check["grasp"]), WRAP), "k"
    problems = [check["beyond_palm"], check["contact"]] + [c["message"] for c in check["collisions"]]
    problems += [lim["message"] for lim in check["limits"]]
    text = "; ".join(p for p in problems if p) or "no grasp of the hand meets it here"
    return f"{head}: not valid\n" + textwrap.fill(text, WRAP), COLLISION


def _marks(marks, span) -> list:
    """``[(x, label), ...]`` (m) sorted, the labels of marks closer than :data:`MARK_MERGE` of ``span`` merged."""
    out = []
    for x, name in sorted(marks, key=lambda m: m[0]):  # stable: the start before the goal at one x
        if out and abs(x - out[-1][0]) < MARK_MERGE * span:
            out[-1] = (out[-1][0], f"{out[-1][1]}, {name}")
        else:
            out.append((x, name))
    return out


def _view(x, bars, marks) -> tuple:
    """The x limits (m) of the bar axis: every valid grasp and every mark, padded (the whole grid where nothing is
    valid)."""
    x = np.asarray(x, dtype=float)
    valid = np.any([v for _, v, _ in bars], axis=0) if bars else np.zeros(x.size, bool)
    if not valid.any():
        at = [m for m, _ in marks]
        return min(float(x[0]), min(at) - VIEW_MIN_PAD), max(float(x[-1]), max(at) + VIEW_MIN_PAD)
    at = np.array([m for m, _ in marks])
    pts = np.concatenate([x[valid], at])
    lo, hi = float(pts.min()), float(pts.max())
    pad = max(VIEW_PAD * (hi - lo), VIEW_MIN_PAD)
    # the grid's ends, but a mark beyond them (a position beyond the palm) stays in view
    lo, hi = max(lo - pad, float(x[0])), min(hi + pad, float(x[-1]))
    return min(lo, at.min() - VIEW_MIN_PAD), max(hi, at.max() + VIEW_MIN_PAD)


def plot_grasp_bars(x, bars, start_x, goal_x, waypoints=(), resolution_text="at least the resolution", ax=None,
                    goal_label="goal"):  # fmt: skip
    """One bar per grasp over the workpiece x (m): ``bars`` a list of ``(label, valid (n,), banded (2, n))``;
    ``resolution_text`` says how wide a band counts (``"\u2265 0.02 N m"``).  The view holds every valid grasp and
    the marks (the start, the waypoints, the goal, marked ``goal_label``; ``goal_x`` None: not marked); the x label
    says where nothing is valid beyond it.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ax = axes_or_new(ax, size=(8.0, 0.6 + BAR_HEIGHT * len(bars)))
    x = np.asarray(x, dtype=float)
    half = 0.5 * (np.diff(x).max() if x.size > 1 else 1e-3)
    from matplotlib.colors import ListedColormap

    n = len(bars)
    # one image, five rows per bar of 0.2 each (top down): two for sliding +x, two for sliding -x, a white gap;
    # bar k's halves meet at y = n - 1 - k (its tick)
    image = np.full((5 * n, x.size), 3, dtype=np.int8)
    for k, (_, valid, banded) in enumerate(bars):
        for d, rows in ((1, slice(5 * k, 5 * k + 2)), (0, slice(5 * k + 2, 5 * k + 4))):
            image[rows] = np.where(banded[d], 2, np.where(valid, 1, 0))[None, :]
    ax.imshow(image, cmap=ListedColormap([INVALID, VALID, BANDED, "white"]), vmin=-0.5, vmax=3.5, aspect="auto",
              interpolation="nearest", origin="upper", extent=(x[0] - half, x[-1] + half, -0.6, n - 0.6))  # fmt: skip
    ax.set_yticks([n - 1 - k for k in range(n)])
    ax.set_yticklabels([label for label, *_ in bars], fontsize=FONT["note"])
    ax.set_ylim(-0.6, n - 0.6 + 0.2)
    marks = [(float(start_x), "start")] + [(float(w), f"w{k + 1}") for k, w in enumerate(list(waypoints)[:-1])]
    if goal_x is not None:  # None: a goal the preview does not place (a turn)
        marks.append((float(goal_x), goal_label))
    lo, hi = _view(x, bars, marks)
    ax.set_xlim(lo, hi)
    whole = lo <= x[0] and hi >= x[-1]
    ax.set_xlabel("workpiece x (m)" + ("" if whole else f"; no grasp is valid elsewhere on the palm "
                                       f"[{x[0]:.3g}, {x[-1]:.3g}] m"), fontsize=FONT["label"])  # fmt: skip
    marks = _marks(marks, hi - lo)
    for xm, name in marks:
        ax.axvline(xm, color="k", lw=1.0, ls="-" if "start" in name else ("--" if goal_label in name else ":"),
                   zorder=4)  # fmt: skip
    top = ax.secondary_xaxis("top")
    top.set_xticks([m for m, _ in marks])
    top.set_xticklabels([name for _, name in marks], fontsize=FONT["note"])
    handles = [Patch(fc=INVALID, label="not a valid configuration"),
               Patch(fc=VALID, label=f"valid, no band {resolution_text} wide"),
               Patch(fc=BANDED, label=f"valid and banded (a band {resolution_text} wide)"),
               Line2D([], [], ls="none", label="upper half of a bar: sliding +x; lower half: sliding -x")]  # fmt: skip
    legend_below(ax, handles, ncol=2)
    return ax


def preview_figure(task, preview):
    """``check.png``: the start and the goal closed (collisions in red) over the grasps' bars.

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    preview : qsplan.planner.reports.preview.Preview

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from qsplan.hands.geometry.collision import Collision
    from qsplan.planner.plotting.hands import hand_limits

    d = preview.as_dict()
    n = len(preview.grasps)
    bars_h = 1.9 + BAR_HEIGHT * n
    turn = preview.slide_end is not None  # a turning goal: its slide's end drawn, the turn said under it
    checks = ((preview.start, d["start"]), (preview.slide_end, d["slide_end"]) if turn else (preview.goal, d["goal"]))
    limits = hand_limits(task.hand, [(task.pose(c.x), _drawable(task, c.q)[0]) for c, _ in checks if c.previewed])
    (x0, x1), (y0, y1) = limits
    hand_h = float(np.clip(0.45 * FIGURE_WIDTH * (y1 - y0) / (x1 - x0), 0.6 * HAND_HEIGHT, 1.6 * HAND_HEIGHT))
    head = 1.2 + (0.15 if turn else 0.0)  # titles over the hands: a turn's slide end says one line more
    fig = Figure(figsize=(FIGURE_WIDTH, hand_h + head + bars_h), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=[hand_h + head, bars_h])
    panels = top.subplots(1, 2)
    for ax, (check, words) in zip(panels, checks):
        if not check.previewed:  # a turning goal the check does not judge: said, nothing drawn
            ax.axis("off")
            ax.text(0.0, 1.0, textwrap.fill(check.message, WRAP), transform=ax.transAxes, ha="left", va="top",
                    fontsize=FONT["note"], color="k")  # fmt: skip
            continue
        hits = tuple(Collision(tuple(c["bodies"]), c["area_m2"], c["depth_m"]) for c in words["collisions"])
        over = tuple(lim.joint for lim in check.limits)
        plot_configuration(task, check.x, check.q, ax=ax, collisions=hits, limits=limits, highlight=over)
        title, colour = _check_title(words)
        if check is preview.slide_end:  # the turn after it (the verdict says how it is planned)
            title += "\nthen " + textwrap.fill(preview.goal.message.partition("; qsplan plan")[0], WRAP)
        ax.set_title(title, fontsize=FONT["note"], color=colour, loc="left")
    ax = bottom.subplots(1, 1)
    bars = [(f"{b.name}  {b.short}", b.valid, b.banded) for b in preview.grasps]
    end = preview.slide_end if turn else preview.goal
    plot_grasp_bars(preview.x, bars, preview.start.x, end.x if end.previewed else None, preview.waypoints,
                    f"\u2265 {preview.resolution:g} {preview.resolution_unit}", ax=ax,
                    goal_label=end.where if turn else "goal")  # fmt: skip
    # a turn not previewed is no failure: the verdict in black when what was previewed holds and nothing is refused
    fine = preview.ok or (turn and preview.start.ok and preview.slide_end.ok and bool(preview.route)) or (
        not preview.goal.previewed and not preview.goal.refused and not turn and preview.start.ok)  # fmt: skip
    ax.set_title(textwrap.fill(preview.verdict, 2 * WRAP), fontsize=FONT["note"], loc="left",
                 color="k" if fine else COLLISION)  # fmt: skip
    fig.suptitle(f"qsplan check: {preview.task}", fontsize=FONT["title"])
    return fig
