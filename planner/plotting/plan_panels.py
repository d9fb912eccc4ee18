"""The pieces plan figures are drawn from: phases in words, band panels, the mode timeline, snapshot choice.

Shared by :mod:`qsplan.planner.plotting.plan` (one figure per view) and
:mod:`qsplan.planner.plotting.card` (the plan card).  Only the plan's public fields are read
(``Plan.phases``, :class:`~qsplan.planner.plan.results.ContactSegmentPlan`; any other phase is
drawn as a free motion of the fingers), so plans with more phases or fields draw too.
matplotlib is imported inside the functions.
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

__all__ = ["draw_band", "effort_words", "is_contact", "joint_math", "joint_title", "mark_narrowest", "phase_colour",
           "phase_label", "plot_mode_timeline", "snapshot_keys", "timeline_handles", "torque_limits"]


def is_contact(phase) -> bool:
    """Whether ``phase`` is an in-contact segment (a torque-controlled finger and a guaranteed band)."""
    from qsplan.planner.plan.results import ContactSegmentPlan

    return isinstance(phase, ContactSegmentPlan)


def effort_words(hand, joint) -> tuple:
    """``(word, unit)`` of a joint's effort: ``("torque", "N m")`` for a revolute joint (the paper's fingers, and
    without a hand), ``("force", "N")`` for a prismatic one."""
    if hand is not None:
        from qsplan.hands.interface import joint_kinds, joint_names

        if dict(zip(joint_names(hand), joint_kinds(hand))).get(joint) == "prismatic":
            return "force", "N"
    return "torque", "N m"


def joint_math(name) -> str:
    """A joint's name for a mathtext subscript (``left_distal`` -> ``left\\_distal``)."""
    return str(name).replace("_", "\\_")


def joint_title(name) -> str:
    """A joint in words: the paper's ``"left finger"``, a described hand's ``"left_distal joint"``."""
    return f"{name} finger" if name in ("left", "right") else f"{name} joint"


def phase_label(phase, hand=None) -> tuple:
    """``(mode, control)`` in words: ``("4S (SSSS)", "right finger torque")`` or ``("regrasp", "fingers velocity")``;
    a described ``hand``'s joints by name (``"left_jaw joint force"``)."""
    from qsplan.mechanics.modes.contact_mode import ContactMode

    if not is_contact(phase):
        return "regrasp", "fingers velocity"
    try:
        kind = ContactMode(phase.mode).kind
    except (ValueError, TypeError):
        kind = str(phase.mode)
    return f"{kind} ({phase.mode})", f"{joint_title(phase.effort_joint)} {effort_words(hand, phase.effort_joint)[0]}"


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


def draw_band(ax, t, lower, upper, command, colour, ylim, *, label=True) -> None:
    """A guaranteed band between ``ylim``: fill, upper edge solid, lower edge dashed, the command bold.

    An upper edge above the plot (or unbounded) is cut at its top and marked with up-triangles; a lower
    edge below it (or unbounded below), at its bottom with down-triangles.
    """
    y0, y1 = ylim
    up, lo = np.asarray(upper, float), np.asarray(lower, float)
    beyond, below = ~(up <= y1), ~(lo >= y0)
    ax.fill_between(t, np.clip(np.where(np.isfinite(lo), lo, y0), y0, y1), np.clip(np.where(np.isfinite(up), up, y1), y0, y1),
                    color=colour, alpha=0.16, lw=0, label="guaranteed band" if label else None)  # fmt: skip
    ax.plot(t, np.where(beyond, np.nan, up), color=colour, lw=1.3, **UPPER, label="upper edge" if label else None)
    ax.plot(t, np.where(below, np.nan, lo), color=colour, lw=1.3, **LOWER, label="lower edge" if label else None)
    for mask, y, marker, what in ((beyond, y1, "^", "upper edge above the plot or unbounded"),
                                  (below, y0, "v", "lower edge below the plot or unbounded")):  # fmt: skip
        if mask.any():
            idx = np.flatnonzero(mask)
            idx = idx[:: max(1, idx.size // 6)]
            ax.plot(t[idx], np.full(idx.size, y), ls="none", marker=marker, ms=5, color=colour, clip_on=False,
                    label=what if label else None)  # fmt: skip
    ax.plot(t, command, color=COMMAND, lw=1.6, label="torque command" if label else None)


def mark_narrowest(ax, seg, ylim, label=True, unit: str = "N m") -> None:
    """The narrowest point of a segment's band: a red double arrow, labelled with its width (off the edges)."""
    k = int(np.argmin(seg.width))
    t, lo, up = float(seg.t[k]), float(seg.lower[k]), float(seg.upper[k])
    top = min(up, ylim[1]) if np.isfinite(up) else ylim[1]
    bottom = max(lo, ylim[0]) if np.isfinite(lo) else ylim[0]  # an edge unbounded below ends at the plot's floor
    ax.annotate("", xy=(t, top), xytext=(t, bottom), arrowprops={"arrowstyle": "<->", "color": NARROWEST, "lw": 1.4},
                annotation_clip=False)  # fmt: skip
    cut = "" if np.isfinite(up) and up <= ylim[1] else " (edge above)"
    cut += "" if np.isfinite(lo) and lo >= ylim[0] else " (edge below)"
    right = t < 0.5 * (seg.t[0] + seg.t[-1])
    c = float(seg.command[k])  # the label sits beside the arrow, halfway from the command to the farther end
    y = 0.5 * (c + top) if top - c > c - bottom else 0.5 * (bottom + c)
    va, dy = "center", 0
    width = torque_text(up - lo, unit) if np.isfinite(up - lo) else "unbounded"
    ax.annotate(f"narrowest {width}{cut}", (t, y), xytext=(3 if right else -3, dy),
                textcoords="offset points", ha="left" if right else "right", va=va, fontsize=FONT["note"],
                color=NARROWEST, bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85})  # fmt: skip
    if label:
        ax.plot([], [], color=NARROWEST, marker="$\\updownarrow$", ls="none", ms=9, label="narrowest band (width)")


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


def plot_mode_timeline(plan, ax=None, marks=None, legend=True, xlabel=True):
    """Which mode each phase keeps and which finger is torque-controlled, against time.

    Labels of boxes too narrow for them are written above their box; the legend names the colours.

    Parameters
    ----------
    plan : Plan
    ax : matplotlib Axes, optional
    marks : sequence of (float, str), optional
        Times (s) to mark with a letter (the plan card's snapshots).
    legend, xlabel : bool
        Draw the colour legend (below) and the time label (the plan card draws its own).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax, size=(9.0, 1.9))
    t0, t1 = float(plan.phases[0].t[0]), float(plan.duration)
    width_in = ax.get_figure(root=True).get_figwidth() * 0.85
    above, last_x = [], -np.inf
    hand = plan.task.hand
    for ph in plan.phases:
        a, b = float(ph.t[0]), float(ph.t[-1])
        colour = phase_colour(ph, hand)
        ax.barh(0, b - a, left=a, height=0.8, color=colour, alpha=0.75, edgecolor="k", lw=0.5)
        mode, control = phase_label(ph, hand)
        text = f"{mode}\n{control}"
        need = max(len(s) for s in text.split("\n")) * FONT["note"] * 0.52 / 72
        if need < 0.92 * (b - a) / max(t1 - t0, 1e-12) * width_in:
            ax.text(0.5 * (a + b), 0, text, ha="center", va="center", fontsize=FONT["note"])
        else:
            above.append((0.5 * (a + b), mode))
    for x, text in above:  # short labels above their boxes, staggered when close
        level = 1 if (x - last_x) / max(t1 - t0, 1e-12) * width_in < 0.8 else 0
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
    ax.set_ylim(-0.9 if marks else -0.5, 1.3 if above else 0.5)
    ax.set_xlim(t0, t1)
    ax.set_yticks([])
    for side in ("left", "right", "top"):
        ax.spines[side].set_visible(False)
    if xlabel:
        ax.set_xlabel("t (s) from the plan's start", fontsize=FONT["label"])
    ax.set_title("contact mode of each phase and the torque-controlled finger", fontsize=FONT["label"], loc="left")
    if legend:
        handles = timeline_handles(plan)
        legend_below(ax, handles=handles, ncol=min(3, len(handles)))
    return ax


def snapshot_keys(plan, per_phase=3) -> list:
    """The configurations to draw: ``per_phase`` along each in-contact segment, the open fingers of each regrasp.

    Returns
    -------
    list of (t, pose, q, effort_joint or None, open)
        Time (s), workpiece pose (3,), joint positions (n_j,), the torque-controlled joint, whether the fingers are
        open.
    """
    out = []
    for ph in plan.phases:
        if is_contact(ph):
            for k in np.unique(np.round(np.linspace(0, ph.t.size - 1, per_phase)).astype(int)):
                out.append((float(ph.t[k]), plan.task.pose(ph.x[k]), ph.q[k], ph.effort_joint, False))
        else:
            k = int(np.argmax(np.abs(ph.q - ph.q[0]).sum(axis=1)))
            x = float(np.ravel(ph.x)[min(k, np.size(ph.x) - 1)])
            out.append((float(ph.t[k]), plan.task.pose(x), ph.q[k], None, True))
    return out
