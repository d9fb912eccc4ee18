"""The plan card: one A4 page an operator reads at a glance before running a plan (``plan_card.png``).

From top to bottom: the task and a one-line verdict (certified row by row, re-simulated at N friction
vectors); hand snapshots lettered A, B, ...; then on one shared time axis the contact-mode timeline
(the letters mark the snapshots' instants, each segment names its torque-controlled finger), each
torque-controlled joint's command inside its guaranteed band with the narrowest point of every band
marked and labelled with its width, and each joint's velocity command.  Text is at least 7.5 pt on the
printed page.  Only the plan's public fields are read (see :mod:`qsplan.planner.plotting.plan_panels`).
"""

from __future__ import annotations

import textwrap

import numpy as np

from qsplan.planner.plotting.plan_panels import (
    draw_band,
    effort_words,
    is_contact,
    joint_math,
    joint_title,
    mark_narrowest,
    plot_mode_timeline,
    snapshot_keys,
    timeline_handles,
    torque_limits,
)
from qsplan.planner.plotting.style import A4_PORTRAIT, FONT, NARROWEST, joint_colour, torque_text

__all__ = ["CARD_DPI", "LEGEND_LABEL_CHARS", "MAX_SNAPSHOTS", "card_snapshots", "plan_card", "verdict"]

#: Resolution (dots per inch) the card is written at: 150 keeps 7.5 pt text sharp on an A4 print.
CARD_DPI = 150

#: Snapshots on the card, at most (the instants are thinned evenly beyond it).
MAX_SNAPSHOTS = 10

#: Longest legend label (characters) that three legend columns hold on the A4 page at the legend's 8 pt; longer
#: labels (a described hand's joint names in the timeline's entries) take two columns.
LEGEND_LABEL_CHARS = 44

_OK, _BAD = "#1a7f37", "#b42318"


def verdict(certificate=None, replays=()) -> tuple:
    """``(line, ok)``: the certificate and the re-simulations in one line, and whether both passed.

    Parameters
    ----------
    certificate : qsplan.planner.certify.certify.Certificate, optional
    replays : sequence of qsplan.planner.replay.replay.Replay
    """
    parts, ok = [], True
    if certificate is None:
        parts.append("not certified (no certificate)")
        ok = False
    else:
        pts = max((r.friction_points for r in certificate.rows), default=0)
        what = f"{len(certificate.rows)} rows checked from the task alone, {pts} friction vectors per contact row"
        if certificate.ok:
            parts.append(f"CERTIFIED ({what}, no violation)")
        else:
            parts.append(f"NOT CERTIFIED ({len(certificate.violations)} violations; {what})")
            ok = False
    if replays:
        left = sum(not r.followed for r in replays)
        n = len(replays)
        parts.append(f"re-simulated at {n} friction vector{'s' if n != 1 else ''}: "
                     + ("every run followed the planned modes" if not left else f"{left} LEFT the planned modes"))
        ok &= not left
    else:
        parts.append("not re-simulated")
        ok = False
    return "; ".join(parts), ok


def card_snapshots(plan, limit: int = MAX_SNAPSHOTS) -> list:
    """The card's snapshots: each in-contact segment's start and end (and instants between when there is
    room), each regrasp with open fingers.

    Returns
    -------
    list of (t, pose, q, effort_joint or None, open), at most ``limit``, in time order.
    """
    n_seg = max(1, sum(is_contact(p) for p in plan.phases))
    per_phase = int(np.clip((limit - (len(plan.phases) - n_seg)) // n_seg, 2, 4))
    shots = snapshot_keys(plan, per_phase=per_phase)
    if len(shots) > limit:
        shots = [shots[k] for k in np.unique(np.round(np.linspace(0, len(shots) - 1, limit)).astype(int))]
    return shots


def _letters(n):
    return [chr(ord("A") + k) if k < 26 else f"A{k - 25}" for k in range(n)]


def _shade_other_control(ax, plan, joint, torque: bool):
    """Hatch where ``joint`` is under the other kind of control, and say so where there is room."""
    t0, t1 = float(plan.phases[0].t[0]), float(plan.duration)
    for ph in plan.phases:
        mine = is_contact(ph) and ph.effort_joint == joint
        if mine == torque:
            continue
        a, b = float(ph.t[0]), float(ph.t[-1])
        ax.axvspan(a, b, fc="none", ec="0.8", hatch="////", lw=0, zorder=0)
        if (b - a) > 0.18 * (t1 - t0):
            ax.text(0.5 * (a + b), 0.5, "velocity-controlled" if torque else "torque-controlled (band above)",
                    transform=ax.get_xaxis_transform(), ha="center", va="center", fontsize=FONT["note"],
                    color="0.45", bbox={"fc": "white", "ec": "none", "pad": 1.0})  # fmt: skip


def _offset(sub, points):
    """The subfigure's coordinates shifted down by ``points`` (negative: down)."""
    from matplotlib.transforms import offset_copy

    return offset_copy(sub.transSubfigure, fig=sub.get_figure(root=True), y=points, units="points")


def _facts(plan) -> str:
    task = plan.task
    lo, hi = task.mu_range
    model = "one shared friction coefficient" if task.shared_mu else "each contact's friction coefficient"
    name, t, w = plan.narrowest()
    unit = next((effort_words(task.hand, s.effort_joint)[1] for s in plan.segments if s.name == name), "N m")
    n_seg = len(plan.segments)
    where = f" at t = {t:.3g} s ({str(name).split(':')[0]})" if name else ""
    return (f"Bands guaranteed for {model} in [{lo:g}, {hi:g}]; controller torque resolution "
            f"{task.torque_resolution:g} N m. {n_seg} in-contact segment{'s' if n_seg != 1 else ''}, "
            f"{len(plan.phases) - n_seg} regrasp{'s' if len(plan.phases) - n_seg != 1 else ''}, "
            f"{plan.duration:.3g} s of motion; narrowest band {torque_text(w, unit) if np.isfinite(w) else 'unbounded'}{where}.")  # fmt: skip


def _snapshot_row(sub, plan, shots, letters):
    from qsplan.planner.plotting.hands import hand_limits, plot_hand

    lim = hand_limits(plan.task.hand, [(pose, q) for _, pose, q, _, _ in shots])
    rows = 1 if len(shots) <= 5 else 2
    cols = -(-len(shots) // rows)
    axes = sub.subplots(rows, cols, squeeze=False).ravel()
    for i, (ax, (t, pose, q, effort, opened), letter) in enumerate(zip(axes, shots, letters)):
        plot_hand(plan.task.hand, pose, q, ax=ax, contacts=not opened, effort_joint=effort, limits=lim,
                  scale_bar=i == 0)  # fmt: skip
        ax.set_title(f"{letter}: t = {t:.3g} s" + (", open" if opened else ""), fontsize=FONT["note"], pad=2)
    for ax in axes[len(shots):]:
        ax.set_visible(False)


def plan_card(plan, certificate=None, replays=(), snapshots: int = MAX_SNAPSHOTS):
    """The plan card of ``plan`` as an A4 portrait figure.

    Parameters
    ----------
    plan : qsplan.planner.plan.results.Plan
    certificate : qsplan.planner.certify.certify.Certificate, optional
        The exported plan's certificate (:func:`qsplan.planner.certify.certify.certify_plan`).
    replays : sequence of qsplan.planner.replay.replay.Replay
        The exported plan re-simulated.
    snapshots : int
        Hand snapshots, at most.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from qsplan.hands.interface import joint_names, joint_units

    hand = plan.task.hand
    names, units = joint_names(hand), dict(zip(joint_names(hand), joint_units(hand, "qd")))
    shots = card_snapshots(plan, snapshots)
    letters = _letters(len(shots))
    torque_joints = [j for j in names if any(is_contact(p) and p.effort_joint == j for p in plan.phases)]
    velocity_joints = [j for k, j in enumerate(names) if any(np.isfinite(p.qd[:, k]).any() for p in plan.phases)]
    fig = Figure(figsize=A4_PORTRAIT, layout="constrained")
    head, body = fig.subfigures(2, 1, height_ratios=[0.095, 0.905])
    line, ok = verdict(certificate, replays)
    lines = [(f"Plan card: {plan.task.name}", FONT["suptitle"] + 1, "k")]
    lines += [(s, FONT["label"], "k") for s in textwrap.wrap(_facts(plan), 112)]
    lines += [(s, FONT["label"], _OK if ok else _BAD) for s in textwrap.wrap(line, 100)]
    y = -4.0
    for i, (text, size, colour) in enumerate(lines):  # top down, in points, so that no two lines meet
        head.text(0.01, 1.0, text, fontsize=size, color=colour, va="top", weight="bold" if i == 0 or colour != "k"
                  else "normal", transform=_offset(head, y))  # fmt: skip
        y -= 1.3 * size + (4 if i == 0 else 0)
    heights = [3.3 if len(shots) > 5 else 1.7, 1.0] + [2.3] * len(torque_joints) + [1.05] * len(velocity_joints)
    grid = body.add_gridspec(len(heights), 1, height_ratios=heights)
    _snapshot_row(body.add_subfigure(grid[0]), plan, shots, letters)
    timeline = body.add_subplot(grid[1])
    plot_mode_timeline(plan, timeline, marks=list(zip([s[0] for s in shots], letters)), legend=False, xlabel=False)
    axes = [timeline]
    res = plan.task.torque_resolution
    for i, joint in enumerate(torque_joints):
        ax = body.add_subplot(grid[2 + i], sharex=timeline)
        segs = [p for p in plan.phases if is_contact(p) and p.effort_joint == joint]
        ylim = torque_limits(segs, res)
        word, unit = effort_words(hand, joint)
        for seg in segs:
            draw_band(ax, seg.t, seg.lower, seg.upper, seg.command, joint_colour(hand, joint), ylim, label=False)
            mark_narrowest(ax, seg, ylim, label=False, unit=unit)
        _shade_other_control(ax, plan, joint, torque=True)
        ax.set_ylim(*ylim)
        ax.axhline(0.0, color="0.6", lw=0.5)
        symbol = "\\tau" if word == "torque" else "f"
        ax.set_ylabel(f"${symbol}_{{{joint_math(joint)}}}$ ({unit})", fontsize=FONT["label"])
        ax.set_title(f"{joint_title(joint)}: {word} command inside its guaranteed band", fontsize=FONT["label"],
                     loc="left")  # fmt: skip
        axes.append(ax)
    for joint in velocity_joints:
        ax = body.add_subplot(grid[len(axes) + 1], sharex=timeline)
        for ph in plan.phases:  # a free motion's rows hold the velocity until the next row: steps
            ax.plot(ph.t, ph.qd[:, names.index(joint)], color=joint_colour(hand, joint), lw=1.3,
                    drawstyle="default" if is_contact(ph) else "steps-post")  # fmt: skip
        _shade_other_control(ax, plan, joint, torque=False)
        ax.axhline(0.0, color="0.6", lw=0.5)
        short = joint in ("left", "right")  # a described hand's long joint names stay in the title: short panels
        ax.set_ylabel(f"$\\dot q_{{{joint}}}$ ({units[joint]})" if short else f"$\\dot q$ ({units[joint]})",
                      fontsize=FONT["label"])  # fmt: skip
        ax.set_title(f"{joint_title(joint)}: velocity command", fontsize=FONT["label"], loc="left")
        axes.append(ax)
    switches = [float(p.t[0]) for p in plan.phases[1:]]
    for ax in axes:
        for t in switches:
            ax.axvline(t, color="0.55", lw=0.6, ls=":", zorder=0)
        ax.tick_params(labelsize=FONT["tick"])
        if ax is not axes[-1]:
            ax.tick_params(labelbottom=False)
    timeline.set_xlim(float(plan.phases[0].t[0]), float(plan.duration))
    axes[-1].set_xlabel("t (s) from the plan's start (dotted lines: phase switches)", fontsize=FONT["label"])
    from qsplan.planner.plotting.hands import snapshot_legend_handles

    colour = joint_colour(hand, torque_joints[0]) if torque_joints else "0.3"
    word = effort_words(hand, torque_joints[0])[0] if torque_joints else "torque"
    handles = snapshot_legend_handles(hand=hand) + timeline_handles(plan) + [
        Patch(fc=colour, alpha=0.16, label=f"guaranteed {word} band"),
        Line2D([], [], color=colour, lw=1.3, label="band's upper edge"),
        Line2D([], [], color=colour, lw=1.3, ls="--", label="band's lower edge"),
        Line2D([], [], color=colour, ls="none", marker="^", ms=5, label="edge off the plot or unbounded"),
        Line2D([], [], color="k", lw=1.6, label=f"{word} command"),
        Line2D([], [], color=NARROWEST, ls="none", marker="$\\updownarrow$", ms=9, label="narrowest band, with its width"),
        Patch(fc="none", ec="0.8", hatch="////", label="joint under the other kind of control"),
    ]
    ncol = 3 if max(len(h.get_label()) for h in handles) <= LEGEND_LABEL_CHARS else 2
    body.legend(handles=handles, loc="outside lower center", ncol=ncol, fontsize=FONT["legend"], frameon=False)
    return fig
