"""Layout checks of rendered figures (test helper): texts that overlap, legends over data, labels without units.

Every check draws the figure once with the Agg renderer and compares the renderer's bounding boxes
(display pixels), so it sees what a reader sees: after constrained layout, at the saved size.
"""

from __future__ import annotations

import re

#: Overlap (pixels, each side) tolerated between two boxes: antialiasing and rounding.
SLACK = 1.0


def render(fig):
    """Draw ``fig`` with Agg and return the renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _shown(artist) -> bool:
    """Visible, and so are its axes and every (sub)figure it is in."""
    if not artist.get_visible():
        return False
    ax = getattr(artist, "axes", None)
    if ax is not None and not ax.get_visible():
        return False
    f = artist.get_figure(root=False)
    while f is not None:
        if not f.get_visible():
            return False
        parent = f.get_figure(root=False)
        if parent is f:
            break
        f = parent
    return True


def _is_axes(artist) -> bool:
    return hasattr(artist, "xaxis") and hasattr(artist, "yaxis") and hasattr(artist, "get_window_extent")


def texts(fig) -> list:
    """``(text, bbox)`` of every visible, non-empty text of ``fig`` as drawn (titles, labels, drawn tick labels,
    notes, legends)."""
    from matplotlib.text import Text

    renderer = render(fig)
    ticks, drawn = set(), []  # tick labels are taken from the axes: those of ticks inside the view only
    for ax in fig.findobj(_is_axes):  # secondary axes too (not Axes subclasses)
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            tol = 1e-9 * max(1.0, abs(hi - lo))
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                ticks |= {id(tick.label1), id(tick.label2)}
                if _shown(ax) and tick.get_visible() and lo - tol <= tick.get_loc() <= hi + tol:
                    drawn += [lab for lab in (tick.label1, tick.label2) if lab.get_visible()]
    out = []
    for t in [t for t in fig.findobj(Text) if id(t) not in ticks] + drawn:
        s = t.get_text().strip()
        if not s or not _shown(t):
            continue
        bb = t.get_window_extent(renderer)
        if bb.width > 0 and bb.height > 0:
            out.append((s, bb))
    return out


def _overlap(a, b, slack=SLACK) -> bool:
    return (min(a.x1, b.x1) - max(a.x0, b.x0) > slack) and (min(a.y1, b.y1) - max(a.y0, b.y0) > slack)


def overlapping_texts(fig) -> list:
    """Pairs of texts whose boxes overlap (an empty list is a pass)."""
    items = texts(fig)
    seen, out = set(), []
    for i, (s, a) in enumerate(items):
        for u, b in items[i + 1:]:
            key = (s, u, round(a.x0), round(a.y0), round(b.x0), round(b.y0))
            if _overlap(a, b) and key not in seen:
                seen.add(key)
                out.append((s, u))
    return out


def legends_over_axes(fig) -> list:
    """Legends whose box covers part of a visible plot area (legends belong outside the data)."""
    from matplotlib.axes import Axes
    from matplotlib.legend import Legend

    renderer = render(fig)
    axes = [ax for ax in fig.findobj(Axes) if _shown(ax) and ax.get_navigate() and ax.has_data()]
    out = []
    for leg in fig.findobj(Legend):
        if not _shown(leg):
            continue
        box = leg.get_window_extent(renderer)
        for ax in axes:
            if _overlap(box, ax.get_window_extent(renderer), slack=2.0):
                out.append((", ".join(t.get_text() for t in leg.get_texts())[:60], ax.get_title() or ax.get_ylabel()))
    return out


def labels_without_units(fig, allowed=(r"^\$\\mu_\d\$$", r"^$")) -> list:
    """x and y labels of visible axes that name no unit in parentheses (``"t (s)"``), except ``allowed`` patterns."""
    from matplotlib.axes import Axes

    out = []
    for ax in fig.findobj(Axes):
        if not _shown(ax):
            continue
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if not re.search(r"\((?:[^()]*\b)?(s|m|rad|rad/s|N m|N|oz in|%|-)\b[^()]*\)", label) and not any(
                    re.search(p, label) for p in allowed):  # fmt: skip
                out.append(label)
    return out


def all_text(fig) -> str:
    """Every visible text of ``fig``, joined by newlines (to search for words)."""
    return "\n".join(s for s, _ in texts(fig))
