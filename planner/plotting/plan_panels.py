"""The pieces plan figures are drawn from: phases in words, band panels, slack marks, the mode timeline.

Shared by :mod:`qsplan.planner.plotting.plan` (one figure per view), :mod:`qsplan.planner.plotting.card` (the plan
card) and :mod:`qsplan.planner.plotting.animation`.  Only the plan's public fields are read
(``Plan.phases``, :class:`~qsplan.planner.plan.results.ContactSegmentPlan`; any other phase is
drawn as a free motion of the fingers), so plans with more phases or fields draw too (the snapshots' choice is
:func:`qsplan.planner.plotting.hands.plan_snapshots`).  Phases are numbered as
``plan.csv`` numbers them (``phase`` 0 first).  Band edges are marked as in Fig. 13
(:func:`qsplan.planner.plotting.band_panels.plot_band_sweep`): beyond the plot, filled triangles where an edge is
unbounded, hollow ones where it is finite.  matplotlib is imported inside the functions.
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
    torque_text,
)

__all__ = ["SLACK", "draw_band", "edge_marker", "effort_sense", "effort_words", "is_contact", "joint_math",
           "joint_title", "mark_narrowest", "mark_slack", "phase_colour", "phase_label", "plot_mode_timeline", "slack",
           "timeline_handles", "torque_limits"]

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
    without a hand), ``("force", "N")`` for a prismatic one (units: :data:`qsplan.hands.interface.JOINT_UNITS`)."""
    from qsplan.hands.interface import JOINT_UNITS

    kind = "revolute"
    if hand is not None:
        from qsplan.hands.interface import joint_kinds, joint_names

        kind = dict(zip(joint_names(hand), joint_kinds(hand))).get(joint, "revolute")
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
        return "regrasp", "fingers velocity"
    try:
        kind = ContactMode(phase.mode).kind
    except (ValueError, TypeError):
        kind = str(phase.mode)
    first = phase.modes()[0] if hasattr(phase, "modes") else phase.mode
    lead = f"{ContactMode(first).kind} ({first}) then " if first != phase.mode else ""  # a pivot's transition row
    what = {"hold": "hold: ", "pivot": "pivot: "}.get(getattr(phase, "kind", "slide"), "")
    return (f"{what}{lead}{kind} ({phase.mode})",
            f"{joint_title(phase.effort_joint)} {effort_words(hand, phase.effort_joint)[0]}")


def phase_colour(phase, hand=None) -> str:
    """The colour of a phase: its torque-controlled joint's finger's, grey for a regrasp."""
    if not is_contact(phase):
        return REGRASP
    return finger_colour(phase.effort_joint) if hand is None else joint_colour(hand, phase.effort_joint)


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
    ax.annotate(f"narrowest {torque_text(up - lo, unit)}", (t, y), xytext=(3 if right else -3, 0),
                textcoords="offset points", ha="left" if right else "right", va="center", fontsize=FONT["note"],
                color=NARROWEST, bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85})  # fmt: skip
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
    ax.annotate(f"slack {torque_text(value, unit)}", (t, 0.5 * (c + e)), xytext=(4 if right else -4, 0),
                textcoords="offset points", ha="left" if right else "right", va="center", fontsize=FONT["note"],
                color=SLACK, bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85})  # fmt: skip
    return True


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
    width_in = ax.get_figure(root=True).get_figwidth() * 0.85
    above, last_x = [], -np.inf
    hand = plan.task.hand
    for i, ph in enumerate(plan.phases):
        a, b = float(ph.t[0]), float(ph.t[-1])
        colour = phase_colour(ph, hand)
        ax.barh(0, b - a, left=a, height=0.8, color=colour, alpha=0.75, edgecolor="k", lw=0.5)
        mode, control = phase_label(ph, hand)
        room = 0.92 * (b - a) / max(t1 - t0, 1e-12) * width_in
        if compact:
            short = mode if not is_contact(ph) else f"{mode}, {control}"
            texts = [f"phase {i}: {short}", f"phase {i}", str(i)]
        else:
            texts = [f"phase {i}: {mode}\n{control}"]
        fits = [u for u in texts if max(len(v) for v in u.split("\n")) * FONT["note"] * 0.52 / 72 < room]
        if fits:
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
    if legend:
        handles = timeline_handles(plan)
        legend_below(ax, handles=handles, ncol=min(3, len(handles)))
    return ax
