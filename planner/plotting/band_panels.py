"""Torque bands along a segment drawn the paper's way (Figs. 10-13): one band, and the guaranteed band.

Compute lives in :mod:`qsplan.planner.torque`; this module only draws.  As in the paper, upper
edges are solid and lower edges dashed.  A side beyond the display limit is drawn along the limit:
filled triangles where it is infinite (unbounded), hollow ones where it is finite but off the plot,
and each run of infinite samples is bracketed and labelled over the very times it describes, as the
paper truncated Fig. 10 "at 200 oz.-in.".  Efforts are in N m; a right-hand axis repeats them in the
paper's oz in.  Legends go under the axes (:func:`qsplan.planner.plotting.style.legend_below`).
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.style import (
    BAND_FILL,
    COMMAND,
    COMPETITOR,
    EDGE,
    FONT,
    LOWER,
    NARROWEST,
    NO_BAND,
    SAMPLED,
    UPPER,
    axes_or_new,
    legend_below,
    torque_text,
)

__all__ = ["OZ_IN_PER_N_M", "auto_display_limit", "nice_ceiling", "plot_band_sweep", "plot_guaranteed",
           "secondary_oz_in"]  # fmt: skip

#: 1 N m in ounce-force inches (the paper's torque unit): 1 / (0.0283495 kg * 9.80665 m/s^2 * 0.0254 m).
OZ_IN_PER_N_M = 141.61193227806

#: A competitor is drawn inside the desired mode's band only where it reaches more than this
#: (relative) past the band's edge; touching the edge (a shared boundary) cuts nothing.
_DRAW_RTOL = 1e-6


def nice_ceiling(x: float) -> float:
    """Smallest of 1, 1.5, 2, 3, 4, 5, 6, 8 times a power of ten at or above ``x`` (> 0)."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    e = 10.0 ** np.floor(np.log10(x))
    for m in (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0):
        if m * e >= x * (1 - 1e-12):
            return float(m * e)
    return float(10 * e)


def auto_display_limit(*sweeps) -> float:
    """A display limit (N m) for bands: twice the upper quartile of their finite edges, rounded up."""
    vals = np.concatenate([np.abs(np.r_[s.lower, s.upper]) for s in sweeps]) if sweeps else np.array([])
    vals = vals[np.isfinite(vals)]
    if not vals.size:
        return 1.0
    return nice_ceiling(2.0 * float(np.percentile(vals, 75)))


def secondary_oz_in(ax):
    """A right-hand axis in oz in, the paper's unit."""
    sec = ax.secondary_yaxis("right", functions=(lambda y: y * OZ_IN_PER_N_M, lambda y: y / OZ_IN_PER_N_M))
    sec.set_ylabel("torque (oz in, the paper's unit)", fontsize=FONT["label"] - 1)
    sec.tick_params(labelsize=FONT["tick"] - 1)
    return sec


def _shade_no_band(ax, t, feasible, label):
    dt = (t[-1] - t[0]) / max(len(t) - 1, 1)
    k, labelled = 0, False
    while k < len(t):
        if feasible[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(t) and not feasible[j + 1]:
            j += 1
        ax.axvspan(t[k] - dt / 2, t[j] + dt / 2, color=NO_BAND, zorder=0, label=None if labelled else label)
        labelled = True
        k = j + 1


def _runs(t, mask):
    out, k = [], 0
    while k < len(t):
        if not mask[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(t) and mask[j + 1]:
            j += 1
        out.append((k, j))
        k = j + 1
    return out


def plot_band_sweep(sweep, ax=None, display_limit=None, color=EDGE, fill=BAND_FILL, name=None, title=None, oz_in=True,
                    thin=False, legend=True, bottom=None, notes=True, markers=True):  # fmt: skip
    """One band along a segment, the paper's way (Figs. 10-12).

    Parameters
    ----------
    sweep : qsplan.planner.torque.pointwise.BandSweep
    ax : matplotlib Axes, optional
    display_limit : float, optional
        N m; sides beyond it are drawn along it (filled triangles: infinite; hollow: finite, off the plot).
        Default :func:`auto_display_limit`.
    color, fill : colours of the edges and of the band (``fill=None``: no fill).
    name : str, optional
        Legend prefix (default the sweep's label).
    title : str, optional
    oz_in : bool
        Add the right-hand axis in oz in.
    thin : bool
        Thin lines (for an overlay).
    legend : bool
        Put the legend under the axes.
    bottom : float, optional
        Lower y-limit (N m); default just under the lowest edge or zero.
    notes : bool
        Bracket and label the runs of infinite samples.
    markers : bool
        Mark the sides beyond the display limit (a zoomed panel leaves that to the full one).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    had, prev = bool(ax.lines), ax.get_ylim()  # overlaying on another band: keep its range too
    limit = auto_display_limit(sweep) if display_limit is None else float(display_limit)
    t, feas = sweep.t, sweep.feasible
    name = name or sweep.label
    lo = np.where(feas, np.clip(sweep.lower, -limit, limit), np.nan)
    up = np.where(feas, np.clip(sweep.upper, -limit, limit), np.nan)
    if fill:
        ax.fill_between(t, lo, up, where=feas, color=fill, alpha=0.45, lw=0, label=f"{name}: band")
    lw = 1.1 if thin else 2.4
    ax.plot(t, np.where(np.abs(sweep.upper) > limit, np.nan, up), color=color, lw=lw, **UPPER, label=f"{name}: upper edge")
    ax.plot(t, np.where(np.abs(sweep.lower) > limit, np.nan, lo), color=color, lw=lw, **LOWER, label=f"{name}: lower edge")
    step = max(1, len(t) // 16)
    sides = ((sweep.upper, 1.0), (sweep.lower, -1.0), (sweep.upper, -1.0), (sweep.lower, 1.0)) if markers else ()
    for values, sign in sides:
        v = np.asarray(values, float)
        for infinite in (True, False):
            hit = feas & (np.isinf(v) if infinite else (np.isfinite(v) & (np.abs(v) > limit))) & (np.sign(v) == sign)
            idx = np.flatnonzero(hit)[::step]
            if not idx.size:
                continue
            what = ("unbounded (infinite)" if infinite else "beyond the plotted range (finite)")
            y = sign * limit * (0.96 if thin else 1.0)  # an overlay's marks just inside, not hidden under the band's
            ax.plot(t[idx], np.full(idx.size, y), ls="none", marker="^" if sign > 0 else "v",
                    ms=5 if thin else 6.5, color=color, mfc=color if infinite else "white", mew=1.2, clip_on=False,
                    label=f"{name}: {'upper' if values is sweep.upper else 'lower'} edge {what}")  # fmt: skip
    if notes and not thin:  # say where a side is infinite, over the times it describes
        for a, b in _runs(t, feas & np.isposinf(sweep.upper)):
            y = limit * 1.0
            ax.annotate("", xy=(t[a], y), xytext=(t[b], y), xycoords="data",
                        arrowprops={"arrowstyle": "|-|,widthA=0.3,widthB=0.3", "color": color, "lw": 0.9,
                                    "shrinkA": 0, "shrinkB": 0})  # fmt: skip
            ax.annotate(f"unbounded for t in [{t[a]:.3g}, {t[b]:.3g}] s", (0.5 * (t[a] + t[b]), y), xytext=(0, 5),
                        textcoords="offset points", ha="center", va="bottom", fontsize=FONT["note"], color=color)  # fmt: skip
    if not feas.all():
        _shade_no_band(ax, t, feas, label=f"{name}: infeasible for every torque")
    finite = np.r_[lo[np.isfinite(lo)], up[np.isfinite(up)]]
    low = min(0.0, float(finite.min())) if finite.size else 0.0
    y0 = low - 0.04 * limit if bottom is None else bottom
    b0, t0 = prev if had else (np.inf, -np.inf)
    ax.set_ylim(min(b0, y0), max(t0, limit * 1.12))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("t (s)", fontsize=FONT["label"])
    ax.set_ylabel(f"torque of the {sweep.joint} finger (N m)", fontsize=FONT["label"])
    ax.axhline(0.0, color="0.6", lw=0.6, zorder=0)
    if title:
        ax.set_title(title, fontsize=FONT["title"])
    if legend:
        legend_below(ax)
    if oz_in:
        secondary_oz_in(ax)
    return ax


def plot_guaranteed(bands, ax=None, display_limit=None, show_sampled=True, show_command=True, title=None, oz_in=True):
    """Fig. 13: the band guaranteeing the desired mode and precluding the competitors, with its narrowest point.

    The narrowest point is marked by a double arrow; what it means is said in the title, off the data.

    Parameters
    ----------
    bands : qsplan.planner.torque.sweep.SegmentBands
    ax : matplotlib Axes, optional
    display_limit : float, optional
        N m; default :func:`auto_display_limit` of the guaranteed band, at least four times the narrowest
        point's upper edge.
    show_sampled : bool
        Overlay the paper's sampled band (thin lines).
    show_command : bool
        Overlay the exported command.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.pointwise import narrowest

    ax = axes_or_new(ax, size=(7.0, 4.2))
    g = bands.guaranteed
    band = g.band
    k, w = narrowest(band)
    if display_limit is None:  # show the narrowest point whole, truncate blow-ups
        limit = auto_display_limit(band)
        if k is not None and np.isfinite(band.upper[k]):
            limit = max(limit, nice_ceiling(4.0 * abs(float(band.upper[k]))))
    else:
        limit = float(display_limit)
    plot_band_sweep(band, ax, limit, name="guaranteed", oz_in=False, legend=False)
    t = band.t
    for c, (clo, chi) in g.competitors.items():
        d_lo, d_hi = g.desired.lower, g.desired.upper  # a competitor only touching the band's edge cuts nothing
        with np.errstate(invalid="ignore"):
            inside = (clo < d_hi - _DRAW_RTOL * np.maximum(1.0, np.abs(d_hi))) & (
                chi > d_lo + _DRAW_RTOL * np.maximum(1.0, np.abs(d_lo)))
        hit = np.isfinite(clo) & inside
        if hit.any():
            ax.fill_between(t, np.clip(clo, -limit, limit), np.clip(chi, -limit, limit), where=hit, color=COMPETITOR,
                            alpha=0.3, hatch="//", lw=0, label=f"{c} possible (precluded)")  # fmt: skip
    if show_sampled:
        s = bands.sampled
        n = s.label.split("sampling ")[1].split(" friction")[0] if "sampling " in s.label else "sampled"
        plot_band_sweep(s, ax, limit, color=SAMPLED, fill=None, name=f"paper's method ({n} mu)", oz_in=False,
                        thin=True, legend=False)  # fmt: skip
    if show_command:
        ax.plot(t, np.clip(bands.command, -limit, limit), color=COMMAND, lw=1.2, ls=":", label="exported command")
    note = ""
    if k is not None and np.isfinite(w):
        ax.annotate("", xy=(t[k], band.upper[k]), xytext=(t[k], band.lower[k]),
                    arrowprops={"arrowstyle": "<->", "color": NARROWEST, "lw": 1.6})  # fmt: skip
        ax.plot([], [], color=NARROWEST, marker="$\\updownarrow$", ls="none", ms=10, label="narrowest band")
        note = (f"\nnarrowest: {torque_text(w)} ({w * OZ_IN_PER_N_M:.3g} oz in) at t = {t[k]:.3g} s: the torque "
                "resolution the controller needs")  # fmt: skip
    exact = "exact" if band.exact[band.feasible].all() else f"conservative at {int((~band.exact & band.feasible).sum())} points"
    kind = "one shared coefficient" if g.shared else "each contact's coefficient"
    where = f"friction ({kind}) in [{g.mu_range[0]:g}, {g.mu_range[1]:g}]"
    head = title or f"{ContactMode(band.mode).kind} guaranteed for all {where},\ncompetitors precluded ({exact})"
    ax.set_title(head + note, fontsize=FONT["title"] - 0.5)
    legend_below(ax, ncol=2)
    if oz_in:
        secondary_oz_in(ax)
    return ax
