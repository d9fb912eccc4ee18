"""Plots of finite motions (Section 5.1): the rod's distances and mu-space (Figs. 7-8), pushing snapshots.

Compute lives in :mod:`qsplan.mechanics.motion` and :mod:`hands`; this module only draws.
Every ``plot_*`` function takes ``ax=None`` (a new figure is made) and returns the
axes; the ``*_figure`` functions compose panels and return a
``matplotlib.figure.Figure`` (no pyplot).  matplotlib is imported inside.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "plot_rod_distances",
    "plot_rod_mu_space",
    "plot_mode_timeline",
    "plot_push_snapshots",
    "rod_motion_figure",
    "push_motion_figure",
]

_SLIDE = "#c44e52"
_ROLL = "#4c72b0"


def _axes(ax, size=(6.0, 4.0)):
    if ax is not None:
        return ax
    from qsplan.planner.plotting.style import new_axes

    _, axes = new_axes(1, 1, size=size)
    return axes[0, 0]


def plot_rod_distances(motion, ax=None, closed_form=None):
    """``l1(t)`` and ``l2(t)`` of the rod (Fig. 7), the sliding support drawn thick.

    Parameters
    ----------
    motion : qsplan.mechanics.motion.trajectory.Motion
        Of a :class:`qsplan.hands.rod.RodOnSupports`.
    ax : matplotlib Axes, optional
    closed_form : qsplan.hands.rod.RodClosedForm, optional
        Its switch points are marked with dots, for comparison.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from qsplan.hands.rod import rod_distances

    ax = _axes(ax)
    styles = ({"color": _ROLL, "label": "$l_1$ (support 1)"}, {"color": "#55a868", "label": "$l_2$ (support 2)"})
    labelled = set()
    for seg in motion.segments:
        L = rod_distances(seg.states)
        for i in (0, 1):
            sliding = seg.label[i] == "S"
            kw = dict(color=styles[i]["color"], lw=3.2 if sliding else 1.2, solid_capstyle="butt")
            key = (i, sliding)
            if key not in labelled:
                kw["label"] = styles[i]["label"] + (", sliding" if sliding else ", rolling")
                labelled.add(key)
            ax.plot(seg.times, L[:, i], **kw)
    for t in motion.switch_times[:60]:
        ax.axvline(t, color="0.75", lw=0.5, zorder=0)
    if closed_form is not None:
        ends = closed_form.segments[:-1]
        ax.plot([c.t_end for c in ends] * 2, [c.l1_end for c in ends] + [c.l2_end for c in ends], "k.", ms=3,
                label="closed-form switches")  # fmt: skip
    stop = motion.stopped
    n = len(motion.segments)
    title = f"rod on two supports: {n} segment{'s' if n != 1 else ''}" + (f", stop: {stop.kind}" if stop else "")
    if stop is not None:
        ax.axvline(stop.time, color="k", ls="--", lw=1.0, label=f"stop: {stop.kind}")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("distance from the centre of mass (m)")
    ax.set_title(title, fontsize=10)
    ax.set_ylim(bottom=0.0)
    ax.legend(fontsize=8, loc="upper right")
    return ax


def plot_rod_mu_space(motion, ax=None, max_lines=20):
    """Fig. 8 along the motion: friction rectangle and the partition line ``l1 mu2 = l2 mu1`` at each switch.

    The line through the origin with slope ``l2 / l1`` separates R2S1 (``"SR"``, above)
    from R1S2 (``"RS"``, below).  SR runs with friction at the rectangle's upper-left
    corner ``(mu_1S, mu_2R)``, RS at its lower-right corner ``(mu_1R, mu_2S)``; each switch
    happens when the line reaches the active corner.

    Parameters
    ----------
    motion : qsplan.mechanics.motion.trajectory.Motion
        Of a :class:`qsplan.hands.rod.RodOnSupports`.
    max_lines : int
        Draw at most this many switch lines (the first ones; later ones crowd the corners).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Rectangle

    from qsplan.hands.rod import rod_distances

    ax = _axes(ax, size=(5.0, 4.6))
    fr = motion.system.friction
    (m1R, m2R), (m1S, m2S) = fr.static, fr.kinetic
    top = 1.35 * max(m1R, m2R, 1e-3)
    ax.add_patch(Rectangle((m1S, m2S), m1R - m1S, m2R - m2S, fc="#f0e6c8", ec="k", lw=1.0, label="friction rectangle"))
    ax.plot([m1S], [m2R], "o", color=_SLIDE, ms=7, label="SR: $(\\mu_{1S}, \\mu_{2R})$")
    ax.plot([m1R], [m2S], "s", color=_ROLL, ms=7, label="RS: $(\\mu_{1R}, \\mu_{2S})$")
    mu = np.linspace(0.0, top, 2)
    if motion.segments:
        l1, l2 = rod_distances(motion.segments[0].states[:1])[0]
        ax.plot(mu, mu * l2 / l1, "k--", lw=1.0, label="line at t = 0")
    ends = motion.segments[:-1][:max_lines]
    for seg in motion.segments[:max_lines]:  # the sweep within each segment, faint
        for l1, l2 in rod_distances(seg.states[np.linspace(0, len(seg.states) - 1, 4).astype(int)[1:-1]]):
            ax.plot(mu, mu * l2 / l1, color=_SLIDE if seg.label == "SR" else _ROLL, lw=0.4, alpha=0.35)
    for k, seg in enumerate(ends):
        l1, l2 = rod_distances(seg.states[-1:])[0]
        into_rs = seg.label == "SR"
        ax.plot(mu, mu * l2 / l1, color=_SLIDE if into_rs else _ROLL, lw=1.4,
                label=None if k > 1 else ("switch SR -> RS (line at upper-left corner)" if into_rs
                                          else "switch RS -> SR (line at lower-right corner)"))  # fmt: skip
    if motion.segments:
        last = motion.segments[-1]
        l1, l2 = rod_distances(last.states[-1:])[0]
        ax.plot(mu, mu * l2 / l1, "k-.", lw=1.0, label=f"line at the end, t = {last.t_end:.4g} s")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_aspect("equal")
    ax.set_xlabel("$\\mu_1$")
    ax.set_ylabel("$\\mu_2$")
    ax.set_title(f"partition line $l_1 \\mu_2 = l_2 \\mu_1$, {len(motion.segments[:-1])} switches", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    return ax


def plot_mode_timeline(motion, ax=None):
    """One bar per segment, labelled with its mode (one letter per potential contact, ``-`` apart).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from qsplan.planner.plotting.style import PALETTE

    ax = _axes(ax, size=(6.0, 1.6))
    colours = {}
    for seg in motion.segments:
        c = colours.setdefault(seg.label, PALETTE[len(colours) % len(PALETTE)])
        ax.barh(0, seg.duration, left=seg.t_start, color=c, edgecolor="k", lw=0.5)
        if seg.duration > 0.06 * max(motion.duration, 1e-12):
            ax.text(seg.t_start + seg.duration / 2, 0, seg.label, ha="center", va="center", fontsize=9, family="monospace")
    for ev in motion.events:
        ax.plot(ev.time, 0.5, "kv", ms=5)
        if ev.kind in ("contact", "limit"):
            ax.text(ev.time, 0.62, ev.kind, ha="center", fontsize=7)
    if motion.stopped is not None:
        ax.text(motion.stopped.time, -0.7, f"stop: {motion.stopped.kind}", ha="center", fontsize=8)
    ax.set_yticks([])
    ax.set_ylim(-1, 1)
    ax.set_xlim(0, max(motion.duration if motion.stopped is None else motion.stopped.time, 1e-12))
    ax.set_xlabel("t (s)")
    ax.set_title("contact mode: " + ", ".join(motion.system.contact_names), fontsize=9)
    return ax


def plot_push_snapshots(motion, ax=None, n_frames=6):
    """Snapshots of a pushed polygon (:class:`qsplan.hands.pushing.PushedPolygon`), the floor and the tip's path.

    Frames are evenly spaced in time, plus every event; points in contact at each
    frame are marked.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib import colormaps

    from qsplan.hands.pushing import polygon_world

    ax = _axes(ax, size=(7.0, 3.6))
    system = motion.system
    T, X = motion.times, motion.states
    if T.size == 0:
        return ax
    picks = set(np.searchsorted(T, np.linspace(T[0], T[-1], n_frames)).clip(0, T.size - 1).tolist())
    picks |= {int(np.searchsorted(T, ev.time)) for ev in motion.events if ev.time <= T[-1]}
    picks = sorted(min(i, T.size - 1) for i in picks)
    cmap = colormaps["viridis"]
    for i in picks:
        P = polygon_world(system.vertices, X[i])
        c = cmap(T[i] / max(T[-1], 1e-12))
        ax.fill(P[:, 0], P[:, 1], fc=c, alpha=0.12, ec=c, lw=1.2)
        gaps = system.gaps(X[i])
        touching = np.flatnonzero(gaps <= 1e-6)
        for k in touching:
            p = system.tip(X[i]) if k == 0 else P[system.floor_vertices[k - 1]]
            ax.plot(*p, "o", color=c, ms=4)
    tips = np.array([system.tip(x) for x in X])
    ax.plot(tips[:, 0], tips[:, 1], "k-", lw=1.0, label="finger tip")
    lo, hi = ax.get_xlim()
    ax.fill_between([lo - 0.05, hi + 0.05], [-0.03, -0.03], [0, 0], color="0.6", label="floor")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title("polygon pushed across the floor (frames at events and evenly in time)", fontsize=10)
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    ax.figure.colorbar(ScalarMappable(Normalize(0, T[-1]), cmap), ax=ax, label="t (s)", shrink=0.8)
    return ax


def rod_motion_figure(motion, closed_form=None):
    """Figure with :func:`plot_rod_distances` and :func:`plot_rod_mu_space` side by side."""
    from qsplan.planner.plotting.style import new_axes

    fig, axes = new_axes(2, 1, size=(5.6, 4.6))
    plot_rod_distances(motion, ax=axes[0, 0], closed_form=closed_form)
    plot_rod_mu_space(motion, ax=axes[0, 1])
    return fig


def push_motion_figure(motion):
    """Figure with :func:`plot_push_snapshots` above :func:`plot_mode_timeline`."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 5.6), layout="constrained")
    top, bottom = fig.subplots(2, 1, height_ratios=[3.2, 1.0])
    plot_push_snapshots(motion, ax=top)
    plot_mode_timeline(motion, ax=bottom)
    return fig
