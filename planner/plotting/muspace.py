"""Pictures of mu-space (the paper's Figs. 3, 6, 8 and ``qsplan muspace``) and of the graphical test (Fig. 4).

Compute lives in ``mechanics`` (:func:`qsplan.mechanics.muspace.slices.mu_slice`, the modes' exact
regions :class:`qsplan.mechanics.muspace.regions.MuRegion`); this module only draws.  The fill is
painted from the exact regions at the resolution of the picture, not from the map's cells, so it meets
the exact boundary curves without staircase nicks; a mode has the same colour in every figure
(:func:`qsplan.planner.plotting.style.mode_set_colour`), a region where several modes are feasible
(ambiguous) is striped in their colours, and
the legend (outside the axes, one per figure) lists only the sets that cover an area.  Every function
takes ``ax=None`` (a new figure is made) and returns the axes or the figure; matplotlib is imported
inside the functions.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.scene import plot_contact_scene
from qsplan.planner.plotting.style import (
    FONT,
    JAM,
    PALETTE,
    axes_or_new,
    legend_below,
    mode_set_colour,
)

__all__ = ["MODE_LINE_COLOURS", "legend_handles", "mu_slices_figure", "plot_contact_scene", "plot_friction_rectangle",
           "plot_mu_map", "rod_mu_figure"]

#: Boundary-curve colours by mode enumeration number: each mode's fill colour, darkened.
MODE_LINE_COLOURS = ["#1b355e", "#7a3d12", "#24572f", "#6e1f22", "#3c3161", "#4d3b2c", "#7a3c66", "#3d3d3d",
                     "#6b5f1f", "#1f5f70"]  # fmt: skip

#: Pixels per axis the exact regions are painted at.
PAINT = 480

#: A set of modes gets a legend entry only when it covers at least this fraction of the slice.
MIN_AREA = 1e-3


def _paint(sl, n=PAINT):
    """Sets of feasible modes on an ``n`` x ``n`` raster of the slice, from the exact regions (or the cells)."""
    xs = np.linspace(sl.xs[0], sl.xs[-1], n)
    ys = np.linspace(sl.ys[0], sl.ys[-1], n)
    if getattr(sl, "regions", None) and len(sl.regions) == len(sl.modes):
        P = np.broadcast_to(np.asarray(sl.base_mu, float), (n, n, np.size(sl.base_mu))).copy()
        P[..., sl.x], P[..., sl.y] = xs[None, :], ys[:, None]
        feas = np.stack([reg.contains(P) for reg in sl.regions], axis=-1)
    else:  # nearest cell of the map
        i = np.clip(np.searchsorted(sl.xs, xs), 0, sl.xs.size - 1)
        j = np.clip(np.searchsorted(sl.ys, ys), 0, sl.ys.size - 1)
        feas = sl.feasible[j][:, i]
    keys = np.packbits(feas, axis=-1, bitorder="little").reshape(n * n, -1)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    sets = [tuple(int(k) for k in np.flatnonzero(np.unpackbits(u, bitorder="little")[: feas.shape[-1]])) for u in uniq]
    return xs, ys, sets, inverse.reshape(n, n)


#: Width (pixels of the painted raster) of the stripes of an ambiguous region, one stripe per feasible mode.
STRIPE = 14


def _light(colour, amount=0.25):
    """``colour`` mixed with ``amount`` of white (fills stay light under text and curves)."""
    from matplotlib.colors import to_rgb

    return tuple(c + (1.0 - c) * amount for c in to_rgb(colour))


def _image(sets, index):
    """RGB raster: one colour per mode, diagonal stripes of the members' colours where several are feasible."""
    n_y, n_x = index.shape
    J, I = np.mgrid[0:n_y, 0:n_x]
    out = np.zeros((n_y, n_x, 3))
    for u, s in enumerate(sets):
        mask = index == u
        if not s:
            out[mask] = _light(JAM, 0.0)
            continue
        colours = np.array([_light(mode_set_colour((j,))) for j in s])
        out[mask] = colours[((I + J) // STRIPE % len(s))[mask]]
    return out


def _set_label(sl, s):
    return " + ".join(f"{sl.modes[j].name} ({j + 1})" for j in s) or "jam (no mode)"


def _label_regions(ax, xs, ys, sets, index, min_fraction=0.01):
    """Write the enumeration numbers of the feasible modes inside each sizeable region (as the paper does)."""
    from scipy import ndimage

    X, Y = np.meshgrid(xs, ys)
    for u, s in enumerate(sets):
        text = ",".join(str(j + 1) for j in s) if s else "Jam"
        comps, count = ndimage.label(index == u)
        for c in range(1, count + 1):
            cells = comps == c
            if cells.sum() < min_fraction * cells.size:
                continue
            inner = ndimage.distance_transform_edt(np.pad(cells, 1))[1:-1, 1:-1]  # far from its edge and the axes
            deep = np.argwhere(inner >= 0.8 * inner.max())  # of those, the one nearest the region's centre
            k = tuple(deep[np.argmin(np.sum((deep - np.argwhere(cells).mean(axis=0)) ** 2, axis=1))])
            ax.text(X[k], Y[k], text, ha="center", va="center", fontsize=FONT["note"] + 0.5, weight="bold",
                    bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.6})  # fmt: skip


def legend_handles(sl, sets, index, curves=True) -> list:
    """Legend entries of a drawn slice: the mode sets covering an area, then each mode's boundary curve."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    out = []
    area = np.bincount(index.ravel(), minlength=len(sets)) / index.size
    for u, s in enumerate(sets):
        if area[u] < MIN_AREA:
            continue  # no legend entry without an area (a set on a line only)
        if len(s) > 1:  # stripes of the members' colours, as in the picture (two shown in the legend)
            out.append(Patch(fc=_light(mode_set_colour(s[:1])), hatch="////", ec=_light(mode_set_colour(s[1:2])),
                             lw=0.0, label=_set_label(sl, s) + "  [ambiguous]"))  # fmt: skip
        else:
            out.append(Patch(fc=_light(mode_set_colour(s)), ec="0.3", lw=0.4, label=_set_label(sl, s)))
    if curves:
        for j in sorted({j for s in sets for j in s}):
            out.append(Line2D([], [], color=MODE_LINE_COLOURS[j % len(MODE_LINE_COLOURS)], lw=1.3,
                              label=f"boundary of {sl.modes[j].name} ({j + 1})"))  # fmt: skip
    return out


def plot_mu_map(sl, ax=None, curves=True, numbers=True, title=None, colours=None, samples=400, legend=True):
    """Draw a :class:`qsplan.mechanics.muspace.slices.MuSlice`: regions by mode set, exact boundaries on top.

    Parameters
    ----------
    sl : MuSlice
    ax : matplotlib Axes, optional
    curves : bool
        Draw the exact boundaries (zero sets of the boundary polynomials,
        :meth:`qsplan.mechanics.muspace.regions.MuRegion.boundary_curves`).
    numbers : bool
        Write the modes' enumeration numbers (3S=1, R1S2=2, ... for three contacts) in the regions.
    title : str, optional
    colours : dict, optional
        Ignored (kept for compatibility): a mode set's colour no longer depends on drawing order.
    samples : int
        Samples per axis of each boundary curve.
    legend : bool
        Put the legend under the axes; :func:`mu_slices_figure` draws one for all panels instead.

    Returns
    -------
    matplotlib.axes.Axes
        With ``ax.mu_legend_handles`` (the entries the legend would hold).
    """
    ax = axes_or_new(ax, size=(5.2, 4.6))
    xs, ys, sets, index = _paint(sl)
    ax.imshow(_image(sets, index), origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]), aspect="auto",
              interpolation="nearest")  # fmt: skip
    if curves and sl.xs[-1] > sl.xs[0] and sl.ys[-1] > sl.ys[0]:
        for c in sl.boundary_curves(samples):
            j = sl.modes.index(c.mode)
            ax.plot(c.points[:, 0], c.points[:, 1], color=MODE_LINE_COLOURS[j % len(MODE_LINE_COLOURS)], lw=1.3)
    if numbers:
        _label_regions(ax, xs, ys, sets, index)
    ax.set_xlim(sl.xs[0], sl.xs[-1])
    ax.set_ylim(sl.ys[0], sl.ys[-1])
    ax.set_xlabel(f"$\\mu_{sl.x + 1}$", fontsize=FONT["label"])
    ax.set_ylabel(f"$\\mu_{sl.y + 1}$", fontsize=FONT["label"])
    if title:
        ax.set_title(title, fontsize=FONT["title"])
    ax.mu_legend_handles = legend_handles(sl, sets, index, curves)
    if legend:
        legend_below(ax, ax.mu_legend_handles, ncol=2)
    return ax


def mu_slices_figure(slices, titles, suptitle=None, ncols=2, size=(4.4, 3.9)):
    """Several slices in one figure with one legend for all, outside the panels.

    Parameters
    ----------
    slices : sequence of MuSlice
    titles : sequence of str
    suptitle : str, optional
    ncols : int
    size : (float, float)
        One panel's size (inches).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from qsplan.planner.plotting.style import figure_legend, new_axes

    nrows = -(-len(slices) // ncols)
    fig, axes = new_axes(ncols, nrows, size=size)
    seen = {}
    for ax, sl, title in zip(axes.ravel(), slices, titles):
        plot_mu_map(sl, ax=ax, title=title, legend=False)
        for h in ax.mu_legend_handles:
            seen.setdefault(h.get_label(), h)
    for ax in axes.ravel()[len(slices):]:
        ax.set_visible(False)
    patches = [h for h in seen.values() if not hasattr(h, "get_xdata")]
    lines = [h for h in seen.values() if hasattr(h, "get_xdata")]
    figure_legend(fig, patches + lines, ncol=2)
    if suptitle:
        fig.suptitle(suptitle, fontsize=FONT["suptitle"])
    return fig


def plot_friction_rectangle(ax, mu_static, mu_kinetic, corners=True):
    """The friction rectangle of Fig. 8: ``[mu_1S, mu_1R] x [mu_2S, mu_2R]``, its corners named.

    Parameters
    ----------
    ax : matplotlib Axes
    mu_static, mu_kinetic : (float, float)
        Rolling (static) and sliding (kinetic) coefficients of contacts 1 and 2.
    corners : bool
        Mark the corners where R2S1 (upper left) and R1S2 (lower right) run.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Rectangle

    (m1R, m2R), (m1S, m2S) = mu_static, mu_kinetic
    ax.add_patch(Rectangle((m1S, m2S), m1R - m1S, m2R - m2S, fc="#f0e6c8", ec="k", lw=1.2, alpha=0.9, zorder=3,
                           label="friction rectangle (sliding to rolling values)"))  # fmt: skip
    if corners:
        ax.plot([m1S], [m2R], "o", color=PALETTE[3], ms=7, zorder=4, label="R2S1 runs at ($\\mu_{1S}$, $\\mu_{2R}$)")
        ax.plot([m1R], [m2S], "s", color=PALETTE[0], ms=7, zorder=4, label="R1S2 runs at ($\\mu_{1R}$, $\\mu_{2S}$)")
    return ax


def rod_mu_figure(sl, l1, l2, mu_static=None, mu_kinetic=None):
    """Fig. 8: the rod's slice of mu-space, its boundary ``l1 mu2 = l2 mu1`` and the friction rectangle.

    Parameters
    ----------
    sl : MuSlice
        The rod's slice (:func:`qsplan.hands.examples.paper.rod_scene`).
    l1, l2 : float
        Distances of the supports from the centre of mass (the paper's rod has no units).
    mu_static, mu_kinetic : (float, float), optional
        Rolling and sliding coefficients of the two supports: the friction rectangle.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from qsplan.planner.plotting.style import new_axes

    fig, axes = new_axes(1, 1, size=(5.6, 6.4))
    ax = plot_mu_map(sl, ax=axes[0, 0], legend=False,
                     title=f"Fig. 8 reproduced: the rod, $l_1$ = {l1:g}, $l_2$ = {l2:g}\n"
                           "R2S1 above the line $l_1 \\mu_2 = l_2 \\mu_1$, R1S2 below")  # fmt: skip
    handles = list(ax.mu_legend_handles)
    if mu_static is not None and mu_kinetic is not None:
        plot_friction_rectangle(ax, mu_static, mu_kinetic)
        handles += [h for h in ax.get_legend_handles_labels()[0]]
    legend_below(ax, handles, ncol=2)
    ax.set_aspect("equal")
    return fig
