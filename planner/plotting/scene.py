"""A scene and the graphical test of Corollary 1 (the paper's Figs. 2, 4 and 5), drawn for people.

Compute lives in :mod:`qsplan.mechanics.muspace.graphical`; this module only draws.  Every point of
the construction (contacts, centre of mass, the triangle ``p12 p23 p31``) lies inside the axes; labels
sit beside their points, pushed away from the lines; Brost and Mason's moment labels shade ``E+`` (the
points about which the three contact forces can only turn the workpiece counter-clockwise) and ``E-``
(only clockwise): the line of action of ``g_obj`` must cross the unshaded channel.  The paper's example
scenes carry no units, so neither do the axes unless ``length_unit`` is given.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plotting.style import FONT, axes_or_new, legend_below

__all__ = ["plot_contact_scene"]

_FORCES = ["#d62728", "#2ca02c", "#9467bd"]
_E_PLUS, _E_MINUS = "#c7e9c0", "#dadaeb"
_WORDS = {"3S": "three sliding contacts", "RS": "one rolling and one sliding contact"}


def _away(p, centre, points=8.0):
    """An offset (points) from ``p`` pointing away from ``centre``."""
    d = np.asarray(p, float) - np.asarray(centre, float)
    n = np.linalg.norm(d)
    d = d / n if n > 0 else np.array([1.0, 0.0])
    return points * d


def _label(ax, p, text, centre, box, colour="k"):
    """``text`` beside ``p``, away from ``centre``, growing into the axes (``box``: their limits)."""
    dx, dy = _away(p, centre)
    (x0, x1), (y0, y1) = box
    fx, fy = (p[0] - x0) / (x1 - x0), (p[1] - y0) / (y1 - y0)
    ha = "left" if fx < 0.12 else "right" if fx > 0.88 else ("left" if dx >= 0 else "right")
    va = "bottom" if fy < 0.12 else "top" if fy > 0.88 else ("bottom" if dy >= 0 else "top")
    ax.annotate(text, p, xytext=(dx, dy), textcoords="offset points", ha=ha, va=va, fontsize=FONT["note"] + 1,
                color=colour, bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})  # fmt: skip


def _moment_regions(ax, lines, box, handles):
    """Shade ``E+`` and ``E-`` (Brost and Mason's moment labels) inside ``box``."""
    from matplotlib.patches import Patch

    (x0, x1), (y0, y1) = box
    X, Y = np.meshgrid(np.linspace(x0, x1, 300), np.linspace(y0, y1, 300))
    P = np.stack([X, Y], axis=-1)
    m = np.stack([ln.moment_about(P) for ln in lines])
    for mask, colour, name, sense in ((np.all(m >= 0, axis=0), _E_PLUS, "E+", "counter-clockwise"),
                                      (np.all(m <= 0, axis=0), _E_MINUS, "E\u2212", "clockwise")):  # fmt: skip
        if not mask.any():
            continue
        ax.contourf(X, Y, mask.astype(float), levels=[0.5, 1.5], colors=[colour], alpha=0.55, zorder=0)
        handles.append(Patch(fc=colour, alpha=0.55, label=f"{name}: the contact forces can turn it only {sense} there"))


def plot_contact_scene(scene, mode=None, mu=None, ax=None, title=None, length_unit=None):
    """Draw a scene for operators, with the graphical test of Corollary 1 (Fig. 4).

    Shows the workpiece (the convex hull of the contacts and the centre of mass at the origin:
    raw scenes carry no outline), the contacts, their inward normals, friction-cone edges, the
    lines of action of the active contact forces of ``mode``, the line of action of ``g_obj``, the
    triangle ``p12 p23 p31`` and the moment labels ``E+`` and ``E-``.

    Parameters
    ----------
    scene : Scene
    mode : ContactMode or str, optional
        A 3S or RS mode; default the first kinematically admissible 3S mode, else RS mode.
    mu : array-like, shape (n_c,), optional
        Friction coefficients (default the scene's).
    ax : matplotlib Axes, optional
    title : str, optional
    length_unit : str, optional
        The unit of the axes (``"m"``); default none, as in the paper's examples.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Polygon
    from shapely.geometry import MultiPoint

    from qsplan.mechanics import ContactMode, ModeError, enumerate_modes
    from qsplan.mechanics.muspace.graphical import active_wrenches, contact_points, graphical_test
    from qsplan.mechanics.muspace.regions import mode_kinematics

    ax = axes_or_new(ax, size=(6.2, 6.2))
    mu = scene.mu if mu is None else np.broadcast_to(np.asarray(mu, float), (scene.n_contacts,))
    if mode is not None and not isinstance(mode, ContactMode):
        mode = ContactMode(str(mode).upper())
    if mode is None:
        candidates = sorted((m for m in enumerate_modes(scene.n_contacts, scene.dof) if m.kind in ("3S", "RS")),
                            key=lambda m: m.kind != "3S")  # fmt: skip
        mode = next((m for m in candidates if mode_kinematics(scene, m)[1] is not None), None)
        if mode is None:
            raise ModeError("mode: no 3S or RS mode of this scene passes the kinematic stage")
    gt = graphical_test(active_wrenches(scene, mode, mu), scene.g_obj)
    pts = contact_points(scene)
    R = max(float(np.max(np.linalg.norm(pts, axis=1))), 1e-9)
    L = 0.3 * R
    V = gt.vertices
    finite_v = V[np.all(np.isfinite(V), axis=1)]
    near_v = finite_v[np.linalg.norm(finite_v, axis=1) <= 8 * R]  # farther: said in the title, not drawn
    span = np.vstack([pts, [[0.0, 0.0]], near_v])
    pad = np.maximum(0.45 * L, 0.1 * (span.max(axis=0) - span.min(axis=0)))  # room for the labels inside the axes
    lo, hi = span.min(axis=0) - pad, span.max(axis=0) + pad
    size = hi - lo
    grow = np.maximum(0.0, 0.7 * size[::-1] - size) / 2  # not much flatter than square: room for labels
    lo, hi = lo - grow, hi + grow
    box = ((lo[0], hi[0]), (lo[1], hi[1]))
    handles = []
    _moment_regions(ax, gt.lines, box, handles)
    hull = MultiPoint([tuple(p) for p in pts] + [(0.0, 0.0)]).convex_hull
    centre = np.array(hull.centroid.coords[0])
    if hull.geom_type == "Polygon":
        ax.add_patch(Polygon(np.asarray(hull.exterior.coords), closed=True, fc="#f1e7d0", ec="#a08050", lw=1.0,
                             alpha=0.85, zorder=1))  # fmt: skip
    handles.append(Polygon([[0, 0]], fc="#f1e7d0", ec="#a08050", label="workpiece (hull of the contacts and the centre of mass)"))
    ax.plot([0], [0], "k+", ms=11, mew=1.6, zorder=5)
    handles.append(Line2D([], [], color="k", marker="+", ls="", ms=8, label="centre of mass"))
    for i, p in enumerate(pts):
        n, t = scene.Wn[:2, i], scene.Wt[:2, i]
        ax.annotate("", xy=p + L * n, xytext=p, arrowprops={"arrowstyle": "->", "color": "#2060c0", "lw": 1.2})
        for s in (1, -1):
            e = n + s * mu[i] * t
            e = e / np.linalg.norm(e)
            ax.plot([p[0], p[0] + L * e[0]], [p[1], p[1] + L * e[1]], color="#7a7a7a", ls="--", lw=0.9, zorder=3)
        ax.plot(*p, "o", color="k", ms=5, zorder=6)
        _label(ax, p, f"{i + 1} ({mode.letters[i]})", centre, box)
    handles += [Line2D([], [], color="k", marker="o", ls="", ms=5,
                       label="contact i (its letter: S slides, R rolls, B breaks)"),  # fmt: skip
                Line2D([], [], color="#2060c0", lw=1.2, label="inward normal"),
                Line2D([], [], color="#7a7a7a", ls="--", lw=0.9, label="friction-cone edges")]  # fmt: skip
    at = list(mode.sliding) if mode.kind == "3S" else [mode.rolling[0], mode.rolling[0], mode.sliding[0]]
    for k, line in enumerate(gt.lines):
        ax.axline(tuple(line.point), tuple(line.point + line.direction), color=_FORCES[k], lw=1.0, alpha=0.9, zorder=2)
        p = pts[at[k]]
        ax.annotate("", xy=p, xytext=p - 0.8 * L * line.direction,
                    arrowprops={"arrowstyle": "-|>", "color": _FORCES[k], "lw": 1.4})  # fmt: skip
        handles.append(Line2D([], [], color=_FORCES[k], lw=1.0, label=f"line of action of contact force {k + 1} (at contact {at[k] + 1})"))
    if gt.g_line is not None:
        gl = gt.g_line
        ax.axline(tuple(gl.point), tuple(gl.point + gl.direction), color="k", lw=1.6, zorder=4)
        ax.annotate("", xy=gl.point + L * gl.direction, xytext=gl.point,
                    arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.6})  # fmt: skip
        handles.append(Line2D([], [], color="k", lw=1.6, label="line of action of $g_{obj}$"))
        handles.append(Line2D([], [], color="none", label="($g_{obj}$: the external force on the workpiece)"))
    if len(finite_v) == 3:
        ax.add_patch(Polygon(finite_v, closed=True, fc="none", ec="#ff7f0e", lw=1.5, ls=":", zorder=4))
        handles.append(Line2D([], [], color="#ff7f0e", ls=":", lw=1.5, label="triangle p12 p23 p31"))
    tri_centre = finite_v.mean(axis=0) if len(finite_v) else centre
    off = []
    for name, v in zip(("p12", "p23", "p31"), V):
        if np.all(np.isfinite(v)) and np.linalg.norm(v) <= 8 * R:
            ax.plot(*v, "o", color="#ff7f0e", ms=4, zorder=5)
            _label(ax, v, name, tri_centre, box, colour="#c25400")
        elif np.all(np.isfinite(v)):
            off.append(f"{name} at ({v[0]:.3g}, {v[1]:.3g})")
    ax.set_xlim(*box[0])
    ax.set_ylim(*box[1])
    ax.set_aspect("equal", adjustable="box")
    verdict = "feasible" if gt.feasible else "not feasible"
    yes = {True: "yes", False: "no"}
    checks = (f"external force in the negative span of the contact forces: {yes[bool(gt.negative_span)]};\n"
              f"it turns the workpiece against them about p12, p23 and p31: {yes[bool(np.all(gt.moment_sense))]}")  # fmt: skip
    head = title or f"{mode.name} ({mode.letters}): {_WORDS.get(mode.kind, mode.kind)}, {verdict} by Corollary 1"
    ax.set_title(head + "\n" + checks + (f"\n(off the plot: {', '.join(off)})" if off else ""), fontsize=FONT["label"])
    unit = f" ({length_unit})" if length_unit else ""
    ax.set_xlabel(f"x{unit}", fontsize=FONT["label"])
    ax.set_ylabel(f"y{unit}", fontsize=FONT["label"])
    legend_below(ax, handles=handles, ncol=2)
    return ax
