"""The pieces plan figures are drawn from: phases in words, band panels, slack marks, the mode timeline.

Shared by :mod:`qsplan.planner.plotting.plan` (one figure per view), :mod:`qsplan.planner.plotting.card` (the plan
card) and :mod:`qsplan.planner.plotting.animation`.  Only the plan's public fields are read
(``Plan.phases``, :class:`~qsplan.planner.plan.results.ContactSegmentPlan`; any other phase is
drawn as a free motion of the fingers), so plans with more phases or fields draw too (the snapshots' choice is
:func:`qsplan.planner.plotting.hands.plan_snapshots`).  Phases are numbered as
``plan.csv`` numbers them (``phase`` 0 first).  Band edges are marked as in Fig. 13
(:func:`qsplan.planner.plotting.band_panels.plot_band_sweep`): beyond the plot, filled triangles where an edge is
unbounded, hollow ones where it is finite.  Phases of very different torques get panels of their own, a panel
whose command spans more than a decade a log scale (:func:`scale_groups`, :func:`torque_scale`); the labels of the
marks are placed once the figure is laid out, where they cover no line (:func:`place_labels`).  matplotlib is
imported inside the functions.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from qsplan.planner.plotting.style import (
    COMMAND,
    FONT,
    LOWER,
    NARROWEST,
    REGRASP,
    UPPER,
    axes_or_new,
    finger_colour,
    joint_colour,
    legend_below,
    step_colour,
    text_width,
    torque_text,
)

__all__ = ["LOG_SPAN", "MOVABLE", "SCALE_SHARE", "SLACK", "draw_band", "edge_marker", "effort_sense", "effort_words",
           "is_contact", "joint_math", "joint_title", "log_ticks", "mark_narrowest", "mark_slack", "phase_colour",
           "phase_label", "place_labels", "plot_mode_timeline", "scale_groups", "slack", "timeline_handles",
           "torque_limits", "torque_scale"]

#: Colour of the slack marks (the command's margin to the nearer band edge).
SLACK = "#1a7f37"

#: Effort (N m or N) within which two rows' slacks count as equal when choosing where to mark it: rounding of
#: ``command - edge``, far below any controller's resolution.
_SLACK_TIE = 1e-9


def is_contact(phase) -> bool:
    """Whether ``phase`` is an in-contact segment (a torque-controlled finger and a guaranteed band)."""
    from qsplan.planner.plan.results import ContactSegmentPlan

    return isinstance(phase, ContactSegmentPlan)


def effort_words(hand, joint) -> tuple:
    """``(word, unit)`` of a joint's effort: ``("torque", "N m")`` for a revolute joint (the paper's fingers, and
    without a hand), ``("force", "N")`` for a prismatic one (units: :data:`qsplan.hands.protocol.JOINT_UNITS`)."""
    from qsplan.hands.protocol import JOINT_UNITS

    kind = "revolute"
    if hand is not None:
        kind = dict(zip(hand.joint_names, hand.joint_kinds)).get(joint, "revolute")
    return ("force" if kind == "prismatic" else "torque"), JOINT_UNITS[kind]["tau"]


def effort_sense(hand, joint, sign) -> str:
    """Which way an effort of ``sign`` acts, in words: a torque ``"counter-clockwise"`` (positive) or
    ``"clockwise"``, a force ``"along +q"`` (positive: the way its joint position grows) or ``"along -q"``."""
    word, _ = effort_words(hand, joint)
    if word == "torque":
        return "counter-clockwise" if sign > 0 else "clockwise"
    return "along +q" if sign > 0 else "along -q"


def joint_math(name) -> str:
    """A joint's name for a mathtext subscript (``left_distal`` -> ``left\\_distal``)."""
    return str(name).replace("_", "\\_")


def joint_title(name) -> str:
    """A joint in words: the paper's ``"left finger"``, a described hand's ``"left_distal joint"``."""
    return f"{name} finger" if name in ("left", "right") else f"{name} joint"


def phase_label(phase, hand=None) -> tuple:
    """``(mode, control)`` in words: ``("4S (<letters>)", "right finger torque")`` or ``("regrasp", "fingers velocity")``;
    a described ``hand``'s joints by name (``"left_jaw joint force"``)."""
    from qsplan.mechanics.modes.contact_mode import ContactMode

    if not is_contact(phase):
        return phase.label()
    try:
        kind = ContactMode(phase.mode).kind
    except (ValueError, TypeError):
        kind = str(phase.mode)
    first = phase.modes()[0]
    lead = f"{ContactMode(first).kind} ({first}) then " if first != phase.mode else ""  # a pivot's transition row
    return (f"{phase.title_prefix}{lead}{kind} ({phase.mode})",
            f"{joint_title(phase.effort_joint)} {effort_words(hand, phase.effort_joint)[0]}")


def phase_colour(phase, hand=None) -> str:
    """The colour of a phase: its torque-controlled joint's finger's, shaded by what it does (a slide as is, a hold
    lighter, a pivot darker: :func:`qsplan.planner.plotting.style.step_colour`), grey for a regrasp."""
    if not is_contact(phase):
        return REGRASP
    base = finger_colour(phase.effort_joint) if hand is None else joint_colour(hand, phase.effort_joint)
    return step_colour(base, phase.kind)


def torque_limits(segments, resolution=0.0) -> tuple:
    """y-limits (N m) showing every command, lower edge and margin of ``segments``; far upper edges are cut off.

    The top is the larger of 1.5 times the highest command and the highest command plus its margin,
    so the band's room above the command stays visible; the narrowest point's upper edge is
    included when it is within twice that.  Commands all negative (a finger squeezing the other
    way, bands unbounded below) are drawn by the same rule mirrored: far lower edges cut off.
    """
    cmd = np.concatenate([s.command for s in segments])
    if np.all(cmd < 0):
        mirrored = [SimpleNamespace(command=-s.command, margin=s.margin, lower=-s.upper, upper=-s.lower, width=s.width)
                    for s in segments]  # fmt: skip
        bottom, top = torque_limits(mirrored, resolution)
        return -top, -bottom
    low = np.concatenate([s.lower[np.isfinite(s.lower)] for s in segments] + [np.zeros(1)])
    top = max(float(np.max(cmd)) * 1.5, float(np.max(np.concatenate([s.command + s.margin for s in segments]))))
    top = max(top, float(np.max(cmd)) + resolution)
    for s in segments:
        up = float(s.upper[int(np.argmin(s.width))])
        if np.isfinite(up) and up <= 2.0 * top:
            top = max(top, 1.08 * up)
    bottom = float(np.min(low))
    pad = 0.06 * (top - bottom)
    return bottom - pad, top + pad


#: Each phase's own torque range (:func:`torque_limits`) takes at least this share of the height of the panel it is
#: drawn in; phases whose ranges differ more get panels of their own (:func:`scale_groups`): a reorientation's
#: 0.1-0.35 N m slide beside its hold and pivot up to 4 N m.
SCALE_SHARE = 1.0 / 3.0

#: A panel whose commands span more than this ratio (largest to smallest, every command, lower edge and finite upper
#: edge positive) is drawn on a log scale (:func:`torque_scale`): a pivot's command comes down from the transition's
#: 4 N m to 0.09 N m, and its 0.04 N m slack must stay visible at both ends.
LOG_SPAN = 10.0

#: A log panel's bottom: this factor below its least command or lower edge (a margin like the linear panels' 6 %).
_LOG_PAD = 1.5


def scale_groups(segments, resolution=0.0) -> list:
    """``segments`` (one joint's, in time order) split into runs drawn on one torque scale: a segment joins the run
    before it while every member's own range (:func:`torque_limits`) stays at least :data:`SCALE_SHARE` of the run's.

    Returns
    -------
    list of list
        The runs, in time order.
    """
    groups = []
    own = {id(s): float(np.subtract(*torque_limits([s], resolution)[::-1])) for s in segments}
    for seg in segments:
        if groups:
            trial = groups[-1] + [seg]
            lo, hi = torque_limits(trial, resolution)
            if all(own[id(m)] >= SCALE_SHARE * (hi - lo) for m in trial):
                groups[-1] = trial
                continue
        groups.append([seg])
    return groups


def torque_scale(segments, resolution=0.0) -> tuple:
    """``((bottom, top), log)``: the y-limits of a panel of ``segments`` and whether it is drawn on a log scale.

    Linear (:func:`torque_limits`) unless the commands span more than :data:`LOG_SPAN` and every command, finite lower
    edge and finite upper edge is positive: then from :data:`_LOG_PAD` below the least command or lower edge to the
    linear rule's top.
    """
    lin = torque_limits(segments, resolution)
    cmd = np.concatenate([s.command for s in segments])
    lower = np.concatenate([s.lower for s in segments])
    edges = np.concatenate([lower, np.concatenate([s.upper for s in segments])])
    edges = edges[np.isfinite(edges)]
    if not (np.all(cmd > 0) and np.all(edges > 0) and float(np.max(cmd)) > LOG_SPAN * float(np.min(cmd))):
        return lin, False
    low = float(np.min(np.concatenate([cmd, lower[np.isfinite(lower)]])))
    return (low / _LOG_PAD, lin[1]), True


def log_ticks(axis, lo, hi, most: int = 10) -> None:
    """Ticks of a log-scaled ``axis`` from ``lo`` to ``hi`` (positive) in plain numbers (``0.05``, ``1``): at 1, 2 and 5
    times each power of ten, or at the powers alone where that would make more than ``most`` (labels stay apart)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    subs = (1.0,) if 3.0 * np.log10(hi / lo) > most else (1.0, 2.0, 5.0)
    axis.set_major_locator(LogLocator(subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def edge_marker(ax, t, y, side, infinite, colour, label=None, ms=5.0):
    """Triangles at ``y`` marking an edge beyond the plot at times ``t``: up (``side`` "upper") or down, filled where
    the edge is unbounded, hollow where it is finite (Fig. 13's convention)."""
    return ax.plot(t, np.full(np.size(t), y), ls="none", marker="^" if side == "upper" else "v", ms=ms, color=colour,
                   mfc=colour if infinite else "white", mew=1.1, clip_on=False, label=label)  # fmt: skip


def draw_band(ax, t, lower, upper, command, colour, ylim, *, label=True, word="torque") -> set:
    """A guaranteed band between ``ylim``: fill, upper edge solid, lower edge dashed, the command bold.

    An edge beyond the plot is cut at the plot's side and marked there (:func:`edge_marker`): filled triangles
    where it is unbounded, hollow ones where it is finite.

    Returns
    -------
    set of str
        What was drawn, for a legend of drawn marks only: ``"band"``, ``"command"``, ``"upper"``, ``"lower"`` (edges
        in view), ``"upper_inf"``, ``"upper_off"``, ``"lower_inf"``, ``"lower_off"`` (marks beyond the plot).
    """
    y0, y1 = ylim
    up, lo = np.asarray(upper, float), np.asarray(lower, float)
    beyond, below = ~(up <= y1), ~(lo >= y0)
    ax.fill_between(t, np.clip(np.where(np.isfinite(lo), lo, y0), y0, y1), np.clip(np.where(np.isfinite(up), up, y1), y0, y1),
                    color=colour, alpha=0.16, lw=0, label="guaranteed band" if label else None)  # fmt: skip
    drawn = {"band", "command"}
    for side, edge, cut, style, y in (("upper", up, beyond, UPPER, y1), ("lower", lo, below, LOWER, y0)):
        if not cut.all():
            drawn.add(side)
        ax.plot(t, np.where(cut, np.nan, edge), color=colour, lw=1.3, **style,
                label=f"{side} edge" if label and not cut.all() else None)  # fmt: skip
        every = np.flatnonzero(cut)
        every = every[:: max(1, every.size // 6)]  # one spacing for both kinds of mark
        for infinite in (True, False):
            idx = every[np.isinf(edge[every]) == infinite]
            if idx.size:
                what = "unbounded" if infinite else ("above" if side == "upper" else "below") + " the plot (finite)"
                edge_marker(ax, t[idx], y, side, infinite, colour, label=f"{side} edge {what}" if label else None)
                drawn.add(f"{side}_{'inf' if infinite else 'off'}")
    ax.plot(t, command, color=COMMAND, lw=1.6, label=f"{word} command" if label else None)
    return drawn


def mark_narrowest(ax, seg, ylim, label=True, unit: str = "N m") -> bool:
    """The narrowest point of a segment's band: a red double arrow, labelled with its width (off the edges).

    Drawn only when both edges there are finite and inside ``ylim``, so that an arrow is never cut; returns whether
    it was drawn (the width is said in words either way: the plan card's table, the bands' titles).
    """
    k = int(np.argmin(seg.width))
    t, lo, up = float(seg.t[k]), float(seg.lower[k]), float(seg.upper[k])
    if not (np.isfinite(lo) and np.isfinite(up) and ylim[0] <= lo and up <= ylim[1]):
        return False
    ax.annotate("", xy=(t, up), xytext=(t, lo), arrowprops={"arrowstyle": "<->", "color": NARROWEST, "lw": 1.4,
                                                           "shrinkA": 0, "shrinkB": 0})  # fmt: skip
    right = t < 0.5 * (seg.t[0] + seg.t[-1])
    c = float(seg.command[k])  # the label sits beside the arrow, halfway from the command to the farther end
    y = 0.5 * (c + up) if up - c > c - lo else 0.5 * (lo + c)
    if ax.get_yscale() == "log":
        y = float(np.sqrt(c * (up if up - c > c - lo else lo)))
    _movable(ax, f"narrowest {torque_text(up - lo, unit)}", (t, y), right, NARROWEST, 3)
    if label:
        ax.plot([], [], color=NARROWEST, marker="$\\updownarrow$", ls="none", ms=9, label="narrowest band (width)")
    return True


def slack(seg) -> tuple:
    """``(slack, edge, k)``: the command's smallest margin to the nearer band edge along ``seg`` (N m or N), which
    edge that is (``"lower"`` or ``"upper"``) and the first row where it is reached."""
    below, above = seg.command - seg.lower, seg.upper - seg.command
    near = np.minimum(below, above)
    k = int(np.argmin(near))
    return float(near[k]), "lower" if below[k] <= above[k] else "upper", k


def mark_slack(ax, seg, ylim, unit: str = "N m", avoid=None) -> bool:
    """The slack of ``seg`` (:func:`slack`) on the plot: a green bracket from the command to the nearer edge, with its
    value, at a row where it is reached (inside the segment, away from time ``avoid`` s); whether it was drawn."""
    value, edge, _ = slack(seg)
    near = np.minimum(seg.command - seg.lower, seg.upper - seg.command)
    rows = np.flatnonzero(near <= value + _SLACK_TIE)
    edge_room = 0.1 * (seg.t[-1] - seg.t[0])  # the bracket and its label inside the segment
    inner = rows[(seg.t[rows] - seg.t[0] >= edge_room) & (seg.t[-1] - seg.t[rows] >= edge_room)]
    rows = inner if inner.size else rows
    k = int(rows[np.argmax(np.abs(seg.t[rows] - avoid))] if avoid is not None else rows[rows.size // 2])
    t, c = float(seg.t[k]), float(seg.command[k])
    e = float(seg.lower[k] if edge == "lower" else seg.upper[k])
    if not (np.isfinite(e) and ylim[0] <= min(c, e) and max(c, e) <= ylim[1]):
        return False
    ax.annotate("", xy=(t, e), xytext=(t, c), arrowprops={"arrowstyle": "|-|,widthA=0.25,widthB=0.25", "color": SLACK,
                                                         "lw": 1.2, "shrinkA": 0, "shrinkB": 0})  # fmt: skip
    right = t < 0.5 * (seg.t[0] + seg.t[-1])
    y = float(np.sqrt(c * e)) if ax.get_yscale() == "log" else 0.5 * (c + e)
    _movable(ax, f"slack {torque_text(value, unit)}", (t, y), right, SLACK, 4)
    return True


#: ``gid`` of the labels :func:`place_labels` moves off the data once the figure is laid out (a narrowest band's
#: width, a slack's value).
MOVABLE = "qsplan-movable-label"

#: How far (points) :func:`place_labels` looks for room around a label's mark, across and along the time axis.
_LABEL_REACH = (150.0, 90.0)

#: Padding (pixels) around a label's box when it is tested against the data: its rounded box and antialiasing.
_LABEL_PAD = 2.0


def _movable(ax, text, xy, right, colour, gap):
    """A label of the mark at ``xy`` (data), beside it (right of it when ``right``, ``gap`` points away), with a thin
    leader shown only when :func:`place_labels` moves it farther."""
    ann = ax.annotate(text, xy, xytext=(gap if right else -gap, 0), textcoords="offset points",
                      ha="left" if right else "right", va="center", fontsize=FONT["note"], color=colour, gid=MOVABLE,
                      bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85},
                      arrowprops={"arrowstyle": "-", "color": colour, "lw": 0.6, "shrinkA": 0, "shrinkB": 0})  # fmt: skip
    ann.arrow_patch.set_visible(False)
    ann.set_in_layout(False)
    return ann


def _data_shapes(ax):
    """``(lines, extents, points)`` of ``ax``'s data in display pixels: polylines (matplotlib paths), their extents
    (k, 4: x0, y0, x1, y1) and marker positions with their radius (m, 3).  Reference lines (axhline, axvline), spans
    and fills are not covered data: a label on a wide band's fill hides no line of it."""
    from matplotlib.path import Path

    lines, points = [], [np.zeros((0, 3))]
    for ln in ax.get_lines():
        if not ln.get_visible() or ln.get_transform() != ax.transData:
            continue
        xy = ax.transData.transform(np.asarray(ln.get_xydata(), float))
        ok = np.all(np.isfinite(xy), axis=1)
        if ln.get_linestyle() not in ("None", "none", " ", ""):
            cuts = np.flatnonzero(np.diff(ok.astype(int)) != 0) + 1
            lines += [run for run, good in zip(np.split(xy, cuts), np.split(ok, cuts)) if good.all() and len(run) > 1]
        if ln.get_marker() not in (None, "None", "none", "", " "):
            r = 0.5 * ln.get_markersize() * ax.get_figure(root=True).dpi / 72.0
            points.append(np.column_stack([xy[ok], np.full(int(ok.sum()), r)]))
    extents = np.array([[*run.min(axis=0), *run.max(axis=0)] for run in lines]).reshape(-1, 4)
    return [Path(run) for run in lines], extents, np.vstack(points)


def _hits(box, shapes) -> int:
    """How many data items of ``shapes`` (:func:`_data_shapes`) the display box ``box`` = ``(x0, y0, x1, y1)``
    covers."""
    from matplotlib.transforms import Bbox

    x0, y0, x1, y1 = box
    lines, extents, points = shapes
    near = np.flatnonzero((extents[:, 0] <= x1) & (extents[:, 2] >= x0) & (extents[:, 1] <= y1) & (extents[:, 3] >= y0))
    n = 0
    if near.size:
        bbox = Bbox.from_extents(x0, y0, x1, y1)
        n = sum(lines[k].intersects_bbox(bbox, filled=False) for k in near)
    r = points[:, 2]
    n += int(np.sum((points[:, 0] >= x0 - r) & (points[:, 0] <= x1 + r) & (points[:, 1] >= y0 - r)
                    & (points[:, 1] <= y1 + r)))  # fmt: skip
    return int(n)


def _extents(bbox) -> tuple:
    """``(x0, y0, x1, y1)`` of a matplotlib Bbox, the smaller coordinate first."""
    (ax, ay), (bx, by) = bbox.get_points()
    return min(ax, bx), min(ay, by), max(ax, bx), max(ay, by)


def _overlap(a, b) -> bool:
    """Whether the boxes ``a`` and ``b`` (:func:`_extents`) meet (touching counts, as ``Bbox.overlaps``)."""
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


def place_labels(fig) -> bool:
    """Move every movable label (:data:`MOVABLE`) of ``fig`` where it covers no data line or mark and no other text,
    nearest its mark first: beside it, then above or below it, then farther along the time axis (a thin leader to its
    mark).

    Lays ``fig`` out first (constrained layout): the labels are placed in display pixels of the final page, and are
    left out of the layout so that it stays as measured.  Where no place is free, the one covering least.  Returns
    whether it laid ``fig`` out (False: no label to place, nothing done).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    def axes(f):  # every axes of the figure and its subfigures
        return list(f.axes) + [ax for sub in f.subfigs for ax in axes(sub)]

    labels = [t for ax in axes(fig) for t in ax.texts if t.get_gid() == MOVABLE and t.get_visible()]
    if not labels:
        return False
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    if fig.get_layout_engine() is not None:  # the layout a draw would do, without drawing (the axes' limits, titles
        fig.get_layout_engine().execute(fig)  # and aspect settled on the way: their tight boxes are measured)
    taken = {}  # per axes: the boxes of its texts and marks' arrows (pixels)
    for ann in labels:
        ax = ann.axes
        if ax not in taken:
            for t in ax.texts:  # an annotation's text and arrow where a draw would put them
                if hasattr(t, "update_positions") and t.get_gid() != MOVABLE:
                    t.update_positions(renderer)
            boxes = [_extents(t.get_window_extent(renderer)) for t in ax.texts
                     if t.get_gid() != MOVABLE and t.get_text().strip()]  # fmt: skip
            boxes += [_extents(t.arrow_patch.get_window_extent(renderer)) for t in ax.texts
                      if getattr(t, "arrow_patch", None) is not None and t.get_gid() != MOVABLE]  # fmt: skip
            taken[ax] = (boxes, _data_shapes(ax))
        boxes, shapes = taken[ax]
        frame = ax.get_window_extent(renderer)
        fx0, fy0, fx1, fy1 = (float(v) for v in (frame.x0, frame.y0, frame.x1, frame.y1))
        anchor = [float(v) for v in ax.transData.transform(ann.xy)]
        gap, side = abs(float(ann.xyann[0])), 1.0 if ann.get_horizontalalignment() == "left" else -1.0
        ann.update_positions(renderer)
        size = Text.get_window_extent(ann, renderer)  # the label's box: the same wherever it goes
        w, h, px = size.width, size.height, fig.dpi / 72.0
        best = None
        for dx, dy, ha, va in _label_offsets(gap, side):  # in pixels, as floats: ~1500 boxes tried per card
            x0 = anchor[0] + dx * px - {"left": 0.0, "right": w, "center": 0.5 * w}[ha]
            y0 = anchor[1] + dy * px - {"bottom": 0.0, "top": h, "center": 0.5 * h}[va]
            box = (x0 - _LABEL_PAD, y0 - _LABEL_PAD, (x0 + w) + _LABEL_PAD, (y0 + h) + _LABEL_PAD)
            if not (fx0 <= box[0] and box[2] <= fx1 and fy0 <= box[1] and box[3] <= fy1):
                continue
            reach = (min(box[0], anchor[0]), min(box[1], anchor[1]), max(box[2], anchor[0]),
                     max(box[3], anchor[1]))  # with its leader  # fmt: skip
            cost = 4 * sum(_overlap(b, reach) for b in boxes) + _hits(box, shapes)
            if best is None or cost < best[0]:
                best = (cost, dx, dy, ha, va, box, reach)
            if cost == 0:
                break
        if best is None:  # no place inside the axes: where it was drawn
            continue
        _, dx, dy, ha, va, box, reach = best
        ann.set_position((dx, dy))
        ann.set_horizontalalignment(ha)
        ann.set_verticalalignment(va)
        ann.arrow_patch.set_visible(abs(dy) > 0 or abs(dx) > gap)
        boxes.append(reach if ann.arrow_patch.get_visible() else box)
    return True


def _label_offsets(gap, side) -> list:
    """Offsets (points) and alignments tried for a label ``gap`` points beside its mark, nearest first, its own side
    (``side``: +1 right, -1 left) before the other at one distance."""
    reach_x, reach_y = _LABEL_REACH
    out = []
    for dx in np.concatenate([[gap], np.arange(12.0, reach_x + 1.0, 12.0)]):
        for dy in np.arange(0.0, reach_y + 1.0, 6.0):
            for sx in (side, -side):
                for sy in ((1.0, -1.0) if dy else (1.0,)):
                    out.append((float(np.hypot(dx, dy)), sx != side, sx * dx, sy * dy, "left" if sx > 0 else "right",
                                "center"))  # fmt: skip
    for dy in np.arange(6.0, reach_y + 1.0, 6.0):  # straight above or below the mark
        for sy in (1.0, -1.0):
            out.append((float(dy), False, 0.0, sy * dy, "center", "bottom" if sy > 0 else "top"))
    out.sort(key=lambda o: (o[0], o[1]))
    return [o[2:] for o in out]


def timeline_handles(plan) -> list:
    """Legend entries for the timeline's colours: one per (mode, control) of the plan's phases."""
    from matplotlib.patches import Patch

    out = {}
    hand = plan.task.hand
    for ph in plan.phases:
        mode, control = phase_label(ph, hand)
        out.setdefault((mode, control), Patch(fc=phase_colour(ph, hand), ec="k", lw=0.5, alpha=0.75,
                                              label=f"{mode}, {control}-controlled"))  # fmt: skip
    return list(out.values())


#: Room (inches) a label keeps inside its box on the mode timeline: a little white at each end.
_BAR_PAD = 0.08


def plot_mode_timeline(plan, ax=None, marks=None, legend=True, xlabel=True, compact=False):
    """Which mode each phase keeps and which finger is torque-controlled, against time; phases numbered as in
    ``plan.csv``.

    Labels of boxes too narrow for them are shortened (``compact``) or written above their box; the legend names the
    colours.

    Parameters
    ----------
    plan : Plan
    ax : matplotlib Axes, optional
    marks : sequence of (float, str), optional
        Times (s) to mark with a letter (the plan card's snapshots).
    legend, xlabel : bool
        Draw the colour legend (below) and the time label (the plan card draws its own).
    compact : bool
        One line per box (the plan card's thin bar): ``"phase 0: 4S (<letters>), right finger torque"``, else
        ``"phase 0"``, else ``"0"``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax, size=(9.0, 1.9))
    t0, t1 = float(plan.phases[0].t[0]), float(plan.duration)
    # the axes' width before the layout (inches): the figure's default margins, narrower than constrained layout
    # leaves, so a label judged to fit its box does
    width_in = ax.get_position().width * ax.get_figure(root=True).get_figwidth()
    above, last_x = [], -np.inf
    hand = plan.task.hand
    for i, ph in enumerate(plan.phases):
        a, b = float(ph.t[0]), float(ph.t[-1])
        colour = phase_colour(ph, hand)
        ax.barh(0, b - a, left=a, height=0.8, color=colour, alpha=0.75, edgecolor="k", lw=0.5)
        mode, control = phase_label(ph, hand)
        room = (b - a) / max(t1 - t0, 1e-12) * width_in - _BAR_PAD
        if compact:
            short = mode if not is_contact(ph) else f"{mode}, {control}"
            texts = [f"phase {i}: {short}", f"phase {i}", str(i)]
        else:
            texts = [f"phase {i}: {mode}\n{control}", f"phase {i}: {mode}", f"phase {i}"]
        fits = [u for u in texts if text_width(u, FONT["note"]) / 72.0 < room]
        if fits and (compact or fits[0] != texts[-1]):
            ax.text(0.5 * (a + b), 0, fits[0], ha="center", va="center", fontsize=FONT["note"])
        else:
            above.append((0.5 * (a + b), str(i) if compact else f"{i}: {mode}"))
    for x, text in above:  # short labels above their boxes, staggered when close
        level = 1 if (x - last_x) / max(t1 - t0, 1e-12) * width_in < 0.8 and not compact else 0
        last_x = x
        ax.annotate(text, (x, 0.4), xytext=(x, 0.6 + 0.4 * level), ha="center", va="bottom", fontsize=FONT["note"],
                    arrowprops={"arrowstyle": "-", "color": "0.3", "lw": 0.6})  # fmt: skip
    groups = []  # marks closer than 0.25 in share one label ("B C D")
    for t, letter in marks or ():
        if groups and (t - groups[-1][-1][0]) / max(t1 - t0, 1e-12) * width_in < 0.25:
            groups[-1].append((t, letter))
        else:
            groups.append([(t, letter)])
    for group in groups:
        ts = [t for t, _ in group]
        ax.plot(ts, [-0.55] * len(ts), ls="none", marker="^", color="k", ms=4, clip_on=False)
        ax.annotate(" ".join(letter for _, letter in group), (float(np.mean(ts)), -0.55), xytext=(0, -3),
                    textcoords="offset points", ha="center", va="top", fontsize=FONT["note"], weight="bold")  # fmt: skip
    ax.set_ylim(-0.9 if marks else -0.5, (1.0 if compact else 1.3) if above else 0.5)
    ax.set_xlim(t0, t1)
    ax.set_yticks([])
    for side in ("left", "right", "top"):
        ax.spines[side].set_visible(False)
    if xlabel:
        ax.set_xlabel("t (s) from the plan's start", fontsize=FONT["label"])
    ax.set_title("phases as numbered in plan.csv: contact mode and the torque-controlled joint", fontsize=FONT["label"],
                 loc="left")  # fmt: skip
    if legend:  # as many columns as the axes' width holds: a wider legend would narrow the axes
        handles = timeline_handles(plan)
        column = max(text_width(h.get_label(), FONT["legend"]) for h in handles) + 3.5 * FONT["legend"]
        legend_below(ax, handles=handles, ncol=int(np.clip(width_in * 72.0 // column, 1, min(3, len(handles)))))
    return ax
