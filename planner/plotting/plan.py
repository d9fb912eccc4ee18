"""Operator plots of a plan of any two-finger hand: bands along the whole plan, the mode timeline, hand snapshots,
and the frames of its animation.

Each function takes a :class:`qsplan.planner.Plan`, draws into ``ax`` (or a new figure) and returns
the axes or the figure; matplotlib is imported inside.  Only the plan's public fields are read
(``Plan.phases``, :class:`~qsplan.planner.plan.results.ContactSegmentPlan`; every other phase is
drawn as a free motion of the fingers), so plans with more phases or fields draw too.
:func:`plan_figures` gives them all, the plan card (:mod:`qsplan.planner.plotting.card`) included,
for ``qsplan demo`` / ``qsplan plan``.  :func:`animation_frames` picks the configurations the animation
(:mod:`qsplan.planner.plotting.animation`) draws, with what the hand does and which way the workpiece slides
at each contact (:func:`sliding_directions`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.geometry import CONTACT_TOL

from qsplan.planner.plotting.hands import fingers_touching, phase_pose, row_state, state_words
from qsplan.planner.plotting.plan_panels import (
    draw_band,
    effort_words,
    is_contact,
    joint_math,
    log_ticks,
    mark_narrowest,
    phase_label,
    place_labels,
    plot_mode_timeline,
    torque_scale,
)
from qsplan.planner.plotting.style import FONT, joint_colour, legend_below, torque_text

__all__ = ["SNAPSHOT_COLUMNS", "Frame", "animation_frames", "plan_figures", "plan_snapshots_figure",
           "plot_mode_timeline", "plot_plan_bands", "sliding_directions"]

#: Hand snapshots per row, at most.
SNAPSHOT_COLUMNS = 6

#: Relative tangential displacement (m) of a contact between two rows below which it is drawn as not sliding: the
#: contact search's tolerance, a micron (far below a row's motion, ~0.5 mm on the bundled tasks).
_SLIDE_TOL = CONTACT_TOL


def plot_plan_bands(plan, axes=None, sharey=False):
    """The guaranteed band and the command of the torque-controlled joint along each in-contact segment.

    One panel per segment (N m against s from the plan's start), titled with its phase number as in
    ``plan.csv``, each scaled to its command, lower edge and margin (bands differ by orders of magnitude
    between segments; a log scale where its command spans more than a decade:
    :func:`qsplan.planner.plotting.plan_panels.torque_scale`), or one scale for all with ``sharey``.  Upper edges solid, lower edges dashed; an
    edge beyond the panel is marked at its side, with filled triangles where it is unbounded and hollow
    ones where it is finite; the narrowest point is marked with its width when both its edges are in
    view, and said in the title either way.

    Parameters
    ----------
    plan : qsplan.planner.plan.results.Plan
    axes : sequence of matplotlib Axes, optional
        One per segment; default a new figure with one row each.
    sharey : bool
        The same torque scale in every panel.

    Returns
    -------
    list of matplotlib Axes
    """
    from qsplan.planner.plotting.style import new_axes

    segs = plan.segments
    own = axes is None
    if own:
        _, grid = new_axes(1, len(segs), size=(8.0, 2.1))
        axes = [row[0] for row in grid]
    res = plan.task.torque_resolution
    shared = torque_scale(segs, res) if sharey else None
    hand = plan.task.hand
    number = {id(p): i for i, p in enumerate(plan.phases)}
    for ax, seg in zip(axes, segs):
        ylim, log = shared or torque_scale([seg], res)
        word, unit = effort_words(hand, seg.effort_joint)
        if log:
            ax.set_yscale("log")
        draw_band(ax, seg.t, seg.lower, seg.upper, seg.command, joint_colour(hand, seg.effort_joint), ylim, word=word)
        mark_narrowest(ax, seg, ylim, unit=unit)
        if log:
            log_ticks(ax.yaxis, *ylim, most=6)
        else:
            ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_ylim(*ylim)
        ax.set_xlim(seg.t[0], seg.t[-1])
        symbol = "\\tau" if word == "torque" else "f"
        ax.set_ylabel(f"${symbol}_{{{joint_math(seg.effort_joint)}}}$ ({unit})", fontsize=FONT["label"])
        mode, control = phase_label(seg, hand)
        width = float(np.min(seg.width))
        ax.set_title(f"phase {number[id(seg)]}: {mode}, {control}-controlled{' (log scale)' if log else ''}; smallest margin "
                     f"{torque_text(np.min(seg.margin), unit)}; narrowest band "
                     f"{torque_text(width, unit) if np.isfinite(width) else 'unbounded'}", fontsize=FONT["note"] + 0.5,
                     loc="left")  # fmt: skip
    axes[-1].set_xlabel("t (s) from the plan's start", fontsize=FONT["label"])
    handles = {}  # every mark drawn in any panel, once
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    legend_below(axes[-1], handles=list(handles.values()), ncol=3)
    lo, hi = plan.task.mu_range
    model = "one shared coefficient" if plan.task.shared_mu else "each contact's coefficient"
    axes[0].get_figure(root=False).suptitle(f"{plan.task.name}: torque bands guaranteed for {model} in [{lo:g}, "
                                            f"{hi:g}];\ncontroller resolution {res:g} N m", fontsize=FONT["title"])  # fmt: skip
    if own:  # the figure is complete: the labels where they cover no data
        place_labels(axes[0].get_figure(root=True))
    return list(axes)


def plan_snapshots_figure(plan, per_phase=3, columns=SNAPSHOT_COLUMNS):
    """Hand snapshots: ``per_phase`` along each in-contact segment, a regrasp's rows off the workpiece, the plan's
    start and end (:func:`qsplan.planner.plotting.hands.plan_snapshots`), each titled with its phase and what the hand
    does there.

    Rows are filled evenly (no empty panel but the last row's), every panel at one scale (a scale
    bar in the first), the torque-controlled finger marked with the way its command pushes it, the marks
    explained in a legend.
    """
    from matplotlib.figure import Figure

    from qsplan.planner.plotting.hands import hand_limits, plan_snapshots, plot_hand, snapshot_legend_handles
    from qsplan.planner.plotting.style import figure_legend

    shots = plan_snapshots(plan, per_phase)
    rows = -(-len(shots) // columns)
    cols = -(-len(shots) // rows)
    lim = hand_limits(plan.task.hand, [(s.pose, s.q) for s in shots])
    w = 2.0
    h = w * (lim[1][1] - lim[1][0]) / (lim[0][1] - lim[0][0]) + 0.45
    fig = Figure(figsize=(w * cols, h * rows + 0.9), layout="constrained")
    flat = fig.subplots(rows, cols, squeeze=False).ravel()
    for i, (ax, s) in enumerate(zip(flat, shots)):
        plot_hand(plan.task.hand, s.pose, s.q, ax=ax, contacts=s.touching, effort_joint=s.effort_joint, limits=lim,
                  scale_bar=i == 0, effort_sign=s.effort if s.effort_joint else None)  # fmt: skip
        ax.set_title(f"t = {s.t:.3g} s\nphase {s.phase}: {state_words(plan, s.phase, s.state)}", fontsize=FONT["note"])
    for ax in flat[len(shots):]:
        ax.set_visible(False)
    handles = snapshot_legend_handles(effort=any(s.effort_joint for s in shots), hand=plan.task.hand,
                                      contacts=any(s.touching for s in shots),
                                      effort_arrow=any(s.effort_joint for s in shots))  # fmt: skip
    figure_legend(fig, handles, ncol=3)
    fig.suptitle(f"{plan.task.name}: the hand along the plan", fontsize=FONT["title"])
    return fig


def plan_figures(plan, certificate=None, replays=()) -> dict:
    """``{"plan_bands", "mode_timeline", "hand_snapshots", "plan_card"}`` -> matplotlib Figure.

    ``certificate`` and ``replays`` give the plan card its verdict line
    (:func:`qsplan.planner.plotting.card.plan_card`).
    """
    from qsplan.planner.plotting.card import plan_card

    return {"plan_bands": plot_plan_bands(plan)[0].figure, "mode_timeline": plot_mode_timeline(plan).figure,
            "hand_snapshots": plan_snapshots_figure(plan), "plan_card": plan_card(plan, certificate, replays)}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class Frame:
    """One frame of the animation.

    Attributes
    ----------
    t : float
        Time from the plan's start (s).
    phase : int
        The phase, numbered as ``plan.csv``'s ``phase`` column.
    row : int
        The phase's row at or before ``t``.
    pose : ndarray, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : ndarray, shape (n_j,)
        Joint positions (rad or m).
    state : str
        What the hand does, one of :data:`qsplan.planner.plotting.hands.STATES`.
    contacts : list of (point, direction)
        Contact points (m, shape (2,)) and the unit direction the workpiece slides along there (zeros: it does not);
        empty where a finger is off the workpiece.
    """

    t: float
    phase: int
    row: int
    pose: np.ndarray
    q: np.ndarray
    state: str
    contacts: list


def _rigid(a, b):
    """The rotation (2, 2) and translation (2,) taking the points ``a`` (k, 2) onto ``b`` (k, 2) (least squares)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    r = (u @ vt).T
    if np.linalg.det(r) < 0:  # a reflection is never a link's motion
        vt[-1] *= -1
        r = (u @ vt).T
    return r, cb - r @ ca


def sliding_directions(hand, pose0, q0, pose1, q1) -> list:
    """Which way the workpiece slides at each contact of ``(pose0, q0)`` on its way to ``(pose1, q1)``.

    Each contact's point is followed on the workpiece and on the touching body (the palm, or the link nearest the
    point, moved rigidly between the two configurations); their difference along the contact's tangent is the
    workpiece's slip against the body.

    Returns
    -------
    list of (point, direction)
        The contact point (m, shape (2,)) and the unit tangent (shape (2,)) the workpiece slides along there, zeros
        where it slips less than :data:`_SLIDE_TOL`.  Raises :class:`~qsplan.mechanics.errors.SceneError` when a
        finger does not touch (:func:`qsplan.hands.contacts.found.drawable_contacts`).
    """
    from shapely.geometry import Point, Polygon

    from qsplan.hands.described.build import as_hand
    from qsplan.hands.contacts.found import drawable_contacts

    hand = as_hand(hand)  # the door: a hand record becomes a described hand
    before, after = hand.body_polygons(pose0, q0), hand.body_polygons(pose1, q1)
    rw, tw = _rigid(before["workpiece"], after["workpiece"])
    links = [n for n in before if n not in ("palm", "workpiece")]
    out = []
    for c in drawable_contacts(hand, pose0, q0):
        p = np.asarray(c.point, dtype=float)
        body = p  # on the palm, which does not move
        if c.body >= 0:
            name = min(links, key=lambda n: Polygon(before[n]).distance(Point(p)))
            r, t = _rigid(before[name], after[name])
            body = r @ p + t
        tangent = np.array([-c.normal[1], c.normal[0]])
        along = float(((rw @ p + tw) - body) @ tangent)
        out.append((p, np.sign(along) * tangent if abs(along) > _SLIDE_TOL else np.zeros(2)))
    return out


def _instant(plan, key) -> float:
    """Time (s) of ``(phase, row, weight)``: the row's, or ``weight`` of the way to the next row."""
    i, k, w = key
    t = plan.phases[i].t
    return float(t[k]) + (w * float(t[k + 1] - t[k]) if w else 0.0)


def _keys(plan, max_frames) -> list:
    """``(phase, row, weight)`` of each frame in time order: every phase's ends and regrasp row (thinned evenly beyond
    ``max_frames``), then instants evenly in time; a contact phase's instant snaps to its nearest row, a regrasp's
    lies ``weight`` of the way to its next row.  At a switch (two phases, one time) the later phase's row is kept."""
    keys = [(i, k, 0.0) for i, ph in enumerate(plan.phases) for k in range(ph.t.size)
            if k in (0, ph.t.size - 1) or not is_contact(ph)]  # fmt: skip
    if len(keys) > max_frames:
        keys = [keys[j] for j in np.unique(np.round(np.linspace(0, len(keys) - 1, max_frames)).astype(int))]
    starts = np.array([float(p.t[0]) for p in plan.phases])
    for t in np.linspace(float(plan.phases[0].t[0]), plan.duration, max(0, max_frames - len(keys)) + 2)[1:-1]:
        i = int(np.searchsorted(starts, t, side="right") - 1)
        ph = plan.phases[i]
        k = int(np.clip(np.searchsorted(ph.t, t, side="right") - 1, 0, ph.t.size - 2))
        w = (t - float(ph.t[k])) / max(float(ph.t[k + 1] - ph.t[k]), 1e-300)
        keys.append((i, k + int(w > 0.5), 0.0) if is_contact(ph) else (i, k, float(w)))
    by_time = {}
    for key in sorted(keys, key=lambda key: (_instant(plan, key), key[0])):
        by_time[round(_instant(plan, key), 9)] = key  # nanosecond rounding: one time, one frame
    return [by_time[t] for t in sorted(by_time)]


def animation_frames(plan, max_frames: int) -> list:
    """The animation's frames, in time order, at most ``max_frames`` (at least the plan's first and last rows).

    Returns
    -------
    list of Frame
    """
    hand = plan.task.hand
    out = []
    for i, k, w in _keys(plan, max_frames):
        ph = plan.phases[i]
        pose = phase_pose(plan, ph, k)
        q = np.asarray(ph.q[k], float) if w == 0.0 else (1.0 - w) * ph.q[k] + w * ph.q[k + 1]
        t = _instant(plan, (i, k, w))
        if w == 0.0:
            state = row_state(plan, i, k)[0]
        else:  # between a regrasp's rows: off the workpiece, or closing onto it when the next row touches
            off = [s for s, on in fingers_touching(hand, pose, q).items() if not on]
            nxt = not [s for s, on in fingers_touching(hand, pose, ph.q[k + 1]).items() if not on]
            state = ("closing" if nxt else "open") if off else "holding"
        contacts = []
        if state in ("open", "closing") and any(fingers_touching(hand, pose, q).values()):  # one finger replaced
            try:
                contacts = sliding_directions(hand, pose, q, pose, q)
            except SceneError:
                contacts = []
        if state in ("sliding", "holding", "pivoting"):
            j = min(k + 1, ph.t.size - 1)
            moving = is_contact(ph) and j != k
            nxt = (phase_pose(plan, ph, j), ph.q[j]) if moving else (pose, q)
            try:
                contacts = sliding_directions(hand, pose, q, *nxt)
                if is_contact(ph) and j == k and k > 0:  # a segment's last row slides as the row before it did
                    prev = sliding_directions(hand, phase_pose(plan, ph, k - 1), ph.q[k - 1], pose, q)
                    contacts = [(p, d) for (p, _), (_, d) in zip(contacts, prev)]
            except SceneError:  # touching, but not in the grasp's contact set (between rows): no contact drawn
                contacts = []
        out.append(Frame(t, i, k, pose, q, state, contacts))
    return out
