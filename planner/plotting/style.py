"""Plots for people: mu-space maps.  Compute lives in ``mechanics``; this module only draws.

Every function takes ``ax=None`` (a new figure is made) and returns the axes.
matplotlib is imported inside the functions so that importing qsplan stays light.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PALETTE", "axes_or_new", "plot_mu_slice", "new_axes", "save_figure"]

#: Colours for mode sets, in order of first appearance; "jam" is always light grey.
PALETTE = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860", "#da8bc3", "#8c8c8c", "#ccb974", "#64b5cd"]
_JAM = "#e8e8e8"


def new_axes(ncols=1, nrows=1, size=(4.2, 3.8)):
    """A fresh Figure (no pyplot, no display needed) and its axes array."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size[0] * ncols, size[1] * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    return fig, axes


def axes_or_new(ax, size=(6.4, 3.6)):
    """``ax``, or the axes of a new figure of ``size`` (inches) when ``ax`` is None."""
    if ax is not None:
        return ax
    _, axes = new_axes(1, 1, size=size)
    return axes[0, 0]


def save_figure(fig, path, option: str = "path", dpi: int = 110, force: bool = True, inputs=()) -> None:
    """Write ``fig`` to ``path`` atomically (parent folders created; the format from the suffix).

    Written by :func:`qsplan.planner.export.files.atomic_write`: a temporary file renamed over
    ``path``, never through a symbolic link, never over one of ``inputs``; an existing file is
    replaced only with ``force`` (True by default for callers that checked their outputs first).
    An unwritable or refused path raises a :class:`~qsplan.mechanics.QsplanError` naming ``option``
    (the caller's name for the path).
    """
    from pathlib import Path

    from qsplan.mechanics import QsplanError
    from qsplan.planner.export.files import atomic_write

    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        atomic_write(path, lambda f: fig.savefig(f, format=fmt, dpi=dpi, bbox_inches="tight"), binary=True,
                     force=force, inputs=inputs, field=option)  # fmt: skip
    except OSError as exc:
        raise QsplanError(f"{option}: cannot write {str(path)!r}: {exc.strerror or exc}") from None


def plot_mu_slice(mumap, xs, ys, ax=None, xlabel="$\\mu_1$", ylabel="$\\mu_2$", title=None, names=True, colours=None):
    """Draw a 2-D slice of a :class:`qsplan.mechanics.muspace.maps.MuMap` as labelled regions.

    Each cell gets the colour of its *set* of feasible modes; jammed cells (no
    mode) are light grey and overlaps (ambiguity) are their own sets, so both
    are explicit.  The legend names each set by the modes' paper names and
    their enumeration numbers (3S=1, R1S2=2, ... for three contacts).

    Parameters
    ----------
    mumap : MuMap
        Built on ``grid_points(..., xs, ys)`` (row ``j * len(xs) + i`` is ``(xs[i], ys[j])``).
    xs, ys : array-like, shape (nx,), (ny,)
    ax : matplotlib Axes, optional
    colours : dict, optional
        Mode set (tuple of mode indices) -> colour; pass the same dict to several
        panels so that a set keeps its colour across them (new sets are added to it).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    if ax is None:
        _, axes = new_axes()
        ax = axes[0, 0]
    xs, ys = np.asarray(xs), np.asarray(ys)
    feas = mumap.feasible.reshape(ys.size, xs.size, -1)
    keys = np.packbits(feas, axis=-1, bitorder="little")
    flat = keys.reshape(ys.size * xs.size, -1)
    uniq, inverse = np.unique(flat, axis=0, return_inverse=True)
    inverse = inverse.reshape(ys.size, xs.size)
    sets = [np.flatnonzero(np.unpackbits(u, bitorder="little")[: feas.shape[-1]]) for u in uniq]
    shared = {} if colours is None else colours
    colours, labels = [], []
    for s in sets:
        if s.size == 0:
            colours.append(_JAM)
            labels.append("jam (no mode)")
        else:
            key = tuple(int(j) for j in s)
            if key not in shared:
                shared[key] = PALETTE[len(shared) % len(PALETTE)]
            colours.append(shared[key])
            label = " + ".join(f"{mumap.modes[j].name} ({j + 1})" if names else mumap.modes[j].letters for j in s)
            labels.append(label + ("  [ambiguous]" if s.size > 1 else ""))
    dx = (xs[-1] - xs[0]) / max(xs.size - 1, 1) / 2
    dy = (ys[-1] - ys[0]) / max(ys.size - 1, 1) / 2
    ax.imshow(
        inverse, origin="lower", cmap=ListedColormap(colours), vmin=-0.5, vmax=len(colours) - 0.5,
        extent=(xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy), aspect="auto", interpolation="nearest",
    )  # fmt: skip
    ax.legend(handles=[Patch(color=c, label=l) for c, l in zip(colours, labels)], loc="upper right", fontsize=7, framealpha=0.85)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=10)
    return ax
