"""The one style of every qsplan figure: colours, text sizes, legends off the data, A4 pages, saving.

Every figure module draws with these, so that a reader learns a figure once:

* a finger has one colour everywhere (snapshots, timelines, bands, the plan card): :data:`FINGER`;
* a set of feasible modes has one colour in every mu-space figure (Figs. 3, 6, 8, ``qsplan muspace``):
  :func:`mode_set_colour` depends only on the modes' enumeration numbers, never on drawing order;
* band edges are drawn as in the paper: upper edges solid, lower edges dashed (:data:`UPPER`,
  :data:`LOWER`), and an infinite edge is said in words (:func:`torque_text`), never as ``inf N m``;
* legends sit outside the axes (:func:`legend_below`, :func:`legend_right`, :func:`figure_legend`), so
  they never cover data.

Figures are :class:`matplotlib.figure.Figure` objects (no pyplot, no display needed); matplotlib is
imported inside the functions so that importing qsplan stays light.
"""

from __future__ import annotations

import functools
import math

__all__ = [
    "A4_LANDSCAPE",
    "A4_PORTRAIT",
    "BAND_FILL",
    "COMMAND",
    "COMPETITOR",
    "EDGE",
    "FINGER",
    "FONT",
    "JAM",
    "LOWER",
    "NARROWEST",
    "NO_BAND",
    "PALETTE",
    "REGRASP",
    "SAMPLED",
    "STEP_SHADE",
    "UPPER",
    "axes_or_new",
    "body_style",
    "figure_legend",
    "finger_colour",
    "joint_colour",
    "legend_below",
    "lay_out_once",
    "legend_right",
    "mode_set_colour",
    "new_axes",
    "plot_mu_slice",
    "save_figure",
    "save_rendered",
    "step_colour",
    "text_width",
    "torque_text",
]

#: Mode colours by enumeration number (mode ``j``, 0-based, gets ``PALETTE[j % 10]``).
PALETTE = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860", "#da8bc3", "#8c8c8c", "#ccb974", "#64b5cd"]
#: Cells where no mode is feasible (a jam).
JAM = "#e8e8e8"

#: One colour per finger (edges; faces are lighter): the same in snapshots, timelines and bands.
FINGER = {"left": "#2171b5", "right": "#d94801"}
_BODIES = {"palm": ("#d9d9d9", "#636363"), "left": ("#9ecae1", FINGER["left"]), "right": ("#fdae6b", FINGER["right"]),
           "workpiece": ("#fff7bc", "#8c6d31")}  # fmt: skip
_OTHER_BODY = ("#dadaeb", "#54278f")
#: A phase without a torque-controlled joint (a regrasp).
REGRASP = "#bdbdbd"

#: What an in-contact phase does, in its colour (:func:`step_colour`): the torque-controlled finger's colour for a
#: slide, mixed this much with white for a hold (nothing moves) and with black for a pivot (the workpiece turns), so
#: that the finger stays recognisable and the three kinds differ in every timeline and legend.
STEP_SHADE = {"slide": 0.0, "hold": 0.6, "pivot": -0.45}

#: Bands: fill, edges, the command, the narrowest point, competitors, samples without a band, the paper's method.
BAND_FILL = "#9ecae1"
EDGE = "#1f3b73"
COMMAND = "#000000"
NARROWEST = "#d62728"
COMPETITOR = "#c44e52"
NO_BAND = "#eeeeee"
SAMPLED = "#e377c2"
#: Line styles of band edges, as in the paper: upper solid, lower dashed.
UPPER = {"ls": "-"}
LOWER = {"ls": "--"}

#: Text sizes (points): at least 7 pt on paper, so an A4 print stays readable.
FONT = {"suptitle": 11, "title": 10, "label": 9, "tick": 8, "legend": 8, "note": 7.5}

#: Page sizes (inches).
A4_PORTRAIT = (8.27, 11.69)
A4_LANDSCAPE = (11.69, 8.27)


def finger_colour(name: str) -> str:
    """The edge colour of finger ``name`` (:data:`FINGER`); other joints of a chain get purple."""
    return FINGER.get(str(name), _OTHER_BODY[1])


def joint_colour(hand, name: str) -> str:
    """The colour of joint ``name`` of ``hand``: its finger's (:data:`FINGER`; a chain hand's links share their
    finger's colour)."""
    return finger_colour(hand.finger_of_joint.get(str(name), name))


def step_colour(colour, kind: str) -> str:
    """``colour`` shaded for a phase of ``kind`` (``"slide"``, ``"hold"``, ``"pivot"``: :data:`STEP_SHADE`; any other
    kind unchanged)."""
    from matplotlib.colors import to_hex, to_rgb

    f = STEP_SHADE.get(str(kind), 0.0)
    towards = 1.0 if f > 0 else 0.0
    return to_hex(tuple(c + abs(f) * (towards - c) for c in to_rgb(colour)))


def text_width(text, size, bold=False) -> float:
    """Width (points) of ``text``'s longest line drawn at ``size`` points in the default font (its glyphs' outline,
    no figure or renderer needed)."""
    return max(_line_width(line, float(size), bool(bold)) for line in str(text).split("\n"))


@functools.lru_cache(maxsize=4096)
def _line_width(line, size, bold) -> float:
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    if not line.strip():
        return 0.0
    prop = FontProperties(weight="bold" if bold else "normal")
    return float(TextPath((0, 0), line, size=size, prop=prop).get_extents().width)


def body_style(name: str) -> tuple:
    """``(face, edge)`` colours of a drawn body: palm, fingers, workpiece, any other link of a chain."""
    return _BODIES.get(str(name), _OTHER_BODY)


def mode_set_colour(modes) -> str:
    """The colour of a set of feasible modes, the same in every figure.

    One mode ``j`` (0-based enumeration number) gets ``PALETTE[j % 10]``; several modes (an
    ambiguous set) the mean of their colours (drawn hatched by the mu-space plots); none is
    :data:`JAM`.

    Parameters
    ----------
    modes : iterable of int
    """
    from matplotlib.colors import to_hex, to_rgb

    modes = sorted(int(j) for j in modes)
    if not modes:
        return JAM
    rgb = [to_rgb(PALETTE[j % len(PALETTE)]) for j in modes]
    return to_hex(tuple(sum(c[k] for c in rgb) / len(rgb) for k in range(3)))


def torque_text(value, unit: str = "N m", side: str = "upper") -> str:
    """An effort for people: ``"0.139 N m"``, ``"unbounded above"`` (``inf``), ``"unbounded below"``, ``"none"`` (NaN)."""
    v = float(value)
    if math.isnan(v):
        return "none"
    if math.isinf(v):
        return "unbounded above" if v > 0 else "unbounded below"
    return f"{v:.3g} {unit}"


def new_axes(ncols=1, nrows=1, size=(4.2, 3.8)):
    """A fresh Figure (no pyplot, no display needed) and its axes array, shape (nrows, ncols).

    ``size`` is the size of one panel (inches); the layout is constrained, so labels and legends
    placed outside the axes get room.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size[0] * ncols, size[1] * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for ax in axes.ravel():
        ax.tick_params(labelsize=FONT["tick"])
    return fig, axes


def axes_or_new(ax, size=(6.4, 3.6)):
    """``ax``, or the axes of a new figure of ``size`` (inches) when ``ax`` is None."""
    if ax is not None:
        return ax
    _, axes = new_axes(1, 1, size=size)
    return axes[0, 0]


def legend_below(ax, handles=None, ncol: int = 2, **kw):
    """The legend under the axes, below its tick labels and x label, so that it never hides data; returns it
    (or None).  The offset is in points, so it holds for axes of any height."""
    from matplotlib.transforms import ScaledTranslation

    handles = handles if handles is not None else ax.get_legend_handles_labels()[0]
    if not handles:
        return None
    lines = 1 + ax.get_xlabel().count("\n") if ax.get_xlabel() else 0
    drop = (1.6 * FONT["tick"] + 1.5 * FONT["label"] * lines + 6.0) / 72.0  # inches: tick labels, x label, a gap
    below = ax.transAxes + ScaledTranslation(0.0, -drop, ax.get_figure(root=True).dpi_scale_trans)
    return ax.legend(handles=handles, fontsize=FONT["legend"], loc="upper center", bbox_to_anchor=(0.5, 0.0),
                     bbox_transform=below, borderaxespad=0.0, ncol=ncol, frameon=False, **kw)  # fmt: skip


def legend_right(ax, handles=None, **kw):
    """The legend right of the axes, top-aligned; returns it (or None)."""
    handles = handles if handles is not None else ax.get_legend_handles_labels()[0]
    if not handles:
        return None
    return ax.legend(handles=handles, fontsize=FONT["legend"], loc="upper left", bbox_to_anchor=(1.02, 1.0),
                     borderaxespad=0.0, frameon=False, **kw)  # fmt: skip


def figure_legend(fig, handles, ncol: int = 3, where: str = "lower center", **kw):
    """One legend for all panels of ``fig``, outside them (constrained layout makes room); returns it."""
    return fig.legend(handles=handles, loc=f"outside {where}", ncol=ncol, fontsize=FONT["legend"], frameon=False, **kw)


def save_figure(fig, path, option: str = "path", dpi: int = 110, force: bool = True, inputs=(), tight: bool = True) -> None:
    """Write ``fig`` to ``path`` atomically (parent folders created; the format from the suffix).

    Written by :func:`qsplan.planner.export.files.atomic_write`: a temporary file renamed over
    ``path``, never through a symbolic link, never over one of ``inputs``; an existing file is
    replaced only with ``force`` (True by default for callers that checked their outputs first).
    PNG files record ``Software: qsplan <version>``.  ``tight`` crops the page to its content (a page
    meant for print, the plan card, keeps its size with ``tight=False``).  An unwritable or refused path raises a
    :class:`~qsplan.mechanics.QsplanError` naming ``option`` (the caller's name for the path).
    """
    from pathlib import Path

    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    meta = _png_metadata() if fmt == "png" else None
    _write(path, lambda f: fig.savefig(f, format=fmt, dpi=dpi, bbox_inches="tight" if tight else None, metadata=meta),
           option, force, inputs)


def lay_out_once(fig, dpi: float) -> None:
    """Lay ``fig`` out at ``dpi`` (its layout engine, once) and keep that layout: a figure saved with
    ``bbox_inches="tight"`` is otherwise laid out twice more (once to measure its extent, once to draw), to the same
    positions."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    engine = fig.get_layout_engine()
    if engine is None:
        return
    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.set_dpi(dpi)
    engine.execute(fig)
    fig.set_layout_engine("none")


def save_rendered(fig, path, option: str = "path", force: bool = True, inputs=()) -> None:
    """Write what ``fig``'s Agg canvas last drew (``canvas.draw()``, at the figure's dpi) to the PNG ``path``, as
    :func:`save_figure` writes a PNG (``savefig``'s own last step), without drawing it again; the arguments as there.
    """
    from matplotlib.image import imsave

    _write(path, lambda f: imsave(f, fig.canvas.buffer_rgba(), format="png", origin="upper", dpi=fig.dpi,
                                  metadata=_png_metadata()), option, force, inputs)  # fmt: skip


def _png_metadata() -> dict:
    """The PNG text chunks qsplan writes: ``Software: qsplan <version>``."""
    from qsplan import __version__

    return {"Software": f"qsplan {__version__}"}


def _write(path, write, option, force, inputs) -> None:
    """``write(file)`` into ``path`` by :func:`qsplan.planner.export.files.atomic_write` (binary); an OS error as a
    :class:`~qsplan.mechanics.QsplanError` naming ``option``."""
    from qsplan.mechanics import QsplanError
    from qsplan.planner.export.files import atomic_write

    try:
        atomic_write(path, write, binary=True, force=force, inputs=inputs, field=option)
    except OSError as exc:
        raise QsplanError(f"{option}: cannot write {str(path)!r}: {exc.strerror or exc}") from None


def plot_mu_slice(mumap, xs, ys, ax=None, xlabel="$\\mu_1$", ylabel="$\\mu_2$", title=None, names=True, colours=None):
    """Draw a 2-D slice of a :class:`qsplan.mechanics.muspace.maps.MuMap` cell by cell (no exact boundaries).

    Kept for maps without regions; :func:`qsplan.planner.plotting.muspace.plot_mu_map` draws a
    :class:`~qsplan.mechanics.muspace.slices.MuSlice` with its exact regions.  Each cell gets the
    colour of its set of feasible modes (:func:`mode_set_colour`); the legend, right of the axes,
    names each set present.  ``colours`` is accepted for compatibility and ignored: colours no
    longer depend on the order of drawing.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import numpy as np
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    ax = axes_or_new(ax, size=(5.0, 4.2))
    xs, ys = np.asarray(xs), np.asarray(ys)
    feas = mumap.feasible.reshape(ys.size, xs.size, -1)
    keys = np.packbits(feas, axis=-1, bitorder="little").reshape(ys.size * xs.size, -1)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    sets = [np.flatnonzero(np.unpackbits(u, bitorder="little")[: feas.shape[-1]]) for u in uniq]
    cols = [mode_set_colour(s) for s in sets]
    labels = [" + ".join(f"{mumap.modes[j].name} ({j + 1})" if names else mumap.modes[j].letters for j in s)
              or "jam (no mode)" for s in sets]  # fmt: skip
    dx = (xs[-1] - xs[0]) / max(xs.size - 1, 1) / 2
    dy = (ys[-1] - ys[0]) / max(ys.size - 1, 1) / 2
    ax.imshow(inverse.reshape(ys.size, xs.size), origin="lower", cmap=ListedColormap(cols), vmin=-0.5,
              vmax=len(cols) - 0.5, extent=(xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy), aspect="auto",
              interpolation="nearest")  # fmt: skip
    legend_right(ax, [Patch(color=c, label=l) for c, l in zip(cols, labels)])
    ax.set_xlabel(xlabel, fontsize=FONT["label"])
    ax.set_ylabel(ylabel, fontsize=FONT["label"])
    if title:
        ax.set_title(title, fontsize=FONT["title"])
    return ax
