"""The plan card: one A4 page an operator reads at a glance before running a plan (``plan_card.png``).

From top to bottom: the task, its facts and a table with a line per phase (numbered as ``plan.csv``
numbers them): what the hand does, the commanded joint, the command's range and which way it acts, the
slack (the command's margin to the nearer band edge) and the narrowest band, in the joint's unit; the
one-line verdict (certified row by row, re-simulated at N friction vectors); hand snapshots lettered A,
B, ..., the plan's start and end always among them, each titled with what the hand does there (sliding,
holding, pivoting on vertex K, open, closing: :func:`qsplan.planner.plotting.hands.state_words`), on one row or
two, as large as the page allows; then on one shared time axis a thin mode bar (the letters mark the snapshots'
instants; a slide, a hold and a pivot each in its own shade), each torque-controlled joint's command inside its
guaranteed band with the slack and the narrowest point marked (their labels where they cover no line:
:func:`qsplan.planner.plotting.plan_panels.place_labels`), one panel per run of phases on one scale
(:func:`~qsplan.planner.plotting.plan_panels.scale_groups`; a log scale where the command spans more than a decade),
edges beyond the plot marked as in Fig. 13 (filled: unbounded, hollow: finite), and each joint's velocity command
as a controller is sent it (:meth:`qsplan.planner.plan.results.Plan.sample`, the rule of ``qsplan sample``; joints
never velocity-controlled at once share a panel).  The legend lists what is drawn, nothing else.  Text is at least
7.5 pt on the printed page.  Only the plan's public fields are read (see
:mod:`qsplan.planner.plotting.plan_panels`).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

import numpy as np

from qsplan.planner.plan.results import HoldPhase, PivotPhase
from qsplan.planner.plan.sampling import tick_times
from qsplan.planner.plotting.hands import plan_snapshots, pivot_vertex, state_words
from qsplan.planner.plotting.plan_panels import (
    SLACK,
    draw_band,
    effort_sense,
    effort_words,
    is_contact,
    joint_math,
    joint_title,
    log_ticks,
    mark_narrowest,
    mark_slack,
    phase_label,
    place_labels,
    plot_mode_timeline,
    scale_groups,
    slack,
    timeline_handles,
    torque_scale,
)
from qsplan.planner.plotting.style import A4_PORTRAIT, FONT, NARROWEST, joint_colour, text_width, torque_text
from qsplan.planner.plotting.verdict import expected_verdict, verdict

__all__ = ["CARD_DPI", "LEGEND_LABEL_CHARS", "MAX_SNAPSHOTS", "MIN_SNAPSHOT_WIDTH", "VELOCITY_RATE", "VELOCITY_TICKS",
           "CardDraft", "card_snapshots", "draft_card", "finish_card", "phase_rows", "plan_card", "verdict", "warm_up"]

#: Resolution (dots per inch) the card is written at: 150 keeps 7.5 pt text sharp on an A4 print.
CARD_DPI = 150

#: Snapshots on the card, at most (the instants are thinned evenly beyond it; the start and the end stay).
MAX_SNAPSHOTS = 10

#: Longest legend label (characters) that three legend columns hold on the A4 page at the legend's 8 pt; longer
#: labels (a described hand's joint names in the timeline's entries) take two columns.
LEGEND_LABEL_CHARS = 44

#: Width (points) the header's table may take: the A4 page's 595 pt less its margins.
_TABLE_WIDTH = 570.0

#: The velocity panels draw what a controller is sent (:meth:`qsplan.planner.plan.results.Plan.sample`, the rule of
#: ``qsplan sample``): each tick's velocity held until the next, at this rate (Hz, a usual joint controller's) ...
VELOCITY_RATE = 1000.0
#: ... or coarser, at most this many ticks over a long plan (a 20 s plan at 1 kHz; ~1 ms of drawing per thousand).
VELOCITY_TICKS = 20_000

#: Snapshots drawn narrower than this (inches on the page, ~190 px at :data:`CARD_DPI`) in one row go on two rows.
MIN_SNAPSHOT_WIDTH = 1.25

#: Heights on the page (inches of the body's grid, its ratios, each with its title): the thin mode bar; a torque
#: panel and a velocity panel as usual and at least (a crowded card shrinks its panels to their least before its
#: snapshots); a snapshot's title; the width the snapshots' row takes, and a snapshot's at most; the legend's line
#: and the body's margins (the grid's height is the body's less the legend and the time axis' label).
_TIMELINE_HEIGHT = 0.45
_TORQUE_HEIGHT, _VELOCITY_HEIGHT, _TORQUE_MIN, _VELOCITY_MIN = 2.3, 1.05, 1.6, 0.75
_SNAPSHOT_TITLE, _SNAPSHOT_ROW_WIDTH, _SNAPSHOT_MAX_WIDTH = 0.4, 7.9, 2.0
_LEGEND_LINE, _BODY_MARGIN = 0.16, 0.6
#: Height (in) of a row of small snapshots, counted when deciding whether more than two velocity panels fit (a chain
#: hand whose four joints each move at some time, as when a finger is replaced mid-turn: one panel, a line each).
_SNAPSHOT_LEAST = 0.6
#: A torque panel drawn lower than this (in, after the layout squeezes an overfull page alike) is short
#: (:func:`_torque_panel`): ``finger_replaced_task``'s nine phases leave its three panels 1.16 in, where the narrowest
#: marks of a hold and a pivot sharing a panel met, and a log scale's ticks at 1, 2 and 5 per decade did.
_SHORT_TORQUE = 1.3
#: Most ticks of a short panel's log scale (:func:`qsplan.planner.plotting.plan_panels.log_ticks`): its powers of ten.
_SHORT_LOG_TICKS = 5

_OK, _BAD = "#1a7f37", "#b42318"
#: Characters per line of the verdict in the header (bold, 9 pt: the page's width).
_VERDICT_CHARS = 100
_COLUMNS = ("phase", "t (s)", "what the hand does", "commanded", "command, its direction", "slack", "narrowest band")


def card_snapshots(plan, limit: int = MAX_SNAPSHOTS) -> list:
    """The card's snapshots (:func:`qsplan.planner.plotting.hands.plan_snapshots`): the plan's start and end, each
    phase's ends, a regrasp's rows off the workpiece, and instants along each in-contact segment while there is room.

    Returns
    -------
    list of qsplan.planner.plotting.hands.Snapshot
        At most ``limit`` (at least the start and the end), in time order.
    """
    n_seg = max(1, sum(is_contact(p) for p in plan.phases))
    others = sum(p.t.size for p in plan.phases if not is_contact(p))
    per_segment = int(np.clip((limit - others) // n_seg, 2, 4))
    return plan_snapshots(plan, per_segment=per_segment, limit=max(2, limit))


def _range(values, unit) -> str:
    lo, hi = float(np.min(values)), float(np.max(values))
    if f"{lo:.3g}" == f"{hi:.3g}":
        return torque_text(lo, unit)
    return f"{torque_text(lo, unit) if np.isinf(lo) else f'{lo:.3g}'} to {torque_text(hi, unit)}"


def phase_rows(plan) -> list:
    """The header table's rows, one per phase (numbered as ``plan.csv``): the cells of the card's columns in words
    (phase, times, what the hand does, commanded joint, command range and direction, slack, narrowest band); a cell
    may hold two lines."""
    hand = plan.task.hand
    rows = []
    for i, ph in enumerate(plan.phases):
        times = f"{float(ph.t[0]):.3g} to {float(ph.t[-1]):.3g}"
        if not is_contact(ph):
            from qsplan.planner.plotting.hands import fingers_touching

            pose = ph.poses(plan.task.hand.rest_height)[0]
            off = {s for k in range(ph.t.size) for s, on in fingers_touching(hand, pose, ph.q[k]).items() if not on}
            who = "both fingers" if len(off) == 2 else f"the {next(iter(off))} finger" if off else "the fingers"
            rows.append((str(i), times, ph.does(who), "velocity only", "-", "-", "-"))
            continue
        word, unit = effort_words(hand, ph.effort_joint)
        mode, _ = phase_label(ph, hand)
        signs = set(np.sign(ph.command[ph.command != 0]).tolist())
        sense = "zero" if not signs else "changes sign" if len(signs) > 1 else effort_sense(hand, ph.effort_joint, *signs)
        value, edge, _ = slack(ph)
        room = f"{torque_text(value, unit)}\nto the {edge} edge" if np.isfinite(value) else "unbounded:\nno edge"
        k = int(np.argmin(ph.width))
        w = float(ph.width[k])
        side = "lower" if np.isinf(ph.lower).all() else "upper"
        narrow = f"{torque_text(w, unit)} at {float(ph.t[k]):.3g} s" if np.isfinite(w) else f"none: {side}\nedge unbounded"
        does = _does(plan, i, mode.removeprefix(ph.title_prefix))
        rows.append((str(i), times, does,
                     f"{joint_title(ph.effort_joint)} {word}", f"{_range(ph.command, unit)}\n{sense}",
                     room, narrow))  # fmt: skip
    return rows


def _does(plan, i, mode) -> str:
    """What phase ``i`` (in contact) does, for the card's table: a slide's direction and length, a hold's ramp, a
    pivot's vertex and angles; ``mode`` its mode in words."""
    ph = plan.phases[i]
    if isinstance(ph, HoldPhase):
        return f"holds: nothing moves\nin {mode}, torque ramps"
    if isinstance(ph, PivotPhase):
        th = np.degrees(ph.poses(plan.task.hand.rest_height)[[0, -1], 2])
        on = "" if pivot_vertex(plan, i) is None else f" on vertex {pivot_vertex(plan, i)},"
        return f"pivots{on} {th[0]:.3g} to {th[1]:.3g} deg\nin {mode}"
    dx = float(ph.x[-1] - ph.x[0])
    return f"slides {'left' if dx < 0 else 'right'} {abs(dx) * 1000:.3g} mm\nin {mode}"


def _letters(n):
    return [chr(ord("A") + k) if k < 26 else f"A{k - 25}" for k in range(n)]


def _velocity_controlled(plan, joint) -> list:
    """Per phase, whether ``joint`` is velocity-controlled in it (not its torque-controlled joint)."""
    return [not (is_contact(ph) and ph.effort_joint == joint) for ph in plan.phases]


def _velocity_panels(plan, joints, units) -> list:
    """The velocity panels: ``joints`` in groups that share one, joints of one unit never velocity-controlled in the
    same phase (the paper hand's fingers when each is torque-controlled in turn: one panel, a line each)."""
    groups = []
    for joint in joints:
        mine = np.array(_velocity_controlled(plan, joint))
        for group in groups:
            if units[group[0]] == units[joint] and not any(np.any(mine & _velocity_controlled(plan, j)) for j in group):
                group.append(joint)
                break
        else:
            groups.append([joint])
    return groups


def _joints_title(joints) -> str:
    """Joints in words: ``"left and right finger"``, ``"left_jaw and right_jaw joint"``."""
    word = "finger" if all(j in ("left", "right") for j in joints) else "joint"
    return f"{', '.join(joints[:-1])} and {joints[-1]} {word}"


def _shade_other_control(ax, plan, joint, torque: bool) -> bool:
    """Hatch where ``joint`` (or every joint of a list) is under the other kind of control, and say so where there is
    room; whether any."""
    t0, t1 = float(plan.phases[0].t[0]), float(plan.duration)
    drawn = False
    joints = joint if isinstance(joint, (list, tuple)) else [joint]
    for ph in plan.phases:
        mine = any(is_contact(ph) and ph.effort_joint == j for j in joints)
        if torque and mine:
            continue
        if not torque and not all(is_contact(ph) and ph.effort_joint == j for j in joints):
            continue
        a, b = float(ph.t[0]), float(ph.t[-1])
        ax.axvspan(a, b, fc="none", ec="0.8", hatch="////", lw=0, zorder=0)
        drawn = True
        _note(ax, a, b, t0, t1, "velocity-controlled" if torque else "torque-controlled (band above)", box=True)
    return drawn


def _note(ax, a, b, t0, t1, text, box=False) -> None:
    """A grey note across a stretch ``a`` to ``b`` (s) of a panel spanning ``t0`` to ``t1``, where it fits (the
    panel's width before the layout, a little narrower than after)."""
    room = (b - a) / max(t1 - t0, 1e-12) * ax.get_position().width * ax.get_figure(root=True).get_figwidth() * 72.0
    if text_width(text, FONT["note"]) + 8.0 < room:
        ax.text(0.5 * (a + b), 0.5, text, transform=ax.get_xaxis_transform(), ha="center", va="center",
                fontsize=FONT["note"], color="0.45", bbox={"fc": "white", "ec": "none", "pad": 1.0} if box else None)


def _facts(plan) -> str:
    task = plan.task
    lo, hi = task.mu_range
    model = "one shared friction coefficient" if task.shared_mu else "each contact's friction coefficient"
    n_seg = len(plan.segments)
    n_reg = len(plan.phases) - n_seg
    units = {effort_words(task.hand, p.effort_joint) for p in plan.segments}
    word, unit = units.pop() if len(units) == 1 else ("effort", "N m or N")
    text = (f"Bands guaranteed for {model} in [{lo:g}, {hi:g}]; controller {word} resolution {task.torque_resolution:g} "
            f"{unit}. {n_seg} in-contact segment{'s' if n_seg != 1 else ''}, "
            f"{n_reg} regrasp{'s' if n_reg != 1 else ''}, {plan.duration:.3g} s of motion.")
    if plan.segments:
        i, seg = min(((i, p) for i, p in enumerate(plan.phases) if is_contact(p)), key=lambda ip: slack(ip[1])[0])
        unit = effort_words(task.hand, seg.effort_joint)[1]
        value, edge, _ = slack(seg)
        text += (f" Smallest slack {torque_text(value, unit)} (phase {i}, to its {edge} edge)" if np.isfinite(value)
                 else " Every band is unbounded on both sides (no slack limit)")  # fmt: skip
        name, t, w = plan.narrowest()
        if np.isfinite(w):
            j, narrow = next((i, p) for i, p in enumerate(plan.phases) if is_contact(p) and p.name == name)
            width = torque_text(w, effort_words(task.hand, narrow.effort_joint)[1])
            text += f"; narrowest band {width} at t = {t:.3g} s (phase {j})."
        else:
            text += "; no band is bounded on both sides, so only the slack limits the command."
    return text


def _header(head, lines, xs) -> list:
    """The header's ``lines`` (:func:`_header_lines`) top down, in points, so that no two lines meet; the text
    artists, in order."""
    y, out = -4.0, []
    for i, (text, size, colour, bold) in enumerate(lines):
        cells = text if isinstance(text, tuple) else (text,)  # a table row: cells at the measured columns
        for x, cell in zip(xs if isinstance(text, tuple) else (0.0,), cells):
            out.append(head.text(0.01, 1.0, cell, fontsize=size, color=colour, va="top",
                                 weight="bold" if bold else "normal", linespacing=1.15,
                                 transform=_offset(head, y, x)))  # fmt: skip
        y -= _height(text, size) + (4 if i == 0 else 0)
    return out


def _height(text, size) -> float:
    """Height (points) a header line of ``size`` points takes (a table row: its tallest cell)."""
    cells = text if isinstance(text, tuple) else (text,)
    return 1.3 * size + 1.15 * size * max(c.count("\n") for c in cells)


def _header_lines(plan, verdict_line, ok) -> tuple:
    """``(lines, column x positions)``: each line ``(text or cells, size, colour, bold)``."""
    rows = phase_rows(plan)
    size, gap = FONT["note"], 9.0
    widths = [max(text_width(line, size, bold=r is _COLUMNS) for r in rows + [_COLUMNS] for line in r[c].split("\n"))
              for c in range(len(_COLUMNS))]  # fmt: skip
    xs = list(np.cumsum([0.0] + [w + gap for w in widths[:-1]]))
    lines = [(f"Plan card: {plan.task.name}", FONT["suptitle"] + 1, "k", True)]
    lines += [(s, FONT["label"], "k", False) for s in textwrap.wrap(_facts(plan), 112, break_on_hyphens=False)]
    if xs[-1] + widths[-1] <= _TABLE_WIDTH:
        lines += [(_COLUMNS, size, "k", True)] + [(r, size, "k", False) for r in rows]
    else:  # too wide for columns: one sentence per phase
        for r in rows:
            cells = [c.replace("\n", " ") for c in r]
            text = f"phase {cells[0]} ({cells[1]} s): {cells[2]}; "
            text += "; ".join(f"{h} {v}" for h, v in zip(_COLUMNS[3:], cells[3:]))
            lines += [(s, size, "k", False) for s in textwrap.wrap(text, 130)]
    lines += [(s, FONT["label"], _OK if ok else _BAD, True) for s in _verdict_lines(verdict_line)]
    return lines, xs


def _verdict_lines(line) -> list:
    """The verdict ``line`` as the header's lines (the last ones)."""
    return textwrap.wrap(line, _VERDICT_CHARS)


def _offset(sub, points, x_points=0.0):
    """The subfigure's coordinates shifted down by ``points`` (negative: down) and right by ``x_points``."""
    from matplotlib.transforms import offset_copy

    return offset_copy(sub.transSubfigure, fig=sub.get_figure(root=True), x=x_points, y=points, units="points")


def _layout(plan, shots, n_torque, n_velocity, grid_in) -> tuple:
    """``(snapshot rows, snapshot block height, torque panel height, velocity panel height)`` (inches of the body's
    grid, ``grid_in`` high; its ratios).

    The snapshots on one row while they are at least :data:`MIN_SNAPSHOT_WIDTH` wide there (else two), as wide as
    their columns allow up to :data:`_SNAPSHOT_MAX_WIDTH`; the panels share the rest in proportion to their usual
    heights, never below their least (then the snapshots give way).
    """
    from qsplan.planner.plotting.hands import hand_limits

    (x0, x1), (y0, y1) = hand_limits(plan.task.hand, [(s.pose, s.q) for s in shots])
    aspect = (y1 - y0) / (x1 - x0)
    rows = 1 if _SNAPSHOT_ROW_WIDTH / len(shots) - 0.2 >= MIN_SNAPSHOT_WIDTH else 2
    cols = -(-len(shots) // rows)
    width = min(_SNAPSHOT_ROW_WIDTH / cols - 0.2, _SNAPSHOT_MAX_WIDTH)
    least = n_torque * _TORQUE_MIN + n_velocity * _VELOCITY_MIN
    room = grid_in - _TIMELINE_HEIGHT - least  # for the snapshots, the panels at their least
    snap = min(rows * (width * aspect + _SNAPSHOT_TITLE), max(room, rows * (0.6 * width * aspect + _SNAPSHOT_TITLE)))
    want = n_torque * _TORQUE_HEIGHT + n_velocity * _VELOCITY_HEIGHT
    k = (grid_in - _TIMELINE_HEIGHT - snap) / want if want else 1.0
    return rows, snap, max(_TORQUE_HEIGHT * k, _TORQUE_MIN), max(_VELOCITY_HEIGHT * k, _VELOCITY_MIN)


def _snapshot_row(sub, plan, shots, letters, rows) -> set:
    """The snapshots on ``rows`` rows, each titled with its letter, time, role and what the hand does; what was
    drawn."""
    from qsplan.planner.plotting.hands import hand_limits, plot_hand

    lim = hand_limits(plan.task.hand, [(s.pose, s.q) for s in shots])
    cols = -(-len(shots) // rows)
    column = 72.0 * _SNAPSHOT_ROW_WIDTH / cols - 6.0  # points: a title's room
    axes = sub.subplots(rows, cols, squeeze=False).ravel()
    drawn = set()
    # the scale bar on the first snapshot without an effort's marker (a regrasp's), where no marker crowds its label
    bar = next((i for i, s in enumerate(shots) if not s.effort_joint), 0)
    for i, (ax, s, letter) in enumerate(zip(axes, shots, letters)):
        plot_hand(plan.task.hand, s.pose, s.q, ax=ax, contacts=s.touching, effort_joint=s.effort_joint, limits=lim,
                  scale_bar=i == bar, effort_sign=s.effort if s.effort_joint else None)  # fmt: skip
        drawn |= ({"contacts"} if s.touching else set()) | ({"effort"} if s.effort_joint else set())
        role = {"start": ", start", "end": ", end"}.get(s.role, "")
        state = state_words(plan, s.phase, s.state)
        state = state if len(s.off) != 1 or s.state not in ("open", "closing") else f"{s.off[0]} finger {s.state}"
        title = f"{letter}: t = {s.t:.3g} s{role}\nphase {s.phase}: {state}"
        if text_width(title, FONT["note"]) > column:  # too wide for its column: the phase on the first line
            title = f"{letter}: t = {s.t:.3g} s{role}, phase {s.phase}\n{state}"
        ax.set_title(title, fontsize=FONT["note"], pad=2)
    for ax in axes[len(shots):]:
        ax.set_visible(False)
    return drawn


def _phases_text(numbers) -> str:
    """Phase numbers in words: ``"phase 0"``, ``"phases 1-2"``, ``"phases 1, 3"``."""
    if len(numbers) == 1:
        return f"phase {numbers[0]}"
    run = list(range(numbers[0], numbers[-1] + 1)) == list(numbers)
    return f"phases {numbers[0]}-{numbers[-1]}" if run else "phases " + ", ".join(str(n) for n in numbers)


def _torque_panel(ax, plan, joint, segs, res, parts: int, short: bool = False) -> set:
    """One joint's commands inside their bands on one scale (``segs``, one of :func:`scale_groups`' runs; ``parts``
    runs in all), slack and narrowest marked; what was drawn.  ``short``: the panel is squeezed (a page of many phases
    and panels): the narrowest band marked once, at the panel's narrowest, and a log scale ticked at its powers of ten
    only, so that labels stay apart."""
    hand = plan.task.hand
    ylim, log = torque_scale(segs, res)
    word, unit = effort_words(hand, joint)
    drawn = set()
    if log:
        ax.set_yscale("log")
    narrowest = min(segs, key=lambda seg: float(np.min(seg.width)))
    for seg in segs:
        drawn |= draw_band(ax, seg.t, seg.lower, seg.upper, seg.command, joint_colour(hand, joint), ylim, label=False)
        k = int(np.argmin(seg.width))
        if (seg is narrowest or not short) and mark_narrowest(ax, seg, ylim, label=False, unit=unit):
            drawn.add("narrowest")
        if mark_slack(ax, seg, ylim, unit=unit, avoid=float(seg.t[k])):
            drawn.add("slack")
    if _shade_other_control(ax, plan, joint, torque=True):
        drawn.add("hatch")
    if parts > 1:  # this joint's phases drawn on another scale: said where there is room
        t0, t1 = float(plan.phases[0].t[0]), float(plan.duration)
        for ph in plan.phases:
            if is_contact(ph) and ph.effort_joint == joint and not any(ph is m for m in segs):
                _note(ax, float(ph.t[0]), float(ph.t[-1]), t0, t1, "in its own panel (another scale)")
    ax.set_ylim(*ylim)
    if log:
        log_ticks(ax.yaxis, *ylim, most=_SHORT_LOG_TICKS if short else 10)
    else:
        ax.axhline(0.0, color="0.6", lw=0.5)
    symbol = "\\tau" if word == "torque" else "f"
    plus = "counter-clockwise" if word == "torque" else "along +q"
    # one line (a second outgrew a short panel: a regrasp plan's release holds add a joint's panel); a described
    # hand's long name stays in the title, as the velocity panels'; the sign there too
    name = f"_{{{joint_math(joint)}}}" if joint in ("left", "right") else ""
    ax.set_ylabel(f"${symbol}{name}$ ({unit})", fontsize=FONT["label"])
    number = {id(p): i for i, p in enumerate(plan.phases)}
    which = f", {_phases_text([number[id(m)] for m in segs])}" if parts > 1 else ""
    which += " (log scale)" if log else ""
    which += f"; +: {plus}"
    ax.set_title(f"{joint_title(joint)}: {word} command inside its guaranteed band{which}", fontsize=FONT["label"],
                 loc="left")  # fmt: skip
    return drawn


#: Every key :func:`_legend_handles` knows (the most a legend may list).
_ALL_MARKS = frozenset({"contacts", "effort", "band", "upper", "lower", "upper_inf", "upper_off", "lower_inf", "lower_off",
                        "command", "slack", "narrowest", "hatch"})


def _legend_handles(plan, drawn, torque_joints) -> list:
    """Legend entries of what was drawn (``drawn``: keys of the snapshots', bands' and marks' drawings)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from qsplan.planner.plotting.hands import snapshot_legend_handles

    hand = plan.task.hand
    colour = joint_colour(hand, torque_joints[0]) if torque_joints else "0.3"
    word = effort_words(hand, torque_joints[0])[0] if torque_joints else "torque"
    marks = {"upper_inf": ("^", True, "upper edge unbounded"),
             "upper_off": ("^", False, "upper edge above the plot (finite)"),
             "lower_inf": ("v", True, "lower edge unbounded"),
             "lower_off": ("v", False, "lower edge below the plot (finite)")}
    handles = snapshot_legend_handles(effort="effort" in drawn, hand=hand, contacts="contacts" in drawn,
                                      effort_arrow="effort" in drawn) + timeline_handles(plan)  # fmt: skip
    entries = [("band", Patch(fc=colour, alpha=0.16, label=f"guaranteed {word} band")),
               ("upper", Line2D([], [], color=colour, lw=1.3, label="band's upper edge")),
               ("lower", Line2D([], [], color=colour, lw=1.3, ls="--", label="band's lower edge"))]
    entries += [(key, Line2D([], [], color=colour, ls="none", marker=m, ms=5, mfc=colour if filled else "white",
                             mew=1.1, label=label)) for key, (m, filled, label) in marks.items()]  # fmt: skip
    entries += [("command", Line2D([], [], color="k", lw=1.6, label=f"{word} command")),
                ("slack", Line2D([], [], color=SLACK, lw=1.2, marker="_", ms=7,
                                 label="slack: command to the nearer edge")),
                ("narrowest", Line2D([], [], color=NARROWEST, ls="none", marker="$\\updownarrow$", ms=9,
                                     label="narrowest band, with its width")),
                ("hatch", Patch(fc="none", ec="0.8", hatch="////", label="joint under the other kind of control"))]  # fmt: skip
    return handles + [h for key, h in entries if key in drawn]


def plan_card(plan, certificate=None, replays=(), snapshots: int = MAX_SNAPSHOTS, stated=None):
    """The plan card of ``plan`` as an A4 portrait figure.

    Parameters
    ----------
    plan : qsplan.planner.plan.results.Plan
    certificate : qsplan.planner.certify.certify.Certificate, optional
        The exported plan's certificate (:func:`qsplan.planner.certify.certify.certify_plan`).
    replays : sequence of qsplan.planner.replay.replay.Replay
        The exported plan re-simulated.
    snapshots : int
        Hand snapshots, at most (at least 2: the start and the end).
    stated : tuple, optional
        The verdict ``(line, ok)`` as :func:`~qsplan.planner.plotting.verdict.verdict` gives it (``certificate`` and
        ``replays`` are then not read).

    Returns
    -------
    matplotlib.figure.Figure
        Laid out once and kept so (its layout engine ``"none"`` after it): saved at any dpi without another layout
        pass, the labels where :func:`~qsplan.planner.plotting.plan_panels.place_labels` put them.
    """
    return _card(plan, stated or verdict(certificate, replays), snapshots)[0]


def _card(plan, stated, snapshots) -> tuple:
    """``(figure, the verdict's text artists)`` of :func:`plan_card` with the verdict ``stated`` = ``(line, ok)``."""
    from matplotlib.figure import Figure

    hand = plan.task.hand
    names, units = hand.joint_names, dict(zip(hand.joint_names, hand.joint_units("qd")))
    shots = card_snapshots(plan, snapshots)
    letters = _letters(len(shots))
    torque_joints = [j for j in names if any(is_contact(p) and p.effort_joint == j for p in plan.phases)]
    velocity_joints = [j for k, j in enumerate(names) if any(np.isfinite(p.qd[:, k]).any() for p in plan.phases)]
    velocity_panels = _velocity_panels(plan, velocity_joints, units)
    fig = Figure(figsize=A4_PORTRAIT, layout="constrained", dpi=CARD_DPI)  # laid out as it is written
    lines, xs = _header_lines(plan, *stated)
    head_in = (8.0 + sum(_height(text, size) for text, size, _, _ in lines) + 4.0) / 72.0
    head, body = fig.subfigures(2, 1, height_ratios=[head_in, A4_PORTRAIT[1] - head_in])
    texts = _header(head, lines, xs)
    res = plan.task.torque_resolution
    panels = [(joint, segs, len(groups)) for joint in torque_joints
              for groups in [scale_groups([p for p in plan.phases if is_contact(p) and p.effort_joint == joint], res)]
              for segs in groups]  # fmt: skip
    entries = len(_legend_handles(plan, _ALL_MARKS, torque_joints))  # at most: what is drawn is known later
    grid_in = A4_PORTRAIT[1] - head_in - _BODY_MARGIN - _LEGEND_LINE * -(-entries // 2)
    room = grid_in - _TIMELINE_HEIGHT - _SNAPSHOT_LEAST - len(panels) * _TORQUE_MIN
    if len(velocity_panels) > 2 and len(velocity_panels) * _VELOCITY_MIN > room:  # no room: one panel per unit
        velocity_panels = [[j for j in velocity_joints if units[j] == u]
                           for u in dict.fromkeys(units[j] for j in velocity_joints)]  # fmt: skip
    rows, snap_h, torque_h, velocity_h = _layout(plan, shots, len(panels), len(velocity_panels), grid_in)
    heights = [snap_h, _TIMELINE_HEIGHT] + [torque_h] * len(panels) + [velocity_h] * len(velocity_panels)
    short = torque_h * min(1.0, grid_in / sum(heights)) < _SHORT_TORQUE  # the layout squeezes every height alike
    grid = body.add_gridspec(len(heights), 1, height_ratios=heights)
    drawn = _snapshot_row(body.add_subfigure(grid[0]), plan, shots, letters, rows)
    timeline = body.add_subplot(grid[1])
    plot_mode_timeline(plan, timeline, marks=list(zip([s.t for s in shots], letters)), legend=False, xlabel=False,
                       compact=True)  # fmt: skip
    axes = [timeline]
    for i, (joint, segs, parts) in enumerate(panels):
        ax = body.add_subplot(grid[2 + i], sharex=timeline)
        drawn |= _torque_panel(ax, plan, joint, segs, res, parts, short)
        axes.append(ax)
    ticks = plan.sample(tick_times(plan.duration, min(VELOCITY_RATE, VELOCITY_TICKS / plan.duration)))
    for group in velocity_panels:
        ax = body.add_subplot(grid[len(axes) + 1], sharex=timeline)
        for joint in group:  # what the controller is sent: each tick's velocity held until the next (qsplan sample's
            # rule); nan under torque control
            ax.plot(ticks.t, ticks.qd[:, names.index(joint)], color=joint_colour(hand, joint), lw=1.3,
                    drawstyle="steps-post")  # fmt: skip
        if _shade_other_control(ax, plan, group, torque=False):
            drawn.add("hatch")
        ax.axhline(0.0, color="0.6", lw=0.5)
        joint = group[0]
        ax.set_ylabel(f"$\\dot q$ ({units[joint]})", fontsize=FONT["label"])  # the joint named in the title
        what = (f"{joint_title(joint)}: velocity command" if len(group) == 1 else
                f"{_joints_title(group)}: velocity command, each in its colour while velocity-controlled")
        ax.set_title(what, fontsize=FONT["label"], loc="left")
        axes.append(ax)
    switches = [float(p.t[0]) for p in plan.phases[1:]]
    for ax in axes:
        for t in switches:
            ax.axvline(t, color="0.55", lw=0.6, ls=":", zorder=0)
        ax.tick_params(labelsize=FONT["tick"])
        if ax is not axes[-1]:
            ax.tick_params(labelbottom=False)
    timeline.set_xlim(float(plan.phases[0].t[0]), float(plan.duration))
    axes[-1].set_xlabel("t (s) from the plan's start" + (" (dotted lines: phase switches)" if switches else ""),
                        fontsize=FONT["label"])  # fmt: skip
    handles = _legend_handles(plan, drawn, torque_joints)
    ncol = 3 if max(len(h.get_label()) for h in handles) <= LEGEND_LABEL_CHARS else 2
    body.legend(handles=handles, loc="outside lower center", ncol=ncol, fontsize=FONT["legend"], frameon=False)
    if not place_labels(fig):  # once the layout is known: the marks' labels where they cover no data
        fig.draw_without_rendering()  # no label to place: laid out all the same
    fig.set_layout_engine("none")  # one layout pass: drawn as measured at any dpi
    return fig, texts[len(texts) - len(_verdict_lines(stated[0])):]


def warm_up() -> None:
    """Load what the first card of a process would load while drawing (matplotlib's figure and axes modules, the
    fonts, the mathtext parser) by drawing a small figure with the same kinds of artists: a drawing process does this
    while the plan is searched, and drafts its card at full speed once the plan comes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(2.0, 2.0), layout="constrained", dpi=20)
    head, body = fig.subfigures(2, 1)
    head.text(0.0, 1.0, "qsplan", weight="bold", fontsize=FONT["label"], va="top")
    ax = body.add_subplot()
    ax.plot([0.0, 1.0], [1.0, 2.0], marker="^", mfc="white")
    ax.fill_between([0.0, 1.0], [0.0, 0.0], [1.0, 1.0], alpha=0.2)
    ax.annotate("$\\tau$", (0.5, 1.5), xytext=(4, 0), textcoords="offset points", fontsize=FONT["note"],
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none"}, arrowprops={"arrowstyle": "-"})
    ax.set_ylabel("$\\dot q_{left}$ (rad/s)", fontsize=FONT["label"])
    ax.set_title("qsplan", fontsize=FONT["label"], loc="left")
    body.legend(handles=[Line2D([], [], marker="$\\updownarrow$", ls="none", label="band")], loc="outside lower center")
    text_width("qsplan", FONT["note"], bold=True)
    text_width("qsplan", FONT["note"])
    FigureCanvasAgg(fig).draw()


@dataclass(frozen=True, slots=True, eq=False)
class CardDraft:
    """A plan card drawn at :data:`CARD_DPI` but for its verdict (:func:`draft_card`; :func:`finish_card` writes it).

    Attributes
    ----------
    plan : qsplan.planner.plan.results.Plan
    snapshots : int
    figure : matplotlib.figure.Figure
        Drawn on its Agg canvas, the verdict's lines hidden.
    verdict : tuple of matplotlib.text.Text
        The verdict's lines, in order.
    """

    plan: object
    snapshots: int
    figure: object
    verdict: tuple


def draft_card(plan, replays: int, snapshots: int = MAX_SNAPSHOTS) -> CardDraft:
    """The plan card drawn before its verdict is known, at :data:`CARD_DPI`, with room for the verdict
    :func:`expected_verdict` wraps to (a plan certified and re-simulated ``replays`` times without fault); the
    verdict's lines are left blank for :func:`finish_card`.

    The card's only part that depends on the certificate and the re-simulations is that line: the rest is drawn
    while they run (``qsplan plan``'s drawing process).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig, texts = _card(plan, expected_verdict(plan, replays), snapshots)
    for t in texts:
        t.set_visible(False)
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()  # at CARD_DPI, the figure's
    return CardDraft(plan, int(snapshots), fig, tuple(texts))


def finish_card(draft: CardDraft, stated, path, option: str = "path", force: bool = True, inputs=()) -> None:
    """Write the card of ``draft`` (:func:`draft_card`) with its verdict ``stated`` = ``(line, ok)``
    (:func:`~qsplan.planner.plotting.verdict.verdict`) to the PNG ``path``, as
    :func:`~qsplan.planner.plotting.style.save_figure` writes :func:`plan_card`'s.

    When the verdict takes as many lines as the draft left for it, only those lines are drawn, onto the draft's
    pixels (the layout is the same); else the card is drawn again whole with it.
    """
    from qsplan.planner.plotting.style import save_figure, save_rendered

    line, ok = stated
    lines = _verdict_lines(line)
    if len(lines) != len(draft.verdict):
        fig = plan_card(draft.plan, stated=stated, snapshots=draft.snapshots)
        save_figure(fig, path, option=option, dpi=CARD_DPI, force=force, inputs=inputs, tight=False)
        return
    renderer = draft.figure.canvas.get_renderer()
    for text, s in zip(draft.verdict, lines):
        text.set_text(s)
        text.set_color(_OK if ok else _BAD)
        text.set_visible(True)
        text.draw(renderer)
    save_rendered(draft.figure, path, option=option, force=force, inputs=inputs)
