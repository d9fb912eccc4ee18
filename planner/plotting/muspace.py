"""Pictures of mu-space (Figs. 3, 6, 8) and of the graphical test (Fig. 4).

Compute lives in ``mechanics`` (:func:`qsplan.mechanics.muspace.slices.mu_slice`,
:mod:`qsplan.mechanics.muspace.graphical`); this module only draws.  Every function takes
``ax=None`` (a new figure is made) and returns the axes; matplotlib is imported
inside the functions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_mu_map", "plot_contact_scene", "MODE_LINE_COLOURS"]

#: Boundary-curve colours per mode (enumeration index modulo the list): dark, to stand out on the fills.
MODE_LINE_COLOURS = ["#1b1b1b", "#8b0000", "#00008b", "#006400", "#8b008b", "#b8860b", "#008b8b", "#4b0082"]


def _label_regions(ax, sl, min_fraction=0.01):
    """Write the enumeration numbers of the feasible modes inside each sizeable region (as the paper does)."""
    from scipy import ndimage

    f = sl.feasible
    keys = np.packbits(f, axis=-1, bitorder="little").reshape(f.shape[0] * f.shape[1], -1)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(f.shape[:2])
    X, Y = np.meshgrid(sl.xs, sl.ys)
    for u, key in enumerate(uniq):
        modes = np.flatnonzero(np.unpackbits(key, bitorder="little")[: f.shape[-1]])
        text = ",".join(str(j + 1) for j in modes) if modes.size else "Jam"
        comps, count = ndimage.label(inverse == u)
        for c in range(1, count + 1):
            cells = comps == c
            if cells.sum() < min_fraction * cells.size:
                continue
            cx, cy = X[cells].mean(), Y[cells].mean()
            k = np.argmin((X[cells] - cx) ** 2 + (Y[cells] - cy) ** 2)  # a cell of the region near its centroid
            ax.text(X[cells][k], Y[cells][k], text, ha="center", va="center", fontsize=8, weight="bold")


def plot_mu_map(sl, ax=None, curves=True, numbers=True, title=None, colours=None, samples=400):
    """Draw a :class:`qsplan.mechanics.muspace.slices.MuSlice`: cells by mode set, exact region boundaries on top.

    Cells take the colour of their set of feasible modes (jams light grey, overlaps
    their own colour, see :func:`qsplan.planner.plotting.style.plot_mu_slice`).  The boundary of each
    mode's region is drawn from the zero sets of its boundary polynomials
    (:meth:`qsplan.mechanics.muspace.regions.MuRegion.boundary_curves`), not from the cells.

    Parameters
    ----------
    sl : MuSlice
    ax : matplotlib Axes, optional
    curves : bool
        Draw the exact boundaries.
    numbers : bool
        Write the modes' enumeration numbers (3S=1, R1S2=2, ... for three contacts) in the regions.
    title : str, optional
    colours : dict, optional
        Shared mode-set colours across panels (see :func:`qsplan.planner.plotting.style.plot_mu_slice`).
    samples : int
        Samples per axis of each boundary curve.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.lines import Line2D

    from qsplan.planner.plotting.style import plot_mu_slice

    ax = plot_mu_slice(sl.mumap, sl.xs, sl.ys, ax=ax, xlabel=f"$\\mu_{sl.x + 1}$", ylabel=f"$\\mu_{sl.y + 1}$",
                       title=title, colours=colours)  # fmt: skip
    handles = list(ax.get_legend().legend_handles)
    if curves and sl.xs[-1] > sl.xs[0] and sl.ys[-1] > sl.ys[0]:
        drawn = set()
        for c in sl.boundary_curves(samples):
            j = sl.modes.index(c.mode)
            colour = MODE_LINE_COLOURS[j % len(MODE_LINE_COLOURS)]
            ax.plot(c.points[:, 0], c.points[:, 1], color=colour, lw=1.3)
            if j not in drawn:
                drawn.add(j)
                handles.append(Line2D([], [], color=colour, lw=1.3, label=f"boundary of {c.mode.name} ({j + 1})"))
    if numbers:
        _label_regions(ax, sl)
    ax.set_xlim(sl.xs[0], sl.xs[-1])
    ax.set_ylim(sl.ys[0], sl.ys[-1])
    ax.legend(handles=handles, loc="upper right", fontsize=6, framealpha=0.85)
    return ax


def plot_contact_scene(scene, mode=None, mu=None, ax=None, title=None):
    """Draw a scene for operators, with the graphical test of Corollary 1 (Fig. 4).

    Shows the workpiece (the convex hull of the contacts and the centre of mass at
    the origin: raw scenes carry no outline), the contacts, their inward normals,
    friction-cone edges, the lines of action of the active contact forces of
    ``mode``, the line of action of ``g_obj``, and the triangle ``p12 p23 p31``.

    Parameters
    ----------
    scene : Scene
    mode : ContactMode or str, optional
        A 3S or RS mode; default the first kinematically admissible 3S mode, else RS mode.
    mu : array-like, shape (n_c,), optional
        Friction coefficients (default the scene's).
    ax : matplotlib Axes, optional
    title : str, optional

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

    from qsplan.planner.plotting.style import new_axes

    if ax is None:
        _, axes = new_axes(size=(6.0, 5.5))
        ax = axes[0, 0]
    mu = scene.mu if mu is None else np.broadcast_to(np.asarray(mu, float), (scene.n_contacts,))
    if mode is not None and not isinstance(mode, ContactMode):
        mode = ContactMode(str(mode).upper())
    if mode is None:
        candidates = [m for m in enumerate_modes(scene.n_contacts, scene.dof) if m.kind in ("3S", "RS")]
        candidates.sort(key=lambda m: m.kind != "3S")
        mode = next((m for m in candidates if mode_kinematics(scene, m)[1] is not None), None)
        if mode is None:
            raise ModeError("mode: no 3S or RS mode of this scene passes the kinematic stage")
    W = active_wrenches(scene, mode, mu)
    gt = graphical_test(W, scene.g_obj)

    pts = contact_points(scene)
    R = max(1.0, float(np.max(np.linalg.norm(pts, axis=1))))
    L = 0.3 * R
    hull = MultiPoint([tuple(p) for p in pts] + [(0.0, 0.0)]).convex_hull
    if hull.geom_type == "Polygon":
        ax.add_patch(Polygon(np.asarray(hull.exterior.coords), closed=True, fc="#f1e7d0", ec="#a08050", lw=1.0))
    ax.plot([0], [0], "k+", ms=10, mew=1.5)
    handles = [
        Polygon([[0, 0]], fc="#f1e7d0", ec="#a08050", label="workpiece (hull of contacts, centre of mass)"),
        Line2D([], [], color="k", marker="+", ls="", ms=8, label="centre of mass (origin)"),
    ]
    for i, p in enumerate(pts):
        n, t = scene.Wn[:2, i], scene.Wt[:2, i]
        ax.annotate("", xy=p + L * n, xytext=p, arrowprops=dict(arrowstyle="->", color="#2060c0", lw=1.2), in_layout=False)
        for s in (1, -1):
            e = n + s * mu[i] * t
            e = e / np.linalg.norm(e)
            ax.plot([p[0], p[0] + L * e[0]], [p[1], p[1] + L * e[1]], color="#7a7a7a", ls="--", lw=0.9)
        ax.plot(*p, "o", color="k", ms=5)
        ax.text(p[0], p[1], f"  {i + 1} ({mode.letters[i]})", fontsize=9, va="bottom", clip_on=True, in_layout=False)
    handles += [
        Line2D([], [], color="#2060c0", lw=1.2, label="inward normal"),
        Line2D([], [], color="#7a7a7a", ls="--", lw=0.9, label="friction-cone edges"),
    ]
    force_colours = ["#d62728", "#2ca02c", "#9467bd"]
    # the contact each active wrench acts at: sliding contacts in order (3S); the rolling one twice, then the sliding one (RS)
    at = list(mode.sliding) if mode.kind == "3S" else [mode.rolling[0], mode.rolling[0], mode.sliding[0]]
    for k, line in enumerate(gt.lines):
        ax.axline(tuple(line.point), tuple(line.point + line.direction), color=force_colours[k], lw=1.0, alpha=0.9)
        p = pts[at[k]]
        ax.annotate("", xy=p, xytext=p - 0.8 * L * line.direction,
                    arrowprops=dict(arrowstyle="-|>", color=force_colours[k], lw=1.4), in_layout=False)  # fmt: skip
        label = f"line of action, force {k + 1} (contact {at[k] + 1})"
        handles.append(Line2D([], [], color=force_colours[k], lw=1.0, label=label))
    if gt.g_line is not None:
        gl = gt.g_line
        ax.axline(tuple(gl.point), tuple(gl.point + gl.direction), color="k", lw=1.6)
        ax.annotate("", xy=gl.point + L * gl.direction, xytext=gl.point,
                    arrowprops=dict(arrowstyle="-|>", color="k", lw=1.6), in_layout=False)  # fmt: skip
        handles.append(Line2D([], [], color="k", lw=1.6, label="line of action of $g_{obj}$"))
    V = gt.vertices
    if np.all(np.isfinite(V)):
        ax.add_patch(Polygon(V, closed=True, fc="#ff7f0e", alpha=0.18, ec="#ff7f0e", lw=1.5, ls=":"))
        for name, v in zip(("p12", "p23", "p31"), V):
            ax.text(v[0], v[1], name, fontsize=8, color="#ff7f0e", clip_on=True, in_layout=False)
        handles.append(Line2D([], [], color="#ff7f0e", ls=":", lw=1.5, label="triangle p12 p23 p31"))
    span = np.vstack([pts, [[0.0, 0.0]], V[np.all(np.isfinite(V), axis=1)]])
    span = span[np.linalg.norm(span, axis=1) <= 4 * R]
    lo, hi = span.min(axis=0) - 0.6 * L, span.max(axis=0) + 0.6 * L
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    verdict = "feasible" if gt.feasible else "infeasible"
    sense = "".join("+" if s else "-" for s in gt.moment_sense)
    checks = f"negative span {'yes' if gt.negative_span else 'no'}, moment sense {sense}"
    ax.set_title(title or f"{mode.name} ({mode.letters}): graphical test {verdict}\n{checks}", fontsize=9)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=7, framealpha=0.85)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return ax
