"""Plots for operators: the two-finger hand at one configuration and strips of snapshots (Fig. 9).

Compute lives in :mod:`qsplan.hands`; this module only draws.  ``plot_*`` functions take
``ax=None`` (a new figure is made) and return the axes; ``*_figure`` functions return a
``matplotlib.figure.Figure`` (no pyplot).  matplotlib is imported inside the functions.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.style import axes_or_new

__all__ = ["hand_strip_figure", "plot_hand"]


def plot_hand(hand, pose, q=None, ax=None, alpha=1.0, contacts=True, label_joints=False):
    """The palm, the fingers and the workpiece at one configuration (Fig. 9).

    Parameters
    ----------
    hand : qsplan.hands.two_finger.TwoFingerHand
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (2,), optional
        Joint angles (rad); default the fingers' tangency angles.
    contacts : bool
        Mark the contacts found from the geometry, with their normals.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Polygon as Patch

    from qsplan.hands.two_finger_scene import hand_contacts, hand_geometric_scene, hand_polygons

    ax = axes_or_new(ax, size=(3.2, 2.6))
    polys = hand_polygons(hand, pose, q)
    styles = {"palm": ("#bdbdbd", "#636363"), "left": ("#6baed6", "#08519c"), "right": ("#fd8d3c", "#a63603"),
              "workpiece": ("#fff7bc", "#8c6d31")}  # fmt: skip
    for name in ("palm", "left", "right", "workpiece"):
        face, edge = styles[name]
        ax.add_patch(Patch(polys[name], closed=True, facecolor=face, edgecolor=edge, lw=1.0, alpha=alpha))
    if contacts:
        gs = hand_geometric_scene(hand, pose, q)
        scale = 0.12 * hand.finger_length
        for c in hand_contacts(gs):
            ax.plot(*c.point, "o", ms=3.5, color="k", alpha=alpha)
            ax.arrow(*c.point, *(scale * c.normal), width=0.0, head_width=0.2 * scale, color="k", lw=0.8,
                     length_includes_head=True, alpha=alpha)  # fmt: skip
    if label_joints:
        for name, p in zip(("left", "right"), hand.pivots):
            ax.annotate(name, p, xytext=(0, -11), textcoords="offset points", ha="center", fontsize=7)
    r = hand.finger_base + 0.5 * hand.finger_length
    ax.set_xlim(-r, r)
    ax.set_ylim(-0.3 * hand.finger_length, 1.05 * hand.finger_length)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    return ax


def hand_strip_figure(samples, n=5, title=None):
    """A strip of ``n`` hand snapshots along a sampled segment, with times and joint angles.

    Parameters
    ----------
    samples : qsplan.hands.segments.SegmentSamples
    n : int
        At least 2.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from qsplan.planner.plotting.style import new_axes

    n = max(2, int(n))
    fig, axes = new_axes(n, 1, size=(2.6, 2.4))
    idx = np.unique(np.round(np.linspace(0, len(samples) - 1, n)).astype(int))
    seg = samples.segment
    for ax, k in zip(axes[0], idx):
        plot_hand(seg.hand, samples.pose[k], samples.q[k], ax=ax, label_joints=k == idx[0])
        ax.set_title(f"t = {samples.t[k]:.3g} s\nq = ({np.degrees(samples.q[k, 0]):.1f}, "
                     f"{np.degrees(samples.q[k, 1]):.1f}) deg", fontsize=8)  # fmt: skip
    for ax in axes[0][len(idx):]:
        ax.set_visible(False)
    fig.suptitle(title or f"{seg.name} ({seg.mode}; {seg.effort_joint} finger torque-controlled)", fontsize=9)
    return fig
