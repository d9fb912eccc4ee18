"""Plots for operators: a two-finger hand at one configuration, strips of snapshots (Fig. 9), and which
configurations of a plan to draw.

Compute lives in :mod:`qsplan.hands`; this module only draws.  ``plot_*`` functions take
``ax=None`` (a new figure is made) and return the axes; ``*_figure`` functions return a
``matplotlib.figure.Figure`` (no pyplot).  matplotlib is imported inside the functions.

Every body :meth:`qsplan.hands.protocol.Hand.body_polygons` returns is drawn (palm, workpiece and
every link: the paper's two fingers, or every link of a described hand's chains, each in its
finger's colour); the torque-controlled joint's link is drawn with a thick outline and marked
``tau``, with an arrow the way its commanded effort pushes it (:func:`effort_direction`); contacts are dots with
their inward normals; a scale bar on the palm gives the size.  :func:`snapshot_legend_handles` explains the marks.
:func:`plan_snapshots` picks a plan's configurations to draw and says of each what the hand does there
(:func:`row_state`: sliding, holding, open, closing), from the rows and the bodies' polygons alone
(:func:`fingers_touching`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.model.geometry import CONTACT_TOL

from qsplan.planner.plotting.plan_panels import is_contact
from qsplan.planner.plotting.style import FONT, axes_or_new, body_style, joint_colour

__all__ = ["phase_pose", "SAME_CONFIGURATION", "STATES", "TOUCH_TOL", "Snapshot", "effort_direction", "fingers_touching", "hand_limits", "hand_strip_figure",
           "pivot_vertex", "plan_snapshots", "plot_hand", "row_state", "snapshot_legend_handles", "state_words"]

#: Relative length of the drawn contact normals (of the finger length, :attr:`qsplan.hands.protocol.Hand.finger_reach`).
_NORMAL = 0.12

#: Relative length of the arrow of the commanded effort on its link (of the finger length).
_EFFORT_ARROW = 0.22

#: Distance (m) within which a finger touches the workpiece: the contact search's own tolerance
#: (:data:`qsplan.mechanics.model.geometry.CONTACT_TOL`), so a drawing calls touching what the planner does.
TOUCH_TOL = CONTACT_TOL

#: Joint step (rad or m) of the finite difference that finds which way an effort pushes its link: far above
#: rounding (1e-16 relative), far below any visible motion (10 micrometres at the tip of a 10 cm link).
_EFFORT_STEP = 1e-4

#: Two rows whose workpiece poses and joints differ by at most this (m, rad; m for a prismatic joint) show one
#: configuration (:func:`plan_snapshots` draws it once): a micron or a microradian, far below what a drawing shows,
#: far above the rounding of a hold's end and the pivot's closed-form start (1e-16 relative).
SAME_CONFIGURATION = 1e-6

#: What the hand does at a row of a plan, in the operator's words (:func:`row_state`; a pivot's in full:
#: :func:`state_words`).
STATES = ("sliding", "holding", "pivoting", "open", "closing")


def fingers_touching(hand, pose, q) -> dict:
    """``{"left": bool, "right": bool}``: whether any link of each finger is within :data:`TOUCH_TOL` of the workpiece.

    Parameters
    ----------
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
    """
    from shapely.geometry import Polygon

    from qsplan.hands.described.build import as_hand

    hand = as_hand(hand)  # the door: a hand record becomes a described hand
    polys = hand.body_polygons(pose, q)
    work = Polygon(polys["workpiece"])
    out = {"left": False, "right": False}
    for joint, side in hand.finger_of_joint.items():
        out[side] |= bool(Polygon(polys[joint]).distance(work) <= TOUCH_TOL)
    return out


def effort_direction(hand, pose, q, joint, sign) -> tuple:
    """``(point, direction)``: the centre of ``joint``'s link (m, shape (2,)) and the unit vector (shape (2,)) it moves
    along when the joint's effort has the sign of ``sign`` (a torque turns it, a force pushes it along its axis)."""
    from qsplan.hands.described.build import as_hand

    hand = as_hand(hand)  # the door: a hand record becomes a described hand
    q = np.asarray(q, dtype=float)
    step = np.zeros_like(q)
    step[hand.joint_names.index(joint)] = _EFFORT_STEP * np.sign(sign)
    a = hand.body_polygons(pose, q)[joint]
    b = hand.body_polygons(pose, q + step)[joint]
    d = (b - a).mean(axis=0)
    return a.mean(axis=0), d / max(float(np.hypot(*d)), 1e-300)


def hand_limits(hand, configurations, pad: float = 0.08) -> tuple:
    """``((x0, x1), (y0, y1))`` (m) holding the fingers and the workpiece of every ``(pose, q)``, padded.

    The palm is cut at the limits (it is wider than anything that moves), so snapshots keep no empty
    margin; its thickness stays in view (the scale bar is drawn on it).
    """
    from qsplan.hands.described.build import as_hand

    hand = as_hand(hand)  # the door: a hand record becomes a described hand
    pts = [np.vstack([p for name, p in hand.body_polygons(pose, q).items() if name != "palm"])
           for pose, q in configurations]  # fmt: skip
    pts = np.vstack(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = hi - lo
    x = (lo[0] - pad * span[0], hi[0] + pad * span[0])
    return x, (min(lo[1], -hand.palm_thickness), hi[1] + pad * span[1])


def _scale_bar(ax, hand, limits):
    """A bar of a round length (1, 2 or 5 cm or mm) drawn on the palm, under the workpiece, labelled right of it."""
    (x0, x1), _ = limits
    target = 0.3 * (x1 - x0)
    e = 10.0 ** np.floor(np.log10(target))
    length = max(m * e for m in (1.0, 2.0, 5.0) if m * e <= target)
    label = f"{length * 100:g} cm" if length >= 0.01 else f"{length * 1000:g} mm"
    xm, y = 0.5 * (x0 + x1), -0.5 * hand.palm_thickness
    ax.plot([xm - length / 2, xm + length / 2], [y, y], color="k", lw=2.0, solid_capstyle="butt", zorder=4)
    ax.annotate(label, (xm + length / 2, y), xytext=(3, 0), textcoords="offset points", ha="left", va="center",
                fontsize=FONT["note"], zorder=4)  # fmt: skip


def plot_hand(hand, pose, q=None, ax=None, alpha=1.0, contacts=True, label_joints=False, effort_joint=None,
              limits=None, scale_bar=True, effort_sign=None):  # fmt: skip
    """The palm, the fingers and the workpiece at one configuration (Fig. 9).

    Parameters
    ----------
    hand : qsplan.hands.protocol.Hand
        Or a hand record (:class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand`,
        :class:`~qsplan.hands.chains.hand.ChainHand`), converted at the door
        (:func:`qsplan.hands.described.build.as_hand`).
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,), optional
        Joint positions (rad or m); the paper's hand's default: the fingers' tangency angles.
    contacts : bool
        Mark the contacts found from the geometry (dots) with their normals into the workpiece (arrows).
    label_joints : bool
        Name each joint under its axis.
    effort_joint : str, optional
        The torque-controlled joint: its link drawn with a thick outline and a ``tau`` mark.
    effort_sign : float, optional
        The sign of its commanded effort: an arrow from its link's centre the way the effort pushes the link
        (:func:`effort_direction`).
    limits : ((float, float), (float, float)), optional
        Axes limits (m); default :func:`hand_limits` of this configuration.
    scale_bar : bool
        Draw a scale bar (the axes carry no ticks).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Polygon as Patch

    from qsplan.hands.described.build import as_hand
    from qsplan.hands.contacts.found import drawable_contacts

    hand = as_hand(hand)  # the door: a hand record becomes a described hand
    ax = axes_or_new(ax, size=(3.2, 2.6))
    polys = hand.body_polygons(pose, q)
    finger = hand.finger_of_joint
    order = ["palm"] + [n for n in polys if n not in ("palm", "workpiece")] + ["workpiece"]
    for name in order:
        face, edge = body_style(finger.get(name, name))  # a chain's links in their finger's colours
        thick = name == effort_joint
        ax.add_patch(Patch(polys[name], closed=True, facecolor=face, edgecolor=edge, lw=2.4 if thick else 1.0,
                           alpha=alpha, zorder=3 if thick else 2))  # fmt: skip
    if effort_joint in polys:
        tip = polys[effort_joint].mean(axis=0)
        colour = joint_colour(hand, effort_joint)
        ax.annotate("$\\tau$", tip, ha="center", va="center", fontsize=FONT["label"], color=colour, weight="bold",
                    zorder=6, bbox={"boxstyle": "circle,pad=0.15", "fc": "white", "ec": colour, "lw": 1.0})  # fmt: skip
        if effort_sign is not None and np.sign(effort_sign) != 0:
            p, d = effort_direction(hand, pose, q, effort_joint, effort_sign)
            ax.annotate("", xy=p + _EFFORT_ARROW * hand.finger_reach * d, xytext=p, zorder=6,
                        arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.6, "shrinkA": 7, "shrinkB": 0})  # fmt: skip
    if contacts:
        scale = _NORMAL * hand.finger_reach
        for c in drawable_contacts(hand, pose, q):
            ax.plot(*c.point, "o", ms=3.5, color="k", alpha=alpha, zorder=5)
            ax.arrow(*c.point, *(scale * c.normal), width=0.0, head_width=0.2 * scale, color="k", lw=0.8,
                     length_includes_head=True, alpha=alpha, zorder=5)  # fmt: skip
    if label_joints:
        for name, p in zip(hand.joint_names, hand.joint_axes(q)):
            ax.annotate(name, p, xytext=(0, -9), textcoords="offset points", ha="center", va="top",
                        fontsize=FONT["note"], color=joint_colour(hand, name))  # fmt: skip
    limits = limits or hand_limits(hand, [(pose, q)])
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if scale_bar:
        _scale_bar(ax, hand, limits)
    return ax


def snapshot_legend_handles(effort: bool = True, hand=None, contacts: bool = True, effort_arrow: bool = False) -> list:
    """Legend entries explaining the snapshots: the fingers, and what is drawn of ``contacts`` (dots, normals), the
    torque-controlled finger (a described ``hand``'s: the torque-controlled joint's link) and its ``effort_arrow``."""
    from matplotlib.lines import Line2D

    from matplotlib.patches import Patch

    chain = hand is not None and any(len(f) > 1 for f in hand.finger_joints)  # fingers of several links
    out = [Patch(fc=body_style(n)[0], ec=body_style(n)[1], label=f"{n} finger" + ("'s links" if chain else ""))
           for n in ("left", "right")]  # fmt: skip
    if contacts:
        out += [Line2D([], [], ls="none", marker="o", ms=4, color="k", label="contact"),
                Line2D([], [], color="k", lw=0.8, marker=">", ms=4, markevery=[1], label="contact normal (into the workpiece)")]  # fmt: skip
    if effort:
        what = "torque-controlled joint's link" if chain else "torque-controlled finger"
        out.append(Line2D([], [], ls="none", marker="$\\tau$", ms=8, color="0.2", label=f"{what} (thick outline)"))
    if effort_arrow:
        out.append(Line2D([], [], color="0.2", lw=1.6, marker=">", ms=5, markevery=[1],
                          label="the way its commanded effort pushes it"))  # fmt: skip
    return out


def hand_strip_figure(samples, n=5, title=None):
    """A strip of ``n`` hand snapshots along a sampled segment, with times and joint angles.

    Parameters
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
    n : int
        At least 2.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from qsplan.hands.described.build import as_hand
    from qsplan.planner.plotting.style import figure_legend

    n = max(2, int(n))
    idx = np.unique(np.round(np.linspace(0, len(samples) - 1, n)).astype(int))
    seg = samples.segment
    hand = as_hand(seg.hand)  # the door: a segment's record (the paper hand by its parameters) as a described hand
    lim = hand_limits(hand, [(samples.pose[k], samples.q[k]) for k in idx])
    w = 2.3
    h = w * (lim[1][1] - lim[1][0]) / (lim[0][1] - lim[0][0])
    fig = Figure(figsize=(w * len(idx), h + 1.2), layout="constrained")
    axes = fig.subplots(1, len(idx), squeeze=False)[0]
    for ax, k in zip(axes, idx):
        plot_hand(hand, samples.pose[k], samples.q[k], ax=ax, effort_joint=seg.effort_joint, limits=lim,
                  scale_bar=k == idx[0])
        ax.set_title(f"t = {samples.t[k]:.3g} s\nq = ({np.degrees(samples.q[k, 0]):.1f}, "
                     f"{np.degrees(samples.q[k, 1]):.1f}) deg (left, right)", fontsize=FONT["note"])  # fmt: skip
    figure_legend(fig, snapshot_legend_handles(), ncol=5)
    fig.suptitle(title or f"{seg.name}\nmode {seg.mode}: the {seg.effort_joint} finger torque-controlled, "
                 "the other velocity-controlled", fontsize=FONT["title"])  # fmt: skip
    return fig


@dataclass(frozen=True, slots=True, eq=False)
class Snapshot:
    """One configuration of a plan drawn for the operator (the plan card's and the snapshots figure's panels).

    Attributes
    ----------
    t : float
        Time from the plan's start (s).
    phase, row : int
        The phase (numbered as ``plan.csv``'s ``phase`` column) and its row.
    pose : ndarray, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : ndarray, shape (n_j,)
        Joint positions (rad or m).
    effort_joint : str or None
        The torque-controlled joint (None in a regrasp).
    effort : float
        Its command at the row (N m or N; NaN in a regrasp).
    state : str
        What the hand does there, one of :data:`STATES` (:func:`row_state`).
    off : tuple of str
        The fingers off the workpiece (``"left"``, ``"right"``).
    role : str
        ``"start"`` (the plan's first row), ``"end"`` (its last) or ``""``.
    """

    t: float
    phase: int
    row: int
    pose: np.ndarray
    q: np.ndarray
    effort_joint: str | None
    effort: float
    state: str
    off: tuple
    role: str

    @property
    def touching(self) -> bool:
        """A finger on the workpiece (its contacts can be drawn): every finger, or one while the other is replaced."""
        return len(self.off) < 2


def phase_pose(plan, phase, k) -> np.ndarray:
    """The workpiece's pose (m, m, rad) at row ``k`` of ``phase`` (its last row beyond it): turned in a pivot."""
    pose = phase.poses(plan.task.hand.rest_height)
    return pose[min(k, len(pose) - 1)]


def _off(plan, phase, k) -> tuple:
    touching = fingers_touching(plan.task.hand, phase_pose(plan, phase, k), phase.q[k])
    return tuple(side for side, on in touching.items() if not on)


def row_state(plan, i, k) -> tuple:
    """``(state, off)``: what the hand does at row ``k`` of phase ``i`` (from the rows), and its fingers off the
    workpiece.

    ``"open"``: a finger is off the workpiece (:func:`qsplan.planner.plotting.hands.fingers_touching`);
    ``"closing"``: off, after a row already off and before a row where every finger touches again (the fingers'
    approach to the next grasp); ``"pivoting"``: a pivot phase (the workpiece turns on a palm vertex);
    ``"holding"``: a hold phase, or every finger touches and the workpiece stays (a regrasp's release and re-closed
    grasp); ``"sliding"``: every finger touches and the workpiece moves along the phase.
    """
    ph = plan.phases[i]
    off = _off(plan, ph, k)
    if off:
        n = ph.t.size
        approach = 0 < k < n - 1 and not _off(plan, ph, k + 1) and bool(_off(plan, ph, k - 1))
        return ("closing" if approach else "open"), off
    if is_contact(ph) and ph.state_word is not None:  # a pivot or a hold: said by its kind
        return ph.state_word, off
    moving = np.size(ph.x) > 1 and float(np.ptp(ph.x)) > 0.0
    return ("sliding" if moving else "holding"), off


def pivot_vertex(plan, i):
    """The workpiece vertex (as the task writes it) phase ``i`` pivots on, from the plan's ``sequence`` (one step per
    phase, :class:`qsplan.planner.plan.steps.PivotStep`); None when the plan does not say (or phase ``i`` is no
    pivot)."""
    from qsplan.planner.plan.steps import PivotStep, route_steps

    steps = route_steps(plan.sequence)
    if len(steps) != len(plan.phases) or not isinstance(steps[i], PivotStep):
        return None
    return int(steps[i].vertex)


def state_words(plan, i, state) -> str:
    """``state`` (:func:`row_state`) of phase ``i`` for a title: a pivot's with its vertex (``"pivoting on vertex
    1"``), any other as it is."""
    if state != "pivoting":
        return state
    vertex = pivot_vertex(plan, i)
    return "pivoting" if vertex is None else f"pivoting on vertex {vertex}"


def _candidates(plan, per_segment) -> dict:
    """``{(phase, row): priority}``: 0 the plan's first and last rows; 1 each phase's ends and a regrasp's first and
    last rows off the workpiece; 2 the rest (a segment's inner samples, a regrasp's other rows; a hold has none)."""
    out = {}
    for i, ph in enumerate(plan.phases):
        n = ph.t.size
        if is_contact(ph):  # a hold moves nothing: its ends only
            count = max(2, per_segment) if ph.moves else 2
            rows = np.unique(np.round(np.linspace(0, n - 1, count)).astype(int))
            out |= {(i, int(k)): 1 if k in (0, n - 1) else 2 for k in rows}
        else:
            off = [k for k in range(n) if _off(plan, ph, k)]
            out |= {(i, k): 1 if k in (0, n - 1) or (off and k in (off[0], off[-1])) else 2 for k in range(n)}
    last = len(plan.phases) - 1
    out |= {(0, 0): 0, (last, plan.phases[last].t.size - 1): 0}
    return out


def _same_configuration(plan, a, b) -> bool:
    """Whether rows ``a`` and ``b`` (``(phase, row, ...)``) show one configuration (:data:`SAME_CONFIGURATION`)."""
    (i, k), (j, m) = a[:2], b[:2]
    pa, pb = phase_pose(plan, plan.phases[i], k), phase_pose(plan, plan.phases[j], m)
    qa, qb = np.asarray(plan.phases[i].q[k], float), np.asarray(plan.phases[j].q[m], float)
    return bool(np.max(np.abs(pa - pb)) <= SAME_CONFIGURATION and np.max(np.abs(qa - qb)) <= SAME_CONFIGURATION)


def plan_snapshots(plan, per_segment: int = 3, limit: int | None = None) -> list:
    """The configurations to draw, in time order: the plan's start and end always, each phase's ends, ``per_segment``
    rows along each in-contact segment and a regrasp's rows off the workpiece, at most ``limit``.

    Where two phases meet (same time, same configuration) the later phase's row is kept; a row showing the
    configuration of the row before it (after a hold: nothing moved) is left out.  Beyond ``limit`` the rows of least
    priority go first, thinned evenly (the start and the end stay).

    Returns
    -------
    list of Snapshot
    """
    cand = _candidates(plan, per_segment)
    by_t = {}
    for (i, k), prio in sorted(cand.items()):  # at a switch the later phase's row wins, with the best priority
        t = float(plan.phases[i].t[k])
        old = by_t.get(t)
        by_t[t] = (i, k, min(prio, old[2]) if old else prio)
    keys = []
    for key in (by_t[t] for t in sorted(by_t)):  # nothing moved since the last one (a hold): the same picture
        if keys and key[2] > 0 and _same_configuration(plan, keys[-1], key):
            continue
        keys.append(key)
    if limit is not None and len(keys) > limit:
        kept = []
        for prio in (0, 1, 2):
            group = [key for key in keys if key[2] == prio]
            room = max(0, int(limit) - len(kept))
            if len(group) > room:
                picks = np.unique(np.round(np.linspace(0, len(group) - 1, room)).astype(int)) if room else []
                group = [group[j] for j in picks]
            kept += group
        keys = sorted(kept, key=lambda key: float(plan.phases[key[0]].t[key[1]]))
    out, last = [], (len(plan.phases) - 1, plan.phases[-1].t.size - 1)
    for i, k, _ in keys:
        ph = plan.phases[i]
        state, off = row_state(plan, i, k)
        effort = float(ph.command[k]) if is_contact(ph) else float("nan")
        role = "start" if (i, k) == (0, 0) else "end" if (i, k) == last else ""
        out.append(Snapshot(float(ph.t[k]), i, k, phase_pose(plan, ph, k), np.asarray(ph.q[k], float),
                            ph.effort_joint if is_contact(ph) else None, effort, state, off, role))  # fmt: skip
    return out
