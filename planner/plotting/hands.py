"""Plots for operators: a two-finger hand at one configuration and strips of snapshots (Fig. 9).

Compute lives in :mod:`qsplan.hands`; this module only draws.  ``plot_*`` functions take
``ax=None`` (a new figure is made) and return the axes; ``*_figure`` functions return a
``matplotlib.figure.Figure`` (no pyplot).  matplotlib is imported inside the functions.

Every body :func:`qsplan.hands.interface.hand_body_polygons` returns is drawn (palm, workpiece and
every link: the paper's two fingers, or every link of a described hand's chains, each in its
finger's colour); the torque-controlled joint's link is drawn with a thick outline and marked
``tau``; contacts are dots with their inward normals; a scale bar on the palm gives the size.
:func:`snapshot_legend_handles` explains the marks.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.style import FONT, axes_or_new, body_style, joint_colour

__all__ = ["hand_limits", "hand_strip_figure", "plot_hand", "snapshot_legend_handles"]

#: Relative length of the drawn contact normals (of the finger length, :func:`qsplan.hands.interface.finger_reach`).
_NORMAL = 0.12


def hand_limits(hand, configurations, pad: float = 0.08) -> tuple:
    """``((x0, x1), (y0, y1))`` (m) holding the fingers and the workpiece of every ``(pose, q)``, padded.

    The palm is cut at the limits (it is wider than anything that moves), so snapshots keep no empty
    margin; its thickness stays in view (the scale bar is drawn on it).
    """
    from qsplan.hands.interface import hand_body_polygons, palm_thickness

    pts = [np.vstack([p for name, p in hand_body_polygons(hand, pose, q).items() if name != "palm"])
           for pose, q in configurations]  # fmt: skip
    pts = np.vstack(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = hi - lo
    x = (lo[0] - pad * span[0], hi[0] + pad * span[0])
    return x, (min(lo[1], -palm_thickness(hand)), hi[1] + pad * span[1])


def _scale_bar(ax, hand, limits):
    """A bar of a round length (1, 2 or 5 cm or mm) drawn on the palm, under the workpiece, labelled right of it."""
    from qsplan.hands.interface import palm_thickness

    (x0, x1), _ = limits
    target = 0.3 * (x1 - x0)
    e = 10.0 ** np.floor(np.log10(target))
    length = max(m * e for m in (1.0, 2.0, 5.0) if m * e <= target)
    label = f"{length * 100:g} cm" if length >= 0.01 else f"{length * 1000:g} mm"
    xm, y = 0.5 * (x0 + x1), -0.5 * palm_thickness(hand)
    ax.plot([xm - length / 2, xm + length / 2], [y, y], color="k", lw=2.0, solid_capstyle="butt", zorder=4)
    ax.annotate(label, (xm + length / 2, y), xytext=(3, 0), textcoords="offset points", ha="left", va="center",
                fontsize=FONT["note"], zorder=4)  # fmt: skip


def plot_hand(hand, pose, q=None, ax=None, alpha=1.0, contacts=True, label_joints=False, effort_joint=None,
              limits=None, scale_bar=True):  # fmt: skip
    """The palm, the fingers and the workpiece at one configuration (Fig. 9).

    Parameters
    ----------
    hand : qsplan.hands.two_finger.TwoFingerHand or qsplan.hands.chain_hand.ChainHand
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
    limits : ((float, float), (float, float)), optional
        Axes limits (m); default :func:`hand_limits` of this configuration.
    scale_bar : bool
        Draw a scale bar (the axes carry no ticks).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Polygon as Patch

    from qsplan.hands.interface import contacts_at, finger_of_joint, finger_reach, hand_body_polygons

    ax = axes_or_new(ax, size=(3.2, 2.6))
    polys = hand_body_polygons(hand, pose, q)
    finger = finger_of_joint(hand)
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
    if contacts:
        scale = _NORMAL * finger_reach(hand)
        for c in contacts_at(hand, pose, q):
            ax.plot(*c.point, "o", ms=3.5, color="k", alpha=alpha, zorder=5)
            ax.arrow(*c.point, *(scale * c.normal), width=0.0, head_width=0.2 * scale, color="k", lw=0.8,
                     length_includes_head=True, alpha=alpha, zorder=5)  # fmt: skip
    if label_joints:
        from qsplan.hands.interface import joint_axes, joint_names

        for name, p in zip(joint_names(hand), joint_axes(hand, q)):
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


def snapshot_legend_handles(effort: bool = True, hand=None) -> list:
    """Legend entries explaining the snapshots: the fingers, contacts, normals, the torque-controlled finger (a
    described ``hand``'s: the torque-controlled joint's link)."""
    from matplotlib.lines import Line2D

    from matplotlib.patches import Patch

    chain = hand is not None and any(len(f) > 1 for f in hand.finger_joints)  # fingers of several links
    out = [Patch(fc=body_style(n)[0], ec=body_style(n)[1], label=f"{n} finger" + ("'s links" if chain else ""))
           for n in ("left", "right")]  # fmt: skip
    out += [Line2D([], [], ls="none", marker="o", ms=4, color="k", label="contact"),
           Line2D([], [], color="k", lw=0.8, marker=">", ms=4, markevery=[1], label="contact normal (into the workpiece)")]  # fmt: skip
    if effort:
        what = "torque-controlled joint's link" if chain else "torque-controlled finger"
        out.append(Line2D([], [], ls="none", marker="$\\tau$", ms=8, color="0.2", label=f"{what} (thick outline)"))
    return out


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
    from matplotlib.figure import Figure

    from qsplan.planner.plotting.style import figure_legend

    n = max(2, int(n))
    idx = np.unique(np.round(np.linspace(0, len(samples) - 1, n)).astype(int))
    seg = samples.segment
    lim = hand_limits(seg.hand, [(samples.pose[k], samples.q[k]) for k in idx])
    w = 2.3
    h = w * (lim[1][1] - lim[1][0]) / (lim[0][1] - lim[0][0])
    fig = Figure(figsize=(w * len(idx), h + 1.2), layout="constrained")
    axes = fig.subplots(1, len(idx), squeeze=False)[0]
    for ax, k in zip(axes, idx):
        plot_hand(seg.hand, samples.pose[k], samples.q[k], ax=ax, effort_joint=seg.effort_joint, limits=lim,
                  scale_bar=k == idx[0])
        ax.set_title(f"t = {samples.t[k]:.3g} s\nq = ({np.degrees(samples.q[k, 0]):.1f}, "
                     f"{np.degrees(samples.q[k, 1]):.1f}) deg (left, right)", fontsize=FONT["note"])  # fmt: skip
    figure_legend(fig, snapshot_legend_handles(), ncol=5)
    fig.suptitle(title or f"{seg.name}\nmode {seg.mode}: the {seg.effort_joint} finger torque-controlled, "
                 "the other velocity-controlled", fontsize=FONT["title"])  # fmt: skip
    return fig
