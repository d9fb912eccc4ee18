"""Plots for operators: torque bands along a segment (Figs. 10-13) and the speed/accuracy chart of bands.

Compute lives in :mod:`qsplan.planner.torque`; this module only draws.  The panels are drawn by
:mod:`qsplan.planner.plotting.band_panels` (upper edges solid, lower edges dashed, infinite and
off-plot sides marked apart); this module composes the paper's figures: Fig. 10 (frictionless),
Fig. 11 (the highest friction) and Fig. 12 (the competing modes), each with a zoom on the lower edge
(the torque the mode needs) when the full range would hide it, and Fig. 13 (the guaranteed band).

Every ``plot_*`` function takes ``ax=None`` (a new figure is made) and returns the axes;
``*_figure`` functions return a ``matplotlib.figure.Figure`` (no pyplot).
matplotlib is imported inside the functions.
"""

from __future__ import annotations

import textwrap

import numpy as np

from qsplan.planner.plotting.band_panels import (
    OZ_IN_PER_N_M,
    auto_display_limit,
    plot_band_sweep,
    plot_guaranteed,
    secondary_oz_in,
)
from qsplan.planner.plotting.hands import hand_strip_figure, plot_hand
from qsplan.planner.plotting.style import COMPETITOR, FONT, PALETTE, axes_or_new, legend_below

__all__ = [
    "OZ_IN_PER_N_M",
    "auto_display_limit",
    "competitor_note",
    "hand_strip_figure",
    "plot_band_sweep",
    "plot_guaranteed",
    "plot_hand",
    "plot_speed_accuracy",
    "segment_band_figures",
]

#: A zoom panel on the lower edge is added when the lower edge stays under this fraction of the display limit.
ZOOM_FRACTION = 0.15


def _contact_words(samples) -> dict:
    """Contact name -> words (``"palm:0"`` -> ``"the left palm vertex"``), from the first sample's geometry."""
    from qsplan.mechanics.muspace.graphical import contact_points

    scene = samples.scenes[0]
    names = list(scene.contact_names)
    palm = [i for i, n in enumerate(names) if n.startswith("palm")]
    words = {n: n for n in names}
    if len(palm) == 2:
        x = contact_points(scene)[palm, 0]
        left, right = (palm[0], palm[1]) if x[0] <= x[1] else (palm[1], palm[0])
        words[names[left]], words[names[right]] = "the left palm vertex", "the right palm vertex"
    for n in names:
        if n.startswith(("left", "right")):
            words[n] = f"the {n.split(':')[0]} finger's contact"
    return words


def competitor_note(bands) -> str:
    """Which competitor Fig. 12 shows, in words, and whether the paper's R2S (the left palm vertex rolling, the
    right one lifting) competes at all on this segment."""
    from qsplan.mechanics.modes.contact_mode import ContactMode

    S = bands.samples
    words = _contact_words(S)
    names = list(S.scenes[0].contact_names)
    verbs = {"R": "rolls", "S": "slides", "B": "lifts off"}
    hi = bands.guaranteed.mu_range[1]
    lines = []
    for c, sw in bands.competitors_at_high_mu.items():
        if not sw.feasible.any():
            continue
        what = ", ".join(f"{words[n]} {verbs[ch]}" for n, ch in zip(names, c) if ch != "S")
        spans = ", ".join(f"[{a:.3g}, {b:.3g}] s" for a, b in sw.feasible_spans())
        lines.append(f"{ContactMode(c).kind} {c}: {what}; feasible at mu = {hi:g} for t in {spans}")
    paper = [c for c in bands.competitors_at_high_mu if ContactMode(c).kind == "R2S"
             and all((ch == "R") == (words[n] == "the left palm vertex") and (ch == "B") == (words[n] == "the right palm vertex")
                     for n, ch in zip(names, c) if n.startswith("palm"))]  # fmt: skip
    for c in paper:
        if not bands.competitors_at_high_mu[c].feasible.any():
            lines.append(f"the paper's R2S ({c}: the left palm vertex rolls, the workpiece turns counter-clockwise) "
                         f"is nowhere feasible here: our hand's dimensions are not the paper's (it gives none)")  # fmt: skip
    return "\n".join(lines) or f"no competing mode is feasible at mu = {hi:g}"


def _with_zoom(size=(8.0, 6.4)):
    """A figure with a full panel over a zoom panel sharing the time axis."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    top, zoom = fig.subplots(2, 1, sharex=True, height_ratios=[2.2, 1.0])
    top.tick_params(labelbottom=False)
    return fig, top, zoom


def _zoom_panel(ax, sweeps, styles, top_ax):
    """The band edges of ``sweeps`` up to three times the first one's largest lower edge (the torque the mode needs)."""
    first = sweeps[0]
    lows = first.lower[first.feasible & np.isfinite(first.lower)]
    top = 3.0 * float(np.max(np.abs(lows))) if lows.size and np.max(np.abs(lows)) > 0 else 0.1
    for s, kw in zip(sweeps, styles):
        plot_band_sweep(s, ax, top, oz_in=False, legend=False, notes=False, markers=False, **kw)
    ax.set_ylim(min(0.0, float(np.min(lows)) if lows.size else 0.0) - 0.05 * top, top)
    ax.set_title("zoom on the lower edge: the torque the mode needs", fontsize=FONT["label"], loc="left")
    top_ax.set_xlabel("")
    legend_below(ax, handles=top_ax.get_legend_handles_labels()[0], ncol=2)
    secondary_oz_in(ax)
    return ax


def _needs_zoom(limit, *sweeps) -> bool:
    lows = np.concatenate([s.lower[s.feasible & np.isfinite(s.lower)] for s in sweeps])
    return bool(lows.size) and float(np.max(np.abs(lows))) < ZOOM_FRACTION * limit and float(np.max(np.abs(lows))) > 0


def segment_band_figures(bands, display_limit=None, strip=5) -> dict:
    """Figs. 10-13 and the snapshot strip for one segment.

    Parameters
    ----------
    bands : qsplan.planner.torque.sweep.SegmentBands
    display_limit : float, optional
        N m for every band figure; default per figure (:func:`auto_display_limit`).
    strip : int
        Snapshots in the strip.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``fig10_frictionless``, ``fig11_mu_high``, ``fig12_competitors``, ``fig13_guaranteed``, ``hand_strip``.
    """
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.plotting.style import new_axes

    out = {}
    hi = bands.guaranteed.mu_range[1]
    lim = display_limit
    kind = ContactMode(bands.frictionless.mode).kind
    for key, sweep, title in (("fig10_frictionless", bands.frictionless, f"Fig. 10: the {kind} band without friction (mu = 0)"),
                              ("fig11_mu_high", bands.at_high_mu, f"Fig. 11: the {kind} band at mu = {hi:g}")):  # fmt: skip
        limit = lim or auto_display_limit(sweep)
        if _needs_zoom(limit, sweep):
            fig, ax, zoom = _with_zoom()
            plot_band_sweep(sweep, ax, limit, title=title, name=kind, legend=False)
            _zoom_panel(zoom, [sweep], [{"name": kind}], ax)
        else:
            fig, axes = new_axes(1, 1, size=(8.0, 4.8))
            plot_band_sweep(sweep, axes[0, 0], limit, title=title, name=kind)
        out[key] = fig
    live = {c: s for c, s in bands.competitors_at_high_mu.items() if s.feasible.any()}
    lim12 = lim or auto_display_limit(bands.at_high_mu, *live.values())
    fig, ax, zoom = _with_zoom(size=(8.0, 7.0))
    grey = {"color": "0.45", "fill": None, "name": f"{kind} (Fig. 11)", "thin": True}
    plot_band_sweep(bands.at_high_mu, ax, lim12, oz_in=False, legend=False, **grey)
    styles = [grey]
    for c, s in live.items():
        style = {"color": COMPETITOR, "fill": "#f4a582", "name": f"{ContactMode(c).kind} {c}"}
        plot_band_sweep(s, ax, lim12, oz_in=False, legend=False, **style)
        styles.append(style)
    names = ", ".join(f"{ContactMode(c).kind} ({c})" for c in live) or "none feasible"
    note = "\n".join(textwrap.fill(line, 100) for line in competitor_note(bands).split("\n"))
    ax.set_title(f"Fig. 12: the competing modes at mu = {hi:g}: {names}\n{note}", fontsize=FONT["label"])
    secondary_oz_in(ax)
    _zoom_panel(zoom, [bands.at_high_mu, *live.values()], styles, ax)
    out["fig12_competitors"] = fig
    fig, axes = new_axes(1, 1, size=(8.0, 5.4))
    plot_guaranteed(bands, axes[0, 0], lim)
    axes[0, 0].set_title("Fig. 13: " + axes[0, 0].get_title(), fontsize=FONT["title"] - 0.5)
    out["fig13_guaranteed"] = fig
    out["hand_strip"] = hand_strip_figure(bands.samples, strip)
    return out


def plot_speed_accuracy(rows, ax=None, title=None):
    """Band error against computing time for exact and sampled guaranteed bands.

    Sampled methods are points (error on a log axis, labelled with their sample count); exact methods
    have no error, so they are not drawn as if they had one: each is a vertical line at its time,
    labelled in words.

    Parameters
    ----------
    rows : sequence of dict
        Each with ``"method"`` (``"exact box"``, ``"sampled box"``, ``"exact shared"``, ``"sampled shared"``),
        ``"samples"`` (int or None), ``"time"`` (s) and ``"error"`` (N m: the largest amount by which the band
        is wider than the exact one along the segment; 0 for exact methods).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    ax = axes_or_new(ax, size=(6.8, 4.6))
    colours = {"box": PALETTE[0], "shared": PALETTE[1]}
    words = {"box": "each contact's mu", "shared": "one shared mu"}
    for kind in ("box", "shared"):
        samp = sorted((r for r in rows if r["method"] == f"sampled {kind}" and r["error"] > 0), key=lambda r: r["samples"])
        if samp:
            x = [r["time"] for r in samp]
            y = [r["error"] for r in samp]
            ax.plot(x, y, "o-", color=colours[kind], ms=5,
                    label=f"paper's sampling, {words[kind]} ({samp[0]['samples']}..{samp[-1]['samples']} samples)")  # fmt: skip
            for k, (r, xx, yy) in enumerate(zip(samp, x, y)):
                ax.annotate(str(r["samples"]), (xx, yy), xytext=(4, 4 if k % 2 else -10), textcoords="offset points",
                            fontsize=FONT["note"], color=colours[kind])  # fmt: skip
        for r in rows:
            if r["method"] == f"exact {kind}":
                ax.axvline(r["time"], color=colours[kind], ls="--", lw=1.4,
                           label=f"exact, {words[kind]}: {r['time']:.2g} s, no error")  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain = FuncFormatter(lambda v, _: f"{v:g}")
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(plain)
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("time for the whole segment (s)", fontsize=FONT["label"])
    ax.set_ylabel("band error: largest excess width (N m)", fontsize=FONT["label"])
    ax.set_title(title or "guaranteed torque band: speed against accuracy", fontsize=FONT["title"])
    ax.grid(True, which="major", lw=0.3, alpha=0.6)
    legend_below(ax, ncol=1)
    return ax
