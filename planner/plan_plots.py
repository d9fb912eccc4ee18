"""Operator plots of a two-finger plan: bands along the whole plan, the mode timeline, hand snapshots.

Each function takes a :class:`planner.plan.Plan`, draws into ``ax`` (or a new
figure) and returns the axes or the figure; matplotlib is imported inside.
:func:`plan_figures` gives all three for ``qsplan demo`` / ``qsplan plan``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_plan_bands", "plot_mode_timeline", "plan_snapshots_figure", "plan_figures"]

_COLOURS = {"left": "#08519c", "right": "#a63603"}


def _finite_top(plan):
    tops = [np.max(np.abs(v[np.isfinite(v)])) for s in plan.segments for v in (s.lower, s.upper, s.command)
            if np.isfinite(v).any()]  # fmt: skip
    return 1.2 * max(tops + [plan.task.torque_resolution])


def plot_plan_bands(plan, ax=None, display_limit=None):
    """The guaranteed band and the command of the effort-controlled finger along the whole plan (N m vs s).

    Regrasps are shaded; infinite band sides are drawn at ``display_limit`` (default: 1.2 x the largest finite value).
    """
    from .plan import ContactSegmentPlan
    from .plots import new_axes

    if ax is None:
        _, axes = new_axes(1, 1, size=(9.0, 3.6))
        ax = axes[0][0]
    L = display_limit or _finite_top(plan)
    for ph in plan.phases:
        if not isinstance(ph, ContactSegmentPlan):
            ax.axvspan(ph.t[0], ph.t[-1], color="0.9", lw=0)
            continue
        c = _COLOURS[ph.effort_joint]
        lo, hi = np.clip(ph.lower, -L, L), np.clip(ph.upper, -L, L)
        ax.fill_between(ph.t, lo, hi, color=c, alpha=0.18, lw=0)
        ax.plot(ph.t, lo, "--", color=c, lw=1.0)
        ax.plot(ph.t, hi, "-", color=c, lw=1.0)
        ax.plot(ph.t, np.clip(ph.command, -L, L), ":", color="k", lw=1.2)
        ax.text(0.5 * (ph.t[0] + ph.t[-1]), 0.92 * L, f"{ph.mode}, tau_{ph.effort_joint}", ha="center", fontsize=7)
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_ylim(-L, L)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("torque (N m)")
    name, t, w = plan.narrowest()
    lo, hi = plan.task.mu_range
    ax.set_title(f"{plan.task.name}: guaranteed bands (mu in [{lo:g}, {hi:g}]) and commands (dotted); "
                 f"narrowest {w:.3g} N m at t = {t:.3g} s; grey: regrasp", fontsize=8)  # fmt: skip
    return ax


def plot_mode_timeline(plan, ax=None):
    """Which mode each phase keeps and which finger is torque-controlled, against time."""
    from .plan import ContactSegmentPlan
    from .plots import new_axes

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
    from .band_plots import plot_hand
    from .plan import ContactSegmentPlan
    from .plots import new_axes

    shots = []
    for ph in plan.phases:
        if isinstance(ph, ContactSegmentPlan):
            for k in np.unique(np.round(np.linspace(0, ph.t.size - 1, per_phase)).astype(int)):
                shots.append((ph.t[k], plan.task.pose(ph.x[k]), ph.q[k], True))
        else:
            k = int(np.argmax(np.abs(ph.q - ph.q[0]).sum(axis=1)))
            shots.append((ph.t[k], plan.task.pose(ph.x), ph.q[k], False))
    fig, axes = new_axes(len(shots), 1, size=(2.2, 2.2))
    for ax, (t, pose, q, contact) in zip(axes[0], shots):
        plot_hand(plan.task.hand, pose, q, ax=ax, contacts=contact)
        ax.set_title(f"t = {t:.3g} s" + ("" if contact else " (open)"), fontsize=7)
    fig.suptitle(plan.task.name, fontsize=9)
    return fig


def plan_figures(plan) -> dict:
    """``{"plan_bands", "mode_timeline", "hand_snapshots"}`` -> matplotlib Figure."""
    return {"plan_bands": plot_plan_bands(plan).figure, "mode_timeline": plot_mode_timeline(plan).figure,
            "hand_snapshots": plan_snapshots_figure(plan)}  # fmt: skip
