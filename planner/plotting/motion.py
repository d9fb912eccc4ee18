"""Plots of finite motions (Section 5.1): the rod's distances and mu-space (Figs. 7-8), pushing snapshots.

Compute lives in :mod:`qsplan.mechanics.motion` and :mod:`hands`; this module only draws.
Every ``plot_*`` function takes ``ax=None`` (a new figure is made) and returns the
axes; the ``*_figure`` functions compose panels and return a
``matplotlib.figure.Figure`` (no pyplot).  matplotlib is imported inside.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.style import FONT, legend_below

__all__ = [
    "STOP_WORDS",
    "contact_words",
    "stop_words",
    "plot_rod_distances",
    "plot_rod_mu_space",
    "plot_mode_timeline",
    "plot_push_snapshots",
    "rod_motion_figure",
    "push_motion_figure",
]

_SLIDE = "#c44e52"
_ROLL = "#4c72b0"

#: Why a simulation stopped, in words (:data:`qsplan.mechanics.motion.trajectory.STOP_KINDS`).
STOP_WORDS = {"ambiguous": "several modes possible (ambiguous)", "jam": "no mode possible (jam)",
              "no_persistent_mode": "no mode can continue", "zeno": "the switches accumulate (Zeno)",
              "limit": "a limit is reached", "max_switches": "too many switches"}  # fmt: skip


def stop_words(kind: str) -> str:
    """A stop kind in words (``"zeno"`` -> ``"the switches accumulate (Zeno)"``)."""
    return STOP_WORDS.get(kind, str(kind).replace("_", " "))


def contact_words(name: str) -> str:
    """A contact's name for people (``"floor@v2"`` -> ``"floor under corner 3"``)."""
    head, sep, vertex = str(name).partition("@v")
    return f"{head} under corner {int(vertex) + 1}" if sep and vertex.isdigit() else str(name)


def _axes(ax, size=(6.0, 4.0)):
    from qsplan.planner.plotting.style import axes_or_new

    return axes_or_new(ax, size=size)


def plot_rod_distances(motion, ax=None, closed_form=None):
    """``l1(t)`` and ``l2(t)`` of the rod (Fig. 7), the sliding support drawn thick.

    Parameters
    ----------
    motion : qsplan.mechanics.motion.trajectory.Motion
        Of a :class:`qsplan.hands.examples.rod.RodOnSupports`.
    ax : matplotlib Axes, optional
    closed_form : qsplan.hands.examples.rod.RodClosedForm, optional
        Its switch points are marked with dots, for comparison.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from qsplan.hands.examples.rod import rod_distances

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
    if closed_form is not None and len(closed_form.segments) > 1:  # on top of the curves, hollow: never hidden
        ends = closed_form.segments[:-1]
        ax.plot([c.t_end for c in ends] * 2, [c.l1_end for c in ends] + [c.l2_end for c in ends], ls="none",
                marker="o", ms=4.5, mfc="white", mec="k", mew=0.9, zorder=5, label="switch of the closed form")  # fmt: skip
    stop = motion.stopped
    n = len(motion.segments)
    title = f"rod on two supports: {n} stretch{'es' if n != 1 else ''} of one mode"
    if stop is not None:
        title += f"; stops at t = {stop.time:.3g} s: {stop_words(stop.kind)}"
        ax.axvline(stop.time, color="k", ls="--", lw=1.0, label="stop")
    ax.set_xlabel("t (s)", fontsize=FONT["label"])
    ax.set_ylabel("distance from the centre of mass (m)", fontsize=FONT["label"])
    ax.set_title(title, fontsize=FONT["label"])
    ax.set_ylim(bottom=0.0)
    legend_below(ax, ncol=2)
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
        Of a :class:`qsplan.hands.examples.rod.RodOnSupports`.
    max_lines : int
        Draw at most this many switch lines (the first ones; later ones crowd the corners).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Rectangle

    from qsplan.hands.examples.rod import rod_distances

    ax = _axes(ax, size=(5.0, 4.6))
    fr = motion.system.friction
    (m1R, m2R), (m1S, m2S) = fr.static, fr.kinetic
    top = 1.35 * max(m1R, m2R, 1e-3)
    if m1R > m1S and m2R > m2S:  # a rectangle with an area (equal static and kinetic friction: a point)
        ax.add_patch(Rectangle((m1S, m2S), m1R - m1S, m2R - m2S, fc="#f0e6c8", ec="k", lw=1.0, zorder=3,
                               label="friction rectangle (sliding to rolling values)"))  # fmt: skip
    # the two corners may coincide (equal static and kinetic friction): a big hollow circle around a small square
    ax.plot([m1S], [m2R], "o", ms=11, mfc="none", mec=_SLIDE, mew=2.0, zorder=6,
            label="SR (R2S1) runs at $(\\mu_{1S}, \\mu_{2R})$")  # fmt: skip
    ax.plot([m1R], [m2S], "s", color=_ROLL, ms=6, zorder=7, label="RS (R1S2) runs at $(\\mu_{1R}, \\mu_{2S})$")
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
    ax.set_xlabel("$\\mu_1$", fontsize=FONT["label"])
    ax.set_ylabel("$\\mu_2$", fontsize=FONT["label"])
    n = len(motion.segments[:-1])
    at = f"at each of the {n} switches" if n > 1 else ("at the switch" if n else "at the start and the end, no switch")
    ax.set_title(f"Fig. 8 along the motion: the partition line $l_1 \\mu_2 = l_2 \\mu_1$\n{at} "
                 "(faint: between switches)", fontsize=FONT["label"])  # fmt: skip
    legend_below(ax, ncol=1)
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
    end = max(motion.duration if motion.stopped is None else motion.stopped.time, 1e-12)
    for ev in motion.events:
        ax.plot(ev.time, 0.5, "kv", ms=5)
        if ev.kind in ("contact", "limit"):
            words = "a contact appears" if ev.kind == "contact" else "a limit is reached"
            right = ev.time > 0.8 * end
            ax.annotate(words, (ev.time, 0.62), xytext=(-4 if right else 4, 2), textcoords="offset points",
                        ha="right" if right else "left", fontsize=FONT["note"])  # fmt: skip
    if motion.stopped is not None:
        ax.annotate(f"stop: {stop_words(motion.stopped.kind)}", (motion.stopped.time, -0.7), xytext=(-4, 0),
                    textcoords="offset points", ha="right", fontsize=FONT["note"])  # fmt: skip
    ax.set_yticks([])
    ax.set_ylim(-1, 1)
    ax.set_xlim(0, end)
    names = ", ".join(contact_words(n) for n in motion.system.contact_names)
    ax.set_xlabel(f"t (s)\nmode: one letter per contact ({names}): R rolls, S slides, - not touching",
                  fontsize=FONT["label"])  # fmt: skip
    ax.set_title("contact mode of each stretch of the motion", fontsize=FONT["label"])
    return ax


def plot_push_snapshots(motion, ax=None, n_frames=6):
    """Snapshots of a pushed polygon (:class:`qsplan.hands.examples.pushing.PushedPolygon`), the floor and the tip's
    path.

    Frames are evenly spaced in time, plus every event; points in contact at each
    frame are marked.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib import colormaps

    from qsplan.hands.examples.pushing import polygon_world

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
    ax.plot([], [], "o", color="0.3", ms=4, label="a point in contact at that frame")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)", fontsize=FONT["label"])
    ax.set_ylabel("y (m)", fontsize=FONT["label"])
    legend_below(ax, ncol=3)
    ax.set_title("a box pushed across the floor by a finger (frames at events and evenly in time)", fontsize=FONT["label"])
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
