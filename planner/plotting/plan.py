"""Operator plots of a plan of any two-finger hand: bands along the whole plan, the mode timeline, hand snapshots.

Each function takes a :class:`qsplan.planner.Plan`, draws into ``ax`` (or a new figure) and returns
the axes or the figure; matplotlib is imported inside.  Only the plan's public fields are read
(``Plan.phases``, :class:`~qsplan.planner.plan.results.ContactSegmentPlan`; every other phase is
drawn as a free motion of the fingers), so plans with more phases or fields draw too.
:func:`plan_figures` gives them all, the plan card (:mod:`qsplan.planner.plotting.card`) included,
for ``qsplan demo`` / ``qsplan plan``.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.plan_panels import (
    draw_band,
    effort_words,
    joint_math,
    mark_narrowest,
    phase_label,
    plot_mode_timeline,
    snapshot_keys,
    torque_limits,
)
from qsplan.planner.plotting.style import FONT, joint_colour, legend_below, torque_text

__all__ = ["SNAPSHOT_COLUMNS", "plan_figures", "plan_snapshots_figure", "plot_mode_timeline", "plot_plan_bands"]

#: Hand snapshots per row, at most.
SNAPSHOT_COLUMNS = 6


def plot_plan_bands(plan, axes=None, sharey=False):
    """The guaranteed band and the command of the torque-controlled joint along each in-contact segment.

    One panel per segment (N m against s from the plan's start), each scaled to its command, lower
    edge and margin (bands differ by orders of magnitude between segments), or one scale for all
    with ``sharey``.  Upper edges solid, lower edges dashed; an upper edge above the panel or
    unbounded is marked with up-triangles; the narrowest point is marked with its width.

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
    if axes is None:
        _, grid = new_axes(1, len(segs), size=(8.0, 2.1))
        axes = [row[0] for row in grid]
    res = plan.task.torque_resolution
    shared = torque_limits(segs, res) if sharey else None
    hand = plan.task.hand
    for i, (ax, seg) in enumerate(zip(axes, segs)):
        ylim = shared or torque_limits([seg], res)
        word, unit = effort_words(hand, seg.effort_joint)
        draw_band(ax, seg.t, seg.lower, seg.upper, seg.command, joint_colour(hand, seg.effort_joint), ylim, label=i == 0)
        mark_narrowest(ax, seg, ylim, label=i == 0, unit=unit)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_ylim(*ylim)
        ax.set_xlim(seg.t[0], seg.t[-1])
        symbol = "\\tau" if word == "torque" else "f"
        ax.set_ylabel(f"${symbol}_{{{joint_math(seg.effort_joint)}}}$ ({unit})", fontsize=FONT["label"])
        mode, control = phase_label(seg, hand)
        ax.set_title(f"{seg.name.split(':')[0]}: {mode}, {control}-controlled; smallest margin "
                     f"{torque_text(np.min(seg.margin), unit)}", fontsize=FONT["note"] + 0.5, loc="left")  # fmt: skip
    axes[-1].set_xlabel("t (s) from the plan's start", fontsize=FONT["label"])
    legend_below(axes[-1], handles=axes[0].get_legend_handles_labels()[0], ncol=3)
    lo, hi = plan.task.mu_range
    model = "one shared coefficient" if plan.task.shared_mu else "each contact's coefficient"
    axes[0].get_figure(root=False).suptitle(f"{plan.task.name}: torque bands guaranteed for {model} in [{lo:g}, "
                                            f"{hi:g}];\ncontroller resolution {res:g} N m", fontsize=FONT["title"])  # fmt: skip
    return list(axes)


def plan_snapshots_figure(plan, per_phase=3, columns=SNAPSHOT_COLUMNS):
    """Hand snapshots: ``per_phase`` along each in-contact segment and the open grasp of each regrasp.

    Rows are filled evenly (no empty panel but the last row's), every panel at one scale (a scale
    bar in the first), the torque-controlled finger marked, the marks explained in a legend.
    """
    from matplotlib.figure import Figure

    from qsplan.planner.plotting.hands import hand_limits, plot_hand, snapshot_legend_handles
    from qsplan.planner.plotting.style import figure_legend

    shots = snapshot_keys(plan, per_phase)
    rows = -(-len(shots) // columns)
    cols = -(-len(shots) // rows)
    lim = hand_limits(plan.task.hand, [(pose, q) for _, pose, q, _, _ in shots])
    w = 2.0
    h = w * (lim[1][1] - lim[1][0]) / (lim[0][1] - lim[0][0]) + 0.35
    fig = Figure(figsize=(w * cols, h * rows + 0.9), layout="constrained")
    flat = fig.subplots(rows, cols, squeeze=False).ravel()
    for i, (ax, (t, pose, q, effort, opened)) in enumerate(zip(flat, shots)):
        plot_hand(plan.task.hand, pose, q, ax=ax, contacts=not opened, effort_joint=effort, limits=lim,
                  scale_bar=i == 0)  # fmt: skip
        ax.set_title(f"t = {t:.3g} s" + (" (fingers open)" if opened else ""), fontsize=FONT["note"])
    for ax in flat[len(shots):]:
        ax.set_visible(False)
    figure_legend(fig, snapshot_legend_handles(hand=plan.task.hand), ncol=3)
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
