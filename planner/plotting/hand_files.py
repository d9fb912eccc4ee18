"""Plot a hand description (issue 15): its palm, fingers and joints at one pose.

Compute lives in :mod:`qsplan.hands.description` and :mod:`qsplan.mechanics.model.manipulator`
(:func:`~qsplan.mechanics.model.manipulator.link_polygons`,
:func:`~qsplan.hands.description.model.joint_frames`); this module only draws.  matplotlib is
imported inside the function.
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.description.model import joint_frames
from qsplan.mechanics.model.manipulator import check_joint_positions, link_polygons
from qsplan.planner.plotting.style import FONT, axes_or_new, body_style, finger_colour, legend_below

__all__ = ["plot_hand_description"]

#: Half-length of a prismatic joint's double arrow, as a fraction of the drawing's width.
_ARROW = 0.03


def _joint_text(name: str, kind: str, q: float) -> str:
    value = f"{np.degrees(q):.0f} deg" if kind == "revolute" else f"{q * 1e3:.1f} mm"
    return f"{name}\n{value}"


def plot_hand_description(desc, q=None, workpiece=None, ax=None):
    """The palm, the links and the joints of a hand description at one pose.

    Links are filled in their finger's colour; a revolute joint is a circle, a prismatic joint a
    double arrow along its axis on the link (its travel between the limits dotted); each joint is
    labelled with its name and position.

    Parameters
    ----------
    desc : qsplan.hands.description.HandDescription
    q : array-like, shape (n_j,), optional
        Joint positions (rad; m for a prismatic joint); default each joint at the middle of its limits.
    workpiece : array-like, shape (k, 2), optional
        A workpiece polygon to draw, world frame (m).
    ax : matplotlib.axes.Axes, optional
        Default: the axes of a new figure.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch, Patch
    from matplotlib.patches import Polygon as PolygonPatch
    from matplotlib.ticker import FuncFormatter

    man = desc.manipulator
    q = desc.mid_limits if q is None else check_joint_positions(man, q)
    links = link_polygons(man, q)
    frames = joint_frames(desc, q)
    wp = None if workpiece is None else np.asarray(workpiece, dtype=float).reshape(-1, 2)

    ax = axes_or_new(ax, size=(6.0, 3.8))
    face, edge = body_style("palm")
    ax.add_patch(PolygonPatch(desc.palm, closed=True, facecolor=face, edgecolor=edge, lw=1.0, zorder=1))
    if wp is not None:
        face, edge = body_style("workpiece")
        ax.add_patch(PolygonPatch(wp, closed=True, facecolor=face, edgecolor=edge, lw=1.0, zorder=2))
    for finger, poly in zip(desc.finger_of_joint, links):
        face, edge = body_style(finger)
        ax.add_patch(PolygonPatch(np.asarray(poly.exterior.coords), closed=True, facecolor=face, edgecolor=edge,
                                  lw=1.0, alpha=0.9, zorder=3))  # fmt: skip

    pts = np.vstack([desc.palm] + [np.asarray(p.exterior.coords) for p in links] + ([wp] if wp is not None else []))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = float((hi - lo).max())
    poses = frames.copy()
    for i, kind in enumerate(desc.joint_kinds):
        if kind == "prismatic":
            poses[i, :2] += q[i] * np.array([np.cos(frames[i, 2]), np.sin(frames[i, 2])])
    # labels in a column outside each finger's links (left of the left finger, right of the right one), at the
    # joint's height or above the finger's previous label, with a leader line: they never cover a link of
    # their own finger, nor each other
    fig = ax.get_figure(root=True)
    box = ax.get_position()
    span = (hi - lo) * 1.12
    per_pt = max(span[0] / (box.width * fig.get_figwidth() * 72), span[1] / (box.height * fig.get_figheight() * 72))
    gap = 2.8 * FONT["note"] * per_pt  # two lines of text, in m
    column, label_y = {}, np.empty(len(poses))
    for finger in desc.fingers:
        idx = list(finger.joints)
        xs = np.concatenate([np.asarray(links[i].exterior.coords)[:, 0] for i in idx] + [poses[idx, 0]])
        column[finger.name] = xs.min() - 0.05 * size if finger.name == "left" else xs.max() + 0.05 * size
        previous = -np.inf
        for i in sorted(idx, key=lambda i: poses[i, 1]):
            label_y[i] = previous = max(poses[i, 1] + 0.015 * size, previous + gap)
    for i, (finger, kind) in enumerate(zip(desc.finger_of_joint, desc.joint_kinds)):
        colour = finger_colour(finger)
        x, y, a = poses[i]
        if kind == "revolute":
            ax.plot(x, y, "o", ms=6, mfc="white", mec=colour, mew=1.5, zorder=6)
        else:
            u = np.array([np.cos(a), np.sin(a)])
            travel = frames[i, :2] + np.outer(desc.joint_limits[i], u)
            ax.plot(*travel.T, ls=":", lw=1.2, color=colour, zorder=5)
            half = _ARROW * size * u
            ax.add_patch(FancyArrowPatch(poses[i, :2] - half, poses[i, :2] + half, arrowstyle="<|-|>",
                                         mutation_scale=9, color=colour, lw=1.3, zorder=6))  # fmt: skip
        left = finger == "left"
        ax.annotate(_joint_text(desc.joint_names[i], kind, q[i]), (x, y), xytext=(column[finger], label_y[i]),
                    ha="right" if left else "left", va="bottom", fontsize=FONT["note"], color=colour, zorder=7,
                    arrowprops={"arrowstyle": "-", "color": colour, "lw": 0.6, "shrinkA": 0, "shrinkB": 4})  # fmt: skip
        width = 0.62 * FONT["note"] * len(desc.joint_names[i]) * per_pt  # the label's width (m), estimated
        lo[0], hi[0] = min(lo[0], column[finger] - width), max(hi[0], column[finger] + width)
        hi[1] = max(hi[1], label_y[i] + gap)

    pad = 0.06 * size
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    mm = FuncFormatter(lambda v, _: f"{v * 1e3:g}")
    ax.xaxis.set_major_formatter(mm)
    ax.yaxis.set_major_formatter(mm)
    ax.set_xlabel("x (mm)", fontsize=FONT["label"])
    ax.set_ylabel("y (mm)", fontsize=FONT["label"])
    ax.tick_params(labelsize=FONT["tick"])
    ax.set_title(desc.name, fontsize=FONT["title"])

    handles = [Patch(fc=body_style(n)[0], ec=body_style(n)[1], label=f"{n} finger") for n in ("left", "right")]
    if "revolute" in desc.joint_kinds:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="white", mec="0.3", ms=6, label="revolute joint"))
    if "prismatic" in desc.joint_kinds:
        handles.append(Line2D([], [], color="0.3", marker="$\\leftrightarrow$", ls="none", ms=12,
                              label="prismatic joint (travel dotted)"))  # fmt: skip
    if wp is not None:
        handles.append(Patch(fc=body_style("workpiece")[0], ec=body_style("workpiece")[1], label="workpiece"))
    legend_below(ax, handles, ncol=len(handles))
    return ax
