"""Operator plots of a two-finger plan: bands along the whole plan, the mode timeline, hand snapshots.

Each function takes a :class:`qsplan.planner.Plan`, draws into ``ax`` (or a new
figure) and returns the axes or the figure; matplotlib is imported inside.
:func:`plan_figures` gives all three for ``qsplan demo`` / ``qsplan plan``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_plan_bands", "plot_mode_timeline", "plan_snapshots_figure", "plan_figures"]

_COLOURS = {"left": "#08519c", "right": "#a63603"}

#: Hand snapshots per row.
SNAPSHOT_COLUMNS = 6


def _panel_limits(seg, resolution):
    """y-limits (N m) showing a segment's command and finite band sides; a far or infinite side is cut off."""
    vals = np.concatenate([seg.command, seg.lower[np.isfinite(seg.lower)]])
    lo, hi = float(vals.min()), float(seg.command.max())
    span = max(hi - lo, resolution)
    return lo - 0.6 * span, hi + 1.5 * span


def plot_plan_bands(plan, axes=None):
    """The guaranteed band and the command of the effort-controlled finger along each in-contact segment.

    One panel per segment (N m vs s from the plan's start), each scaled to its own command and
    lower band side, since bands differ by orders of magnitude between segments; an upper side
    beyond the panel (or infinite) is cut off at its top, marked "band continues above".

    Parameters
    ----------
    plan : qsplan.planner.planning.plan.Plan
    axes : sequence of matplotlib Axes, optional
        One per segment; default a new figure with one row each.

    Returns
    -------
    list of matplotlib Axes
    """
    from qsplan.planner.plotting.style import new_axes

    segs = plan.segments
    if axes is None:
        _, grid = new_axes(1, len(segs), size=(9.0, 2.3))
        axes = [row[0] for row in grid]
    res = plan.task.torque_resolution
    for ax, seg in zip(axes, segs):
        c = _COLOURS[seg.effort_joint]
        y0, y1 = _panel_limits(seg, res)
        ax.fill_between(seg.t, np.clip(seg.lower, y0, y1), np.clip(seg.upper, y0, y1), color=c, alpha=0.18, lw=0,
                        label="guaranteed band")  # fmt: skip
        ax.plot(seg.t, seg.lower, "--", color=c, lw=1.0)
        ax.plot(seg.t, np.where(np.isfinite(seg.upper), seg.upper, np.nan), "-", color=c, lw=1.0)
        ax.plot(seg.t, seg.command, ":", color="k", lw=1.4, label="command")
        if np.any(seg.upper > y1):
            ax.text(0.99, 0.96, "band continues above", transform=ax.transAxes, ha="right", va="top", fontsize=7)
        ax.axhline(0.0, color="0.5", lw=0.5)
        ax.set_ylim(y0, y1)
        ax.set_ylabel(f"tau_{seg.effort_joint} (N m)")
        k = int(np.argmin(seg.width))
        ax.set_title(f"{seg.name}: {seg.mode}, narrowest band {seg.width[k]:.3g} N m at t = {seg.t[k]:.3g} s, "
                     f"smallest margin {np.min(seg.margin):.3g} N m", fontsize=8)  # fmt: skip
    axes[-1].set_xlabel("t (s) from the plan's start")
    axes[0].legend(fontsize=7, loc="upper left")
    lo, hi = plan.task.mu_range
    axes[0].figure.suptitle(f"{plan.task.name}: torque bands guaranteed for every mu in [{lo:g}, {hi:g}]"
                            f"{' (shared)' if plan.task.shared_mu else ' per contact'}; resolution {res:g} N m",
                            fontsize=9)  # fmt: skip
    return list(axes)


def plot_mode_timeline(plan, ax=None):
    """Which mode each phase keeps and which finger is torque-controlled, against time."""
    from qsplan.planner.planning.results import ContactSegmentPlan
    from qsplan.planner.plotting.style import new_axes

    if ax is None:
        _, axes = new_axes(1, 1, size=(9.0, 1.6))
        ax = axes[0][0]
    for ph in plan.phases:
        contact = isinstance(ph, ContactSegmentPlan)
        colour = _COLOURS[ph.effort_joint] if contact else "0.75"
        ax.barh(0, ph.t[-1] - ph.t[0], left=ph.t[0], color=colour, alpha=0.6, edgecolor="k", lw=0.5)
        label = f"{ph.mode}\n{ph.effort_joint} torque" if contact else "free\nregrasp"
        ax.text(0.5 * (ph.t[0] + ph.t[-1]), 0, label, ha="center", va="center", fontsize=7)
    ax.set_yticks([])
    ax.set_xlabel("t (s)")
    ax.set_title("mode timeline", fontsize=8)
    return ax


def plan_snapshots_figure(plan, per_phase=3):
    """Hand snapshots: ``per_phase`` along each in-contact segment and the open grasp of each regrasp."""
    from qsplan.planner.plotting.hands import plot_hand
    from qsplan.planner.planning.results import ContactSegmentPlan
    from qsplan.planner.plotting.style import new_axes

    shots = []
    for ph in plan.phases:
        if isinstance(ph, ContactSegmentPlan):
            for k in np.unique(np.round(np.linspace(0, ph.t.size - 1, per_phase)).astype(int)):
                shots.append((ph.t[k], plan.task.pose(ph.x[k]), ph.q[k], True))
        else:
            k = int(np.argmax(np.abs(ph.q - ph.q[0]).sum(axis=1)))
            shots.append((ph.t[k], plan.task.pose(ph.x), ph.q[k], False))
    ncols = min(len(shots), SNAPSHOT_COLUMNS)
    fig, axes = new_axes(ncols, -(-len(shots) // ncols), size=(2.4, 2.4))
    flat = axes.ravel()
    for ax, (t, pose, q, contact) in zip(flat, shots):
        plot_hand(plan.task.hand, pose, q, ax=ax, contacts=contact)
        ax.set_title(f"t = {t:.3g} s" + ("" if contact else " (open)"), fontsize=8)
    for ax in flat[len(shots):]:
        ax.set_visible(False)
    fig.suptitle(plan.task.name, fontsize=9)
    return fig


def plan_figures(plan) -> dict:
    """``{"plan_bands", "mode_timeline", "hand_snapshots"}`` -> matplotlib Figure."""
    return {"plan_bands": plot_plan_bands(plan)[0].figure, "mode_timeline": plot_mode_timeline(plan).figure,
            "hand_snapshots": plan_snapshots_figure(plan)}  # fmt: skip
