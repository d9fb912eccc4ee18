"""Plots for operators: torque bands along a segment (Figs. 10-13); hand snapshots are in :mod:`.hands`.

Compute lives in :mod:`qsplan.planner.torque`; this module only draws.
As in the paper, upper bounds are bold solid curves and lower bounds bold dashed
ones; a side beyond the display limit (or infinite) is drawn along the limit with
up (down) arrows and said so in the legend, as the paper truncated Fig. 10 "at 200
oz.-in.".  Efforts are in N m; a right-hand axis repeats them in the paper's oz in.

Every ``plot_*`` function takes ``ax=None`` (a new figure is made) and returns the
axes; ``*_figure`` functions return a ``matplotlib.figure.Figure`` (no pyplot).
matplotlib is imported inside the functions.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.hands import hand_strip_figure, plot_hand
from qsplan.planner.plotting.style import axes_or_new

__all__ = [
    "OZ_IN_PER_N_M",
    "auto_display_limit",
    "hand_strip_figure",
    "plot_band_sweep",
    "plot_guaranteed",
    "plot_hand",
    "plot_speed_accuracy",
    "segment_band_figures",
]

#: 1 N m in ounce-force inches (the paper's torque unit): 1 / (0.0283495 kg * 9.80665 m/s^2 * 0.0254 m).
OZ_IN_PER_N_M = 141.61193227806

_UPPER = "#1f3b73"
_LOWER = "#1f3b73"
_FILL = "#9ecae1"
_COMP = "#c44e52"
_NOBAND = "#eeeeee"

#: A competitor is drawn inside the desired mode's band only where it reaches more than this
#: (relative) past the band's edge; touching the edge (a shared boundary) cuts nothing.
_DRAW_RTOL = 1e-6


def _axes(ax, size=(6.4, 3.6)):
    return axes_or_new(ax, size)


def _nice_ceiling(x: float) -> float:
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
    return _nice_ceiling(2.0 * float(np.percentile(vals, 75)))


def _secondary_oz_in(ax):
    sec = ax.secondary_yaxis("right", functions=(lambda y: y * OZ_IN_PER_N_M, lambda y: y / OZ_IN_PER_N_M))
    sec.set_ylabel("oz in (the paper's unit)", fontsize=8)
    sec.tick_params(labelsize=7)
    return sec


def _shade_no_band(ax, t, feasible, label="no band"):
    dt = (t[-1] - t[0]) / max(len(t) - 1, 1)
    labelled = False
    k = 0
    while k < len(t):
        if feasible[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(t) and not feasible[j + 1]:
            j += 1
        ax.axvspan(t[k] - dt / 2, t[j] + dt / 2, color=_NOBAND, zorder=0, label=None if labelled else label)
        labelled = True
        k = j + 1


def _clipped(values, limit):
    """Values clipped to ``[-limit, limit]`` and the mask of clipped (or infinite) points."""
    v = np.asarray(values, dtype=float)
    over = np.isfinite(v) & (np.abs(v) > limit) | np.isinf(v)
    return np.clip(v, -limit, limit), over


def plot_band_sweep(sweep, ax=None, display_limit=None, color=_UPPER, fill=_FILL, name=None, title=None, oz_in=True,
                    thin=False):
    """One band along a segment, the paper's way (Figs. 10-12).

    Parameters
    ----------
    sweep : qsplan.planner.torque.pointwise.BandSweep
    ax : matplotlib Axes, optional
    display_limit : float, optional
        N m; sides beyond it (or infinite) are drawn along it with arrows.  Default
        :func:`auto_display_limit`.
    color, fill : colours of the edges and of the band.
    name : str, optional
        Legend prefix (default the sweep's label).
    title : str, optional
    oz_in : bool
        Add the right-hand axis in oz in.
    thin : bool
        Thin lines (for an overlay).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    had, prev = bool(ax.lines), ax.get_ylim()  # overlaying on another band: keep its range too
    limit = auto_display_limit(sweep) if display_limit is None else float(display_limit)
    t, feas = sweep.t, sweep.feasible
    name = name or sweep.label
    lo, lo_cut = _clipped(sweep.lower, limit)
    up, up_cut = _clipped(sweep.upper, limit)
    lo, up = np.where(feas, lo, np.nan), np.where(feas, up, np.nan)
    if fill:
        ax.fill_between(t, lo, up, where=feas, color=fill, alpha=0.45, lw=0, label=f"{name}: band")
    lw = 1.1 if thin else 2.6
    ax.plot(t, up, color=color, lw=lw, ls="-", label=f"{name}: upper bound")
    ax.plot(t, lo, color=color, lw=lw, ls="--", label=f"{name}: lower bound")
    step = max(1, len(t) // 14)
    raw = np.r_[sweep.upper, sweep.lower]
    ys = np.r_[up, lo]
    cut = np.r_[up_cut, lo_cut] & np.r_[feas, feas]
    tt = np.r_[t, t]
    for sign, marker in ((1.0, "^"), (-1.0, "v")):
        idx = np.flatnonzero(cut & (np.sign(raw) == sign))
        if idx.size:
            idx = idx[:: step] if idx.size > step else idx
            ax.plot(tt[idx], ys[idx], ls="none", marker=marker, ms=5 if thin else 6, color=color,
                    label=f"{name}: beyond {sign * limit:+g} N m (or infinite)")  # fmt: skip
    if not thin:  # say where a side is infinite, not merely off scale
        for a, b in sweep.infinite_upper_spans():
            ax.annotate(f"infinite for t in [{a:.3g}, {b:.3g}] s", ((a + b) / 2, limit), xytext=(0, 4),
                        textcoords="offset points", ha="center", va="bottom", fontsize=7, color=color)  # fmt: skip
    if not feas.all():
        _shade_no_band(ax, t, feas, label=f"{name}: infeasible for every torque")
    finite = np.r_[lo[np.isfinite(lo)], up[np.isfinite(up)]]
    bottom = min(0.0, float(finite.min())) if finite.size else 0.0
    b0, t0 = prev if had else (np.inf, -np.inf)
    ax.set_ylim(min(b0, bottom - 0.04 * limit), max(t0, limit * 1.08))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"torque of joint {sweep.joint!r} (N m)")
    ax.axhline(0.0, color="0.6", lw=0.6, zorder=0)
    if title:
        ax.set_title(title, fontsize=10)
    _legend(ax)
    if oz_in:
        _secondary_oz_in(ax)
    return ax


def _legend(ax):
    """The legend under the axes, so that it never hides a band."""
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)


def plot_guaranteed(bands, ax=None, display_limit=None, show_sampled=True, show_command=True, title=None, oz_in=True):
    """Fig. 13: the band guaranteeing the desired mode and precluding the competitors, with its narrowest point.

    Parameters
    ----------
    bands : qsplan.planner.torque.sweep.SegmentBands
    ax : matplotlib Axes, optional
    display_limit : float, optional
        N m; default :func:`auto_display_limit` of the guaranteed band.
    show_sampled : bool
        Overlay the paper's sampled band (thin lines).
    show_command : bool
        Overlay the exported command (dotted).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.pointwise import narrowest

    ax = _axes(ax, size=(7.0, 4.0))
    g = bands.guaranteed
    band = g.band
    k, w = narrowest(band)
    if display_limit is None:  # show the narrowest point whole, truncate blow-ups
        limit = auto_display_limit(band)
        if k is not None and np.isfinite(band.upper[k]):
            limit = max(limit, _nice_ceiling(4.0 * abs(float(band.upper[k]))))
    else:
        limit = float(display_limit)
    kind = "one shared mu" if g.shared else "each contact's mu"
    where = f"{kind} in [{g.mu_range[0]:g}, {g.mu_range[1]:g}]"
    plot_band_sweep(band, ax, limit, name="guaranteed", oz_in=False)
    t = band.t
    for c, (clo, chi) in g.competitors.items():
        # a competitor that only touches the band's edge (shared boundary) cuts nothing: not drawn
        d_lo, d_hi = g.desired.lower, g.desired.upper
        with np.errstate(invalid="ignore"):
            inside = (clo < d_hi - _DRAW_RTOL * np.maximum(1.0, np.abs(d_hi))) & (
                chi > d_lo + _DRAW_RTOL * np.maximum(1.0, np.abs(d_lo)))
        hit = np.isfinite(clo) & inside
        if hit.any():
            ax.fill_between(t, np.clip(clo, -limit, limit), np.clip(chi, -limit, limit), where=hit, color=_COMP,
                            alpha=0.3, hatch="//", lw=0, label=f"{c} possible (precluded)")  # fmt: skip
    if show_sampled:
        s = bands.sampled
        n = s.label.split("sampling ")[1].split(" friction")[0]
        plot_band_sweep(s, ax, limit, color="#e377c2", fill=None, name=f"paper's method ({n} mu)",
                        oz_in=False, thin=True)  # fmt: skip
    if show_command:
        ax.plot(t, np.clip(bands.command, -limit, limit), color="k", lw=1.0, ls=":", label="exported command")
    if k is not None and np.isfinite(w):
        ax.annotate("", xy=(t[k], band.upper[k]), xytext=(t[k], band.lower[k]),
                    arrowprops={"arrowstyle": "<->", "color": "#d62728", "lw": 1.6})  # fmt: skip
        ha = "right" if t[k] > 0.5 * (t[0] + t[-1]) else "left"
        ax.annotate(f"narrowest: {w:.3g} N m ({w * OZ_IN_PER_N_M:.3g} oz in)\nat t = {t[k]:.3g} s: the torque\n"
                    "resolution the controller needs",
                    xy=(t[k], band.upper[k]), xytext=(-14 if ha == "right" else 14, 40),
                    textcoords="offset points", ha=ha, fontsize=8, color="#d62728")  # fmt: skip
    exact = "exact" if band.exact[band.feasible].all() else f"conservative at {int((~band.exact & band.feasible).sum())} points"
    ax.set_title(title or f"{ContactMode(band.mode).kind} guaranteed for {where}, competitors precluded ({exact})", fontsize=10)
    _legend(ax)
    if oz_in:
        _secondary_oz_in(ax)
    return ax



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
    fig, ax = new_axes(1, 1, size=(8.0, 4.6))
    plot_band_sweep(bands.frictionless, ax[0, 0], lim if lim else auto_display_limit(bands.frictionless),
                    title=f"Fig. 10: {bands.frictionless.label}")  # fmt: skip
    out["fig10_frictionless"] = fig
    fig, ax = new_axes(1, 1, size=(8.0, 4.6))
    plot_band_sweep(bands.at_high_mu, ax[0, 0], lim if lim else auto_display_limit(bands.at_high_mu),
                    title=f"Fig. 11: {bands.at_high_mu.label}")  # fmt: skip
    out["fig11_mu_high"] = fig
    fig, ax = new_axes(1, 1, size=(8.0, 4.6))
    live = {c: s for c, s in bands.competitors_at_high_mu.items() if s.feasible.any()}
    lim12 = lim if lim else auto_display_limit(bands.at_high_mu, *live.values())
    plot_band_sweep(bands.at_high_mu, ax[0, 0], lim12, color="0.55", fill=None,
                    name=ContactMode(bands.at_high_mu.mode).kind, oz_in=False, thin=True)  # fmt: skip
    for c, s in live.items():
        plot_band_sweep(s, ax[0, 0], lim12, color=_COMP, fill="#f4a582", name=f"{ContactMode(c).kind} {c}", oz_in=False)
    names = ", ".join(f"{ContactMode(c).kind} ({ContactMode(c).name}, {c})" for c in live) or "none feasible"
    ax[0, 0].set_title(f"Fig. 12: competing modes at mu = {hi:g}: {names}", fontsize=10)
    if not live:
        ax[0, 0].text(0.5, 0.5, f"no competing mode is feasible at mu = {hi:g}", transform=ax[0, 0].transAxes,
                      ha="center", fontsize=9, color=_COMP)  # fmt: skip
    _secondary_oz_in(ax[0, 0])
    out["fig12_competitors"] = fig
    fig, ax = new_axes(1, 1, size=(8.0, 5.2))
    plot_guaranteed(bands, ax[0, 0], lim, title=None)
    ax[0, 0].set_title("Fig. 13: " + ax[0, 0].get_title(), fontsize=10)
    out["fig13_guaranteed"] = fig
    out["hand_strip"] = hand_strip_figure(bands.samples, strip)
    return out


def plot_speed_accuracy(rows, ax=None, title=None):
    """Band error against computing time for exact and sampled guaranteed bands (log-log).

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
    ax = _axes(ax, size=(6.4, 4.2))
    errs = [r["error"] for r in rows if r["error"] > 0 and np.isfinite(r["error"])]
    floor = (min(errs) / 10.0) if errs else 1e-12
    colours = {"box": "#4c72b0", "shared": "#dd8452"}
    for kind in ("box", "shared"):
        samp = sorted((r for r in rows if r["method"] == f"sampled {kind}"), key=lambda r: r["samples"])
        if samp:
            x = [r["time"] for r in samp]
            y = [max(r["error"], floor) for r in samp]
            ax.plot(x, y, "o-", color=colours[kind], label=f"sampled, {kind} mu (n = {samp[0]['samples']}..{samp[-1]['samples']})")
            for r, xx, yy in zip(samp, x, y):
                ax.annotate(str(r["samples"]), (xx, yy), xytext=(3, 3), textcoords="offset points", fontsize=7)
        for r in rows:
            if r["method"] == f"exact {kind}":
                ax.plot([r["time"]], [floor], "*", ms=14, color=colours[kind], label=f"exact, {kind} mu (error 0, drawn at the floor)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time for the whole segment (s)")
    ax.set_ylabel("band error: largest excess width (N m)")
    ax.set_title(title or "guaranteed torque band: speed against accuracy", fontsize=10)
    _legend(ax)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    return ax
